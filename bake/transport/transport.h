/* Light transport: incident radiance at receivers, as SH9, by the series expansion of the
 * rendering equation (seed 001 §2.3), Lambertian surfaces. Method, error model and the
 * guaranteed furnace bounds: bake/transport/TRANSPORT.md.
 *
 * Summary: a radiosity cache of surface cells (each triangle side split into m² sub-triangles,
 * as fine as options.cell_size asks — the baker passes the texel size — or by area from a
 * budget; independent of lightmap UVs) is filled bounce by bounce: bounce 1 = punctual direct
 * (shadow rays) + emission (gather rays and next-event estimation, combined by multiple
 * importance sampling) + sky (gather rays); bounce k = albedo/π × irradiance gathered from
 * bounce k−1 with fresh rays. Bounces stop when the per-bounce energy ratio q has settled; the
 * rest of the Neumann series is added per cell as L_K·q/(1−q). Receivers then gather the cache's
 * radiance (final gather, emitters again by MIS of gather hits and light samples) plus punctual
 * direct light. Hits closer than 1.5 cell sizes are evaluated at the exact point (one more
 * gather from there) instead of reading the cell; the inside of closed solids is black
 * (bake/transport/solid.h); a texel with a footprint starts each ray from a random point of the
 * part of its square its chart covers. Progressive passes double the samples; each pass runs two
 * independent halves (own cache, own receiver rays), whose difference estimates the error; a
 * probe of continued far hits estimates the cache's bias (TRANSPORT.md §Bias).
 *
 * Determinism: every random number comes from a counter-based hash of (seed, half, pass,
 * bounce, item, sample); each item (cell or receiver) is computed by one thread in a fixed
 * order and all reductions run sequentially in item order, so the output is byte-identical for
 * any thread count. */
#ifndef BK_TRANSPORT_H
#define BK_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/lbk.h"
#include "lbk/sh.h"
#include "scene/scene.h"
#include "scene/tracer.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bk_receiver {
    float position[3];
    float normal[3];   /* unit: a surface texel gathering over the hemisphere around it;
                          zero: a volumetric probe gathering over the full sphere */
    /* Optional footprint (texels): footprint_count entries of options.footprint from
     * footprint_first. Each gather ray then leaves from a random point of the texel's square:
     * on the footprint triangle that covers it (its own position and interpolated normal), or
     * from position/normal where no footprint triangle covers it. The texel's value is so the
     * average over its square, as a renderer's bake of the same texel is (TRANSPORT.md). */
    uint32_t footprint_first, footprint_count;
    /* s0, t0, width, height: a box of the square that holds every point a footprint triangle
     * covers (points are drawn in it, so a sliver of a chart is sampled as well as a whole
     * square); width or height <= 0: the whole square */
    float footprint_box[4];
    /* Cells of the square (an 8 x 8 grid over [0,1]^2, bit 8*row + column) whose footprint points
     * lie beyond another surface seen from the texel's own point (bk_texels_push_out): a wall
     * texel whose square runs under a sill or into a box pushed through the wall. No ray leaves
     * from them; zero: the whole footprint. */
    uint64_t footprint_hidden;
} bk_receiver;

#define BK_FOOTPRINT_GRID 8
/* Whether texel-local (s, t) lies in a cell of `hidden` (bk_receiver.footprint_hidden). */
static inline int bk_footprint_cell_hidden(uint64_t hidden, double s, double t)
{
    if (!hidden) return 0;
    int cx = (int)(s * BK_FOOTPRINT_GRID), cy = (int)(t * BK_FOOTPRINT_GRID);
    cx = cx < 0 ? 0 : cx >= BK_FOOTPRINT_GRID ? BK_FOOTPRINT_GRID - 1 : cx;
    cy = cy < 0 ? 0 : cy >= BK_FOOTPRINT_GRID ? BK_FOOTPRINT_GRID - 1 : cy;
    return (int)((hidden >> (cy * BK_FOOTPRINT_GRID + cx)) & 1u);
}

/* One triangle of a texel's footprint: the barycentrics (u, v) of scene triangle `tri` (the
 * p = (1-u-v)·v0 + u·v1 + v·v2 convention of bk_hit) as affine functions of the texel-local
 * coordinates (s, t) in [0,1]²: u = uv[0][0] + uv[0][1]·s + uv[0][2]·t, v likewise. A point
 * belongs to it when u, v >= 0 and u + v <= 1. */
