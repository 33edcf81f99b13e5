/* Profile files: a small INI dialect (tools/convert/profiles/README.md). Strict on purpose: an unknown
 * key, a duplicate key or a value out of range is an error with a line number, because a typo in
 * a shipping profile must not silently produce a different pack. */
#include "tools/convert/profile.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "tools/common/lmap_decode.h"
#include <unistd.h>

#include "tools/common/error_util.h"
#include "lbk/container.h"

uint32_t tl_fourcc_parse(const char *s)
{
    size_t n = strlen(s);
    if (n < 1 || n > 4) return 0;
    char c[4] = {' ', ' ', ' ', ' '};
    for (size_t i = 0; i < n; i++) {
        if (!isgraph((unsigned char)s[i])) return 0;
        c[i] = s[i];
    }
    return LBK_FOURCC(c[0], c[1], c[2], c[3]);
}

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t') s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r')) s[--n] = '\0';
    return s;
}

static int parse_u32(const char *v, uint32_t *out)
{
    if (!*v || !isdigit((unsigned char)*v)) return -1;
    errno = 0;
    char *end;
    unsigned long long x = strtoull(v, &end, 10);
    if (errno || *end || x > UINT32_MAX) return -1;
    *out = (uint32_t)x;
    return 0;
}

static int is_pow2(uint32_t v) { return v && !(v & (v - 1)); }

/* "drop" | "none" | "zstd" | "zstd:N" */
static int parse_rule(const char *v, tl_section_rule *r)
{
    r->ship = TL_SHIP_KEEP;
    r->compression = LBK_COMPRESSION_NONE;
    r->zstd_level = 0;
    if (!strcmp(v, "drop")) {
        r->ship = TL_SHIP_DROP;
        return 0;
    }
    if (!strcmp(v, "none")) return 0;
    if (!strncmp(v, "zstd", 4)) {
        r->compression = LBK_COMPRESSION_ZSTD;
        r->zstd_level = 19;
        if (v[4] == '\0') return 0;
        uint32_t level;
        if (v[4] != ':' || parse_u32(v + 5, &level) || level < 1 || level > 22) return -1;
        r->zstd_level = (int)level;
        return 0;
    }
    return -1;
}

