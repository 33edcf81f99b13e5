/* The calls of distributed bakes (lbk/bake_dist.h): a unit's part, the inputs a plan lists,
 * a part's check and the merge, each one bake (bk_pipeline_bake) with a recorder or a player
 * (bake/dist/dist.h); the hash of the options that shape a bake's bytes. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/dist/cache_share.h"
#include "bake/dist/dist.h"
#include "bake/pipeline/pipeline.h"
#include "lbk/bake_dist.h"

#define XXH_INLINE_ALL /* as the rest of the baker: liblbkbake links no xxhash of its own */
#include <xxhash.h>

/* The identity of the options that shape a bake's bytes (not threads, callbacks, allocator):
 * a part baked with other options is refused by the merge instead of replayed under them. */
static void hash_str(XXH64_state_t *st, const char *s)
{
    XXH64_update(st, s ? s : "", s ? strlen(s) + 1 : 1);
}

uint64_t bk_pipeline_options_hash(const lbk_bake_desc *options, int budgets)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    if (options) memcpy(&d, options, options->size && options->size < sizeof d ? options->size : sizeof d);
    XXH64_state_t *st = XXH64_createState();
    if (!st) return 0;
    XXH64_reset(st, 0x6c626b70);
    if (!budgets) d.target_error = d.time_limit = 0, d.max_samples = 0;
    const int64_t ints[] = {d.preset, (int64_t)d.seed, d.max_samples, d.max_bounces, d.sky_override, d.no_glg,
                            d.octahedral_probes, d.no_seam_stitch, d.door_method, d.denoise, d.timestamp, d.block_align};
    const double reals[] = {d.target_error, d.time_limit, d.texel_density, d.glg_spacing, d.sky[0], d.sky[1], d.sky[2],
                            d.dls_threshold};
    XXH64_update(st, ints, sizeof ints);
    XXH64_update(st, reals, sizeof reals);
    hash_str(st, d.sky_exr);
    hash_str(st, d.revision);
    hash_str(st, d.allow_outside);
    if (d.glg_lighting || d.glg_lighting_threshold > 0) { /* (absent from older hashes: same values) */
        const double gl[2] = {(double)d.glg_lighting, (double)d.glg_lighting_threshold};
        XXH64_update(st, gl, sizeof gl);
    }
    if (d.light_culling || d.light_culling_delta > 0) { /* (absent from older hashes: same values) */
        const double lc[2] = {(double)d.light_culling, d.light_culling_delta};
        XXH64_update(st, lc, sizeof lc);
    }
    if (d.glossy_vpl || d.glossy_vpl_photons || d.glossy_vpl_delta > 0) { /* (absent from older hashes) */
        const double gv[3] = {(double)d.glossy_vpl, (double)d.glossy_vpl_photons, d.glossy_vpl_delta};
        XXH64_update(st, gv, sizeof gv);
    }
    if (d.adaptive) { /* (absent from older hashes: on) */
        const int64_t ad = d.adaptive;
        XXH64_update(st, &ad, sizeof ad);
    }
    if (d.max_page || d.max_probes || d.texel_budget) { /* (absent from older hashes: the defaults) */
        const uint64_t sz[3] = {(uint64_t)d.max_page, d.max_probes, d.texel_budget};
        XXH64_update(st, sz, sizeof sz);
    }
    if (d.error_map) { /* units must record the variance the merge's map needs */
        const int64_t em = d.error_map;
        XXH64_update(st, &em, sizeof em);
    }
    /* the baker's version: another transport gives other values for the same options, so its
     * parts and checkpoints are refused rather than mixed with this one's (absent before 1.8.1) */
    const int64_t version[3] = {LBK_BAKE_LIBRARY_VERSION_MAJOR, LBK_BAKE_LIBRARY_VERSION_MINOR,
                                LBK_BAKE_LIBRARY_VERSION_PATCH};
    XXH64_update(st, version, sizeof version);
    uint64_t h = XXH64_digest(st);
    XXH64_freeState(st);
    return h;
}

lbk_result lbk_bake_unit_from_file(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash, uint32_t units,
                                   uint32_t unit, void **part, size_t *part_size)
{
    return lbk_bake_unit_shared(path, desc, plan_hash, units, unit, NULL, NULL, part, part_size);
}

/* The shared cache folder's failure, sent as the bake's ERROR message. */
static void share_error(const lbk_bake_desc *desc, const char *why)
{
    if (desc && desc->message) desc->message(desc->user, LBK_BAKE_SEVERITY_ERROR, why);
}

