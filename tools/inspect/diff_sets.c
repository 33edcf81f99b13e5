/* lbk diff of the light sets and doors (spec/diff-json.md "light_sets", "doors"): each set's
 * entries per target space lined up by texel position or probe index, judged in noise mode against
 * the noise of the full runs they came from. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tools/inspect/diff.h"

typedef struct tol {
    double abs_tol, rel_tol;
    const tl_noise_model *noise; /* NULL: tolerance mode */
} tol;

/* ---- light sets ------------------------------------------------------------------------------ */

typedef struct set_entries {
    uint32_t space, set, payload;
    uint64_t count, cap;
    uint32_t *targets;
    uint8_t *payloads;
    int failed;
} set_entries;

static int gather(void *user, uint32_t target, uint32_t count, const uint32_t *sets, const uint8_t *payloads)
{
    set_entries *e = user;
    for (uint32_t i = 0; i < count; i++) {
        if (sets[i] != e->set) continue;
        if (e->count == e->cap) {
            uint64_t nc = e->cap ? 2 * e->cap : 256;
            uint32_t *nt = realloc(e->targets, (size_t)nc * sizeof *nt);
            if (nt) e->targets = nt;
            uint8_t *np = realloc(e->payloads, (size_t)nc * e->payload);
            if (np) e->payloads = np;
            if (!nt || !np) {
                e->failed = 1;
                return 1;
            }
            e->cap = nc;
        }
        e->targets[e->count] = target;
        memcpy(e->payloads + (size_t)e->count * e->payload, payloads + (size_t)i * e->payload, e->payload);
        e->count++;
    }
    return 0;
}

static int collect_set(const lbk_dls_view *v, uint32_t set, uint32_t space, set_entries *e)
{
    memset(e, 0, sizeof *e);
    e->space = space;
    e->set = set;
    e->payload = space == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD;
    for (uint32_t c = 0; c < lbk_dls_cluster_count(v); c++) {
        lbk_dls_cluster_info ci;
        lbk_dls_cluster_get(v, c, &ci);
        if (ci.space != space) continue;
        int member = 0;
        for (uint32_t i = 0; i < ci.set_count; i++) {
            uint32_t s;
            lbk_dls_cluster_set_get(v, c, i, &s);
            member |= s == set;
        }
        if (member && lbk_dls_cluster_decode(v, c, gather, e) != LBK_OK) return -1;
        if (e->failed) return -1;
    }
    return 0;
}

typedef struct keyed {
    uint64_t key;
    uint64_t index;
} keyed;

static int cmp_keyed(const void *x, const void *y)
{
    const keyed *a = x, *b = y;
    return (a->key > b->key) - (a->key < b->key);
}

/* Texel targets become (page, y, x) keys so bakes whose pages differ in size still line up;
 * probe targets are their index. Sorted, because entry order depends on the clustering. */
static keyed *sorted_keys(const tl_bake *bk, const set_entries *e)
{
    keyed *k = malloc(((size_t)e->count + 1) * sizeof *k);
    if (!k) return NULL;
    for (uint64_t i = 0; i < e->count; i++) {
        uint64_t key = e->targets[i];
        if (e->space == LBK_DLS_SPACE_TEXEL && bk->has_lmap) {
            for (uint32_t page = bk->lmap.page_count; page-- > 0;) { /* pages ascend by first_texel */
                lbk_lmap_planes pg;
                lbk_lmap_planes_get(&bk->lmap, page, &pg);
                if (pg.first_texel > e->targets[i]) continue;
                const uint64_t local = e->targets[i] - pg.first_texel;
                key = ((uint64_t)page << 32) | ((local / pg.width) << 16) | (local % pg.width);
                break;
            }
        }
        k[i] = (keyed){key, i};
    }
    qsort(k, (size_t)e->count, sizeof *k, cmp_keyed);
    return k;
}