typedef struct bk_footprint_tri {
    uint32_t tri;
    float uv[2][3];
} bk_footprint_tri;

/* The world point p and unit shading normal n (the geometric normal where the mesh has none) of
 * texel-local (s, t) on the first of a texel's `count` footprint triangles that covers it.
 * Returns 0 where none covers it or the covering triangle is degenerate. */
int bk_footprint_point(const bk_scene *scene, const bk_footprint_tri *tris, uint32_t count, double s, double t,
                       double p[3], double n[3]);

/* Whether another surface crosses the segment from a to b, two points of a texel's surface with
 * unit normals na, nb (both ends raised 0.1 % of the segment's length along them): a hit on one
 * of the `count` footprint triangles or on triangle `own` (UINT32_MAX: none) is the texel's own
 * surface and is stepped over, as is a hit on a door of `scene` (NULL: none is a door): a door
 * moves. 1 crossed, 0 clear. */
int bk_footprint_segment_blocked(const bk_tracer *tracer, const bk_scene *scene, const bk_footprint_tri *tris,
                                 uint32_t count, uint32_t own, const double a[3], const double na[3], const double b[3],
                                 const double nb[3]);

/* Whether receiver r's footprint point p (normal n) at texel-local (s, t) lies beyond another
 * surface seen from r's own point, and so is no sample of r: r's hidden cell mark, where the
 * cell and its eight neighbours agree; else (the covering surface's edge runs near) the
 * segment test above from r's point, in `scene` (the one footprints index). `tris` is the whole
 * footprint table (options.footprint). */
int bk_footprint_sample_hidden(const bk_tracer *tracer, const bk_scene *scene, const bk_footprint_tri *tris,
                               const bk_receiver *r, double s, double t, const double p[3], const double n[3]);

/* One point of the error-against-time record, written after every pass. */
/* Receiver classes, in the order the pipeline lists receivers (bk_transport_options.class_end). */
enum { BK_CLASS_TEXEL, BK_CLASS_GLG, BK_CLASS_LLG, BK_RECEIVER_CLASSES };

typedef struct bk_transport_sample {
    double seconds;               /* since bk_transport_run started */
    double samples_per_receiver;  /* gather rays per receiver so far (both halves, all passes): the
                                     lead class's mean (class_mean_samples) */
    double est_rel_rmse;          /* estimated relative RMSE of the result so far (TRANSPORT.md) */
    int bounces;                  /* bounces computed explicitly in the last pass (tail excluded) */
    int pass;
    /* the same estimate per receiver class (options.class_end; 0 for an empty class): texels,
     * GLG probes, LLG probes, and the probes together */
    double class_rel_rmse[BK_RECEIVER_CLASSES];
    double probe_rel_rmse;
    double class_samples[BK_RECEIVER_CLASSES]; /* the samples so far of each class's receivers that
                                                  sampled longest */
    /* the mean over each class's receivers (over its stop subset where it has one) of their own
     * samples: below class_samples where adaptive sampling (options.adaptive) let converged
     * blocks stop while others went on */
    double class_mean_samples[BK_RECEIVER_CLASSES];
} bk_transport_sample;

/* ---- distributed bakes (bake/dist/DIST.md) ----------------------------------------------
 * A run cut by receivers: a unit gathers only receivers [begin, end) and hands what it computed
 * to `record_*`; the merge replays every unit's record instead of tracing (`replay_*`), so the
 * error estimates, the report and the stats are computed from the same numbers in the same
 * order as a run over all receivers (byte-identical). A run with an error target can be cut:
 * its stop reads only the stop receivers (options.stop_receivers), which every unit gathers too,
 * unrecorded. No time_limit (LBK_ERR_INVALID_ARGUMENT): the passes it allows depend on the
 * machine. */

/* One finished pass. x_acc/b_acc: per receiver, per half, the pass-weighted accumulators of the
 * error scalar and the bias probe (indexed by receiver; a unit's are valid in [begin, end)). */