lbk_result lbk_bake_unit_shared(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash, uint32_t units,
                                uint32_t unit, const lbk_bake_unit_desc *shared, lbk_bake_unit_stats *stats, void **part,
                                size_t *part_size)
{
    if (!part || !part_size) return LBK_ERR_INVALID_ARGUMENT;
    *part = NULL;
    *part_size = 0;
    if (!path || units == 0 || units > BK_PART_MAX_UNITS || unit >= units) return LBK_ERR_INVALID_ARGUMENT;
    lbk_bake_unit_desc sd;
    memset(&sd, 0, sizeof sd);
    if (shared) memcpy(&sd, shared, shared->size && shared->size < sizeof sd ? shared->size : sizeof sd);
    bk_dist *d = NULL;
    const uint64_t options_hash = bk_pipeline_options_hash(desc, 1);
    lbk_result r = bk_dist_create(0, plan_hash, options_hash, units, unit, NULL, &d);
    if (r) return r;
    bk_cache_share *cs = NULL;
    if (sd.cache_dir) {
        char why[512] = "";
        r = bk_cache_share_open(sd.cache_dir, plan_hash, options_hash, sd.lease, &cs, why, sizeof why);
        if (r) {
            if (why[0]) share_error(desc, why);
            bk_dist_destroy(d);
            return r;
        }
        bk_dist_set_cache_share(d, cs);
    }
    lbk_bake_output *out = NULL;
    r = bk_pipeline_bake(path, NULL, desc, &out, d, part, part_size, NULL, NULL, NULL);
    if (stats && stats->size >= sizeof *stats) bk_cache_share_get_stats(cs, stats);
    bk_dist_destroy(d);
    bk_cache_share_close(cs);
    return r;
}

lbk_result lbk_bake_cache_dir_remove(const char *cache_dir)
{
    if (!cache_dir) return LBK_ERR_INVALID_ARGUMENT;
    return bk_cache_share_remove(cache_dir) ? LBK_ERR_IO : LBK_OK;
}

void lbk_bake_part_free(void *part) { free(part); }

lbk_result lbk_bake_inputs_from_file(const char *path, const lbk_bake_desc *desc, lbk_bake_input **inputs, size_t *count,
                                     uint32_t *runs)
{
    if (!inputs || !count) return LBK_ERR_INVALID_ARGUMENT;
    *inputs = NULL;
    *count = 0;
    if (runs) *runs = 0;
    if (!path) return LBK_ERR_INVALID_ARGUMENT;
    lbk_bake_output *out = NULL;
    return bk_pipeline_bake(path, NULL, desc, &out, NULL, NULL, NULL, inputs, count, runs);
}

void lbk_bake_inputs_free(lbk_bake_input *inputs) { free(inputs); }

lbk_result lbk_bake_part_check(const void *part, size_t size, uint64_t plan_hash, uint32_t units, lbk_bake_part_info *info,
                               char *err, size_t err_len)
{
    bk_part_view v;
    char why[256];
    lbk_result r = bk_part_parse(part, size, &v, why, sizeof why);
    if (r) {
        if (err && err_len) snprintf(err, err_len, "%s", r == LBK_ERR_OUT_OF_MEMORY ? "out of memory" : why);
        return r;
    }
    free(v.runs);
    if (info) {
        memset(info, 0, sizeof *info);
        info->plan_hash = v.plan_hash;
        info->units = v.units;
        info->unit = v.unit;
        info->runs = v.run_count;
        info->total_runs = v.total_runs;
        info->first_run = v.first_run;
        info->receivers = v.receiver_count;
        bk_dist_range(v.receiver_count, v.total_runs, v.units, v.unit, v.first_run, &info->first, &info->end);
    }
    if (plan_hash && v.plan_hash != plan_hash) {
        if (err && err_len)
            snprintf(err, err_len, "belongs to another plan (plan hash %016llx, this plan's is %016llx)",
                     (unsigned long long)v.plan_hash, (unsigned long long)plan_hash);
        return LBK_ERR_BAD_INPUT;
    }
    if (units && v.units != units) {
        if (err && err_len) snprintf(err, err_len, "is unit %u of %u, this plan has %u units", v.unit, v.units, units);
        return LBK_ERR_BAD_INPUT;
    }
    return LBK_OK;
}

