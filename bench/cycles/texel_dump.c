/* texel_dump: every receiver of an lbk bake that a Cycles "sensor" can measure, as text.
 *
 *   texel_dump SCENE.gltf BAKE.lbk OUT.tsv [--preset fast|high] [--texel-density D]
 *                                          [--llg-vertices N] [--footprint K] [--jitter SEED]
 *
 * The .lbk holds lighting per texel but not where a texel is in the world. This program
 * rebuilds the baker's layout (import → classify → atlas → texels → push-out, the same calls
 * and options as bake/pipeline/phase_layout.c) to get each texel's world sample point and
 * normal, checks that the layout matches the file (pages, page sizes, every lightmapped
 * object's rectangle, and the LMUV section rebuilt from it equal to the file's byte for byte:
 * the page coordinate of every lightmapped vertex), and reads the lighting from the file with liblbk: the AHD texel decoded
 * along the normal (lbk_lmap_page_irradiance, tangent-space +Z) times the section's scale =
 * the irradiance (lux) a runtime would shade with. LLG objects (props lit by a local light grid)
 * are measured at up to N of their vertices (lbk_llg_vertex_irradiance: grid SH × self-
 * visibility at the vertex, along the vertex normal).
 *
 * Output (tab-separated; '#' lines are the header):
 *   # key value            scene, lbk, est_rel_rmse (the bake's own estimate, REPT last
 *                          record), spp, passes, status, lmap_scale, lmuv_checked (LMUV
 *                          records found equal; 0: the file has none), sensor_offset
 *   # object IDX REP NAME  REP = lightmap | llg | none (OBJS order = scene order)
 *   # material IDX NAME
 *   kind obj mat page x y  px py pz  nx ny nz  size  Er Eg Eb  flags
 * kind: T texel (page/x/y its texel; size = metres per texel; flags = enum bk_texel_flag),
 * V LLG vertex (x = vertex index in its grid; size = 0; flags 0 or HIDDEN), P footprint
 * point of the T row before it (--footprint K, see write_footprint). Rows come in the order the
 * baker stores them (page-major, row-major; then LLG objects in scene order): deterministic.
 *
 * Edge texels (BK_TEXEL_EDGE: the centre lies outside every triangle, so the baker samples the
 * nearest point, on the triangle's border; since the atlas branch also the ring of texels that
 * bilinear filtering reads around a chart, and every texel of a face thinner than a texel) are
 * written 1 % of a texel (at most half the triangle's inradius) inside every edge of their triangle:
 * at a border the point lies on the plane of the neighbouring surface too (a cabinet's bottom
 * edge on the floor, a wall's top edge on the ceiling), and a sensor there sees through that
 * surface (measured: 0.57 lux of sky under a cabinet whose texel reads 0.004). 1 % of a
 * texel changes nothing a texel resolves; lbk's value is that of its own point.
 *
 * Sensors: cycles_bake.py raises each sensor `sensor_offset` (header; 1e-4 of the level's
 * largest extent, 1 mm in a 10 m room) along its normal. A receiver whose raised point is
 * enclosed by geometry — at least half of 16 hemisphere rays from it end on back faces, the rule
 * of lbk's own inside test — gets flag 0x100 (HIDDEN): e.g. the strip of wall behind a window
 * sill that sits flush against it. It is invisible, has no reference value (a sensor there sees
 * the inside of the sill), and run.py leaves it out of every statistic (counted).
 * A texel whose sample point the push-out moved off its own surface — more than 1 % of a texel
 * from its triangle's plane, e.g. the ceiling above the Cornell box's light, moved under the
 * light — gets flag 0x200 (OFFPLANE): its own surface there is covered by another one, so it is
 * invisible too, and its value is a convention (the baker may light the moved point or, with
 * footprint sampling, its own covered surface); run.py leaves it out as well (counted).
 *
 * The lighting comes through the public API only (liblbk's readers). The sample points do not:
 * where the baker put a texel's sample (the nearest point for edge and ring texels, the push-out
 * from behind walls) is in no section, so the layout is rebuilt with the current pipeline's
 * internals (bake/pipeline/phase_layout.c bk_phase_layout: the same calls, options and preset table).
 * It links the baker's internals (like bench_transport.c) but writes nothing the baker reads;
 * the layout it rebuilds must come from the same source tree as the lbk that baked the file
 * (the checks above fail loudly otherwise). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/atlas.h"
#include "bake/layout/classify.h"
#include "bake/layout/texels.h"
#include "bake/layout/uv_math.h"
#include "bake/pipeline/pipeline.h"
#include "bake/pipeline/uv_section.h"
#include "scene/import.h"
#include "scene/scene.h"
#include "scene/tracer.h"
#include "bench/bench_util.h"
#include "lbk/container.h"
#include "lbk/lightmap.h"
#include "lbk/lightmap_uv.h"
#include "lbk/llg.h"
#include "lbk/objects.h"
#include "lbk/report.h"

#define DUMP_HIDDEN 0x100u
#define DUMP_OFFPLANE 0x200u

/* The preset's texel density, from the pipeline's own table (bake/pipeline/bake.c); 0: unknown. */
static float preset_density(const char *preset)
{
    for (int i = 0; i < LBK_BAKE_PRESET_COUNT_; i++)
        if (preset && !strcmp(preset, bk_presets[i].name)) return bk_presets[i].texel_density;
    return 0;
}