typedef struct bk_transport_pass_record {
    int pass, bounces;
    double samples_per_receiver;  /* the lead class's (bk_transport_stats.samples_per_receiver) */
    double weight_sum[BK_RECEIVER_CLASSES], class_samples[BK_RECEIVER_CLASSES]; /* per class */
    double *x_acc[2], *b_acc[2];
} bk_transport_pass_record;

/* What a run adds up to. The cache's part is global (every unit traces it alike); the
 * receivers' part is the unit's own. */
typedef struct bk_transport_totals {
    int passes, stop, nee, bounces;
    double q, tail_fraction;
    uint64_t cells;
    uint64_t cache_rays, cache_shadow, cache_nonfinite;
    uint64_t recv_rays, recv_shadow, recv_nonfinite;
    /* the octahedral probes, in the one unit that gathers them (its receiver slice starts at 0):
     * their count (else 0), rays and estimated error (bk_transport_stats.octa_*) */
    uint64_t octa_count;
    double octa_rays, octa_rel_rmse;
} bk_transport_totals;

/* ---- checkpoints (resume after a crash, continue to a lower error) -------------------------
 * After every pass the run's whole state is handed to `save`; at the start of a run `load` may
 * hand back the state of its last saved pass, and the run goes on from there: the passes that
 * follow are the ones an uninterrupted run makes (every pass depends only on the seed and its
 * index, never on the caches of the pass before), so the result is byte-identical. */
#define BK_TRANSPORT_MAX_PASSES 32
typedef struct bk_transport_state {
    int passes;                 /* passes finished */
    double weight_sum[BK_RECEIVER_CLASSES], spp[BK_RECEIVER_CLASSES]; /* per receiver class */
    int active[BK_RECEIVER_CLASSES], stop[BK_RECEIVER_CLASSES];
    int chain_bounces[2];
    double chain_q[2], chain_tail[2], chain_total[2];
    uint64_t cache_rays, cache_shadow, cache_nonfinite, rays, shadow, nonfinite;
    size_t count;
    /* per receiver (count): the halves' accumulators and the outputs' running sums (before the
     * final normalisation); radiance always, direct/irradiance as the run's outputs have them */
    double *x_acc[2], *b_acc[2];
    void *radiance, *direct;    /* lbk_sh9_rgb arrays */
    float *irradiance;
    bk_transport_sample samples[BK_TRANSPORT_MAX_PASSES]; /* what each pass reported */
    /* per cache cell (cells): the rough marks the last pass left for the next (TRANSPORT.md) */
    size_t cells;
    uint8_t *rough;
    /* per adaptive block (blocks; TRANSPORT.md §Adaptive sampling): the sum of the weights of
     * the passes it sampled in */
    size_t blocks;
    double *block_weight;
} bk_transport_state;

typedef struct bk_transport_checkpoint {
    void *user;
    lbk_result (*save)(void *user, const bk_transport_state *state);
    /* fills state (its arrays allocated by the transport for state->count receivers, NULL where
     * the run has no such output): 1 when a saved state was loaded, 0 when there is none, else
     * an lbk_result error (negated) */
    int (*load)(void *user, bk_transport_state *state);
} bk_transport_checkpoint;

struct bk_transport_output;

/* One bounce of a run's radiosity cache, handed to bk_transport_split.cache_bounce: every cell's
 * value must end up in out (3 floats per cell), computed here (compute) or read from where
 * another process that computed it published it (then add_counts adds what it traced). The
 * values of a cell depend only on the scene, the options, the seed, (pass, half, bounce) and the
 * earlier bounces, so any split of the cells between processes gives the same floats. */
typedef struct bk_cache_bounce {
    int pass, half, bounce, rays;
    size_t cells;
    float *out;
    /* computes cells [begin, end) into out; counts: the rays, shadow rays and non-finite values
     * they made */
    lbk_result (*compute)(void *ctx, size_t begin, size_t end, uint64_t counts[3]);
    void (*add_counts)(void *ctx, const uint64_t counts[3]);
    void *ctx;
} bk_cache_bounce;

