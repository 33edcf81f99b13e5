/* Dynamic light sets (seed 001 §3): per-set sparse contributions to lightmap texels and SH9 probes,
 * grouped into combination clusters with the seed's packed prefix indices, and the reference
 * runtime that applies L = L_B + Σ_j ω_j S_j. Normative layout: spec/container.md §12.
 *
 * Three parts:
 *   - the builder (lbk_dls_build): sets + sparse per-set entries → DLS section bytes;
 *   - the view (lbk_dls_open / lbk_dls_close): a checked, read-only view of DLS section bytes;
 *   - the runtime (lbk_dls_runtime_open / lbk_dls_apply / lbk_dls_runtime_close): final texels
 *     and probes for weights, in place in the engine's upload buffers, with the regions that
 *     changed; lbk_dls_apply_begin / _job / _end split one apply over the caller's threads.
 * Doors (lbk/door.h) are DLS sets of kinds 1–3 whose weights follow the door's opening.
 * The builder's tuning and statistics are experimental (LBK_STATIC_LINKING_ONLY, at the end).
 *
 * Thread safety: the builder and every view function are safe to call from any thread, and a
 * view may be shared once open (it is read-only). A runtime is used by one thread at a time
 * (lbk_dls_apply rewrites its state and the output buffers), except that the jobs between
 * lbk_dls_apply_begin and lbk_dls_apply_end may run concurrently on any threads;
 * lbk_dls_effective_weights and the dirty getters only read it. */
#ifndef LBK_DLS_H
#define LBK_DLS_H

#include "lbk/lbk.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a set's contribution is. The weight each kind gets at apply time: see lbk_dls_apply. */
typedef enum lbk_dls_set_kind {
    LBK_DLS_KIND_LIGHTS = 0,        /* a dynamic light set: the lights' direct + bounced light */
    LBK_DLS_KIND_DOOR_OPEN = 1,     /* light that flows through a door when it is open (weight ω) */
    LBK_DLS_KIND_DOOR_CLOSED = 2,   /* light bouncing off the closed door (weight 1 − ω) */
    LBK_DLS_KIND_COMBINATION = 3,   /* extra light of a combination state (weight Π member weights) */
    LBK_DLS_KIND_COUNT_
} lbk_dls_set_kind;

/* Where an entry lands. Target indices: texels are numbered pages in order, row-major within a
 * page (as LMAP numbers them); GLG probes by GLG probe index; LLG probes by index into the
 * concatenated LLG probe array. */
typedef enum lbk_dls_space {
    LBK_DLS_SPACE_TEXEL = 0, /* payload: 8-byte AHD texel (lbk_ahd_texel_pack layout) */
    LBK_DLS_SPACE_GLG = 1,   /* payload: 28-byte SH9 probe (lbk_sh9_pack layout) */
    LBK_DLS_SPACE_LLG = 2,   /* payload: 28-byte SH9 probe */
    LBK_DLS_SPACE_COUNT_
} lbk_dls_space;

/* Cluster forms (one dispatch each), spec §12.5. */
typedef enum lbk_dls_form {
    LBK_DLS_FORM_DEDICATED = 0, /* one combination of 1–8 sets; k entries per target */
    LBK_DLS_FORM_PACKED = 1,    /* class (1): small combinations (≤ 128 targets), same k ≤ 4 */
    LBK_DLS_FORM_PREFIX2 = 2,   /* class (2): 5–8 entries per target, 2-bit prefix, u16 base / 16 */
    LBK_DLS_FORM_PREFIX3 = 3,   /* class (2): 9–16 entries per target, 3-bit prefix, u16 base / 8 */
    LBK_DLS_FORM_PREFIX8 = 4,   /* class (3): 17–255 entries per target, 8-bit prefix, u32 base / 16 */
    LBK_DLS_FORM_COUNT_
} lbk_dls_form;

