/* What changed in the inputs and options of two bakes, from their META provenance (the keys of
 * spec/container.md §6.2): options, files, lights, materials, and per object whether its geometry,
 * material or options changed — the why next to lbk diff's what. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/inspect/diff.h"

const char *tl_change_kind_name(int kind)
{
    static const char *const names[] = {"option", "file", "light", "material", "object"};
    return kind >= 0 && kind <= TL_CHANGE_OBJECT ? names[kind] : "unknown";
}

/* The value of a META key as a NUL-terminated copy; NULL when absent (or out of memory). */
static char *meta_value(const tl_bake *b, const char *key)
{
    lbk_string v;
    if (!b->has_meta || lbk_meta_find(&b->meta, key, &v) != LBK_OK) return NULL;
    char *p = malloc(v.size + 1);
    if (p) {
        memcpy(p, v.data, v.size);
        p[v.size] = '\0';
    }
    return p;
}

static char *dup_or_null(const char *s) { return s ? strdup(s) : NULL; }

typedef struct changes {
    tl_diff_result *r;
    size_t cap;
    int failed;
} changes;

static void add_change(changes *c, int kind, int status, const char *name, const char *a, const char *b,
                       const char *fmt, ...) __attribute__((format(printf, 7, 8)));
static void add_change(changes *c, int kind, int status, const char *name, const char *a, const char *b,
                       const char *fmt, ...)
{
    if (c->failed) return;
    tl_diff_result *r = c->r;
    if (r->change_count == c->cap) {
        size_t nc = c->cap ? 2 * c->cap : 16;
        tl_diff_change *n = realloc(r->changes, nc * sizeof *n);
        if (!n) {
            c->failed = 1;
            return;
        }
        r->changes = n;
        c->cap = nc;
    }
    tl_diff_change *ch = &r->changes[r->change_count];
    memset(ch, 0, sizeof *ch);
    ch->kind = kind;
    ch->status = status;
    snprintf(ch->name, sizeof ch->name, "%s", name);
    ch->a = dup_or_null(a);
    ch->b = dup_or_null(b);
    va_list ap;
    va_start(ap, fmt);
    char line[1024];
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    ch->what = strdup(line);
    if ((a && !ch->a) || (b && !ch->b) || !ch->what) {
        free(ch->a), free(ch->b), free(ch->what);
        c->failed = 1;
        return;
    }
    r->change_count++;
}

/* ---- lines of "name<TAB>fields" (scene.lights, scene.materials) or "hash bytes role path" ------ */

typedef struct line {
    char *key, *rest; /* pointers into a copy of the value, NUL-terminated */
} line;

/* Splits value (modified in place) into lines; key = up to `sep` (TAB, or the 3rd space for files). */
static line *split_lines(char *value, int files, size_t *count)
{
    *count = 0;
    if (!value) return calloc(1, sizeof(line));
    size_t n = 0;
    for (const char *p = value; *p; p++) n += *p == '\n';
    line *out = calloc(n + 1, sizeof *out);
    if (!out) return NULL;
    char *p = value;
    while (*p) {
        char *nl = strchr(p, '\n');
        if (nl) *nl = '\0';
        line *l = &out[(*count)++];
        if (files) { /* "hash bytes role path": the path is the key */
            char *s = p;
            for (int k = 0; k < 3 && s; k++) s = strchr(s + (k ? 1 : 0), ' ');
            if (s) {
                *s = '\0';
                l->key = s + 1, l->rest = p;
            } else {
                l->key = p, l->rest = p + strlen(p);
            }
        } else {
            char *tab = strchr(p, '\t');
            if (tab) *tab = '\0';
            l->key = p;
            l->rest = tab ? tab + 1 : p + strlen(p);
        }
        if (!nl) break;
        p = nl + 1;
    }
    return out;
}

static const line *find_line(const line *v, size_t n, const char *key)
{
    for (size_t i = 0; i < n; i++)
        if (!strcmp(v[i].key, key)) return &v[i];
    return NULL;
}

/* The "k=v" fields of a and b that differ, as "k a → b; …" (tokens without '=' compare whole). */
static void field_changes(const char *a, const char *b, char *out, size_t size)
{
    out[0] = '\0';
    size_t used = 0;
    char ta[1024], tb[1024];
    snprintf(ta, sizeof ta, "%s", a);
    snprintf(tb, sizeof tb, "%s", b);
    char *sa, *sb;
    char *pa = strtok_r(ta, " ", &sa);
    char *pb = strtok_r(tb, " ", &sb);
    for (; pa || pb; pa = pa ? strtok_r(NULL, " ", &sa) : NULL, pb = pb ? strtok_r(NULL, " ", &sb) : NULL) {
        if (pa && pb && !strcmp(pa, pb)) continue;
        const char *ea = pa ? strchr(pa, '=') : NULL, *eb = pb ? strchr(pb, '=') : NULL;
        int k;
        if (ea && eb && ea - pa == eb - pb && !strncmp(pa, pb, (size_t)(ea - pa)))
            k = snprintf(out + used, size - used, "%s%.*s %s -> %s", used ? "; " : "", (int)(ea - pa), pa, ea + 1, eb + 1);
        else if (pa && !ea && pb && !eb && strlen(pa) == 16)
            continue; /* the hash of the fields listed: a field below says what changed */
        else
            k = snprintf(out + used, size - used, "%s%s -> %s", used ? "; " : "", pa ? pa : "(none)", pb ? pb : "(none)");
        if (k < 0 || (size_t)k >= size - used) break;
        used += (size_t)k;
    }
}