int tl_profile_parse(const char *text, size_t size, const char *origin, tl_profile *out, char err[TL_ERR_LEN])
{
    memset(out, 0, sizeof *out);
    out->text_hash = XXH3_64bits(text, size);
    out->defaults.compression = LBK_COMPRESSION_NONE;
    enum { TOP, SECTIONS, LMAP } group = TOP;
    int have_name = 0, have_align = 0, have_default = 0, have_pitch = 0, have_page = 0, have_max_page = 0, have_desc = 0, have_plane[2] = {0, 0};
    size_t pos = 0;
    int line_no = 0;
    while (pos < size) {
        size_t end = pos;
        while (end < size && text[end] != '\n') end++;
        line_no++;
        char line[512];
        if (end - pos >= sizeof line) return tl_fail(err, -1, "%s:%d: line longer than %zu bytes", origin, line_no, sizeof line - 1);
        if (memchr(text + pos, '\0', end - pos)) return tl_fail(err, -1, "%s:%d: NUL byte in profile", origin, line_no);
        memcpy(line, text + pos, end - pos);
        line[end - pos] = '\0';
        pos = end + 1;
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        char *s = trim(line);
        if (!*s) continue;
        if (*s == '[') {
            char *close = strchr(s, ']');
            if (!close || *trim(close + 1)) return tl_fail(err, -1, "%s:%d: expected [group]", origin, line_no);
            *close = '\0';
            char *g = trim(s + 1);
            if (!strcmp(g, "sections")) group = SECTIONS;
            else if (!strcmp(g, "lmap")) group = LMAP;
            else return tl_fail(err, -1, "%s:%d: unknown group [%s] (known: [sections], [lmap])", origin, line_no, g);
            continue;
        }
        char *eq = strchr(s, '=');
        if (!eq) return tl_fail(err, -1, "%s:%d: expected 'key = value'", origin, line_no);
        *eq = '\0';
        char *key = trim(s), *val = trim(eq + 1);
        if (!*key) return tl_fail(err, -1, "%s:%d: empty key", origin, line_no);
        if (group == TOP) {
            if (!strcmp(key, "name")) {
                if (have_name++) return tl_fail(err, -1, "%s:%d: duplicate key 'name'", origin, line_no);
                size_t n = strlen(val);
                if (n == 0 || n >= sizeof out->name) return tl_fail(err, -1, "%s:%d: name must be 1..%zu characters", origin, line_no, sizeof out->name - 1);
                for (size_t i = 0; i < n; i++)
                    if (!isalnum((unsigned char)val[i]) && val[i] != '-' && val[i] != '_' && val[i] != '.')
                        return tl_fail(err, -1, "%s:%d: name may contain only letters, digits, '-', '_' and '.'", origin, line_no);
                memcpy(out->name, val, n + 1);
            } else if (!strcmp(key, "description")) {
                if (have_desc++) return tl_fail(err, -1, "%s:%d: duplicate key 'description'", origin, line_no);
                snprintf(out->description, sizeof out->description, "%s", val);
            } else if (!strcmp(key, "alignment")) {
                if (have_align++) return tl_fail(err, -1, "%s:%d: duplicate key 'alignment'", origin, line_no);
                if (parse_u32(val, &out->alignment) || !is_pow2(out->alignment) || out->alignment < LBK_MIN_ALIGNMENT ||
                    out->alignment > LBK_MAX_ALIGNMENT)
                    return tl_fail(err, -1, "%s:%d: alignment '%s' must be a power of two in [%u, %u]", origin, line_no, val,
                                LBK_MIN_ALIGNMENT, LBK_MAX_ALIGNMENT);
            } else {
                return tl_fail(err, -1, "%s:%d: unknown key '%s' (known: name, description, alignment)", origin, line_no, key);
            }
        } else if (group == SECTIONS) {
            tl_section_rule r;
            if (parse_rule(val, &r))
                return tl_fail(err, -1, "%s:%d: '%s' is not drop, none, zstd or zstd:LEVEL (1..22)", origin, line_no, val);
            if (!strcmp(key, "default")) {
                if (have_default++) return tl_fail(err, -1, "%s:%d: duplicate key 'default'", origin, line_no);
                out->defaults = r;
                continue;
            }
            uint32_t type = tl_fourcc_parse(key);
            if (!type) return tl_fail(err, -1, "%s:%d: '%s' is not a section type (1-4 characters, e.g. LMAP)", origin, line_no, key);
            for (size_t i = 0; i < out->rule_count; i++)
                if (out->rules[i].type == type) return tl_fail(err, -1, "%s:%d: duplicate rule for section %s", origin, line_no, key);
            if (out->rule_count == TL_PROFILE_MAX_RULES) return tl_fail(err, -1, "%s:%d: more than %d section rules", origin, line_no, TL_PROFILE_MAX_RULES);
            r.type = type;
            out->rules[out->rule_count++] = r;
        } else if (!strcmp(key, "plane0") || !strcmp(key, "plane1")) {
            const int k = key[5] - '0';
            if (have_plane[k]++) return tl_fail(err, -1, "%s:%d: duplicate key '%s'", origin, line_no, key);
            const int f = tl_lmap_format_parse(k, val);
            if (f < 0)
                return tl_fail(err, -1, "%s:%d: %s '%s' is not an encoding (%s)", origin, line_no, key, val,
                               k == 0 ? "r11g11b10f, bc6h, astc4x4_hdr" : "rgba8, bc5_bc4, astc4x4");
            out->lmap_format[k] = (uint32_t)f;
        } else {
            uint32_t v;
            int *seen;
            uint32_t *dst;
            if (!strcmp(key, "max_page")) {
                if (have_max_page++) return tl_fail(err, -1, "%s:%d: duplicate key '%s'", origin, line_no, key);
                if (parse_u32(val, &v) || (v != 0 && (v < 64 || v > LBK_LMAP_MAX_DIM)))
                    return tl_fail(err, -1, "%s:%d: max_page '%s' must be 0 or in [64, %u]", origin, line_no, val,
                                   (unsigned)LBK_LMAP_MAX_DIM);
                out->lmap_max_page = v;
                continue;
            }
            if (!strcmp(key, "row_pitch_alignment")) seen = &have_pitch, dst = &out->lmap_row_pitch_alignment;
            else if (!strcmp(key, "page_alignment")) seen = &have_page, dst = &out->lmap_page_alignment;
            else return tl_fail(err, -1, "%s:%d: unknown key '%s' in [lmap] (known: row_pitch_alignment, page_alignment, max_page, plane0, plane1)", origin, line_no, key);
            if ((*seen)++) return tl_fail(err, -1, "%s:%d: duplicate key '%s'", origin, line_no, key);
            if (parse_u32(val, &v) || (v != 0 && (!is_pow2(v) || v > LBK_MAX_ALIGNMENT)))
                return tl_fail(err, -1, "%s:%d: %s '%s' must be 0 or a power of two up to %u", origin, line_no, key, val, LBK_MAX_ALIGNMENT);
            *dst = v;
        }
    }
    if (!have_name) return tl_fail(err, -1, "%s: missing 'name'", origin);
    if (!have_align) return tl_fail(err, -1, "%s: missing 'alignment'", origin);
    if (!have_default) return tl_fail(err, -1, "%s: missing 'default' in [sections]", origin);
    return 0;
}