#define LBK_DLS_TEXEL_PAYLOAD 8u
#define LBK_DLS_PROBE_PAYLOAD 28u
#define LBK_DLS_MAX_DEDICATED_SETS 8u
#define LBK_DLS_MAX_PACKED_SETS 4u        /* class (1) handles fewer than 5 overlaps */
#define LBK_DLS_SMALL_COMBINATION 128u    /* targets: at most this many → class (1)/(2) */
#define LBK_DLS_MAX_OVERLAPS 255u         /* per target; more → LBK_ERR_OVERLAPS */
#define LBK_DLS_MAX_CLUSTER_SETS 255u     /* per cluster (slots are u8) */
#define LBK_DLS_PREFIX16_MAX_ENTRIES 65535u /* class (2) bases are u16 */
#define LBK_DLS_NO_SET 0xFFFFFFFFu

/* ---- building -------------------------------------------------------------------------- */

/* One set's entries in one target space. targets: distinct indices < the space's target count,
 * in any order; payloads: count × payload size (8 or 28 bytes), entry i for targets[i].
 * lbk_dls_sparse and lbk_dls_set_desc are array elements (frozen). */
typedef struct lbk_dls_sparse {
    uint64_t count;
    const uint32_t *targets;
    const void *payloads;
} lbk_dls_sparse;

typedef struct lbk_dls_set_desc {
    const char *name;                 /* UTF-8, non-empty, unique among the sets */
    uint32_t kind;                    /* lbk_dls_set_kind */
    uint32_t light_count;             /* names of the lights whose light the set holds */
    const char *const *light_names;
    uint32_t member_count;            /* combinations: ≥ 2 distinct non-combination set indices */
    const uint32_t *members;
    lbk_dls_sparse entries[LBK_DLS_SPACE_COUNT_]; /* indexed by lbk_dls_space */
} lbk_dls_set_desc;

/* Size-tagged (lbk.h): set size with LBK_DLS_BUILD_DESC_INIT. */
typedef struct lbk_dls_build_desc {
    size_t size;
    uint32_t set_count;
    const lbk_dls_set_desc *sets;
    /* Size of each target space: LMAP texels, GLG probes, LLG probes (≤ 2^32 each). */
    uint64_t target_count[LBK_DLS_SPACE_COUNT_];
} lbk_dls_build_desc;
#define LBK_DLS_BUILD_DESC_INIT LBK_SIZED_INIT(lbk_dls_build_desc)

typedef struct lbk_dls_tuning lbk_dls_tuning; /* experimental: LBK_STATIC_LINKING_ONLY */
typedef struct lbk_dls_stats lbk_dls_stats;   /* experimental: LBK_STATIC_LINKING_ONLY */

/* Size-tagged (lbk.h): set size with LBK_DLS_BUILD_OPTIONS_INIT; NULL options mean defaults. */
typedef struct lbk_dls_build_options {
    size_t size;
    const lbk_allocator *allocator; /* NULL: malloc/free; also allocates the output */
    const lbk_dls_tuning *tuning;   /* NULL: the defaults (experimental) */
} lbk_dls_build_options;
#define LBK_DLS_BUILD_OPTIONS_INIT LBK_SIZED_INIT(lbk_dls_build_options)

/* Builds the DLS section. Deterministic: the output depends only on the content of desc (the
 * order of each set's entries does not matter). Errors: LBK_ERR_INVALID_ARGUMENT (bad kind,
 * name, members, duplicate target in a set), LBK_ERR_RANGE (target ≥ target_count),
 * LBK_ERR_OVERLAPS (a target touched by more than 255 sets), LBK_ERR_LIMIT, LBK_ERR_OUT_OF_MEMORY.
 * *out is allocated with options->allocator; free it with lbk_free. stats: NULL, or the
 * experimental statistics of the result (as lbk_dls_stats_get). */
LBK_API lbk_result lbk_dls_build(const lbk_dls_build_desc *desc, const lbk_dls_build_options *options,
                                 void **out, size_t *out_size, lbk_dls_stats *stats);

