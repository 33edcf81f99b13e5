/* REPT: build, view and validate (spec/container.md §7, spec/validation.md 350–399). */
#include <math.h>

#include "lbk/report.h"

#include "internal.h"

static double rd_f64(const uint8_t *p)
{
    uint64_t u = lbk_rd64(p);
    double v;
    memcpy(&v, &u, 8);
    return v;
}

static void wr_f64(uint8_t *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    lbk_wr64(p, u);
}

static bool nonneg_finite(double v) { return isfinite(v) && v >= 0.0; }

const char *lbk_bake_status_name(uint32_t status)
{
    switch (status) {
    case LBK_BAKE_CONVERGED: return "converged";
    case LBK_BAKE_TARGET_REACHED: return "target reached";
    case LBK_BAKE_TIME_LIMIT: return "time limit";
    case LBK_BAKE_SAMPLE_LIMIT: return "sample limit";
    default: return "unknown";
    }
}

static void read_record(const uint8_t *r, lbk_report_record *out)
{
    out->elapsed_seconds = rd_f64(r + 0);
    out->rays_traced = lbk_rd64(r + 8);
    out->samples_per_texel = lbk_rd32(r + 16);
    out->bounces = lbk_rd32(r + 20);
    out->texel_rel_rmse = lbk_rdf32(r + 24);
    out->probe_rel_rmse = lbk_rdf32(r + 28);
}

lbk_result lbk_report_build(const lbk_report *caller_report, const lbk_allocator *allocator, void **out, size_t *size)
{
    if (!caller_report || !out || !size) return LBK_ERR_INVALID_ARGUMENT;
    lbk_report in;
    lbk_result rc = LBK_SIZED_IN(&in, caller_report, lbk_report, record_count);
    if (rc != LBK_OK) return rc;
    const lbk_report *rep = &in;
    if (!rep->records && rep->record_count) return LBK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    *size = 0;
    if (rep->record_count == 0 || rep->status >= LBK_BAKE_STATUS_COUNT_ || (rep->flags & ~LBK_REPORT_HAS_TIMES))
        return LBK_ERR_INVALID_ARGUMENT;
    if (!nonneg_finite(rep->time_limit_seconds) || !nonneg_finite(rep->target_rel_rmse)) return LBK_ERR_RANGE;
    for (uint32_t i = 0; i < rep->record_count; i++) {
        const lbk_report_record *r = &rep->records[i], *p = i ? &rep->records[i - 1] : NULL;
        if (!nonneg_finite(r->elapsed_seconds) || !nonneg_finite(r->texel_rel_rmse) ||
            !nonneg_finite(r->probe_rel_rmse))
            return LBK_ERR_RANGE;
        if (!(rep->flags & LBK_REPORT_HAS_TIMES) && r->elapsed_seconds != 0.0) return LBK_ERR_RANGE;
        if (p && (r->elapsed_seconds < p->elapsed_seconds || r->rays_traced < p->rays_traced ||
                  r->samples_per_texel < p->samples_per_texel))
            return LBK_ERR_RANGE;
    }
    uint64_t total = LBK_REPORT_HEADER_SIZE + (uint64_t)LBK_REPORT_RECORD_SIZE * rep->record_count;
    uint8_t *b = total <= SIZE_MAX ? lbk_calloc(allocator, 1, (size_t)total) : NULL;
    if (!b) return LBK_ERR_OUT_OF_MEMORY;
    lbk_wr32(b + 0, rep->status);
    lbk_wr32(b + 4, rep->flags);
    lbk_wr32(b + 8, rep->record_count);
    lbk_wr32(b + 12, rep->max_samples_per_texel);
    wr_f64(b + 16, rep->time_limit_seconds + 0.0); /* + 0.0 turns -0 into +0: one encoding per value */
    lbk_wrf32(b + 24, rep->target_rel_rmse + 0.0f);
    for (uint32_t i = 0; i < rep->record_count; i++) {
        const lbk_report_record *r = &rep->records[i];
        uint8_t *o = b + LBK_REPORT_HEADER_SIZE + (size_t)LBK_REPORT_RECORD_SIZE * i;
        wr_f64(o + 0, r->elapsed_seconds + 0.0);
        lbk_wr64(o + 8, r->rays_traced);
        lbk_wr32(o + 16, r->samples_per_texel);
        lbk_wr32(o + 20, r->bounces);
        lbk_wrf32(o + 24, r->texel_rel_rmse + 0.0f);
        lbk_wrf32(o + 28, r->probe_rel_rmse + 0.0f);
    }
    *out = b;
    *size = (size_t)total;
    return LBK_OK;
}

lbk_result lbk_report_open(const void *data, size_t size, lbk_report_view *out)
{
    if (!out || (!data && size)) return LBK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const uint8_t *d = data;
    if (size < LBK_REPORT_HEADER_SIZE) return LBK_ERR_TRUNCATED;
    uint32_t n = lbk_rd32(d + 8);
    uint64_t need = LBK_REPORT_HEADER_SIZE + (uint64_t)LBK_REPORT_RECORD_SIZE * n;
    if (need > size) return LBK_ERR_TRUNCATED;
    if (need != size) return LBK_ERR_CORRUPT;
    out->header.size = sizeof out->header;
    out->header.status = lbk_rd32(d + 0);
    out->header.flags = lbk_rd32(d + 4);
    out->header.record_count = n;
    out->header.max_samples_per_texel = lbk_rd32(d + 12);
    out->header.time_limit_seconds = rd_f64(d + 16);
    out->header.target_rel_rmse = lbk_rdf32(d + 24);
    out->record_bytes = d + LBK_REPORT_HEADER_SIZE;
    return LBK_OK;
}