typedef struct dump {
    bk_scene scene;
    bk_object_class *classes;
    bk_atlas atlas;
    bk_texels texels;
    bk_tracer *tracer;
    lbk_reader *reader;
    lbk_objects_view objs;
    lbk_lmap_view lmap;
    int have_lmap;
    lbk_llg_view llg;
    int have_llg;
    uint32_t lmuv_checked; /* LMUV records found equal to the rebuilt layout's */
} dump;

static int die(const char *msg, const char *detail)
{
    fprintf(stderr, "texel_dump: %s%s%s\n", msg, detail ? ": " : "", detail ? detail : "");
    return 1;
}

/* bake.c recentres a level that lies far from the origin; the texel positions would then be
 * in another frame. None of the bench scenes does; refuse rather than write wrong positions. */
static int far_from_origin(const bk_scene *s)
{
    double extent = 0;
    for (int k = 0; k < 3; k++) extent = fmax(extent, (double)s->bounds_max[k] - s->bounds_min[k]);
    for (int k = 0; k < 3; k++) {
        double mid = 0.5 * ((double)s->bounds_min[k] + s->bounds_max[k]);
        if (isfinite(mid) && fabs(mid) > 2 * extent && nearbyint(mid) != 0) return 1;
    }
    return 0;
}

static int build_layout(dump *d, const char *scene_path, const char *preset, float density)
{
    char msg[512];
    bk_import_options io;
    memset(&io, 0, sizeof io);
    io.recentre = 1; /* as the pipeline imports; written positions get the origin back */
    if (bk_import_gltf(scene_path, &io, &d->scene, msg, sizeof msg)) return die("import", msg);
    if (far_from_origin(&d->scene)) return die("the level lies far from the origin (the baker recentres it)", NULL);
    bk_scene *s = &d->scene;
    d->classes = calloc(s->object_count ? s->object_count : 1, sizeof *d->classes);
    uint8_t *lightmapped = calloc(s->object_count ? s->object_count : 1, 1);
    if (!d->classes || !lightmapped) return die("out of memory", NULL);
    if (bk_classify_objects(s, NULL, d->classes)) return die("classify failed", NULL);
    size_t n_lm = 0;
    for (size_t i = 0; i < s->object_count; i++) n_lm += lightmapped[i] = d->classes[i].rep == BK_REP_LIGHTMAP;
    bk_atlas_options ao;
    memset(&ao, 0, sizeof ao);
    ao.default_density = preset_density(preset);
    if (!(ao.default_density > 0)) return die("unknown preset", preset);
    ao.density_override = density > 0 ? density : 0;
    if (n_lm && bk_atlas_build(s, lightmapped, &ao, &d->atlas)) return die("atlas failed", NULL);
    free(lightmapped);
    if (bk_tracer_create(s, 0, &d->tracer)) return die("tracer failed", NULL);
    if (n_lm) {
        if (bk_texels_build(s, &d->atlas, &d->texels)) return die("texels failed", NULL);
        bk_pushout_options po;
        memset(&po, 0, sizeof po);
        if (bk_texels_push_out(&d->texels, s, d->tracer, &po, NULL)) return die("push-out failed", NULL);
    }
    return 0;
}