/* ---- reading --------------------------------------------------------------------------- */

typedef struct lbk_dls_view lbk_dls_view;

/* Checks every structural rule of spec/container.md §12 (the DLS rules of spec/validation.md
 * except the cross-section ones) and returns LBK_ERR_CORRUPT / LBK_ERR_TRUNCATED if any fails.
 * The bytes are not copied and must outlive the view. */
LBK_API lbk_result lbk_dls_open(const void *data, size_t size, const lbk_allocator *allocator,
                                lbk_dls_view **out);
LBK_API void lbk_dls_close(lbk_dls_view *view);

typedef struct lbk_dls_set_info {
    const char *name;       /* not NUL-terminated */
    uint32_t name_length;
    uint32_t kind;
    uint32_t light_count;
    uint32_t member_count;
} lbk_dls_set_info;

typedef struct lbk_dls_cluster_info {
    uint32_t form;          /* lbk_dls_form */
    uint32_t space;         /* lbk_dls_space */
    uint32_t set_count;     /* dedicated: the combination; others: union of the sub-groups' sets */
    uint32_t overlaps;      /* entries per target for dedicated and packed; 0 for prefix forms */
    uint32_t target_count;
    uint32_t entry_count;
    uint32_t run_count;
    uint32_t subgroup_count; /* packed only */
} lbk_dls_cluster_info;

LBK_API uint32_t lbk_dls_set_count(const lbk_dls_view *view);
LBK_API lbk_result lbk_dls_set_get(const lbk_dls_view *view, uint32_t set, lbk_dls_set_info *out);
LBK_API lbk_result lbk_dls_set_light_get(const lbk_dls_view *view, uint32_t set, uint32_t i, const char **name,
                                         uint32_t *length);
LBK_API lbk_result lbk_dls_set_member_get(const lbk_dls_view *view, uint32_t set, uint32_t i, uint32_t *member);
/* LBK_ERR_NOT_FOUND when no set has that name. */
LBK_API lbk_result lbk_dls_set_find(const lbk_dls_view *view, const char *name, uint32_t *set);
/* Target space sizes the section was built for. */
LBK_API uint64_t lbk_dls_target_count(const lbk_dls_view *view, uint32_t space);
LBK_API uint32_t lbk_dls_cluster_count(const lbk_dls_view *view);
LBK_API lbk_result lbk_dls_cluster_get(const lbk_dls_view *view, uint32_t cluster, lbk_dls_cluster_info *out);
LBK_API lbk_result lbk_dls_cluster_set_get(const lbk_dls_view *view, uint32_t cluster, uint32_t i, uint32_t *set);

/* The 14 arrays of the section (spec/container.md §12.3), for a GPU path that uploads the section
 * bytes as they are and reads clusters, runs, prefix words, bases, slots and payloads in its
 * shaders (gpu/). */
typedef enum lbk_dls_array {
    LBK_DLS_ARRAY_SETS = 0,
    LBK_DLS_ARRAY_LIGHT_REFS,
    LBK_DLS_ARRAY_MEMBERS,
    LBK_DLS_ARRAY_CLUSTERS,
    LBK_DLS_ARRAY_CLUSTER_SETS,
    LBK_DLS_ARRAY_RUNS,
    LBK_DLS_ARRAY_SUBGROUPS,
    LBK_DLS_ARRAY_PREFIX_WORDS,
    LBK_DLS_ARRAY_BASE16,
    LBK_DLS_ARRAY_BASE32,
    LBK_DLS_ARRAY_SLOTS,
    LBK_DLS_ARRAY_TEXEL_ENTRIES,
    LBK_DLS_ARRAY_PROBE_ENTRIES,
    LBK_DLS_ARRAY_STRINGS,
    LBK_DLS_ARRAY_COUNT_
} lbk_dls_array;
/* Byte offset (a multiple of 16) within the section bytes and element count of one array. */
LBK_API lbk_result lbk_dls_array_get(const lbk_dls_view *view, uint32_t array, uint64_t *offset, uint64_t *count);