lbk_result lbk_report_record_get(const lbk_report_view *v, uint32_t index, lbk_report_record *out)
{
    if (!v || !out) return LBK_ERR_INVALID_ARGUMENT;
    if (index >= v->header.record_count) return LBK_ERR_NOT_FOUND;
    read_record(v->record_bytes + (size_t)LBK_REPORT_RECORD_SIZE * index, out);
    return LBK_OK;
}

/* ---- validation -------------------------------------------------------------------------- */

void lbk_validate_rept(lbk_vctx *ctx, const uint8_t *d, size_t size)
{
    if (size < LBK_REPORT_HEADER_SIZE) {
        lbk_vreport(ctx, 350, 0, "REPT is %zu bytes, its header needs 32", size);
        return;
    }
    lbk_report_view v;
    uint32_t n = lbk_rd32(d + 8);
    if (lbk_report_open(d, size, &v) != LBK_OK) {
        lbk_vreport(ctx, 351, 8, "REPT of %u records needs %llu bytes, section has %zu", n,
                    (unsigned long long)(LBK_REPORT_HEADER_SIZE + (uint64_t)LBK_REPORT_RECORD_SIZE * n), size);
        return;
    }
    const lbk_report *h = &v.header;
    if (h->status >= LBK_BAKE_STATUS_COUNT_) lbk_vreport(ctx, 352, 0, "REPT status %u is not 0..3", h->status);
    if (h->flags & ~LBK_REPORT_HAS_TIMES)
        lbk_vreport(ctx, 353, 4, "REPT unknown flag bits 0x%08x", h->flags & ~LBK_REPORT_HAS_TIMES);
    if (lbk_rd32(d + 28)) lbk_vreport(ctx, 353, 28, "REPT reserved field is 0x%08x, must be 0", lbk_rd32(d + 28));
    if (!nonneg_finite(h->time_limit_seconds))
        lbk_vreport(ctx, 354, 16, "REPT time_limit_seconds %g is not finite and non-negative", h->time_limit_seconds);
    if (!nonneg_finite(h->target_rel_rmse))
        lbk_vreport(ctx, 354, 24, "REPT target_rel_rmse %g is not finite and non-negative", (double)h->target_rel_rmse);
    if (n == 0) {
        lbk_vreport(ctx, 358, 8, "REPT record_count is 0");
        return;
    }
    lbk_report_record prev = {0}, r = {0};
    for (uint32_t i = 0; i < n && !ctx->stop; i++) {
        uint64_t ro = LBK_REPORT_HEADER_SIZE + (uint64_t)LBK_REPORT_RECORD_SIZE * i;
        read_record(d + ro, &r);
        if (!nonneg_finite(r.elapsed_seconds))
            lbk_vreport(ctx, 354, ro, "REPT record %u: elapsed_seconds %g is not finite and non-negative", i,
                        r.elapsed_seconds);
        if (!nonneg_finite(r.texel_rel_rmse))
            lbk_vreport(ctx, 354, ro + 24, "REPT record %u: texel_rel_rmse %g is not finite and non-negative", i,
                        (double)r.texel_rel_rmse);
        if (!nonneg_finite(r.probe_rel_rmse))
            lbk_vreport(ctx, 354, ro + 28, "REPT record %u: probe_rel_rmse %g is not finite and non-negative", i,
                        (double)r.probe_rel_rmse);
        if (!(h->flags & LBK_REPORT_HAS_TIMES) && r.elapsed_seconds != 0.0)
            lbk_vreport(ctx, 356, ro, "REPT record %u: elapsed_seconds %g but HAS_TIMES is clear", i,
                        r.elapsed_seconds);
        if (i > 0 && (r.elapsed_seconds < prev.elapsed_seconds || r.rays_traced < prev.rays_traced ||
                      r.samples_per_texel < prev.samples_per_texel))
            lbk_vreport(ctx, 355, ro, "REPT record %u: elapsed, rays or samples smaller than in record %u", i, i - 1);
        prev = r;
    }
    /* The status must be explicable by the header limits and the last record. */
    if (h->status == LBK_BAKE_TARGET_REACHED &&
        !(h->target_rel_rmse > 0 && r.texel_rel_rmse <= h->target_rel_rmse))
        lbk_vreport(ctx, 357, 0, "REPT says target reached but target %g, last texel error %g",
                    (double)h->target_rel_rmse, (double)r.texel_rel_rmse);
    if (h->status == LBK_BAKE_TIME_LIMIT && !(h->time_limit_seconds > 0))
        lbk_vreport(ctx, 357, 0, "REPT says time limit but no time limit is recorded");
    if (h->status == LBK_BAKE_SAMPLE_LIMIT &&
        !(h->max_samples_per_texel > 0 && r.samples_per_texel >= h->max_samples_per_texel))
        lbk_vreport(ctx, 357, 0, "REPT says sample limit but limit %u, last record %u samples per texel",
                    h->max_samples_per_texel, r.samples_per_texel);
}