static int open_bake(dump *d, const char *lbk_path)
{
    if (lbk_reader_open_file(lbk_path, NULL, &d->reader)) return die("cannot open", lbk_path);
    const void *data;
    size_t size;
    if (lbk_reader_section_by_type(d->reader, LBK_SECTION_OBJS, &data, &size) || lbk_objects_open(data, size, &d->objs))
        return die("no readable OBJS section", lbk_path);
    if (lbk_reader_section_by_type(d->reader, LBK_SECTION_LMAP, &data, &size) == LBK_OK) {
        if (lbk_lmap_open(data, size, &d->lmap)) return die("unreadable LMAP section", lbk_path);
        d->have_lmap = 1;
    }
    if (lbk_reader_section_by_type(d->reader, LBK_SECTION_LLG, &data, &size) == LBK_OK) {
        if (lbk_llg_open(data, size, &d->llg)) return die("unreadable LLG section", lbk_path);
        d->have_llg = 1;
    }
    return 0;
}

/* The LMUV section (spec §16: every lightmapped vertex's page coordinate, the coordinates the
 * texels were rasterised with) built from the rebuilt atlas must be the file's byte for byte:
 * the strongest check that a texel (page, x, y) here is the file's texel (page, x, y). A file
 * without LMUV (a 1.0 bake) is checked by the rectangles alone. */
static int check_lmuv(dump *d)
{
    const void *data;
    size_t size;
    if (lbk_reader_section_by_type(d->reader, LBK_SECTION_LMUV, &data, &size) != LBK_OK) return 0;
    lbk_lmuv_view v;
    if (lbk_lmuv_open(data, size, &v)) return die("unreadable LMUV section", NULL);
    void *mine = NULL;
    size_t mine_size = 0;
    if (bk_uv_section_build(&d->scene, &d->atlas, d->classes, &mine, &mine_size)) return die("LMUV rebuild failed", NULL);
    int same = mine && mine_size == size && !memcmp(mine, data, size);
    lbk_free(NULL, mine);
    if (!same) return die("the rebuilt lightmap coordinates (LMUV) differ from the file's (layout from another source tree?)", NULL);
    d->lmuv_checked = v.record_count;
    return 0;
}

/* The rebuilt layout must be the one the file was baked with. */
static int check_layout(dump *d)
{
    const bk_scene *s = &d->scene;
    if (d->objs.count != s->object_count) return die("OBJS has another object count than the scene", NULL);
    if ((d->texels.page_count > 0) != d->have_lmap) return die("lightmap pages in one of layout/file only", NULL);
    if (d->have_lmap) {
        if (d->lmap.page_count != d->texels.page_count) return die("page count differs from the file", NULL);
        for (uint32_t p = 0; p < d->lmap.page_count; p++) {
            lbk_lmap_page pg;
            if (lbk_lmap_page_get(&d->lmap, p, &pg)) return die("bad LMAP page", NULL);
            if ((int)pg.width != d->texels.pages[p].width || (int)pg.height != d->texels.pages[p].height)
                return die("page size differs from the file (layout from another source tree?)", NULL);
        }
    }
    for (uint32_t i = 0; i < d->objs.count; i++) {
        lbk_object o;
        if (lbk_objects_get(&d->objs, i, &o)) return die("bad OBJS record", NULL);
        int32_t slot = d->atlas.object_slot && i < d->atlas.scene_object_count ? d->atlas.object_slot[i] : -1;
        int lm = d->classes[i].rep == BK_REP_LIGHTMAP && slot >= 0 && d->atlas.objects[slot].page >= 0;
        if (lm != (o.representation == LBK_REPRESENTATION_LIGHTMAP))
            return die("an object's representation differs from the file", s->objects[i].name);
        if (!lm) continue;
        const bk_atlas_object *ao = &d->atlas.objects[slot];
        if (o.index != (uint32_t)ao->page || o.rect_x != (uint32_t)ao->x || o.rect_y != (uint32_t)ao->y ||
            o.rect_w != (uint32_t)ao->w || o.rect_h != (uint32_t)ao->h)
            return die("an object's lightmap rectangle differs from the file", s->objects[i].name);
    }
    return check_lmuv(d);
}