/* Decodes a cluster target by target, in payload order: for each target its index, its entry
 * count, the set index of each entry and the entries' payloads (count × payload size, in set
 * order). Return non-zero from fn to stop early. */
typedef int (*lbk_dls_target_fn)(void *user, uint32_t target, uint32_t count, const uint32_t *sets,
                                 const uint8_t *payloads);
LBK_API lbk_result lbk_dls_cluster_decode(const lbk_dls_view *view, uint32_t cluster, lbk_dls_target_fn fn,
                                          void *user);

/* ---- runtime ----------------------------------------------------------------------------
 * L = L_B + Σ_j w_j S_j for every target, on the CPU, into caller-owned output buffers that an
 * engine uploads as they are. Four parts: open a runtime over the base data and the outputs;
 * apply weights (in one call, or split into jobs the caller runs on its own threads); read back
 * which regions changed; close. The GPU path of the same definition is gpu/ (README, "GPU"). */

struct lbk_door_view;
typedef struct lbk_dls_runtime lbk_dls_runtime;

/* One LMAP page's planes (an array element: frozen). The base planes are where apply reads L_B —
 * lbk_lmap_page_get's irradiance and rgba pointers, used in place — and the output planes where
 * it writes L: mapped staging or upload memory, laid out as the GPU image wants it. Pitches are
 * bytes from one row to the next (0: 4·width, tightly packed as in LMAP); plane 0 holds the u32
 * R11G11B10F words (little-endian, as in LMAP), plane 1 the RGBA bytes. */
typedef struct lbk_dls_page {
    uint32_t width, height;
    const uint8_t *base_irradiance, *base_rgba;
    uint8_t *out_irradiance, *out_rgba;
    size_t base_irradiance_pitch, base_rgba_pitch, out_irradiance_pitch, out_rgba_pitch;
} lbk_dls_page;

/* The linear outputs of one LMAP page (an array element: frozen), for LBK_DLS_RUNTIME_LINEAR:
 * three RGBA32F planes, plane c holding lbk_ahd_linear.c[c] = (e0, g.x, g.y, g.z) of colour
 * channel c (R, G, B) as 4 host-order floats per texel, so that E_c(n) = dot(plane_c, (1, n))
 * (lbk/ahd.h) — three float4 images a shader samples and blends as it likes. Pitches are bytes
 * from one row to the next (0: 16·width; otherwise ≥ 16·width and a multiple of 4). */
typedef struct lbk_dls_linear_page {
    float *out[3];
    size_t out_pitch[3];
} lbk_dls_linear_page;

/* lbk_dls_runtime_desc.flags */
#define LBK_DLS_RUNTIME_SCALAR 0x1u /* use the scalar path even where a SIMD one exists (same bytes) */
/* Linear mode: apply writes L = L_B + Σ_j w_j S_j as floats — the sums the byte mode encodes —
 * into linear outputs instead of AHD / packed SH9 bytes. Open decodes the base of every clustered
 * target and every entry once into the additive forms and keeps them, laid out for streaming
 * (per cluster: the base, then each set slot's entries, struct-of-arrays per plane, 64-byte
 * aligned), so that an apply is multiplies and adds on floats, near memory bandwidth (bench_dls).
 * Memory: 4·(12·(T_c + E_t) + 27·(P_c + E_p)) bytes plus at most 64 bytes per cluster array,
 * where T_c / P_c are the texels / probes that some cluster has (lbk_dls_stats.touched) and E_t /
 * E_p the texel / probe entries (lbk_dls_stats.entries), and 2 MiB of alignment for blocks of
 * 64 MiB or more (those ask Linux for huge pages); lbk_dls_runtime_linear_bytes says it.
 * On the ESTATE-sized level of bench_dls: 338 MB, 7.8× its 43 MB DLS section (open 1–2 s). Outputs: per page
 * the three planes of `linear_pages` (or, in the array form, out_linear_texel), probes as
 * lbk_sh9_rgb (27 floats each, the order of lbk_sh9_rgb.c) in out_linear_glg / out_linear_llg;
 * the byte outputs (out_irradiance_z, out_rgba, out_glg, out_llg, lbk_dls_page.out_*) are
 * neither needed nor written. Exactness: each target's linear output is bit for bit the
 * accumulator the byte mode encodes (decode with lbk_ahd_to_linear / lbk_sh9_unpack, acc = base,
 * acc += w_j·S_j over the entries of non-zero weight in ascending set order, a multiply then an
 * add), whatever path or split; so lbk_ahd_from_linear / lbk_sh9_pack of it are the byte mode's
 * bytes for every target with an entry of non-zero weight; a target without one gets its decoded
 * base (where the byte mode copies the base bytes: their re-encoding need not be those bytes). */
