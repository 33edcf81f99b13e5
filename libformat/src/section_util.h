/* Helpers shared by the payload-section validators of the codec sections (LMAP, GLG, LLG, OCTP). */
#ifndef LBK_SECTION_UTIL_H
#define LBK_SECTION_UTIL_H

#include <math.h>

#include "internal.h"

/* Per-element issues (one per texel or probe) are reported for the first few elements of each
 * kind only, then once with the number left unreported, so a damaged 16k×16k page does not
 * produce 268 million callbacks. */
#define LBK_RATE_KINDS 8
#define LBK_RATE_MAX 8u

typedef struct lbk_rate {
    uint64_t seen[LBK_RATE_KINDS];
    uint64_t first_offset[LBK_RATE_KINDS];
} lbk_rate;

static inline void lbk_rate_init(lbk_rate *r) { memset(r, 0, sizeof *r); }

/* Counts one occurrence of `kind`; true while it should still be reported. */
static inline bool lbk_rate_ok(lbk_rate *r, int kind) { return ++r->seen[kind] <= LBK_RATE_MAX; }

/* Reports "n more" for the kinds whose ids are given (kind i ↔ ids[i]), at the section start. */
static inline void lbk_rate_flush_ids(lbk_vctx *ctx, const lbk_rate *r, const uint32_t *ids, int count)
{
    for (int k = 0; k < count; k++)
        if (ids[k] && r->seen[k] > LBK_RATE_MAX)
            lbk_vreport(ctx, ids[k], 0, "... and %llu more elements with issue %u (not listed)",
                        (unsigned long long)(r->seen[k] - LBK_RATE_MAX), ids[k]);
}
static inline void lbk_rate_flush(lbk_vctx *ctx, const lbk_rate *r, uint32_t id0, uint32_t id1)
{
    const uint32_t ids[2] = {id0, id1};
    lbk_rate_flush_ids(ctx, r, ids, 2);
}

/* Checks that bytes [from, to) are zero; reports the first non-zero one. */
static inline bool lbk_check_zero(lbk_vctx *ctx, uint32_t id, const uint8_t *d, uint64_t from, uint64_t to,
                                  const char *what)
{
    for (uint64_t i = from; i < to; i++)
        if (d[i] != 0) {
            lbk_vreport(ctx, id, i, "%s padding/reserved byte at %llu is 0x%02x", what, (unsigned long long)i, d[i]);
            return false;
        }
    return true;
}

static inline bool lbk_finite3(const float v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

/* R11G11B10F with an exponent-31 (Inf/NaN) channel: never written by an encoder. */
static inline bool lbk_r11g11b10f_special(uint32_t v)
{
    return (v & 0x7c0u) == 0x7c0u || (v & (0x7c0u << 11)) == (0x7c0u << 11) || (v & (0x3e0u << 22)) == (0x3e0u << 22);
}

/* Radiometric scale of a lighting section (spec/container.md §5.7): stored value × scale =
 * physical value. Valid: a positive, normal, finite power of two (sign 0, mantissa 0,
 * exponent field 1..254), so multiplying or dividing by it is exact and never changes rounding. */
static inline bool lbk_scale_bits_ok(uint32_t bits)
{
    const uint32_t e = bits >> 23;
    return (bits & 0x007fffffu) == 0 && e >= 1 && e <= 254;
}
static inline uint32_t lbk_f32_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}
/* A builder's scale argument: 0 means 1; anything else must be a valid scale. */
static inline bool lbk_scale_resolve(float in, float *out)
{
    if (in == 0.0f) in = 1.0f;
    *out = in;
    return lbk_scale_bits_ok(lbk_f32_bits(in));
}
/* Reports `id` when the scale at byte `offset` of section `what` is invalid; true when valid. */
static inline bool lbk_check_scale(lbk_vctx *ctx, uint32_t id, const uint8_t *d, uint64_t offset, const char *what)
{
    const uint32_t bits = lbk_rd32(d + offset);
    if (lbk_scale_bits_ok(bits)) return true;
    float f;
    memcpy(&f, &bits, 4);
    lbk_vreport(ctx, id, offset, "%s scale 0x%08x (%g) is not a positive finite power of two", what, bits, (double)f);
    return false;
}

#endif