static double sensor_offset(const bk_scene *s)
{
    double extent = 0;
    for (int k = 0; k < 3; k++) extent = fmax(extent, (double)s->bounds_max[k] - s->bounds_min[k]);
    return 1e-4 * fmax(extent, 1e-3);
}

/* A sensor is a triangle about sensor_offset / 4 across (cycles_bake.py), raised sensor_offset
 * along the normal; Cycles spreads its samples over it. A point the push-out put 8 ulps in front
 * of another surface (a reveal texel pushed onto the top of a sill resting in the reveal) has that
 * surface running through its sensor: half the samples land inside the sill, and the reference
 * read 0.52-0.69 where the point's own value is twice that (dev level sill_niche_00, every such
 * texel 1.9-2.1x). So the sensor moves away from a surface that crosses a disc of radius
 * sensor_offset around its raised point in its own plane: 8 rays in that plane, each hit at
 * t < r moving the point back by r - t along the ray. At most 1/2 mm in a 5 m level: nothing
 * a texel resolves. */
static void clear_sensor(const dump *d, double p[3], const float nf[3])
{
    const double r = sensor_offset(&d->scene);
    double n[3] = {nf[0], nf[1], nf[2]}, t[3], b[3];
    double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(ln > 0)) return;
    for (int k = 0; k < 3; k++) n[k] /= ln;
    bkv_basis(n, t, b);
    double shift[3] = {0, 0, 0};
    for (int i = 0; i < 8; i++) {
        double a = i * (3.14159265358979323846 / 4.0), dir[3];
        float org[3], df[3];
        for (int k = 0; k < 3; k++) {
            dir[k] = cos(a) * t[k] + sin(a) * b[k];
            org[k] = (float)(p[k] + r * n[k]);
            df[k] = (float)dir[k];
        }
        bk_hit h;
        if (bk_tracer_intersect(d->tracer, org, df, 0.0f, (float)r, &h))
            for (int k = 0; k < 3; k++) shift[k] -= (r - h.t) * dir[k];
    }
    for (int k = 0; k < 3; k++) p[k] += shift[k];
}

static void write_header(const dump *d, FILE *f, const char *scene_path, const char *lbk_path)
{
    fprintf(f, "# scene %s\n# lbk %s\n", scene_path, lbk_path);
    const void *data;
    size_t size;
    lbk_report_view rv;
    lbk_reader *r = d->reader;
    if (lbk_reader_section_by_type(r, LBK_SECTION_REPT, &data, &size) == LBK_OK && lbk_report_open(data, size, &rv) == LBK_OK &&
        rv.header.record_count > 0) {
        lbk_report_record last;
        if (lbk_report_record_get(&rv, rv.header.record_count - 1, &last) == LBK_OK)
            fprintf(f, "# est_rel_rmse %.6g\n# spp %u\n# passes %u\n# status %s\n", (double)last.texel_rel_rmse,
                    last.samples_per_texel, rv.header.record_count, lbk_bake_status_name(rv.header.status));
    }
    if (d->have_lmap) fprintf(f, "# lmap_scale %.9g\n", (double)d->lmap.scale);
    fprintf(f, "# lmuv_checked %u\n", d->lmuv_checked);
    fprintf(f, "# sensor_offset %.9g\n", sensor_offset(&d->scene));
    for (uint32_t i = 0; i < d->objs.count; i++) {
        lbk_object o;
        lbk_objects_get(&d->objs, i, &o);
        fprintf(f, "# object %u %s %.*s\n", i, lbk_representation_name(o.representation), (int)o.name.size, o.name.data);
    }
    for (size_t m = 0; m < d->scene.material_count; m++) fprintf(f, "# material %zu %s\n", m, d->scene.materials[m].name);
}