#define LBK_DLS_RUNTIME_LINEAR 0x2u

/* Texels come either as pages (page_count ≥ 1, in LMAP page order, Σ width·height = the texel
 * count; the four texel arrays are then NULL) or as the four arrays over the global texel index:
 * irradiance_z[i] the R11G11B10F word (host order), rgba[4i..4i+3] the second plane. Probes are
 * 28-byte packed SH9 in GLG / concatenated LLG order. A space with no DLS entries may be left out
 * (its output is then not written). The outputs persist between applies: apply rewrites only
 * the targets whose sets changed (call lbk_dls_runtime_invalidate after touching them). Outputs
 * must not overlap the bases or each other. Size-tagged (lbk.h): set size with
 * LBK_DLS_RUNTIME_DESC_INIT. */
typedef struct lbk_dls_runtime_desc {
    size_t size;
    const lbk_dls_view *dls;
    const struct lbk_door_view *doors; /* optional: door weights drive the kind 1/2 sets */
    const uint32_t *base_irradiance_z; const uint8_t *base_rgba; /* lbk_dls_target_count(TEXEL) */
    const uint8_t *base_glg;  /* 28 × GLG probes */
    const uint8_t *base_llg;  /* 28 × LLG probes */
    uint32_t *out_irradiance_z; uint8_t *out_rgba;
    uint8_t *out_glg;
    uint8_t *out_llg;
    const lbk_allocator *allocator;
    /* appended after the 1.0 layout (size 0 or the 1.0 size: these read as zero) */
    uint32_t page_count;          /* ≥ 1: texels in `pages` instead of the four arrays */
    const lbk_dls_page *pages;
    uint32_t flags;               /* LBK_DLS_RUNTIME_* */
    uint32_t job_targets;         /* targets per job of lbk_dls_apply_begin; 0: 4096 */
    /* appended for the linear mode (LBK_DLS_RUNTIME_LINEAR; ignored without it) */
    const lbk_dls_linear_page *linear_pages; /* with pages: page_count of them, in page order */
    float *out_linear_texel[3];   /* the array form: plane c, 4 floats per texel (as a page's) */
    float *out_linear_glg;        /* 27 floats (lbk_sh9_rgb) × GLG probes */
    float *out_linear_llg;        /* 27 floats × LLG probes */
} lbk_dls_runtime_desc;
#define LBK_DLS_RUNTIME_DESC_INIT LBK_SIZED_INIT(lbk_dls_runtime_desc)

/* Filled by lbk_dls_apply (frozen). */
typedef struct lbk_dls_apply_stats {
    uint32_t clusters_applied;  /* decoded, weighted, summed, re-encoded */
    uint32_t clusters_copied;   /* every weight of the cluster 0: base copied */
    uint32_t clusters_skipped;  /* no weight of the cluster changed */
    uint64_t targets_written;   /* by clusters and by base copies of untouched targets */
} lbk_dls_apply_stats;

/* Checks that the views agree (door sets exist and have the right kinds), that every needed
 * buffer is present and that the pages cover the texels. The views and buffers must outlive the
 * runtime. With LBK_DLS_RUNTIME_LINEAR it also decodes the prepared data (above). */