/* The scale DLS payloads of a space are stored in: their base section's (spec §12.2). */
static float space_scale(const tl_bake *b, uint32_t space)
{
    if (space == LBK_DLS_SPACE_TEXEL) return b->has_lmap ? b->lmap.scale : 1.0f;
    if (space == LBK_DLS_SPACE_GLG) return b->has_glg ? b->glg.scale : 1.0f;
    return b->has_llg ? b->llg.scale : 1.0f;
}

static void eval_payload(uint32_t space, const uint8_t *p, float scale, float *out)
{
    if (space == LBK_DLS_SPACE_TEXEL) {
        lbk_ahd_texel t;
        if (p) lbk_ahd_texel_unpack(p, &t);
        else memset(&t, 0, sizeof t);
        tl_texel_eval(&t, scale, (float(*)[3])out);
    } else {
        lbk_sh9_rgb s;
        if (p) tl_probe_unpack(p, scale, &s);
        else memset(&s, 0, sizeof s);
        tl_probe_eval(&s, (float(*)[3])out);
    }
}

/* Can the targets of a space be lined up? Texels always can (by page and position); probes when
 * both grids have the same layout. */
static int space_comparable(const tl_bake *a, const tl_bake *b, uint32_t space)
{
    if (space == LBK_DLS_SPACE_TEXEL) return a->has_lmap && b->has_lmap;
    if (lbk_dls_target_count(a->dls, space) != lbk_dls_target_count(b->dls, space)) return 0;
    if (space == LBK_DLS_SPACE_GLG) return a->has_glg && b->has_glg && tl_diff_glg_same_layout(a, b);
    if (!a->has_llg || !b->has_llg || a->llg.grid_count != b->llg.grid_count) return 0;
    for (uint32_t g = 0; g < a->llg.grid_count; g++) {
        lbk_llg_grid ga, gb;
        lbk_llg_grid_get(&a->llg, g, &ga);
        lbk_llg_grid_get(&b->llg, g, &gb);
        if (memcmp(ga.dims, gb.dims, sizeof ga.dims)) return 0;
    }
    return 1;
}

/* The level of the base texel or probe under a key (tl_noise_level; 0 where none): the texel's
 * luminance at +Z, or the probe's mean luminance over the probe normals (GLG or LLG space). */
static double base_level(const tl_bake *bk, uint32_t space, uint64_t key)
{
    if (space == LBK_DLS_SPACE_TEXEL) {
        float v[TL_TEXEL_NORMALS][3];
        if (tl_bake_texel_eval(bk, (uint32_t)(key >> 32), (uint32_t)(key & 0xFFFF), (uint32_t)((key >> 16) & 0xFFFF),
                               v))
            return 0;
        return tl_noise_level(v[0], 0, TL_TEXEL_NORMALS);
    }
    lbk_sh9_rgb sh;
    float pos[3], e[TL_PROBE_NORMALS][3];
    if (space == LBK_DLS_SPACE_GLG && bk->has_glg && key < bk->glg.probe_count)
        lbk_glg_probe_get(&bk->glg, (uint32_t)key, pos, &sh);
    else if (space == LBK_DLS_SPACE_LLG && bk->has_llg && key < bk->llg.probe_count)
        tl_probe_unpack(bk->llg.probes + key * LBK_SH9_PACKED_SIZE, bk->llg.scale, &sh);
    else
        return 0;
    tl_probe_eval(&sh, e);
    return tl_noise_level(e[0], 1, TL_PROBE_NORMALS);
}

/* One side of a set's comparison in one space: its entries, sorted by key, and in noise mode
 * per entry (by entry index, not sorted position) its level and its reference level, entry +
 * the base under it, looked up once. */
typedef struct set_side {
    set_entries e;
    keyed *k;
    double *lev, *ref;
} set_side;