static void tri_vertices(const bk_scene *s, uint32_t tri, double v[3][3])
{
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) v[k][a] = s->positions[3 * (size_t)s->tris[3 * (size_t)tri + k] + a];
}

static void tri_normal(double v[3][3], double n[3], double *area2)
{
    double e1[3], e2[3];
    for (int a = 0; a < 3; a++) e1[a] = v[1][a] - v[0][a], e2[a] = v[2][a] - v[0][a];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    *area2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (*area2 > 0)
        for (int a = 0; a < 3; a++) n[a] /= *area2;
}

/* Another triangle of the object with the edge (x, y) (same positions) in the same plane
 * (normals within ~0.5°), or -1: a quad's diagonal, inside one flat surface. */
static int64_t coplanar_neighbour(const bk_scene *s, uint32_t object, uint32_t tri, const double *x, const double *y,
                                  const double n[3])
{
    const bk_object *ob = &s->objects[object];
    for (uint32_t i = ob->first_tri; i < ob->first_tri + ob->tri_count; i++) {
        if (i == tri) continue;
        double w[3][3], m[3], area2;
        tri_vertices(s, i, w);
        int hx = 0, hy = 0;
        for (int k = 0; k < 3; k++) {
            hx |= w[k][0] == x[0] && w[k][1] == x[1] && w[k][2] == x[2];
            hy |= w[k][0] == y[0] && w[k][1] == y[1] && w[k][2] == y[2];
        }
        if (!hx || !hy) continue;
        tri_normal(w, m, &area2);
        if (area2 > 0 && m[0] * n[0] + m[1] * n[1] + m[2] * n[2] > 0.99996) return i;
    }
    return -1;
}

/* The edges p must keep clear of: the triangle's own edges where another surface may meet it
 * (every edge but a diagonal inside a flat face), and those of the coplanar triangles across its
 * diagonals (the bottom edge of a quad, for a point in the quad's other triangle at the corner). */
typedef struct clear_edges {
    double x[6][3], y[6][3];
    int count;
} clear_edges;

static void add_open_edges(const bk_scene *s, const bk_texel *t, uint32_t tri, int64_t skip, const double n[3],
                           clear_edges *ce, int depth)
{
    double v[3][3];
    tri_vertices(s, tri, v);
    for (int k = 0; k < 3; k++) {
        const double *x = v[k], *y = v[(k + 1) % 3];
        int64_t nb = coplanar_neighbour(s, t->object, tri, x, y, n);
        if (nb < 0 && ce->count < 6) {
            memcpy(ce->x[ce->count], x, sizeof ce->x[0]);
            memcpy(ce->y[ce->count], y, sizeof ce->y[0]);
            ce->count++;
        } else if (nb >= 0 && nb != skip && depth == 0) {
            add_open_edges(s, t, (uint32_t)nb, tri, n, ce, 1);
        }
    }
}

/* Moves p, within its triangle's plane, at least 1 % of a texel (at most half the inradius) in
 * from every edge it must keep clear of (above), along the edge's inward normal. Not towards the
 * centroid: on a sliver (a rug's 12 mm side face, 2.2 m long) the centroid lies along the face,
 * and the point stayed 0.01 mm above the floor it stands on. A point the push-out moved farther
 * than that off its triangle keeps its place (it is lbk's sample point, not on this border). */
