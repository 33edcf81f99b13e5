/* Budget files and the check (budget.h). The format follows the conversion profiles': one
 * `key = value` per line, `#` comments, `[group]` lines, strict (an unknown key or group, a repeated
 * key or a bad size is an error naming the line), because a typo in a build gate must not pass
 * silently. */
#include "tools/inspect/budget.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/file_util.h"
#include "tools/convert/profile.h"
#include "lbk/container.h"

const char *tl_budget_kind_name(int kind)
{
    static const char *const n[] = {"total", "section", "object", "light_set"};
    return kind >= 0 && kind <= TL_BUDGET_LIGHT_SET ? n[kind] : "unknown";
}

int tl_budget_parse_size(const char *s, uint64_t *out)
{
    while (isspace((unsigned char)*s)) s++;
    if (!isdigit((unsigned char)*s)) return -1;
    char *end;
    errno = 0;
    const double v = strtod(s, &end);
    if (errno || !isfinite(v) || v < 0) return -1;
    while (isspace((unsigned char)*end)) end++;
    static const struct {
        const char *unit;
        double factor;
    } units[] = {{"", 1},        {"B", 1},           {"kB", 1e3},          {"KB", 1e3}, {"KiB", 1024.0},
                 {"MB", 1e6},    {"MiB", 1048576.0}, {"GB", 1e9},          {"GiB", 1073741824.0}};
    char unit[8] = "";
    size_t n = 0;
    while (end[n] && !isspace((unsigned char)end[n]) && n < sizeof unit - 1) unit[n] = end[n], n++;
    unit[n] = 0;
    const char *rest = end + n;
    while (isspace((unsigned char)*rest)) rest++;
    if (*rest) return -1;
    for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
        if (!strcmp(unit, units[i].unit)) {
            const double bytes = v * units[i].factor;
            if (bytes > 1.8e19 || bytes != floor(bytes)) return -1; /* whole bytes only */
            *out = (uint64_t)bytes;
            return 0;
        }
    return -1;
}

static char *trim(char *s)
{
    while (isspace((unsigned char)*s)) s++;
    char *e = s + strlen(s);
    while (e > s && isspace((unsigned char)e[-1])) *--e = 0;
    return s;
}

/* A key, unquoted, or "quoted" (names with spaces, '=' or '#'). */
static int parse_key(char *k, char *out, size_t size)
{
    size_t n = strlen(k);
    if (n >= 2 && k[0] == '"' && k[n - 1] == '"') {
        k[n - 1] = 0;
        k++;
        n -= 2;
    }
    if (n == 0 || n >= size) return -1;
    memcpy(out, k, n + 1);
    return 0;
}

static int add_rule(tl_budget_rule *rules, size_t *count, const char *name, uint64_t limit)
{
    for (size_t i = 0; i < *count; i++)
        if (!strcmp(rules[i].name, name)) return -2; /* repeated */
    if (*count >= TL_BUDGET_MAX_RULES) return -1;
    snprintf(rules[*count].name, sizeof rules[0].name, "%s", name);
    rules[(*count)++].limit = limit;
    return 0;
}

int tl_budget_parse(const char *text, size_t size, const char *origin, tl_budget *out, char err[TL_ERR_LEN])
{
    memset(out, 0, sizeof *out);
    enum { TOP, SECTIONS, OBJECTS, SETS } group = TOP;
    int have_name = 0;
    size_t pos = 0;
    for (int line_no = 1; pos < size; line_no++) {
        size_t end = pos;
        while (end < size && text[end] != '\n') end++;
        char line[512];
        if (end - pos >= sizeof line) {
            snprintf(err, TL_ERR_LEN, "%s:%d: line longer than %zu bytes", origin, line_no, sizeof line - 1);
            return -1;
        }
        memcpy(line, text + pos, end - pos);
        line[end - pos] = 0;
        pos = end + 1;
        int quoted = 0;
        for (char *c = line; *c; c++) { /* comments outside quotes */
            if (*c == '"') quoted = !quoted;
            if (*c == '#' && !quoted) {
                *c = 0;
                break;
            }
        }
        char *l = trim(line);
        if (!*l) continue;
        if (*l == '[') {
            if (!strcmp(l, "[sections]")) group = SECTIONS;
            else if (!strcmp(l, "[objects]")) group = OBJECTS;
            else if (!strcmp(l, "[light_sets]")) group = SETS;
            else {
                snprintf(err, TL_ERR_LEN, "%s:%d: unknown group %.60s (sections, objects, light_sets)", origin, line_no, l);
                return -1;
            }
            continue;
        }
        char *eq = NULL;
        quoted = 0;
        for (char *c = l; *c && !eq; c++) {
            if (*c == '"') quoted = !quoted;
            if (*c == '=' && !quoted) eq = c;
        }
        if (!eq) {
            snprintf(err, TL_ERR_LEN, "%s:%d: expected key = value", origin, line_no);
            return -1;
        }
        *eq = 0;
        char key[128];
        char *v = trim(eq + 1);
        if (parse_key(trim(l), key, sizeof key)) {
            snprintf(err, TL_ERR_LEN, "%s:%d: empty or overlong key", origin, line_no);
            return -1;
        }
        if (group == TOP && !strcmp(key, "name")) {
            if (have_name++) goto repeated;
            snprintf(out->name, sizeof out->name, "%s", v);
            continue;
        }
        uint64_t bytes;
        if (tl_budget_parse_size(v, &bytes)) {
            snprintf(err, TL_ERR_LEN, "%s:%d: %s: '%.40s' is not a size (bytes, or with B, kB, KiB, MB, MiB, GB, GiB)",
                     origin, line_no, key, v);
            return -1;
        }
        int rc = 0;
        if (group == TOP) {
            if (strcmp(key, "total")) {
                snprintf(err, TL_ERR_LEN, "%s:%d: unknown key %.60s (name, total, or a [group])", origin, line_no, key);
                return -1;
            }
            if (out->has_total++) goto repeated;
            out->total = bytes;
        } else if (group == SECTIONS) {
            const char *name = !strcmp(key, "default") ? "" : key;
            if (*name && !tl_fourcc_parse(name)) {
                snprintf(err, TL_ERR_LEN, "%s:%d: %.60s is not a section type code", origin, line_no, key);
                return -1;
            }
            rc = add_rule(out->sections, &out->section_count, name, bytes);
        } else {
            const char *name = !strcmp(key, "default") ? "" : key;
            rc = group == OBJECTS ? add_rule(out->objects, &out->object_count, name, bytes)
                                  : add_rule(out->sets, &out->set_count, name, bytes);
        }
        if (rc == -2) goto repeated;
        if (rc) {
            snprintf(err, TL_ERR_LEN, "%s:%d: more than %d entries in a group", origin, line_no, TL_BUDGET_MAX_RULES);
            return -1;
        }
        continue;
    repeated:
        snprintf(err, TL_ERR_LEN, "%s:%d: %s given twice", origin, line_no, key);
        return -1;
    }
    if (!out->has_total && !out->section_count && !out->object_count && !out->set_count) {
        snprintf(err, TL_ERR_LEN, "%s: no limit at all (total, [sections], [objects] or [light_sets])", origin);
        return -1;
    }
    if (!have_name) snprintf(out->name, sizeof out->name, "%.63s", origin);
    return 0;
}