LBK_API lbk_result lbk_dls_runtime_open(const lbk_dls_runtime_desc *desc, lbk_dls_runtime **out);
LBK_API void lbk_dls_runtime_close(lbk_dls_runtime *runtime);
/* The bytes the runtime holds for the linear mode's prepared data (0 without LBK_DLS_RUNTIME_LINEAR). */
LBK_API uint64_t lbk_dls_runtime_linear_bytes(const lbk_dls_runtime *runtime);
/* The next apply rewrites every target. */
LBK_API void lbk_dls_runtime_invalidate(lbk_dls_runtime *runtime);

/* Computes L = L_B + Σ_j w_j S_j into the outputs, cluster by cluster (spec/container.md §12.8:
 * decode base and entries to the additive linear forms lbk_ahd_linear / lbk_sh9_rgb, weight,
 * sum, re-encode). Effective weight w_j of set j:
 *   kind 0 (lights):      set_weights[j];
 *   kind 1 (door open):   door_weights[p] if door p of the DOOR view names j, else set_weights[j];
 *   kind 2 (door closed): 1 − door_weights[p] if door p names j, else set_weights[j];
 *   kind 3 (combination): the product of its members' effective weights.
 * set_weights has lbk_dls_set_count entries (NULL: all 0; entries of kind-3 sets are ignored),
 * door_weights one per door (NULL: all doors closed, ω = 0). Weights must be finite.
 * The first call (and the first after invalidate) writes every target: untouched ones get the
 * base bytes. Later calls skip each cluster none of whose sets' effective weights changed; a
 * cluster whose weights are all 0 gets exactly the base bytes. The bytes are those of the
 * scalar definition whichever path (scalar, AVX2) runs and however the work is split.
 * In linear mode the same, with floats for bytes: untouched targets and all-zero clusters get
 * the decoded base, the others the weighted sums (LBK_DLS_RUNTIME_LINEAR); the stats count the
 * same clusters and targets. stats may be NULL. */
LBK_API lbk_result lbk_dls_apply(lbk_dls_runtime *runtime, const float *set_weights, const float *door_weights,
                                 lbk_dls_apply_stats *stats);
/* The effective weights apply would use (lbk_dls_set_count floats). */
LBK_API lbk_result lbk_dls_effective_weights(const lbk_dls_runtime *runtime, const float *set_weights,
                                             const float *door_weights, float *out);

/* lbk_dls_apply split for the caller's threads (engines run these on their job system):
 * begin takes the weights and says how many jobs there are (each about desc.job_targets
 * targets); every job in [0, *job_count) must then run exactly once, in any order, on any
 * threads, concurrently (jobs write disjoint bytes and only read the runtime); end collects the
 * dirty regions and stats. The bytes do not depend on the split, the order or the threads.
 * begin fails (and changes nothing) on bad weights or when the previous begin was not ended. */
LBK_API lbk_result lbk_dls_apply_begin(lbk_dls_runtime *runtime, const float *set_weights, const float *door_weights,
                                       uint32_t *job_count);
LBK_API void lbk_dls_apply_job(lbk_dls_runtime *runtime, uint32_t job);
LBK_API lbk_result lbk_dls_apply_end(lbk_dls_runtime *runtime, lbk_dls_apply_stats *stats);

/* What the last apply wrote, to re-upload only that: per space, ranges of target indices (texels
 * in the global texel index), and with pages, rectangles per page. Both cover every target the
 * apply wrote and may cover unchanged ones too: overlapping, touching and — past the caps —
 * nearby regions are merged. Sorted (ranges by first, rectangles by y then x), disjoint.
 * Empty when nothing changed. Frozen. */