static void inside_triangle(const bk_scene *s, const bk_texel *t, double p[3])
{
    double v[3][3], n[3], area2, perimeter = 0;
    tri_vertices(s, t->tri, v);
    tri_normal(v, n, &area2);
    if (!(area2 > 0)) return;
    for (int k = 0; k < 3; k++) {
        const double *x = v[k], *y = v[(k + 1) % 3];
        perimeter += sqrt((y[0] - x[0]) * (y[0] - x[0]) + (y[1] - x[1]) * (y[1] - x[1]) + (y[2] - x[2]) * (y[2] - x[2]));
    }
    double step = fmin(0.01 * t->texel_size, 0.5 * area2 / perimeter); /* inradius = 2·area / perimeter */
    if (!(step > 0)) return;
    clear_edges ce;
    ce.count = 0;
    add_open_edges(s, t, t->tri, -1, n, &ce, 0);
    for (int pass = 0; pass < 2; pass++) /* twice: at a corner the second edge's move may undo the first's */
        for (int k = 0; k < ce.count; k++) {
            const double *x = ce.x[k], *y = ce.y[k];
            double e[3] = {y[0] - x[0], y[1] - x[1], y[2] - x[2]}, m[3];
            m[0] = n[1] * e[2] - n[2] * e[1], m[1] = n[2] * e[0] - n[0] * e[2], m[2] = n[0] * e[1] - n[1] * e[0];
            double len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]), dist = 0;
            if (!(len > 0)) continue;
            for (int a = 0; a < 3; a++) dist += (p[a] - x[a]) * m[a] / len;
            if (dist < -step && pass == 0) return;
            if (dist < step)
                for (int a = 0; a < 3; a++) p[a] += (step - dist) * m[a] / len;
        }
}

/* See OFFPLANE above. */
static int off_plane(const bk_scene *s, const bk_texel *t)
{
    const float *v[3];
    for (int k = 0; k < 3; k++) v[k] = s->positions + 3 * (size_t)s->tris[3 * (size_t)t->tri + k];
    double e1[3], e2[3], n[3];
    for (int a = 0; a < 3; a++) e1[a] = (double)v[1][a] - v[0][a], e2[a] = (double)v[2][a] - v[0][a];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0)) return 0;
    double dist = 0;
    for (int a = 0; a < 3; a++) dist += ((double)t->position[a] - v[0][a]) * n[a] / len;
    return fabs(dist) > 0.01 * t->texel_size;
}

/* Uniform in [0, 1) from (seed, row, stratum, axis): the benches' SplitMix64 finaliser, the same
 * numbers on every machine. */
static double jitter_u(uint32_t seed, size_t row, int i, int j, int axis)
{
    uint64_t z = ((uint64_t)seed << 40) ^ ((uint64_t)row << 8) ^ ((uint64_t)(unsigned)i << 4) ^ (uint64_t)(unsigned)j;
    return (double)(bench_mix(z * 2 + (uint64_t)axis + 0x9E3779B97F4A7C15ull) >> 11) * (1.0 / 9007199254740992.0);
}

/* Footprint sensors (--footprint K): the texel's value is its irradiance averaged over the part of
 * its square its chart covers, so a point sensor at its sample point measures something else
 * wherever the light changes within a texel (a ceiling texel over the Cornell light's 1 cm gap).
 * Edge texels (centre outside their chart) with a footprint are measured over it too: the baker
 * gathers them over it, and a chart thinner than a texel (an authored layout's face of a table
 * leg, a strip under a texel wide) has only such texels; measured at their one point, the legs of
 * a dev level read 5.3 % error where their footprint mean reads 3.5 % (bench/levels).
 * One point in each of the K × K strata of the footprint box, where a footprint triangle covers
 * it, becomes a row "P obj mat PARENT i j  p n  size  rgb  flags" (PARENT: the data row index of
 * the texel's T row; rgb: the texel's own value; flags HIDDEN where the point is enclosed);
 * run.py averages the Cycles values of the points not HIDDEN into the texel's: the visible part
 * of its square, whatever part of it the baker samples (the baker leaves out the part beyond
 * another surface seen from the texel's point: bake/layout/texels.h, push-out). The point is the stratum's centre
 * (jitter 0) or uniform in it (jitter = a seed): centres are a midpoint rule, biased where the
 * light is curved across a texel — the Cornell ceiling next to the light's gap, where irradiance
 * falls off steeply, read 23–33 % low at K = 2 against K = 4 — while jittered strata average to
 * the footprint mean, and two references with different seeds put that quadrature's spread into
 * the measured reference noise. Returns the rows written. */