typedef struct bk_transport_split {
    int replay;            /* 0: record (a unit), 1: replay (the merge) */
    void *user;
    /* record: called once at the start of every run, in run order: *own = 1 and the receivers
     * [*begin, *end) this unit gathers (and records) in this run; with an error target it also
     * gathers, unrecorded, the receivers its stop rule reads (options.stop_receivers), so every
     * unit of a run stops where the whole run does; *own = 2: the receivers [*begin, *end) (all,
     * or none: the stop rule's receivers only), not recorded (a later run needs its stats); or
     * *own = 0: the unit has no share of the run, which then traces nothing, leaves its outputs 0
     * and reports only its sample schedule (stats passes and samples: a fixed schedule does not
     * depend on tracing; with an error target they are meaningless) */
    lbk_result (*run_range)(void *user, size_t count, int *own, size_t *begin, size_t *end);
    lbk_result (*record_pass)(void *user, const bk_transport_pass_record *pass);
    lbk_result (*record_done)(void *user, const struct bk_transport_output *out, const bk_transport_totals *totals);
    /* replay: totals summed over the units; then every pass (arrays of `count` entries
     * allocated by the transport, filled by the callee); then the outputs of every receiver */
    lbk_result (*replay_totals)(void *user, size_t count, bk_transport_totals *totals);
    lbk_result (*replay_pass)(void *user, bk_transport_pass_record *pass);
    lbk_result (*replay_outputs)(void *user, const struct bk_transport_output *out);
    /* record, optional (NULL: the unit computes the whole cache of every run it traces): shares
     * the cache's bounces with the other units of the run (DIST.md §Shared caches); called for
     * every bounce of every chain of a run the unit traces (own 1 or 2) */
    lbk_result (*cache_bounce)(void *user, const bk_cache_bounce *b);
} bk_transport_split;