static int set_side_load(const tl_bake *bk, uint32_t set, uint32_t space, int levels, set_side *s)
{
    if (collect_set(bk->dls, set, space, &s->e) || !(s->k = sorted_keys(bk, &s->e))) return -1;
    if (!levels) return 0;
    if (!(s->lev = malloc(sizeof *s->lev * (size_t)(2 * s->e.count + 1)))) return -1;
    s->ref = s->lev + s->e.count;
    const int kind = space == LBK_DLS_SPACE_TEXEL ? 0 : 1;
    for (uint64_t j = 0; j < s->e.count; j++) {
        const uint64_t i = s->k[j].index;
        float v[TL_PROBE_NORMALS * 3];
        eval_payload(space, s->e.payloads + (size_t)i * s->e.payload, space_scale(bk, space), v);
        s->lev[i] = tl_noise_level(v, kind, kind ? TL_PROBE_NORMALS : TL_TEXEL_NORMALS);
        s->ref[i] = s->lev[i] + base_level(bk, space, s->k[j].key);
    }
    return 0;
}

static void set_side_free(set_side *s)
{
    free(s->k), free(s->lev), free(s->e.targets), free(s->e.payloads);
}

/* The factor that turns the entries' noise, relative to entry + base, into the noise of the
 * set's mean: RMS of (entry + base) over the mean entry (1 when the set has no light). */
static double mean_scale(double sum_lev, double sum_ref2, uint64_t n)
{
    return sum_lev > 0 ? sqrt(sum_ref2 / (double)n) / (sum_lev / (double)n) : 1;
}

/* A set's probe entries, like its texel entries, carry the noise of the full runs: REPT's probe
 * estimate relative to entry + base probe, and for the mean test that × mean_scale. */
static double set_probe_scale(const set_side *s)
{
    double sum_lev = 0, sum_ref2 = 0;
    for (uint64_t i = 0; i < s->e.count; i++) sum_lev += s->lev[i], sum_ref2 += s->ref[i] * s->ref[i];
    return mean_scale(sum_lev, sum_ref2, s->e.count);
}

static const keyed *find_key(const keyed *k, uint64_t n, uint64_t key)
{
    const keyed probe = {key, 0};
    return bsearch(&probe, k, (size_t)n, sizeof *k, cmp_keyed);
}

/* A light set's texel entries carry the noise of the full runs they came from (a door's open
 * state is the difference of two), so their noise is relative to the entry plus the base texel
 * under it, not to the entry alone: a door's closed-state entries are 5 % of the base light and
 * their own relative noise 25× the base's (bench/diff_reseed.py, room_sets_doors). Measured as
 * objects' is (rect_noise), from the set's own texels: the high-pass of each entry against its 4
 * neighbours 1 and 2 texels away, relative to entry + base, the larger robust spread (-1 when
 * under 16 entries have all four neighbours). Into *scale the set's mean_scale. */
static double set_texel_noise(const set_side *s, double *scale)
{
    const uint64_t count = s->e.count;
    const keyed *k = s->k;
    *scale = 1;
    double *r = malloc(sizeof *r * (size_t)(count + 1));
    if (!r) return -1;
    double sum_lev = 0, sum_ref2 = 0;
    for (uint64_t i = 0; i < count; i++) {
        const double ref = s->ref[k[i].index];
        sum_lev += s->lev[k[i].index], sum_ref2 += ref * ref;
    }
    double sg = -1;
    for (uint64_t d = 1; d <= TL_NOISE_HIGHPASS_REACH; d *= 2) { /* as tl_noise_highpass */
        size_t n = 0;
        for (uint64_t i = 0; i < count; i++) {
            const uint64_t key = k[i].key, x = key & 0xFFFF, y = (key >> 16) & 0xFFFF;
            if (x < d || y < d || x + d > 0xFFFF || y + d > 0xFFFF) continue;
            const keyed *nb[4] = {find_key(k, count, key - d), find_key(k, count, key + d),
                                  find_key(k, count, key - (d << 16)), find_key(k, count, key + (d << 16))};
            if (!nb[0] || !nb[1] || !nb[2] || !nb[3]) continue; /* at the set's or the chart's edge */
            const double ref = s->ref[k[i].index];
            if (!(ref > 0)) continue;
            const double around = s->lev[nb[0]->index] + s->lev[nb[1]->index] + s->lev[nb[2]->index] + s->lev[nb[3]->index];
            r[n++] = (s->lev[k[i].index] - 0.25 * around) / ref;
        }
        sg = fmax(sg, tl_noise_robust_sigma(r, n));
    }
    *scale = mean_scale(sum_lev, sum_ref2, count);
    free(r);
    return sg;
}