int tl_profile_load_file(const char *path, tl_profile *out, char err[TL_ERR_LEN])
{
    FILE *f = fopen(path, "rb");
    if (!f) return tl_fail(err, -1, "cannot open profile %s: %s", path, strerror(errno));
    char buf[65536];
    size_t n = fread(buf, 1, sizeof buf, f);
    int too_big = n == sizeof buf;
    int rerr = ferror(f);
    fclose(f);
    if (rerr) return tl_fail(err, -1, "cannot read profile %s", path);
    if (too_big) return tl_fail(err, -1, "profile %s is larger than %zu bytes", path, sizeof buf - 1);
    return tl_profile_parse(buf, n, path, out, err);
}

tl_section_rule tl_profile_rule(const tl_profile *p, uint32_t type)
{
    for (size_t i = 0; i < p->rule_count; i++)
        if (p->rules[i].type == type) return p->rules[i];
    tl_section_rule r = p->defaults;
    r.type = type;
    return r;
}

/* The search path, in order; returns the number of directories written. */
static int search_dirs(const char *extra_dir, char dirs[][PATH_MAX], int max)
{
    int n = 0;
    const char *env = getenv("LBK_PROFILE_PATH");
    if (env) {
        const char *p = env;
        while (*p && n < max) {
            const char *colon = strchr(p, ':');
            size_t len = colon ? (size_t)(colon - p) : strlen(p);
            if (len && len < PATH_MAX) {
                memcpy(dirs[n], p, len);
                dirs[n++][len] = '\0';
            }
            p += len + (colon ? 1 : 0);
        }
    }
    if (extra_dir && n < max) snprintf(dirs[n++], PATH_MAX, "%s", extra_dir);
    char exe[PATH_MAX];
    ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (len > 0) {
        exe[len] = '\0';
        char *slash = strrchr(exe, '/');
        if (slash) {
            *slash = '\0';
            if (n < max) snprintf(dirs[n++], PATH_MAX, "%.*s/../tools/convert/profiles", PATH_MAX - 32, exe);
            if (n < max) snprintf(dirs[n++], PATH_MAX, "%.*s/../share/lbk/profiles", PATH_MAX - 32, exe);
        }
    }
    if (n < max) snprintf(dirs[n++], PATH_MAX, "tools/convert/profiles");
    return n;
}

int tl_profile_resolve(const char *name, const char *extra_dir, tl_profile *out, char err[TL_ERR_LEN])
{
    size_t len = strlen(name);
    size_t ext = strlen(TL_PROFILE_EXT);
    if (strchr(name, '/') || (len > ext && !strcmp(name + len - ext, TL_PROFILE_EXT)))
        return tl_profile_load_file(name, out, err);
    if (len == 0 || len > 63) return tl_fail(err, -1, "bad profile name '%s'", name);
    char dirs[8][PATH_MAX];
    int n = search_dirs(extra_dir, dirs, 8);
    for (int i = 0; i < n; i++) {
        char path[PATH_MAX + 80];
        snprintf(path, sizeof path, "%.*s/%s%s", PATH_MAX - 1, dirs[i], name, TL_PROFILE_EXT);
        if (access(path, R_OK) == 0) return tl_profile_load_file(path, out, err);
    }
    char known[160];
    tl_profile_list(extra_dir, known, sizeof known);
    return tl_fail(err, -1, "unknown profile '%s' (found: %s; or pass a file path)", name, known[0] ? known : "none");
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

void tl_profile_list(const char *extra_dir, char *buf, size_t size)
{
    buf[0] = '\0';
    char dirs[8][PATH_MAX];
    int n = search_dirs(extra_dir, dirs, 8);
    char names[64][64];
    char *ptrs[64];
    int count = 0;
    for (int i = 0; i < n; i++) {
        DIR *d = opendir(dirs[i]);
        if (!d) continue;
        struct dirent *e;
        while ((e = readdir(d)) && count < 64) {
            size_t l = strlen(e->d_name), x = strlen(TL_PROFILE_EXT);
            if (l <= x || l - x >= 64 || strcmp(e->d_name + l - x, TL_PROFILE_EXT)) continue;
            char nm[64];
            memcpy(nm, e->d_name, l - x);
            nm[l - x] = '\0';
            int dup = 0;
            for (int k = 0; k < count; k++) dup |= !strcmp(names[k], nm);
            if (!dup) {
                memcpy(names[count], nm, l - x + 1);
                ptrs[count] = names[count];
                count++;
            }
        }
        closedir(d);
    }
    qsort(ptrs, (size_t)count, sizeof ptrs[0], cmp_str);
    size_t used = 0;
    for (int i = 0; i < count; i++) {
        int w = snprintf(buf + used, size - used, "%s%s", i ? ", " : "", ptrs[i]);
        if (w < 0 || (size_t)w >= size - used) break;
        used += (size_t)w;
    }
}