typedef struct bk_transport_options {
    uint64_t seed;
    int threads;             /* 0: all online cores */
    int max_bounces;         /* explicit bounces per pass before the analytic tail; 0: 64 */
    int max_samples;         /* budget of gather rays per receiver over the whole run; 0: 4096 */
    double target_error;     /* stop when the estimated relative RMSE <= this; 0: 0.01; < 0: never */
    double time_limit;       /* seconds; 0: none. At least one pass always completes. */
    const char *light_set;   /* NULL or "": the base (lights / emissive objects whose light_set is
                                "", plus the sky); else only that set's lights and emitters, no sky */
    int no_punctual;         /* 1: leave punctual lights out (default 0: included) */
    int no_sky;              /* 1: no sky even in the base */
    int max_cells;           /* radiosity cache cells (both sides counted) shared by area among
                                the triangles without a cell_size; 0: 32768. A triangle always
                                gets at least one cell per side */
    /* Per scene triangle (tri_count entries) or NULL: the wanted cell size in metres, <= 0 for
     * "share max_cells". The baker passes the lightmap's texel size, so the cache is as fine
     * as the lightmap (TRANSPORT.md §Bias). All cells together stay below 4 Mi (sizes grow
     * uniformly if needed). */
    const float *cell_size;
    /* Texel footprints (bk_receiver.footprint_*): the triangles, and the scene whose triangles
     * they index and whose vertex positions and normals place the points (NULL: `scene`; a
     * bake over a scene with some triangles removed passes the full one). */
    const bk_footprint_tri *footprint;
    size_t footprint_count;
    const bk_scene *footprint_scene;
    int cache_rays;          /* gather rays per cell per bounce in pass 0 (doubles per pass); 0: 16 */
    int first_pass_samples;  /* gather rays per receiver per half in pass 0 (doubles); 0: 16 */
    /* Next-event estimation of emissive triangles (one light sample per gather ray, combined
     * with the gather hits by the power heuristic): 0 auto = on unless the emitters cover half
     * the scene's surface or more (gather rays find them anyway; TRANSPORT.md), 1 on, -1 off. */
    int nee;
    /* Called once per cache cell with the triangle's textured albedo; may change it (e.g. 0 for
     * doors in base bakes). Must be deterministic. NULL: none. */
    void (*albedo_hook)(void *user, uint32_t tri, float albedo[3]);
    /* phase is "cache" or "gather"; fraction is the estimated fraction of the whole run.
     * Called on the calling thread after each cache chain and each block of receivers; a
     * non-zero return stops the run with LBK_ERR_CANCELLED (outputs then undefined). */
    int (*progress)(void *user, const char *phase, double fraction);
    void (*report)(void *user, const bk_transport_sample *sample);
    void *user;
    /* Receivers [0, class_end[0]) are texels, [class_end[0], class_end[1]) GLG probes,
     * [class_end[1], class_end[2]) LLG probes (class_end[2] = count): the error is then
     * estimated per class (bk_transport_sample.class_rel_rmse) and each class samples until
     * its own estimate reaches target_error (or its budget or the time runs out): probes,
     * which gather over the whole sphere, go on after the texels have stopped.
     * All 0: one class, the estimate over all. */
    size_t class_end[BK_RECEIVER_CLASSES];
    /* Octahedral probes (OCTP, bake/probes/octa_bake.h): octa_count points (3 floats each)
     * gathered over the sphere in the same final-gather passes as the receivers, on their own
     * random streams, but outside the receivers' outputs, error estimate and stop rule (so a bake
     * with them gives the receivers the same bytes). Each traces octa_ray_factor (0: 4, at most
     * 64) × the pass's rays per half and yields 16 cosine-convolved irradiance texels
     * (bk_transport_output.octa_irradiance). NULL: none. */
    const float *octa_points;
    size_t octa_count;
    int octa_ray_factor;
    /* NULL: a whole run; else a distributed one (above). Copied with the options, so every
     * light-set and door run of a unit or merge is cut the same way. */
    const bk_transport_split *split;
    /* NULL: none; else checkpoints after every pass and resumption (above). Not with split. */
    const bk_transport_checkpoint *checkpoint;
    /* Stochastic light culling of punctual lights (bake/transport/SLC.md): 0 auto = on with more
     * than BK_SLC_AUTO_LIGHTS positional lights, 1 on, -1 off. On, punctual light at receivers
     * and in the cache's first bounce is one culling draw per half and pass (unbiased, in the
     * error estimate) instead of every light with a shadow ray. */
    int slc;
    /* δ relative to the mean punctual irradiance of the positional lights at the receivers
     * (shadowed, as received): a light is accepted for certain where its irradiance exceeds
     * δ × that mean (pass p: δ/2^p), and one draw's level-wide relative RMSE is ≤ √(δ/2);
     * 0: BK_SLC_DEFAULT_DELTA. Smaller: more lights per receiver, less noise. */
    double slc_delta;
    /* Glossy VPLs (seed 002; bake/transport/VPL.md "In the transport"): photons from every
     * point and spot light make a VPL where they land on a glossy cell (its specular lobe),
     * culled stochastically against the receivers' tiles (the seed's spheroids) and gathered
     * at every surface receiver with shadow rays, per half and pass (unbiased, in the error
     * estimate); the receivers' gather then takes those lights at its first glossy hit through
     * the diffuse part only, so the light → glossy → receiver path is counted once.
     * 0 auto = on where the lights' photons put at least BK_VPL_AUTO_SHARE of their flux into
     * glossy surfaces of roughness ≤ BK_VPL_AUTO_ROUGHNESS; 1 on; -1 off. */
    int glossy_vpl;
    size_t glossy_vpl_photons; /* per light and half in pass 0 (pass p: × 2^p); 0: BK_VPL_DEFAULT_PHOTONS */
    double glossy_vpl_delta;   /* δ relative to the mean irradiance the VPLs give the surface
                                  receivers (pass p: δ/2^p); 0: BK_VPL_DEFAULT_DELTA */
    /* The stop rule's receivers per class (TRANSPORT.md §Stop subset): a class of more than
     * this many stops on the estimate over a hash-stratified subset of about this many of its
     * receivers, in whole adaptive blocks (the reported estimate stays over all of them), so a unit of a distributed run
     * can evaluate the stop alone by also gathering that subset; a smaller class stops on all
     * its receivers. 0: BK_TRANSPORT_STOP_RECEIVERS. */
    size_t stop_receivers;
    /* Ray-length limit with probe fallback (seed 003's "sample probes when coverage is low";
     * TRANSPORT.md §Ray-length limit): > 0 and far_radiance set, every final-gather ray of a
     * surface receiver (a texel, an LLG fit target: receivers with a normal) ends at this many
     * metres; one that hits nothing within it asks far_radiance at its end point x for its
     * direction d: where it returns 1 (the probes cover x) L is the ray's radiance (the incident
     * radiance at x arriving from d, e.g. a probe volume's SH9), counted as indirect light;
     * where it returns 0 the ray is traced on from x. A light sample of an emitter farther than
     * the limit is dropped where the probes cover the point at the limit on its way (the
     * gather ray there reads them, and they hold that emitter). Sphere receivers (probes) and
     * the cache trace in full. far_radiance must be deterministic and thread-safe; *hint starts
     * at 0 for each receiver and half and is the callee's to keep (where its last lookup was).
     * 0: off (default), every bake unchanged. */
    double gather_limit;
    int (*far_radiance)(void *user, const double x[3], const double d[3], uint32_t *hint, double L[3]);
    void *far_user;
    /* Adaptive sampling (TRANSPORT.md §Adaptive sampling): 1: with a target, the receivers of a
     * class are taken in blocks of BK_TRANSPORT_BLOCK (receiver index / BK_TRANSPORT_BLOCK, cut
     * at the class bounds); after pass BK_TRANSPORT_ADAPT_PASS and each one after it, a block
     * whose noise per receiver (its two halves' difference) is at most target² × the class's
     * mean square sits the next pass out while the rest of its class goes on, and max_samples
     * bounds the class's mean samples per receiver (bk_transport_sample.class_mean_samples).
     * Probes' blocks adapt once the texels have stopped. 0: off (every receiver of a class
     * samples while the class does). */
    int adaptive;
    /* The path check (TRANSPORT.md §Path check): after the last pass, check_per_group receivers
     * of each group (check_group: per receiver, a group below check_groups or UINT32_MAX for
     * none; surface receivers only) are drawn in proportion to half their share of the group's
     * noise and half their share of its squared light, and each gets check_samples unbiased paths
     * — every hit continued at its exact point, no cell read. Into output.check_*, slot
     * g·check_per_group + j [0: a quarter of the rays the receivers traced in the passes, spread
     * over the checks, 256 … 16384 paths each]. Not in distributed runs. NULL: none. */
    const uint32_t *check_group;
    uint32_t check_groups;
    int check_per_group;
    int check_samples;
} bk_transport_options;