/* The relative noise of one side's set texel entries (set_texel_noise; REPT's estimate spread
 * as for probes when too few to measure, and at least REPT's when the bake was denoised) and the
 * noise of the set's mean, for tl_noise_begin. */
static double set_texel_side_noise(const set_side *s, const tl_noise_model *m, int side, double *mean_noise,
                                   double *scale)
{
    double sg = set_texel_noise(s, scale);
    if (sg < 0) sg = TL_NOISE_REPT_SPREAD * m->rept[side][0];
    sg = fmax(sg, tl_noise_texel_floor(m, side));
    *mean_noise = sg * *scale;
    return sg;
}

/* Starts the noise item of a set's space: the entries' relative noise (*ta, *tb) and the
 * common part, both relative to entry + base. */
static void set_noise_begin(const set_side *sa, const set_side *sb, int kind, int door, const tl_noise_model *m,
                            tl_noise_stats *ns, double *ta, double *tb)
{
    if (kind == 0) {
        double ma, mb, ga, gb;
        *ta = set_texel_side_noise(sa, m, 0, &ma, &ga);
        *tb = set_texel_side_noise(sb, m, 1, &mb, &gb);
        tl_noise_begin(ns, m, door ? TL_NOISE_DOOR_TEXELS : TL_NOISE_SET_TEXELS, ma, mb);
        ns->noise_common = m->common * hypot(ga * m->rept[0][0], gb * m->rept[1][0]);
        return;
    }
    const double ga = set_probe_scale(sa), gb = set_probe_scale(sb), ra = m->rept[0][1], rb = m->rept[1][1];
    tl_noise_begin(ns, m, door ? TL_NOISE_DOOR_PROBES : TL_NOISE_SET_PROBES, ra * ga, rb * gb);
    ns->noise_common = m->common * hypot(ga * ra, gb * rb);
    *ta = ra, *tb = rb;
}

static int compare_set_space(const tl_bake *a, uint32_t set_a, const tl_bake *b, uint32_t set_b, uint32_t space,
                             const tol *t, tl_err_stats *st, tl_noise_stats *ns)
{
    const int kind = space == LBK_DLS_SPACE_TEXEL ? 0 : 1, n = kind ? TL_PROBE_NORMALS : TL_TEXEL_NORMALS;
    set_side sa, sb;
    memset(&sa, 0, sizeof sa), memset(&sb, 0, sizeof sb);
    int rc = -1;
    if (set_side_load(a, set_a, space, t->noise != NULL, &sa) || set_side_load(b, set_b, space, t->noise != NULL, &sb))
        goto out;
    lbk_dls_set_info info;
    lbk_dls_set_get(a->dls, set_a, &info);
    double ta = 0, tb = 0;
    if (t->noise) set_noise_begin(&sa, &sb, kind, info.kind != LBK_DLS_KIND_LIGHTS, t->noise, ns, &ta, &tb);
    uint64_t i = 0, j = 0;
    while (i < sa.e.count || j < sb.e.count) {
        const keyed *xa = NULL, *xb = NULL;
        if (j >= sb.e.count || (i < sa.e.count && sa.k[i].key < sb.k[j].key)) xa = &sa.k[i++];
        else if (i >= sa.e.count || sb.k[j].key < sa.k[i].key) xb = &sb.k[j++];
        else xa = &sa.k[i++], xb = &sb.k[j++];
        const uint64_t key = xa ? xa->key : xb->key;
        float va[TL_PROBE_NORMALS * 3], vb[TL_PROBE_NORMALS * 3];
        eval_payload(space, xa ? sa.e.payloads + (size_t)xa->index * sa.e.payload : NULL, space_scale(a, space), va);
        eval_payload(space, xb ? sb.e.payloads + (size_t)xb->index * sb.e.payload : NULL, space_scale(b, space), vb);
        /* texels: x = position in page, y = row; probes: x = index */
        const uint32_t x = kind ? (uint32_t)key : (uint32_t)(key & 0xFFFF), y = kind ? 0 : (uint32_t)((key >> 16) & 0xFFFF);
        tl_err_add(st, va, vb, 3 * (size_t)n, t->abs_tol, t->rel_tol, x, y, NULL);
        if (t->noise) /* an entry on one side only: the other side's reference is its base alone */
            tl_noise_add_ref(ns, t->noise, va, vb, n, ta, tb, xa ? sa.ref[xa->index] : base_level(a, space, key),
                             xb ? sb.ref[xb->index] : base_level(b, space, key));
    }
    if (t->noise) tl_noise_end(ns, t->noise);
    rc = 0;
out:
    set_side_free(&sa), set_side_free(&sb);
    return rc;
}