static size_t write_footprint(const dump *d, FILE *f, const bk_texel *t, size_t parent, int k, uint32_t jitter,
                              const float rgb[3])
{
    if (k <= 0 || !t->footprint_count || (t->flags & BK_TEXEL_RING)) return 0;
    const float *bx = t->footprint_box;
    const int box = bx[2] > 0 && bx[3] > 0;
    size_t rows = 0;
    uint32_t mat = d->scene.tri_material ? d->scene.tri_material[t->tri] : 0;
    for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) {
            const double ui = jitter ? jitter_u(jitter, parent, i, j, 0) : 0.5;
            const double uj = jitter ? jitter_u(jitter, parent, i, j, 1) : 0.5;
            double s = (i + ui) / k, tt = (j + uj) / k, p[3], n[3];
            if (box) s = bx[0] + s * bx[2], tt = bx[1] + tt * bx[3];
            if (!bk_footprint_point(&d->scene, d->texels.footprint + t->footprint_first, t->footprint_count, s, tt, p,
                                    n))
                continue;
            float nf[3] = {(float)n[0], (float)n[1], (float)n[2]};
            clear_sensor(d, p, nf);
            uint32_t flags = bk_tracer_enclosed(d->tracer, p, nf, sensor_offset(&d->scene)) ? DUMP_HIDDEN : 0;
            fprintf(f, "P\t%u\t%u\t%zu\t%d\t%d\t%.9g\t%.9g\t%.9g\t%.7g\t%.7g\t%.7g\t%.6g\t%.7g\t%.7g\t%.7g\t%u\n",
                    t->object, mat, parent, i, j, p[0] + d->scene.origin[0], p[1] + d->scene.origin[1],
                    p[2] + d->scene.origin[2], nf[0], nf[1], nf[2], t->texel_size, rgb[0], rgb[1], rgb[2], flags);
            rows++;
        }
    return rows;
}

static int write_texels(const dump *d, FILE *f, int footprint, uint32_t jitter)
{
    size_t row = 0;
    for (size_t i = 0; i < d->texels.count; i++) {
        const bk_texel *t = &d->texels.receivers[i];
        if (!(t->flags & BK_TEXEL_VALID)) continue;
        lbk_lmap_page pg;
        float rgb[3];
        const float up[3] = {0, 0, 1}; /* tangent-space normal: the texel's own shading normal */
        if (lbk_lmap_page_get(&d->lmap, t->page, &pg) || lbk_lmap_page_irradiance(&pg, t->x, t->y, up, rgb))
            return die("texel outside its page", NULL);
        uint32_t mat = d->scene.tri_material ? d->scene.tri_material[t->tri] : 0;
        double p[3] = {t->position[0], t->position[1], t->position[2]};
        if (t->flags & BK_TEXEL_EDGE) inside_triangle(&d->scene, t, p);
        clear_sensor(d, p, t->normal);
        const int hidden = bk_tracer_enclosed(d->tracer, p, t->normal, sensor_offset(&d->scene));
        uint32_t flags = t->flags | (hidden ? DUMP_HIDDEN : 0) |
                         (off_plane(&d->scene, t) ? DUMP_OFFPLANE : 0);
        fprintf(f, "T\t%u\t%u\t%u\t%u\t%u\t%.9g\t%.9g\t%.9g\t%.7g\t%.7g\t%.7g\t%.6g\t%.7g\t%.7g\t%.7g\t%u\n", t->object,
                mat, t->page, t->x, t->y, p[0] + d->scene.origin[0], p[1] + d->scene.origin[1],
                p[2] + d->scene.origin[2], t->normal[0], t->normal[1], t->normal[2], t->texel_size,
                rgb[0], rgb[1], rgb[2], flags);
        row += 1 + write_footprint(d, f, t, row, footprint, jitter, rgb);
    }
    return 0;
}

static int by_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* LLG vertices: llg_place.h orders a grid's vertices by ascending global index among the
 * object's triangle corners; up to max_per_object of them, evenly spaced in that order. */