static void diff_lines(changes *c, const tl_bake *a, const tl_bake *b, const char *key, int kind, int files)
{
    char *va = meta_value(a, key), *vb = meta_value(b, key);
    if (!va && !vb) return;
    size_t na, nb;
    line *la = split_lines(va, files, &na), *lb = split_lines(vb, files, &nb);
    if (!la || !lb) {
        c->failed = 1;
        goto out;
    }
    const char *what = tl_change_kind_name(kind);
    for (size_t i = 0; i < na; i++) {
        const line *o = find_line(lb, nb, la[i].key);
        if (!o) {
            add_change(c, kind, TL_DIFF_REMOVED, la[i].key, la[i].rest, NULL, "%s %s removed", what, la[i].key);
        } else if (strcmp(o->rest, la[i].rest)) {
            char f[900];
            if (files) snprintf(f, sizeof f, "%.400s -> %.400s", la[i].rest, o->rest);
            else field_changes(la[i].rest, o->rest, f, sizeof f);
            add_change(c, kind, TL_DIFF_CHANGED, la[i].key, la[i].rest, o->rest, "%s %s changed: %s", what, la[i].key, f);
        }
    }
    for (size_t j = 0; j < nb; j++)
        if (!find_line(la, na, lb[j].key))
            add_change(c, kind, TL_DIFF_ADDED, lb[j].key, NULL, lb[j].rest, "%s %s added", what, lb[j].key);
out:
    free(la), free(lb), free(va), free(vb);
}

/* ---- options: every bake.* key, the writer and the revision ---------------------------------- */

static int option_key(const char *k)
{
    return !strncmp(k, "bake.", 5) || !strcmp(k, "writer") || !strcmp(k, "writer.version") || !strcmp(k, "revision") ||
           !strncmp(k, "convert.", 8);
}

static void diff_options(changes *c, const tl_diff_result *r)
{
    for (size_t i = 0; i < r->param_count; i++) {
        const tl_diff_param *p = &r->params[i];
        if (!option_key(p->key)) continue;
        const char *name = !strncmp(p->key, "bake.", 5) ? p->key + 5 : p->key;
        add_change(c, TL_CHANGE_OPTION, p->status, p->key, p->a, p->b, "%s %s -> %s", name, p->a ? p->a : "(none)",
                   p->b ? p->b : "(none)");
    }
}

/* ---- objects: line i of scene.objects is OBJS record i: geometry, material, options hashes ---- */

static int object_line(const line *v, size_t n, uint32_t index, char hashes[3][17])
{
    if (index >= n) return 0;
    return sscanf(v[index].key, "%16s %16s %16s", hashes[0], hashes[1], hashes[2]) == 3;
}

static void diff_objects_inputs(changes *c, const tl_bake *a, const tl_bake *b, tl_diff_result *r)
{
    char *va = meta_value(a, "scene.objects"), *vb = meta_value(b, "scene.objects");
    size_t na, nb;
    /* the object lines have no TAB: the whole line is the key */
    line *la = split_lines(va, 0, &na), *lb = split_lines(vb, 0, &nb);
    if (!la || !lb) {
        c->failed = 1;
        goto out;
    }
    if (!va || !vb) goto out;
    for (size_t i = 0; i < r->object_count; i++) {
        tl_diff_object *d = &r->objects[i];
        if (d->status == TL_DIFF_ADDED || d->status == TL_DIFF_REMOVED) continue;
        char ha[3][17], hb[3][17];
        if (!object_line(la, na, d->index_a, ha) || !object_line(lb, nb, d->index_b, hb)) continue;
        static const char *const part[3] = {"geometry", "material", "options"};
        char what[64] = "";
        for (int k = 0; k < 3; k++)
            if (strcmp(ha[k], hb[k])) {
                d->inputs_changed |= 1 << k;
                snprintf(what + strlen(what), sizeof what - strlen(what), "%s%s", what[0] ? ", " : "", part[k]);
            }
        if (d->inputs_changed)
            add_change(c, TL_CHANGE_OBJECT, TL_DIFF_CHANGED, d->name, NULL, NULL, "object %s %s changed", d->name, what);
    }
out:
    free(la), free(lb), free(va), free(vb);
}

int tl_diff_provenance(const tl_bake *a, const tl_bake *b, tl_diff_result *r)
{
    changes c = {r, 0, 0};
    if (a->has_meta != b->has_meta) { /* a pack whose profile drops META: nothing to compare */
        add_change(&c, TL_CHANGE_OPTION, a->has_meta ? TL_DIFF_REMOVED : TL_DIFF_ADDED, "META", NULL, NULL,
                   "%s has no META (provenance dropped, e.g. by a pack profile): inputs and options not compared",
                   a->has_meta ? "B" : "A");
        return c.failed ? -1 : 0;
    }
    diff_options(&c, r);
    diff_lines(&c, a, b, "input.files", TL_CHANGE_FILE, 1);
    diff_lines(&c, a, b, "scene.lights", TL_CHANGE_LIGHT, 0);
    diff_lines(&c, a, b, "scene.materials", TL_CHANGE_MATERIAL, 0);
    diff_objects_inputs(&c, a, b, r);
    return c.failed ? -1 : 0;
}
