/* META of a bake: the keys of spec/container.md §6.2. Values are text a person can read and lbk
 * diff can compare line by line; nothing here depends on the machine, the folder or the time
 * (unless --timestamp), so the same inputs and options give the same bytes. */
#include "bake/pipeline/provenance.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#define XXH_INLINE_ALL /* as the rest of the baker: liblbkbake links no xxhash of its own */
#include <xxhash.h>

#include "lbk/meta.h"

int bk_provenance_add_file(bk_scene *scene, const char *path, const char *role)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    XXH3_state_t st;
    XXH3_INITSTATE(&st);
    XXH3_64bits_reset(&st);
    uint64_t bytes = 0;
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) {
        XXH3_64bits_update(&st, buf, n);
        bytes += n;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) return -1;
    bk_input_file *in = realloc(scene->inputs, (scene->input_count + 1) * sizeof *in);
    if (!in) return -1;
    scene->inputs = in;
    bk_input_file *r = &in[scene->input_count++];
    memset(r, 0, sizeof *r);
    const char *base = strrchr(path, '/');
    snprintf(r->path, sizeof r->path, "%s", base ? base + 1 : path);
    snprintf(r->role, sizeof r->role, "%s", role);
    r->bytes = bytes;
    r->hash = XXH3_64bits_digest(&st);
    return 0;
}

/* ---- text building ------------------------------------------------------------------------ */

typedef struct text {
    char *p;
    size_t n, cap;
    int failed;
} text;