static int write_llg_vertices(const dump *d, FILE *f, uint32_t max_per_object)
{
    const bk_scene *s = &d->scene;
    for (uint32_t i = 0; i < d->objs.count; i++) {
        lbk_object o;
        lbk_objects_get(&d->objs, i, &o);
        if (o.representation != LBK_REPRESENTATION_LLG || !d->have_llg) continue;
        const bk_object *ob = &s->objects[i];
        size_t nc = 3 * (size_t)ob->tri_count;
        uint32_t *v = malloc((nc ? nc : 1) * sizeof *v);
        if (!v) return die("out of memory", NULL);
        memcpy(v, s->tris + 3 * (size_t)ob->first_tri, nc * sizeof *v);
        qsort(v, nc, sizeof *v, by_u32);
        size_t n = 0;
        for (size_t k = 0; k < nc; k++)
            if (k == 0 || v[k] != v[k - 1]) v[n++] = v[k];
        lbk_llg_grid g;
        if (lbk_llg_grid_get(&d->llg, o.index, &g) || g.vertex_count != n) {
            free(v);
            return die("an LLG's vertex count differs from the scene object", ob->name);
        }
        size_t step = n > max_per_object && max_per_object ? (n + max_per_object - 1) / max_per_object : 1;
        for (size_t k = 0; k < n; k += step) {
            const float *p = s->positions + 3 * (size_t)v[k], *nn = s->normals + 3 * (size_t)v[k];
            const float pw[3] = {(float)(p[0] + s->origin[0]), (float)(p[1] + s->origin[1]), (float)(p[2] + s->origin[2])};
            float rgb[3];
            if (lbk_llg_vertex_irradiance(&d->llg, o.index, (uint32_t)k, pw, rgb)) {
                free(v);
                return die("LLG vertex irradiance failed", ob->name);
            }
            /* the material of the first triangle using the vertex is not needed: one per object */
            uint32_t mat = s->tri_material ? s->tri_material[ob->first_tri] : 0;
            const double pd[3] = {p[0], p[1], p[2]};
            uint32_t flags = bk_tracer_enclosed(d->tracer, pd, nn, sensor_offset(s)) ? DUMP_HIDDEN : 0;
            fprintf(f, "V\t%u\t%u\t%u\t%zu\t0\t%.9g\t%.9g\t%.9g\t%.7g\t%.7g\t%.7g\t0\t%.7g\t%.7g\t%.7g\t%u\n", i, mat,
                    o.index, k, pw[0], pw[1], pw[2], nn[0], nn[1], nn[2],
                    rgb[0], rgb[1], rgb[2], flags);
        }
        free(v);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: texel_dump SCENE.gltf BAKE.lbk OUT.tsv [--preset fast|high] [--texel-density D] "
                        "[--llg-vertices N] [--footprint K] [--jitter SEED]\n");
        return 2;
    }
    const char *preset = "fast";
    float density = 0;
    uint32_t llg_vertices = 256;
    int footprint = 0;
    uint32_t jitter = 0;
    for (int i = 4; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--preset")) preset = argv[i + 1];
        else if (!strcmp(argv[i], "--texel-density")) density = strtof(argv[i + 1], NULL);
        else if (!strcmp(argv[i], "--llg-vertices")) llg_vertices = (uint32_t)strtoul(argv[i + 1], NULL, 10);
        else if (!strcmp(argv[i], "--footprint")) footprint = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--jitter")) jitter = (uint32_t)strtoul(argv[i + 1], NULL, 10);
        else return die("unknown option", argv[i]);
    }
    dump d;
    memset(&d, 0, sizeof d);
    int rc = build_layout(&d, argv[1], preset, density);
    if (!rc) rc = open_bake(&d, argv[2]);
    if (!rc) rc = check_layout(&d);
    FILE *f = rc ? NULL : fopen(argv[3], "w");
    if (!rc && !f) rc = die("cannot write", argv[3]);
    if (!rc) {
        write_header(&d, f, argv[1], argv[2]);
        if (footprint < 0 || footprint > 8) rc = die("--footprint K: 0 (point sensors) to 8", NULL);
        if (!rc && d.have_lmap) rc = write_texels(&d, f, footprint, jitter);
        if (!rc) rc = write_llg_vertices(&d, f, llg_vertices);
        if (fclose(f)) rc = die("write failed", argv[3]);
    }
    if (d.reader) lbk_reader_close(d.reader);
    if (d.tracer) bk_tracer_destroy(d.tracer);
    bk_texels_free(&d.texels);
    bk_atlas_free(&d.atlas);
    free(d.classes);
    bk_scene_free(&d.scene);
    return rc;
}