static void say_error(const lbk_bake_desc *desc, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void say_error(const lbk_bake_desc *desc, const char *fmt, ...)
{
    if (!desc || !desc->message) return;
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    desc->message(desc->user, LBK_BAKE_SEVERITY_ERROR, text);
}

/* Every part checked and put in unit order before anything is baked: a bad set of parts is
 * refused in a second, not after the layout. */
static lbk_result order_parts(const lbk_bake_desc *desc, uint64_t plan_hash, uint32_t units, const void *const *parts,
                              const size_t *sizes, size_t count, bk_part_view *views)
{
    lbk_result r = LBK_OK;
    size_t k = 0;
    for (; k < count && !r; k++) {
        bk_part_view v;
        char why[256];
        r = bk_part_parse(parts[k], sizes[k], &v, why, sizeof why);
        if (r) {
            say_error(desc, "part %zu: %s", k + 1, r == LBK_ERR_OUT_OF_MEMORY ? "out of memory" : why);
            break;
        }
        if (v.plan_hash != plan_hash) {
            say_error(desc, "part %zu (unit %u) belongs to another plan (plan hash %016llx, this plan's is %016llx)", k + 1,
                      v.unit, (unsigned long long)v.plan_hash, (unsigned long long)plan_hash);
            r = LBK_ERR_BAD_INPUT;
        } else if (v.units != units) {
            say_error(desc, "part %zu is unit %u of %u, this plan has %u units", k + 1, v.unit, v.units, units);
            r = LBK_ERR_BAD_INPUT;
        } else if (views[v.unit].runs) {
            say_error(desc, "unit %u is given twice (parts %zu and another)", v.unit, k + 1);
            r = LBK_ERR_BAD_INPUT;
        } else if (v.receiver_count != views[0].receiver_count && views[0].runs) {
            say_error(desc, "part %zu (unit %u) has %llu receivers, unit 0 has %llu", k + 1, v.unit,
                      (unsigned long long)v.receiver_count, (unsigned long long)views[0].receiver_count);
            r = LBK_ERR_BAD_INPUT;
        }
        if (r) {
            free(v.runs);
            break;
        }
        views[v.unit] = v;
    }
    if (r) return r;
    char missing[256] = "";
    size_t nmiss = 0, len = 0;
    for (uint32_t u = 0; u < units; u++) {
        if (views[u].runs) continue;
        if (nmiss++ < 16 && len < sizeof missing - 16) len += (size_t)snprintf(missing + len, sizeof missing - len, "%s%u", nmiss > 1 ? ", " : "", u);
    }
    if (nmiss) {
        say_error(desc, "%zu of %u units missing: %s%s (lbk bake-unit PLAN K for each)", nmiss, units, missing, nmiss > 16 ? ", ..." : "");
        return LBK_ERR_BAD_INPUT;
    }
    for (uint32_t u = 1; u < units; u++)
        if (views[u].receiver_count != views[0].receiver_count || views[u].total_runs != views[0].total_runs) {
            say_error(desc, "unit %u's part disagrees with unit 0's (receivers, runs): the parts come from different "
                      "scenes, options or lbk versions", u);
            return LBK_ERR_BAD_INPUT;
        }
    return LBK_OK;
}

lbk_result lbk_bake_merge_from_file(const char *path, const lbk_bake_desc *desc, uint64_t plan_hash, uint32_t units,
                                    const void *const *parts, const size_t *part_sizes, size_t part_count,
                                    lbk_bake_output **out)
{
    if (!out) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!path || units == 0 || units > BK_PART_MAX_UNITS || (part_count && (!parts || !part_sizes))) return LBK_ERR_INVALID_ARGUMENT;
    bk_part_view *views = calloc(units, sizeof *views);
    if (!views) return LBK_ERR_OUT_OF_MEMORY;
    lbk_result r = order_parts(desc, plan_hash, units, parts, part_sizes, part_count, views);
    bk_dist *d = NULL;
    const uint64_t oh = bk_pipeline_options_hash(desc, 1);
    for (uint32_t u = 0; !r && u < units; u++)
        if (views[u].options_hash != oh) {
            say_error(desc, "unit %u's part was baked with other bake options than this merge's (seed, samples, "
                      "density, ...): it belongs to another bake", u);
            r = LBK_ERR_BAD_INPUT;
        }
    if (!r) r = bk_dist_create(1, plan_hash, oh, units, 0, views, &d);
    if (!r) r = bk_pipeline_bake(path, NULL, desc, out, d, NULL, NULL, NULL, NULL, NULL);
    bk_dist_destroy(d);
    for (uint32_t u = 0; u < units; u++) free(views[u].runs);
    free(views);
    return r;
}