#define BK_TRANSPORT_STOP_RECEIVERS ((size_t)65536)

/* Adaptive sampling's blocks and the first pass after which one may stop (TRANSPORT.md
 * §Adaptive sampling, measured by bench_estimate and bench-cycles). A distributed run's unit
 * gathers whole blocks (spec/part.md §1.1). */
#define BK_TRANSPORT_BLOCK 64
#define BK_TRANSPORT_ADAPT_PASS 1

/* The light count above which culling is on by default, and the default δ (SLC.md, measured by
 * bench_slc). */
#define BK_SLC_AUTO_LIGHTS 32
#define BK_SLC_DEFAULT_DELTA 0.1

/* Glossy VPLs' defaults and auto rule (VPL.md "In the transport", measured by bench_vpl_bake). */
#define BK_VPL_DEFAULT_PHOTONS 1024
#define BK_VPL_DEFAULT_DELTA 0.1
#define BK_VPL_AUTO_ROUGHNESS 0.3
#define BK_VPL_AUTO_SHARE 0.05

/* Caller-owned output arrays, `count` entries each; NULL pointers are skipped. */
typedef struct bk_transport_output {
    lbk_sh9_rgb *radiance;   /* incident radiance projected on SH9 (zero below a texel's horizon) */
    lbk_sh9_rgb *direct;     /* the part that arrives straight from lights, emitters and sky;
                                radiance − direct is the indirect part */
    float *irradiance;       /* 3 per receiver, estimated directly (not from the SH): texels the
                                irradiance E(n) = ∫_H L cos; probes the fluence ∫_S² L dω */
    /* 1 per receiver: the estimated variance of the result's error scalar X (luminance of the
     * irradiance, texels; fluence/4, probes; TRANSPORT.md §Error estimate), ((A − B)/2)² from the
     * two halves A, B: unbiased, one degree of freedom, 0 where only noise-free punctual light
     * arrives. The denoiser's input (bake/denoise/denoise.h). */
    float *variance;
    /* octa_count × 16 × 3 (options.octa_points): irradiance E(n_t) = ∫ L·max(0, n_t·ω) dω for the
     * 16 directions n_t = lbk_oct_texel_direction(4, t % 4, t / 4), punctual light included */
    float *octa_irradiance;
    /* 2 per receiver: X of the two halves, A then B (what `variance` is made of, with its
     * sign): a linear filter applied to A − B shows how much of the noise it leaves, including
     * the part correlated between receivers (bk_denoiser_error). */
    float *halves;
    /* options.check_groups × check_per_group slots (the path check): the receiver drawn
     * (UINT32_MAX: an empty slot: a group without that many lit receivers), its weight 1/(K·p)
     * (Σ over a group's slots of weight × d estimates Σ of d over the group's receivers), the
     * paths' mean irradiance (3 each) and the variance of its luminance; all four or none */
    uint32_t *check_receiver;
    float *check_weight;
    float *check_irradiance;
    float *check_variance;
} bk_transport_output;