static void set_name(const lbk_dls_view *v, uint32_t s, char *out, size_t size)
{
    lbk_dls_set_info si;
    lbk_dls_set_get(v, s, &si);
    tl_string_copy(out, size, (lbk_string){si.name, si.name_length});
}

static int set_meta_equal(const tl_bake *a, uint32_t sa, const tl_bake *b, uint32_t sb)
{
    lbk_dls_set_info ia, ib;
    lbk_dls_set_get(a->dls, sa, &ia);
    lbk_dls_set_get(b->dls, sb, &ib);
    if (ia.kind != ib.kind || ia.light_count != ib.light_count || ia.member_count != ib.member_count) return 0;
    for (uint32_t i = 0; i < ia.light_count; i++) {
        const char *na, *nb;
        uint32_t la, lb;
        lbk_dls_set_light_get(a->dls, sa, i, &na, &la);
        lbk_dls_set_light_get(b->dls, sb, i, &nb, &lb);
        if (la != lb || memcmp(na, nb, la)) return 0;
    }
    for (uint32_t i = 0; i < ia.member_count; i++) {
        uint32_t ma, mb;
        char xa[128], xb[128];
        lbk_dls_set_member_get(a->dls, sa, i, &ma);
        lbk_dls_set_member_get(b->dls, sb, i, &mb);
        set_name(a->dls, ma, xa, sizeof xa);
        set_name(b->dls, mb, xb, sizeof xb);
        if (strcmp(xa, xb)) return 0;
    }
    return 1;
}

static int diff_sets(const tl_bake *a, const tl_bake *b, const tol *t, tl_diff_result *r)
{
    const uint32_t na = a->dls ? lbk_dls_set_count(a->dls) : 0, nb = b->dls ? lbk_dls_set_count(b->dls) : 0;
    r->sets = calloc((size_t)na + nb + 1, sizeof *r->sets);
    if (!r->sets) return -1;
    int comparable[LBK_DLS_SPACE_COUNT_] = {0};
    if (a->dls && b->dls)
        for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) comparable[sp] = space_comparable(a, b, sp);
    for (uint32_t s = 0; s < na; s++) {
        tl_diff_set *d = &r->sets[r->set_count++];
        set_name(a->dls, s, d->name, sizeof d->name);
        uint32_t sb;
        if (!b->dls || lbk_dls_set_find(b->dls, d->name, &sb) != LBK_OK) {
            d->status = TL_DIFF_REMOVED;
            r->sets_changed++;
            continue;
        }
        d->meta_changed = !set_meta_equal(a, s, b, sb);
        int over = 0;
        for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) {
            if (lbk_dls_target_count(a->dls, sp) == 0 && lbk_dls_target_count(b->dls, sp) == 0) continue;
            if (!comparable[sp]) {
                d->not_comparable[sp] = 1;
                continue;
            }
            d->compared[sp] = 1;
            if (compare_set_space(a, s, b, sb, sp, t, &d->lighting[sp], &d->noise[sp])) return -1;
            if (t->noise) {
                over |= !d->noise[sp].within_noise;
                r->items_beyond_noise += !d->noise[sp].within_noise;
            } else {
                over |= d->lighting[sp].over > 0;
            }
            if (sp == LBK_DLS_SPACE_TEXEL) r->texels_over += d->lighting[sp].over;
            else r->probes_over += d->lighting[sp].over;
        }
        int nc = 0;
        for (uint32_t sp = 0; sp < LBK_DLS_SPACE_COUNT_; sp++) nc |= d->not_comparable[sp];
        d->status = (over || d->meta_changed || nc) ? TL_DIFF_CHANGED : TL_DIFF_SAME;
        if (d->status != TL_DIFF_SAME) r->sets_changed++;
    }
    for (uint32_t s = 0; s < nb; s++) {
        char name[128];
        set_name(b->dls, s, name, sizeof name);
        uint32_t x;
        if (a->dls && lbk_dls_set_find(a->dls, name, &x) == LBK_OK) continue;
        tl_diff_set *d = &r->sets[r->set_count++];
        memcpy(d->name, name, sizeof name);
        d->status = TL_DIFF_ADDED;
        r->sets_changed++;
    }
    return 0;
}