int tl_budget_load(const char *arg, tl_budget *out, char err[TL_ERR_LEN])
{
    uint64_t bytes;
    if (tl_budget_parse_size(arg, &bytes) == 0) {
        memset(out, 0, sizeof *out);
        snprintf(out->name, sizeof out->name, "%.63s", arg);
        out->has_total = 1;
        out->total = bytes;
        return 0;
    }
    void *text;
    size_t n;
    char e2[TL_ERR_LEN];
    if (tl_read_file(arg, &text, &n, e2)) {
        snprintf(err, TL_ERR_LEN, "--budget %.80s: neither a size nor a readable file (%.80s)", arg, e2);
        return -1;
    }
    int rc = tl_budget_parse(text, n, arg, out, err);
    free(text);
    return rc;
}

/* ---- the check ------------------------------------------------------------------------------ */

/* The limit for `name` (its own line, else default); 0 when neither. */
static int limit_for(const tl_budget_rule *rules, size_t n, const char *name, uint64_t *limit)
{
    const tl_budget_rule *def = NULL;
    for (size_t i = 0; i < n; i++) {
        if (!strcmp(rules[i].name, name)) {
            *limit = rules[i].limit;
            return 1;
        }
        if (!rules[i].name[0]) def = &rules[i];
    }
    if (def) *limit = def->limit;
    return def != NULL;
}

typedef struct sink {
    tl_budget_result *r;
    size_t cap;
    int failed;
} sink;

static void check(sink *s, int kind, const char *name, uint64_t bytes, uint64_t limit)
{
    s->r->checked++;
    if (bytes <= limit || s->failed) return;
    if (s->r->violation_count == s->cap) {
        size_t nc = s->cap ? 2 * s->cap : 16;
        tl_budget_violation *v = realloc(s->r->violations, nc * sizeof *v);
        if (!v) {
            s->failed = 1;
            return;
        }
        s->r->violations = v;
        s->cap = nc;
    }
    tl_budget_violation *v = &s->r->violations[s->r->violation_count++];
    v->kind = kind;
    snprintf(v->name, sizeof v->name, "%s", name);
    v->bytes = bytes;
    v->limit = limit;
}

int tl_budget_check(const tl_budget *b, const tl_budget_level *lv, tl_budget_result *out)
{
    memset(out, 0, sizeof *out);
    sink s = {out, 0, 0};
    if (b->has_total) check(&s, TL_BUDGET_TOTAL, "", lv->total, b->total);
    for (size_t i = 0; i < lv->section_count; i++) {
        char t[5];
        lbk_fourcc_string(lv->types[i], t);
        char name[5];
        snprintf(name, sizeof name, "%s", t);
        for (int k = 3; k > 0 && name[k] == ' '; k--) name[k] = 0; /* "GLG " is written GLG */
        uint64_t limit;
        if (limit_for(b->sections, b->section_count, name, &limit)) check(&s, TL_BUDGET_SECTION, name, lv->gpu_bytes[i], limit);
    }
    if (lv->memory) {
        for (size_t i = 0; i < lv->memory->object_count; i++) {
            const tl_object_memory *o = &lv->memory->objects[i];
            uint64_t limit;
            if (limit_for(b->objects, b->object_count, o->name, &limit)) check(&s, TL_BUDGET_OBJECT, o->name, o->total_bytes, limit);
        }
        for (size_t i = 0; i < lv->memory->set_count; i++) {
            const tl_set_memory *m = &lv->memory->sets[i];
            uint64_t limit;
            if (limit_for(b->sets, b->set_count, m->name, &limit)) check(&s, TL_BUDGET_LIGHT_SET, m->name, m->payload_bytes, limit);
        }
    }
    if (s.failed) {
        tl_budget_result_free(out);
        return -1;
    }
    return 0;
}

void tl_budget_result_free(tl_budget_result *r)
{
    free(r->violations);
    memset(r, 0, sizeof *r);
}