enum bk_transport_stop { BK_STOP_TARGET = 0, BK_STOP_TIME, BK_STOP_BUDGET };

typedef struct bk_transport_stats {
    double seconds;
    int passes;
    double samples_per_receiver;
    double est_rel_rmse;
    double est_cache_bias;   /* estimated relative RMS bias of reading the cache's cells at the
                                receivers' far hits (the probes, TRANSPORT.md §Bias); not in
                                est_rel_rmse, which the two halves measure */
    double class_rel_rmse[BK_RECEIVER_CLASSES]; /* per class, as in bk_transport_sample */
    double probe_rel_rmse;
    /* gather rays per receiver of each class (both halves, all its passes): classes sample
     * until their own estimate reaches the target; samples_per_receiver and stop are the
     * texels' (the first class with receivers when there are no texels: the one that sampled
     * longest) */
    double class_samples[BK_RECEIVER_CLASSES];
    double class_mean_samples[BK_RECEIVER_CLASSES]; /* the mean over each class's receivers (adaptive) */
    int bounces;             /* explicit bounces of the last pass */
    double q;                /* per-bounce energy ratio used for the tail (last pass, mean of halves) */
    double tail_fraction;    /* share of the cache's indirect energy that came from the tail */
    size_t cells;
    uint64_t rays;           /* rays traced (gather + shadow) */
    uint64_t shadow_rays;    /* of which shadow rays (punctual lights and light samples) */
    int nee;                 /* 1 when emitters were light-sampled (next-event estimation) */
    uint64_t nonfinite;      /* sample values that were NaN/Inf and were dropped (should be 0) */
    int stop;                /* enum bk_transport_stop */
    double octa_rel_rmse;    /* estimated relative RMSE of the octahedral texels (the two halves,
                                over every texel; TRANSPORT.md's estimate) */
    double octa_rays;        /* gather rays per octahedral probe, both halves, all passes */
    int slc;                 /* 1 when punctual lights were culled (options.slc) */
    double slc_delta;        /* the δ of pass 0 in irradiance units (0 without culling) */
    double slc_lights_tested;/* per receiver over the run: lights its tiles' lists gave it to test */
    int vpl;                 /* 1 when glossy VPLs were gathered (options.glossy_vpl) */
    double vpl_delta;        /* their δ of pass 0 in irradiance units (0 without) */
    double vpl_share;        /* what auto measured: the shooting lights' flux share in sharp glossy
                                VPLs (0 when not measured: no glossy cell or no shooting light) */
    uint64_t vpl_made;       /* VPLs made over the run (both halves, all passes) */
    double vpl_tested;       /* per receiver over the run: VPLs its tiles' lists gave it to test */
    uint64_t check_rays;     /* rays the path check traced (not in rays) */
    int check_samples;       /* its paths per checked receiver */
} bk_transport_stats;

/* Computes radiance at `count` receivers. The tracer must have been built from `scene`.
 * Errors: LBK_ERR_INVALID_ARGUMENT (NULL scene/tracer/output->radiance with count > 0, tracer
 * over another triangle count, non-finite receiver), LBK_ERR_OUT_OF_MEMORY, LBK_ERR_CANCELLED (the
 * progress callback said stop). */
lbk_result bk_transport_run(const bk_scene *scene, const bk_tracer *tracer, const bk_receiver *receivers,
                            size_t count, const bk_transport_options *options,
                            const bk_transport_output *output, bk_transport_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