/* ---- doors ---------------------------------------------------------------------------------- */

static int door_find(const tl_bake *b, const char *name, lbk_door_info *out)
{
    if (!b->door) return 0;
    for (uint32_t i = 0; i < lbk_door_count(b->door); i++) {
        lbk_door_get(b->door, i, out);
        if (strlen(name) == out->name_length && !memcmp(name, out->name, out->name_length)) return 1;
    }
    return 0;
}

static int door_equal(const tl_bake *a, const lbk_door_info *da, const tl_bake *b, const lbk_door_info *db)
{
    if (memcmp(da->centre, db->centre, sizeof da->centre) || memcmp(da->axes, db->axes, sizeof da->axes) ||
        memcmp(da->half_extents, db->half_extents, sizeof da->half_extents))
        return 0;
    char x[128], y[128];
    set_name(a->dls, da->open_set, x, sizeof x);
    set_name(b->dls, db->open_set, y, sizeof y);
    if (strcmp(x, y)) return 0;
    if ((da->closed_set == LBK_DLS_NO_SET) != (db->closed_set == LBK_DLS_NO_SET)) return 0;
    if (da->closed_set != LBK_DLS_NO_SET) {
        set_name(a->dls, da->closed_set, x, sizeof x);
        set_name(b->dls, db->closed_set, y, sizeof y);
        if (strcmp(x, y)) return 0;
    }
    return 1;
}

int tl_diff_doors_run(const tl_bake *a, const tl_bake *b, tl_diff_result *r)
{
    const uint32_t na = a->door ? lbk_door_count(a->door) : 0, nb = b->door ? lbk_door_count(b->door) : 0;
    r->doors = calloc((size_t)na + nb + 1, sizeof *r->doors);
    if (!r->doors) return -1;
    for (uint32_t i = 0; i < na; i++) {
        lbk_door_info da, db;
        lbk_door_get(a->door, i, &da);
        tl_diff_door *d = &r->doors[r->door_count++];
        tl_string_copy(d->name, sizeof d->name, (lbk_string){da.name, da.name_length});
        if (!door_find(b, d->name, &db)) d->status = TL_DIFF_REMOVED;
        else d->status = door_equal(a, &da, b, &db) ? TL_DIFF_SAME : TL_DIFF_CHANGED;
        if (d->status != TL_DIFF_SAME) r->doors_changed++;
    }
    for (uint32_t i = 0; i < nb; i++) {
        lbk_door_info db, da;
        lbk_door_get(b->door, i, &db);
        char name[128];
        tl_string_copy(name, sizeof name, (lbk_string){db.name, db.name_length});
        if (door_find(a, name, &da)) continue;
        tl_diff_door *d = &r->doors[r->door_count++];
        memcpy(d->name, name, sizeof name);
        d->status = TL_DIFF_ADDED;
        r->doors_changed++;
    }
    return 0;
}

int tl_diff_sets_run(const tl_bake *a, const tl_bake *b, double abs_tol, double rel_tol, const tl_noise_model *noise,
                     tl_diff_result *r)
{
    const tol t = {abs_tol, rel_tol, noise};
    return diff_sets(a, b, &t, r);
}