static void put(text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(text *t, const char *fmt, ...)
{
    if (t->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(t->p ? t->p + t->n : NULL, t->p ? t->cap - t->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) {
            t->failed = 1;
            return;
        }
        if (t->p && t->n + (size_t)k < t->cap) {
            t->n += (size_t)k;
            return;
        }
        size_t cap = t->cap ? t->cap : 256;
        while (cap <= t->n + (size_t)k) cap *= 2;
        char *np = realloc(t->p, cap);
        if (!np) {
            t->failed = 1;
            return;
        }
        t->p = np;
        t->cap = cap;
    }
}

/* A name on one line: tab, newline and backslash escaped. */
static void put_name(text *t, const char *s)
{
    for (; *s; s++) {
        if (*s == '\t') put(t, "\\t");
        else if (*s == '\n') put(t, "\\n");
        else if (*s == '\\') put(t, "\\\\");
        else put(t, "%c", *s);
    }
}

static void put_vec(text *t, const float *v, int n)
{
    for (int i = 0; i < n; i++) put(t, "%s%.9g", i ? "," : "", (double)v[i]);
}

/* ---- per-item hashes ------------------------------------------------------------------------ */

static uint64_t image_hash(const bk_scene *s, int index)
{
    if (index < 0 || (size_t)index >= s->image_count) return 0;
    const bk_image *im = &s->images[index];
    XXH3_state_t st;
    XXH3_INITSTATE(&st);
    XXH3_64bits_reset(&st);
    int32_t wh[2] = {im->width, im->height};
    XXH3_64bits_update(&st, wh, sizeof wh);
    XXH3_64bits_update(&st, im->rgba, (size_t)im->width * (size_t)im->height * 4 * sizeof(float));
    return XXH3_64bits_digest(&st);
}

/* What a material contributes to the bake: colours, sidedness and the decoded texture texels. */
static uint64_t material_hash(const bk_scene *s, const bk_material *m)
{
    struct {
        float albedo[3], emission[3];
        int32_t double_sided;
        uint64_t albedo_tex, emission_tex;
    } key;
    memset(&key, 0, sizeof key);
    memcpy(key.albedo, m->albedo, sizeof key.albedo);
    memcpy(key.emission, m->emission, sizeof key.emission);
    key.double_sided = m->double_sided;
    key.albedo_tex = image_hash(s, m->albedo_tex);
    key.emission_tex = image_hash(s, m->emission_tex);
    if (!bk_material_glossy(m)) return XXH3_64bits(&key, sizeof key); /* Lambertian: as before 13.2 */
    /* a glossy material (GGX.md) also bakes by its metallic, roughness and their texture */
    struct {
        uint64_t lambert;
        float metallic, roughness;
        uint64_t metal_rough_tex;
    } gk;
    memset(&gk, 0, sizeof gk);
    gk.lambert = XXH3_64bits(&key, sizeof key);
    gk.metallic = m->metallic;
    gk.roughness = m->roughness;
    gk.metal_rough_tex = image_hash(s, m->metal_rough_tex1 - 1);
    return XXH3_64bits(&gk, sizeof gk);
}

/* geometry: world positions, normals, uv0 and (when it has them) uv1 of every triangle corner;
 * material: the material hash of every triangle; options: the object's lbk_* extras. */
static void object_hashes(const bk_pipeline *b, const uint64_t *mat_hash, const bk_object *o, uint64_t out[3])
{
    const bk_scene *s = &b->scene;
    XXH3_state_t g, m;
    XXH3_INITSTATE(&g);
    XXH3_INITSTATE(&m);
    XXH3_64bits_reset(&g);
    XXH3_64bits_reset(&m);
    for (uint32_t k = 0; k < o->tri_count; k++) {
        const size_t t = (size_t)o->first_tri + k;
        for (int c = 0; c < 3; c++) {
            const size_t v = s->tris[3 * t + c];
            float corner[10] = {0};
            bk_pipeline_to_world(b, &s->positions[3 * v], corner);
            memcpy(corner + 3, &s->normals[3 * v], 3 * sizeof(float));
            if (s->uv0) memcpy(corner + 6, &s->uv0[2 * v], 2 * sizeof(float));
            if (o->has_uv1 && s->uv1) memcpy(corner + 8, &s->uv1[2 * v], 2 * sizeof(float));
            for (int i = 0; i < 10; i++)
                if (corner[i] == 0) corner[i] = 0; /* -0 as +0 */
            XXH3_64bits_update(&g, corner, sizeof corner);
        }
        XXH3_64bits_update(&m, &mat_hash[s->tri_material[t]], sizeof mat_hash[0]);
    }
    out[0] = XXH3_64bits_digest(&g);
    out[1] = XXH3_64bits_digest(&m);
    struct {
        int32_t lighting;
        float texel_density;
        char light_set[64], door[64];
    } opt;
    memset(&opt, 0, sizeof opt);
    opt.lighting = o->lighting;
    opt.texel_density = o->texel_density;
    memcpy(opt.light_set, o->light_set, sizeof opt.light_set);
    memcpy(opt.door, o->door, sizeof opt.door);
    out[2] = XXH3_64bits(&opt, sizeof opt);
}

/* ---- the values -------------------------------------------------------------------------------- */

static void input_files(const bk_scene *s, text *t)
{
    for (size_t i = 0; i < s->input_count; i++) {
        const bk_input_file *f = &s->inputs[i];
        put(t, "%016llx %llu %s ", (unsigned long long)f->hash, (unsigned long long)f->bytes, f->role);
        put_name(t, f->path);
        put(t, "\n");
    }
}

static void materials(const bk_scene *s, const uint64_t *mat_hash, text *t)
{
    for (size_t i = 0; i < s->material_count; i++) {
        const bk_material *m = &s->materials[i];
        put_name(t, m->name);
        put(t, "\t%016llx albedo=", (unsigned long long)mat_hash[i]);
        put_vec(t, m->albedo, 3);
        put(t, " emission=");
        put_vec(t, m->emission, 3);
        put(t, " double_sided=%d albedo_tex=", m->double_sided);
        if (m->albedo_tex >= 0) put(t, "%016llx", (unsigned long long)image_hash(s, m->albedo_tex));
        else put(t, "-");
        put(t, " emission_tex=");
        if (m->emission_tex >= 0) put(t, "%016llx", (unsigned long long)image_hash(s, m->emission_tex));
        else put(t, "-");
        if (bk_material_glossy(m)) { /* only where not Lambertian: Lambertian scenes' META as before */
            put(t, " metallic=%.9g roughness=%.9g metal_rough_tex=", (double)m->metallic, (double)m->roughness);
            if (m->metal_rough_tex1 > 0) put(t, "%016llx", (unsigned long long)image_hash(s, m->metal_rough_tex1 - 1));
            else put(t, "-");
        }
        put(t, "\n");
    }
}

static void lights(const bk_pipeline *b, text *t)
{
    static const char *const type[] = {"point", "spot", "directional"};
    const bk_scene *s = &b->scene;
    for (size_t i = 0; i < s->light_count; i++) {
        const bk_light *l = &s->lights[i];
        float pos[3];
        bk_pipeline_to_world(b, l->position, pos);
        put_name(t, l->name);
        put(t, "\t%s color=", l->type >= 0 && l->type < 3 ? type[l->type] : "unknown");
        put_vec(t, l->color, 3);
        if (l->type != BK_LIGHT_DIRECTIONAL) {
            put(t, " position=");
            put_vec(t, pos, 3);
        }
        if (l->type != BK_LIGHT_POINT) {
            put(t, " direction=");
            put_vec(t, l->direction, 3);
        }
        put(t, " range=%.9g", (double)l->range);
        if (l->type == BK_LIGHT_SPOT) put(t, " cone=%.9g,%.9g", (double)l->inner_cone, (double)l->outer_cone);
        put(t, " set=");
        put_name(t, l->light_set);
        put(t, "\n");
    }
}

static void sky(const bk_scene *s, text *t)
{
    if (s->sky_image >= 0) {
        const char *name = "";
        for (size_t i = 0; i < s->input_count; i++)
            if (!strcmp(s->inputs[i].role, "sky")) name = s->inputs[i].path; /* the last one read is used */
        put(t, "exr ");
        put_name(t, name);
        put(t, " %016llx", (unsigned long long)image_hash(s, s->sky_image));
    } else {
        put_vec(t, s->sky, 3);
    }
}

/* ---- META ------------------------------------------------------------------------------------- */

enum { MAX_PAIRS = 48 };

lbk_result bk_provenance_meta(const bk_pipeline *b, void **data, size_t *size)
{
    const bk_scene *s = &b->scene;
    const lbk_bake_desc *o = b->opt;
    char hash[17], seed[32], density[32], spacing[32], samples[32], target[32], bounces[32], tlimit[32], ts[32],
        threshold[32], in_hash[17];
    lbk_meta_hash_hex(s->source_hash, hash);
    snprintf(seed, sizeof seed, "%llu", (unsigned long long)o->seed);
    snprintf(density, sizeof density, "%g", o->texel_density > 0 ? o->texel_density : b->pre->texel_density);
    snprintf(spacing, sizeof spacing, "%g", o->glg_spacing > 0 ? o->glg_spacing : b->pre->glg_spacing);
    snprintf(samples, sizeof samples, "%d", o->max_samples > 0 ? o->max_samples : b->pre->max_samples);
    snprintf(target, sizeof target, "%g", o->target_error > 0 ? o->target_error : b->pre->target_error);
    snprintf(bounces, sizeof bounces, "%d", o->max_bounces);
    snprintf(tlimit, sizeof tlimit, "%g", o->time_limit);
    snprintf(threshold, sizeof threshold, "%g", o->dls_threshold == 0 ? 0.01 : o->dls_threshold);

    uint64_t *mat_hash = calloc(s->material_count ? s->material_count : 1, sizeof *mat_hash);
    text files = {0}, objects = {0}, mats = {0}, lts = {0}, skyv = {0};
    lbk_result r = LBK_ERR_OUT_OF_MEMORY;
    if (!mat_hash) goto done;
    for (size_t i = 0; i < s->material_count; i++) mat_hash[i] = material_hash(s, &s->materials[i]);
    input_files(s, &files);
    put(&files, "%s", ""); /* an empty list is still a string */
    for (size_t i = 0; i < s->object_count; i++) {
        uint64_t h[3];
        object_hashes(b, mat_hash, &s->objects[i], h);
        put(&objects, "%016llx %016llx %016llx\n", (unsigned long long)h[0], (unsigned long long)h[1],
            (unsigned long long)h[2]);
    }
    put(&objects, "%s", "");
    materials(s, mat_hash, &mats);
    put(&mats, "%s", "");
    lights(b, &lts);
    put(&lts, "%s", "");
    sky(s, &skyv);
    if (files.failed || objects.failed || mats.failed || lts.failed || skyv.failed) goto done;
    lbk_meta_hash_hex(XXH3_64bits(files.p, files.n), in_hash);

    lbk_meta_pair p[MAX_PAIRS];
    size_t n = 0;
    p[n++] = (lbk_meta_pair){LBK_META_WRITER, "lbk bake"};
    p[n++] = (lbk_meta_pair){LBK_META_WRITER_VERSION, LBK_LIBRARY_VERSION_STRING};
    p[n++] = (lbk_meta_pair){LBK_META_SCENE_HASH, hash};
    p[n++] = (lbk_meta_pair){"scene.name", b->scene_name};
    p[n++] = (lbk_meta_pair){"scene.objects", objects.p};
    p[n++] = (lbk_meta_pair){"scene.materials", mats.p};
    p[n++] = (lbk_meta_pair){"scene.lights", lts.p};
    p[n++] = (lbk_meta_pair){"input.files", files.p};
    p[n++] = (lbk_meta_pair){"input.hash", in_hash};
    p[n++] = (lbk_meta_pair){"bake.preset", b->pre->name};
    p[n++] = (lbk_meta_pair){"bake.seed", seed};
    p[n++] = (lbk_meta_pair){"bake.texel_density", density};
    p[n++] = (lbk_meta_pair){"bake.glg_spacing", spacing};
    p[n++] = (lbk_meta_pair){"bake.max_samples", samples};
    p[n++] = (lbk_meta_pair){"bake.target_error", target};
    p[n++] = (lbk_meta_pair){"bake.max_bounces", bounces};
    p[n++] = (lbk_meta_pair){"bake.time_limit", tlimit};
    p[n++] = (lbk_meta_pair){"bake.denoise", o->denoise == LBK_BAKE_DENOISE_OFF ? "off"
                                             : o->denoise == LBK_BAKE_DENOISE_ON ? "on" : "auto"};
    p[n++] = (lbk_meta_pair){"bake.sky", skyv.p};
    p[n++] = (lbk_meta_pair){"bake.no_glg", o->no_glg ? "1" : "0"};
    p[n++] = (lbk_meta_pair){"bake.octahedral", o->octahedral_probes ? "1" : "0"};
    if (o->block_align) p[n++] = (lbk_meta_pair){"bake.block_align", "1"}; /* absent: 0 (older bakes) */
    char culling_delta[32];
    snprintf(culling_delta, sizeof culling_delta, "%g", o->light_culling_delta);
    /* absent: auto and the default δ (so bakes that leave them alone keep their bytes) */
    if (o->light_culling) p[n++] = (lbk_meta_pair){"bake.light_culling", o->light_culling > 0 ? "on" : "off"};
    if (o->light_culling_delta > 0) p[n++] = (lbk_meta_pair){"bake.light_culling_delta", culling_delta};
    char glg_light[32];
    snprintf(glg_light, sizeof glg_light, "%g", o->glg_lighting_threshold > 0 ? o->glg_lighting_threshold : 0.4);
    /* absent: off (older bakes) */
    if (o->glg_lighting) p[n++] = (lbk_meta_pair){"bake.glg_lighting", glg_light};
    if (o->error_map) p[n++] = (lbk_meta_pair){"bake.error_map", "1"}; /* absent: off (older bakes) */
    char octp_levels[16], octp_spacing[32], octp_clip[16];
    snprintf(octp_levels, sizeof octp_levels, "%d", o->octp_levels);
    snprintf(octp_spacing, sizeof octp_spacing, "%g", o->octp_spacing);
    snprintf(octp_clip, sizeof octp_clip, "%d", o->octp_clip);
    /* absent: the defaults (older bakes) */
    if (o->octahedral_probes && o->octp_levels > 0) p[n++] = (lbk_meta_pair){"bake.octp_levels", octp_levels};
    if (o->octahedral_probes && o->octp_spacing > 0) p[n++] = (lbk_meta_pair){"bake.octp_spacing", octp_spacing};
    if (o->octahedral_probes && o->octp_clip > 0) p[n++] = (lbk_meta_pair){"bake.octp_clip", octp_clip};
    char glimit[32];
    snprintf(glimit, sizeof glimit, "%g", o->gather_limit);
    if (o->gather_limit > 0) p[n++] = (lbk_meta_pair){"bake.gather_limit", glimit}; /* absent: off */
    if (o->llg_connected) p[n++] = (lbk_meta_pair){"bake.llg_connected", "1"}; /* absent: off */
    char vpl_photons[16], vpl_delta[32];
    snprintf(vpl_photons, sizeof vpl_photons, "%d", o->glossy_vpl_photons);
    snprintf(vpl_delta, sizeof vpl_delta, "%g", o->glossy_vpl_delta);
    /* absent: auto and the defaults (so bakes that leave them alone keep their bytes) */
    if (o->glossy_vpl) p[n++] = (lbk_meta_pair){"bake.glossy_vpl", o->glossy_vpl > 0 ? "on" : "off"};
    if (o->glossy_vpl_photons > 0) p[n++] = (lbk_meta_pair){"bake.glossy_vpl_photons", vpl_photons};
    if (o->glossy_vpl_delta > 0) p[n++] = (lbk_meta_pair){"bake.glossy_vpl_delta", vpl_delta};
    if (o->adaptive < 0) p[n++] = (lbk_meta_pair){"bake.adaptive", "off"}; /* absent: on */
    char max_page[16], max_probes[16], texel_budget[24];
    snprintf(max_page, sizeof max_page, "%d", o->max_page);
    snprintf(max_probes, sizeof max_probes, "%u", o->max_probes);
    snprintf(texel_budget, sizeof texel_budget, "%llu", (unsigned long long)o->texel_budget);
    /* absent: the defaults (so bakes that leave them alone keep their bytes) */
    if (o->max_page) p[n++] = (lbk_meta_pair){"bake.max_page", max_page};
    if (o->max_probes) p[n++] = (lbk_meta_pair){"bake.max_probes", max_probes};
    if (o->texel_budget) p[n++] = (lbk_meta_pair){"bake.texel_budget", texel_budget};
    p[n++] = (lbk_meta_pair){"bake.dls_threshold", threshold};
    p[n++] = (lbk_meta_pair){"bake.door_method", o->door_method == LBK_BAKE_DOOR_GUIDED ? "guided" : "difference"};
    if (o->revision) p[n++] = (lbk_meta_pair){LBK_META_REVISION, o->revision};
    if (o->timestamp) {
        time_t now = time(NULL);
        struct tm tmv;
        gmtime_r(&now, &tmv);
        strftime(ts, sizeof ts, "%Y-%m-%dT%H:%M:%SZ", &tmv);
        p[n++] = (lbk_meta_pair){LBK_META_TIMESTAMP, ts};
    }
    r = lbk_meta_build(p, n, NULL, data, size);
done:
    free(mat_hash);
    free(files.p), free(objects.p), free(mats.p), free(lts.p), free(skyv.p);
    return r;
}