typedef struct lbk_dls_range {
    uint64_t first, count;
} lbk_dls_range;
typedef struct lbk_dls_rect {
    uint32_t x, y, width, height;
} lbk_dls_rect;
#define LBK_DLS_DIRTY_RANGES 64u /* at most this many ranges per space */
#define LBK_DLS_DIRTY_RECTS 16u  /* at most this many rectangles per page */
LBK_API uint32_t lbk_dls_dirty_range_count(const lbk_dls_runtime *runtime, uint32_t space);
LBK_API lbk_result lbk_dls_dirty_range_get(const lbk_dls_runtime *runtime, uint32_t space, uint32_t i,
                                           lbk_dls_range *out);
LBK_API uint32_t lbk_dls_dirty_rect_count(const lbk_dls_runtime *runtime, uint32_t page);
LBK_API lbk_result lbk_dls_dirty_rect_get(const lbk_dls_runtime *runtime, uint32_t page, uint32_t i,
                                          lbk_dls_rect *out);

#ifdef __cplusplus
}
#endif
#endif

/* ---- experimental: no ABI promise (as zstd's ZSTD_STATIC_LINKING_ONLY) ---------------------
 * Define LBK_STATIC_LINKING_ONLY before including this header to get the builder's tuning knobs
 * and the section statistics. They may change in any release; link liblbk statically. */
#if defined(LBK_STATIC_LINKING_ONLY) && !defined(LBK_DLS_H_STATIC)
#define LBK_DLS_H_STATIC

#ifdef __cplusplus
extern "C" {
#endif

/* How lbk_dls_build groups small combinations into dispatches (spec/container.md §12).
 * Zero-initialised: the defaults. */
struct lbk_dls_tuning {
    /* Packed (class 1) and prefix clusters grow by adding the combination that adds the fewest
     * new sets until they hold this many targets; past it only combinations adding no set join.
     * 0: 256. */
    uint32_t min_dispatch_targets;
    /* Cap on the targets of one class (1) packed cluster. 0: 4096. */
    uint32_t packed_max_targets;
};

/* Statistics of a DLS section for `lbk inspect` and for tuning (Table 1 of seed 001). */
#define LBK_DLS_HISTOGRAM_BINS 18 /* [0] untouched targets, [1..16] that many sets, [17] more */
struct lbk_dls_stats {
    uint32_t set_count;
    uint32_t sets_by_kind[LBK_DLS_KIND_COUNT_];
    uint32_t cluster_count;
    uint32_t clusters_by_form[LBK_DLS_FORM_COUNT_];
    uint32_t packed_subgroups;                      /* class (1) sub-groups over all clusters */
    uint64_t target_count[LBK_DLS_SPACE_COUNT_];    /* size of each space */
    uint64_t touched[LBK_DLS_SPACE_COUNT_];         /* targets with at least one entry */
    uint64_t targets_by_form[LBK_DLS_FORM_COUNT_];
    uint64_t entries[LBK_DLS_SPACE_COUNT_];
    uint64_t histogram[LBK_DLS_SPACE_COUNT_][LBK_DLS_HISTOGRAM_BINS];
    uint64_t section_bytes;
    uint64_t payload_bytes;     /* the entries' 8/28-byte payloads */
    uint64_t ancillary_bytes;   /* everything else: section_bytes − payload_bytes */
    /* The per-target index data of each space: cluster records and set lists, runs, sub-group
     * records, prefix words, bases and slots of the clusters of that space. */
    uint64_t index_bytes[LBK_DLS_SPACE_COUNT_];
    double index_bits_per_target[LBK_DLS_SPACE_COUNT_]; /* 8 × index_bytes / touched (0 if none) */
};

LBK_API lbk_result lbk_dls_stats_get(const lbk_dls_view *view, lbk_dls_stats *out);

/* The path lbk_dls_apply computes with: "scalar" or "avx2" (AVX2 with FMA; chosen at open from
 * the CPU and LBK_DLS_RUNTIME_SCALAR; every path writes the same bytes). */
LBK_API const char *lbk_dls_runtime_path(const lbk_dls_runtime *runtime);

#ifdef __cplusplus
}
#endif
#endif /* LBK_STATIC_LINKING_ONLY */
