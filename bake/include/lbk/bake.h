/* liblbkbake — the light bake kit's baker as a library: a glTF file or an in-memory scene in,
 * a container (lbk_writer or bytes) and the bake report (data, or JSON) out. `lbk bake` is a
 * thin command line over it. Link with `pkg-config --cflags --libs lbk-bake`.
 *
 * Conventions are liblbk's (lbk/lbk.h): every fallible call returns lbk_result, nothing
 * prints or exits, there is no global state, handles are opaque, and zero-initialised structs
 * mean defaults. The structs a caller fills (lbk_bake_desc, lbk_bake_scene) carry their own
 * size so they can grow without breaking callers compiled against an older header.
 *
 * Results of a bake call:
 *   LBK_OK                    *out holds the output;
 *   LBK_ERR_CANCELLED         the progress callback returned non-zero; *out is NULL;
 *   LBK_ERR_BAD_INPUT         the scene is unusable: a glTF the importer rejects, no light, no
 *                             triangle with area, a scene description that breaks its rules, a
 *                             bad lbk_* extra, an unreadable sky EXR (`lbk bake` exit code 4);
 *   LBK_ERR_IO                the input file cannot be opened (exit code 3);
 *   LBK_ERR_INVALID_ARGUMENT  NULL pointers, a size field larger than this library knows with
 *                             non-zero bytes past it, an unknown enum value;
 *   LBK_ERR_OUT_OF_MEMORY, LBK_ERR_INTERNAL
 *                             the bake failed on its own (exit code 5).
 * Every failure except LBK_ERR_CANCELLED sends one LBK_BAKE_SEVERITY_ERROR message that says
 * why (naming the file, node, object or extras key at fault) — unless the desc itself cannot be
 * read (NULL `out`, a size below sizeof(size_t)). The library never writes a file unless asked
 * (lbk_bake_output_write_file, lbk_bake_report_write_json).
 *
 * Determinism: the same input, desc and seed give byte-identical containers for any thread
 * count (every random number is a counter-based hash of the seed and the work item, every
 * reduction runs in item order). Nothing time-dependent enters the container unless asked:
 * `timestamp` stores the bake time in META, and with `time_limit` the number of passes depends
 * on the machine. The report's seconds are wall clock and differ run to run.
 *
 * Threads: `threads` workers (0: one per online core); the calling thread is one of them.
 * Callbacks run on the calling thread only, never concurrently. Independent bakes may run
 * in parallel on different threads (nothing is shared between calls). */
#ifndef LBK_BAKE_H
#define LBK_BAKE_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/container.h"
#include "lbk/lbk.h"
#include "lbk/report.h"

#ifdef __cplusplus
extern "C" {
#endif

#if defined(LBK_BAKE_BUILDING_SHARED) && defined(__GNUC__)
#define LBK_BAKE_API __attribute__((visibility("default")))
#else
#define LBK_BAKE_API
#endif

/* The baker library's version (lbk-bake.pc): the minor grows with every addition to the
 * size-tagged structs below ("added in 1.x"). */
#define LBK_BAKE_LIBRARY_VERSION_MAJOR 1
#define LBK_BAKE_LIBRARY_VERSION_MINOR 12
#define LBK_BAKE_LIBRARY_VERSION_PATCH 0 /* 1.12.0: shared caches of distributed units (lbk_bake_unit_shared) */

/* ---- options ----------------------------------------------------------------------------- */

/* Quality presets (README "Presets"); every value can be overridden in lbk_bake_desc. */
typedef enum lbk_bake_preset {
    LBK_BAKE_PRESET_FAST = 0, /* 8 texels/m, GLG spacing 2 m, 1024 samples, target error 3 % */
    LBK_BAKE_PRESET_HIGH = 1, /* 16 texels/m, GLG spacing 1 m, 16384 samples, target error 1 % */
    LBK_BAKE_PRESET_COUNT_
} lbk_bake_preset;

/* How a door's open contribution is baked (bake/sets/SETS.md). */
typedef enum lbk_bake_door_method {
    LBK_BAKE_DOOR_DIFFERENCE = 0, /* correlated differences of full runs */
    LBK_BAKE_DOOR_GUIDED = 1,     /* seed 001's guided estimator (portal sampling, shadow photons) */
    LBK_BAKE_DOOR_METHOD_COUNT_
} lbk_bake_door_method;

/* Denoising of the baked texels and probes (bake/denoise/DENOISE.md). */
typedef enum lbk_bake_denoise {
    LBK_BAKE_DENOISE_AUTO = 0, /* edge-aware, guided by the transport's own noise estimate, kept per
                                  class (texels, GLG probes) of the base and of each stored set
                                  only where it lowers the estimated error (noise + bias) */
    LBK_BAKE_DENOISE_OFF = 1,  /* the transport's estimate as it is */
    LBK_BAKE_DENOISE_ON = 2,   /* (1.6) the filter everywhere, whatever the estimate says */
    LBK_BAKE_DENOISE_COUNT_
} lbk_bake_denoise;

/* The bake's phases, in order; LBK_BAKE_PHASE_SETS only with light sets or doors. */
typedef enum lbk_bake_phase {
    LBK_BAKE_PHASE_IMPORT = 0, /* read the glTF or convert the description; check the scene */
    LBK_BAKE_PHASE_LAYOUT,     /* representation per object, atlas, texels, GLG and LLG probes */
    LBK_BAKE_PHASE_LIGHT,      /* light transport of the base bake, progressive passes */
    LBK_BAKE_PHASE_SETS,       /* one bake per light set and door state */
    LBK_BAKE_PHASE_WRITE,      /* encode the sections into the container */
    LBK_BAKE_PHASE_COUNT_
} lbk_bake_phase;

typedef struct lbk_bake_progress {
    lbk_bake_phase phase;
    double fraction;        /* of the current phase, in [0, 1]; a new phase starts at 0 */
    double elapsed_seconds; /* since the bake call started, wall clock */
    double est_rel_rmse;    /* the base bake's estimated relative RMSE after its latest pass;
                               < 0 before the first pass */
} lbk_bake_progress;

/* Called at every checkpoint (each phase start, each step of layout, each block of receivers
 * in a transport pass, each set bake). Return 0 to go on; non-zero cancels: the bake stops at
 * that checkpoint, frees everything and returns LBK_ERR_CANCELLED. */
typedef int (*lbk_bake_progress_fn)(void *user, const lbk_bake_progress *progress);

typedef enum lbk_bake_severity {
    LBK_BAKE_SEVERITY_INFO = 0,  /* the log of the bake: one line per transport pass and per
                                    set bake ("pass 2:  224 samples/receiver  est. error ...") */
    LBK_BAKE_SEVERITY_NOTE,      /* a decision worth knowing (no GLG and why, an atlas note) */
    LBK_BAKE_SEVERITY_WARNING,   /* the bake goes on but lost something: import warnings,
                                    saturated or flushed texels, an object without its LLG */
    LBK_BAKE_SEVERITY_ERROR      /* why the call fails (sent once, just before it returns) */
} lbk_bake_severity;

/* One line of text, no newline, no "lbk bake:" prefix; valid during the call only. */
typedef void (*lbk_bake_message_fn)(void *user, lbk_bake_severity severity, const char *message);

/* Texel densities, in texels per metre: lbk_bake_desc.texel_density, lbk_bake_object.texel_density,
 * the glTF extras key lbk_texel_density and `lbk bake --texel-density` all take a density above
 * LBK_BAKE_TEXEL_DENSITY_MIN (exclusive) up to LBK_BAKE_TEXEL_DENSITY_MAX; 0 in a desc or an
 * object means the default (spec/authoring.md: (0, 10000]). */
#define LBK_BAKE_TEXEL_DENSITY_MIN 0.0
#define LBK_BAKE_TEXEL_DENSITY_MAX 10000.0

/* Zero-initialised = defaults (given in brackets). */
typedef struct lbk_bake_desc {
    size_t size;                /* sizeof(lbk_bake_desc) as the caller compiled it; 0: the size
                                   of version 1 (this one), so `lbk_bake_desc d = {0};` is valid
                                   with every later library */
    lbk_bake_preset preset;     /* [fast] */
    int threads;                /* worker threads [0: one per online core] */
    uint64_t seed;              /* used as given, 0 included (`lbk bake` passes 1 unless --seed) */
    double target_error;        /* stop when the estimated relative RMSE reaches this; 0: preset;
                                   < 0: no target, every pass max_samples allows (a fixed schedule:
                                   what a distributed bake needs, lbk/bake_dist.h) */
    double time_limit;          /* seconds for the whole bake from the call, base + every light-set
                                   and door run: each run gets an equal share of what is left;
                                   every run completes at least one pass, and the guided door
                                   estimator and writing are not limited [0: none] */
    int max_samples;            /* gather samples per receiver, whole run [0: preset] */
    int max_bounces;            /* explicit bounces before the analytic tail [0: 64] */
    float texel_density;        /* texels per metre for every object, at most
                                   LBK_BAKE_TEXEL_DENSITY_MAX [0: the object's own
                                   (lbk_texel_density, lbk_bake_object.texel_density), then preset] */
    float glg_spacing;          /* global light grid spacing in metres [0: preset] */
    int sky_override;           /* 1: `sky` (or `sky_exr`) replaces the scene's sky */
    float sky[3];               /* uniform sky radiance, nits */
    const char *sky_exr;        /* with sky_override: an equirectangular EXR instead of `sky` */
    int no_glg;                 /* 1: leave out the global light grid */
    int octahedral_probes;      /* 1: also write OCTP, a probe volume in up to 3 clip levels
                                   (spec §14; octp_* below) */
    int no_seam_stitch;         /* 1: leave lightmap seams unstitched (for comparisons, bench_atlas) [0] */
    double dls_threshold;       /* light sets and doors store a receiver where their light exceeds
                                   this fraction of the mean indirect light of the texels they
                                   light directly [0: 0.01]; < 0: every non-zero receiver */
    lbk_bake_door_method door_method; /* [difference] */
    lbk_bake_denoise denoise;   /* [auto: lightmap texels and GLG probes denoised where that lowers
                                   the estimated error, both presets; bake/denoise/DENOISE.md] */
    const char *revision;       /* stored in META [NULL: none] */
    int timestamp;              /* 1: store the bake time in META (no longer byte-identical) */
    const char *allow_outside;  /* files a glTF names (buffers, images, its lbk_sky EXR) must lie in
                                   its folder (spec/authoring.md); this folder is allowed too [NULL] */
    lbk_bake_progress_fn progress; /* [NULL: none, no cancellation] */
    lbk_bake_message_fn message;   /* [NULL: messages are dropped] */
    void *user;                    /* passed to both callbacks */
    const lbk_allocator *allocator;/* the output, its report and the container bytes [malloc];
                                      the bake's working memory is the C heap */
    /* added in 1.1 of this library (fields past `size` read as 0) */
    int block_align;            /* 1: every chart starts and ends on a 4-texel boundary, so a 4×4
                                   block of a block-compressed pack (lbk convert, BC6H/ASTC) never
                                   holds two charts [0: packed tight] */
    /* added in 1.2 */
    const char *checkpoint_dir; /* after every pass of every transport run, its state into this
                                   folder (made if missing), atomically [NULL: none] */
    int resume;                 /* 1 with checkpoint_dir: runs with a checkpoint continue from
                                   their last finished pass (a killed bake ends byte-identical to
                                   an uninterrupted one; a finished bake given a lower
                                   target_error or a larger max_samples adds passes) [0: a fresh
                                   bake, checkpoints of an earlier one in the folder removed] */
    /* added in 1.3 */
    int light_culling;          /* stochastic light culling of punctual lights
                                   (bake/transport/SLC.md): 1 on, -1 off [0: auto, on with more
                                   than 32 positional lights in a run] */
    double light_culling_delta; /* culling's δ relative to the mean punctual irradiance at the
                                   receivers (smaller: more lights per receiver, less noise)
                                   [0: 0.1] */
    /* The files the bake must read, byte for byte (lbk_bake_inputs_from_file's list, e.g. from a
     * distributed bake's plan): a bake whose import reads other files, or one with other bytes,
     * fails with LBK_ERR_BAD_INPUT naming it, before any light is traced [NULL: no check] */
    const struct lbk_bake_input *expect_inputs;
    size_t expect_input_count;
    /* added in 1.4 */
    int glg_lighting;           /* 1: the global light grid's density follows the lighting: a
                                   coarse probe pass first, probes added where the lighting
                                   varies and a twice as coarse grid where it is smooth
                                   (bake/probes/PROBES.md) [0: placed by geometry and the
                                   scene's lbk_playable boxes only] */
    float glg_lighting_threshold; /* the relative interpolation error that asks for more probes
                                   [0: 0.4, measured by bench_glg] */
    /* added in 1.5 */
    int error_map;              /* 1: the container gets a TERR section (spec/container.md §18,
                                   format 1.4): per lightmap texel the estimated relative standard
                                   error of its irradiance, from the transport's two half
                                   estimates (before denoising, when denoised) [0: none; the
                                   file keeps the bytes it had without the field] */
    /* added in 1.6: the OCTP probe volume's clip levels (with octahedral_probes;
       bake/probes/PROBES.md §OCTP) */
    int octp_levels;            /* at most this many clip levels, 1 … 3; a level that holds the
                                   whole scene is the last [0: 3, so a level up to 32 spacings
                                   across gets one] */
    float octp_spacing;         /* the finest level's probe spacing in metres, each coarser level
                                   doubling it [0: min(GLG spacing, longest extent / 8)] */
    int octp_clip;              /* probes per axis of a clip level, 2 … 32 [0: 32, seed 003] */
    float gather_limit;         /* metres: the base run's final-gather rays from surfaces end here
                                   and read the global light grid (gathered first) where they hit
                                   nothing (bake/transport/TRANSPORT.md §Ray-length limit;
                                   light sets and doors gather in full) [0: off, measured not to
                                   pay] */
    int llg_connected;          /* 1: LLG objects whose bounding boxes touch another's end to end
                                   (pipes, rails, stacked props; neither box inside the other) get
                                   half the probe spacing (seed 001's extra probes for connected
                                   objects; bake/probes/PROBES.md) [0: off] */
    /* added in 1.7: glossy VPLs (seed 002; bake/transport/VPL.md "In the transport") */
    int glossy_vpl;             /* photons from point and spot lights make VPLs on glossy
                                   surfaces, gathered at the lightmap texels (glossy-to-diffuse
                                   caustics): 1 on, -1 off [0: auto, on where the lights put at
                                   least 5 % of their flux into glossy surfaces of roughness
                                   <= 0.3] */
    int glossy_vpl_photons;     /* photons per light and half in the first pass, doubling with
                                   every pass [0: 1024] */
    double glossy_vpl_delta;    /* the VPLs' culling δ relative to the mean irradiance they give
                                   the texels (smaller: more VPLs per texel, less noise) [0: 0.1] */
    /* added in 1.8 */
    int adaptive;               /* adaptive sampling (bake/transport/TRANSPORT.md §Adaptive
                                   sampling): blocks of 64 receivers whose own estimate reached
                                   the target stop sampling while the rest go on; -1 off [0: on;
                                   no effect without a target] */
    /* added in 1.10: levels of millions of texels and hundreds of thousands of probes */
    int max_page;               /* no lightmap page is wider or taller than this many texels,
                                   LBK_BAKE_MAX_PAGE_MIN … 16384, rounded down to a multiple of 4;
                                   a level needs as many pages as its objects fill; an object's
                                   charts share one page (spec/container.md §8), so an object
                                   larger than a page at its density gets a lower one (noted);
                                   a triangle larger than a page gets a chart of its own at the
                                   density that fits, never lowering its object's [0: 4096] */
    uint32_t max_probes;        /* the global light grid's probe cap, reached by coarsening its
                                   spacing (noted) [0: LBK_BAKE_MAX_PROBES_DEFAULT] */
    uint64_t texel_budget;      /* the lightmap's texels (Σ object rectangles) at most; more
                                   scales every density by one factor (noted) [0: 16 Mi] */
    int path_check;             /* texels of each lightmapped object traced by unbiased paths
                                   after the base run's passes, to measure what the stored texels
                                   carry beyond noise (bake/transport/TRANSPORT.md §Path check;
                                   lbk_bake_object_check) [0: 16]; -1 off */
} lbk_bake_desc;

#define LBK_BAKE_MAX_PAGE_MIN 64
#define LBK_BAKE_MAX_PAGE_MAX 16384
#define LBK_BAKE_MAX_PROBES_DEFAULT 262144u

/* A file a bake read (the glTF, its buffers and images, a sky EXR), as META input.files
 * records it (spec/container.md §6.2). */
typedef struct lbk_bake_input {
    char path[256];   /* relative to the scene file's folder; the scene file and a sky EXR by name */
    char role[8];     /* "scene", "buffer", "image", "sky" */
    uint64_t bytes;
    uint64_t xxh3;    /* XXH3-64 of its bytes */
} lbk_bake_input;

/* ---- in-memory scenes ----------------------------------------------------------------------
 * A scene as plain data, for callers that are not glTF-based (an editor, a test). World space,
 * metres, linear colour, y up as in glTF; the units of spec/authoring.md (emission in nits,
 * point and spot lights in candela, directional lights in lux). The description is read
 * during the call only; nothing is kept. Textures are not supported: colours are per material.
 *
 * The conversion follows the glTF importer rule for rule, so a description and a glTF file of
 * the same scene bake to the same sections (tests/install/bake_check.c): triangles without
 * normals are flat-shaded (each gets its own three vertices and its face normal); given normals
 * are normalised; base colours above 1 are clamped (with a warning). META differs: its
 * scene.hash is the XXH3-64 of the description's arrays (not of a file) and its scene.name is
 * lbk_bake_scene.name. A description also gets no LMUV section (spec §16): LMUV maps lightmap
 * UVs onto a glTF file's own nodes, primitives and vertices, which a description does not have. */

typedef enum lbk_bake_lighting {
    LBK_BAKE_LIGHTING_AUTO = 0, /* the baker's heuristic (bake/layout/classify.h) */
    LBK_BAKE_LIGHTING_LIGHTMAP, /* AHD lightmap texels */
    LBK_BAKE_LIGHTING_LLG,      /* a local light grid */
    LBK_BAKE_LIGHTING_NONE      /* not lit by the bake (it still casts shadows and bounces light) */
} lbk_bake_lighting;

typedef struct lbk_bake_material {
    const char *name;        /* [NULL: "material<i>"] */
    float base_color[3];     /* linear albedo, each in [0, 1] (above 1: clamped, warned) */
    float emission[3];       /* radiance in nits, >= 0 */
    int double_sided;
} lbk_bake_material;

/* An object: a named range of triangles with its options (the glTF node extras lbk_*). */
typedef struct lbk_bake_object {
    const char *name;            /* [NULL: "object<i>"]; up to 127 bytes */
    uint32_t first_triangle;     /* objects must tile the triangles in order: object i starts */
    uint32_t triangle_count;     /* where object i-1 ended, the last ends at triangle_count */
    uint32_t material;           /* for its triangles when lbk_bake_scene.triangle_materials is NULL */
    lbk_bake_lighting lighting;  /* lbk_lighting */
    float texel_density;         /* lbk_texel_density: texels per metre [0: the default] */
    const char *light_set;       /* lbk_light_set: its emission forms that set [NULL/"": none] */
    const char *door;            /* lbk_door: the object is that door, closed [NULL/"": none] */
} lbk_bake_object;

typedef enum lbk_bake_light_type {
    LBK_BAKE_LIGHT_POINT = 0,
    LBK_BAKE_LIGHT_SPOT,
    LBK_BAKE_LIGHT_DIRECTIONAL
} lbk_bake_light_type;

typedef struct lbk_bake_light {
    const char *name;            /* [NULL: "light<i>"] */
    lbk_bake_light_type type;
    float color[3];              /* colour × intensity: candela (point, spot) or lux (directional) */
    float position[3];           /* point, spot */
    float direction[3];          /* the direction light travels (spot, directional; normalised;
                                    zero for a spot or directional light: the light is skipped,
                                    with a warning, as the importer does) */
    float range;                 /* [0: infinite] */
    float inner_cone, outer_cone;/* spot: radians, 0 <= inner <= outer <= pi/2, outer > 0 */
    const char *light_set;       /* lbk_light_set [NULL/"": static, in the base bake] */
} lbk_bake_light;

typedef struct lbk_bake_scene {
    size_t size;                 /* as lbk_bake_desc.size: 0 = version 1 (this one) */
    const char *name;            /* META scene.name and the report's input [NULL: "scene"] */
    size_t vertex_count;
    const float *positions;      /* 3 per vertex, finite */
    const float *normals;        /* 3 per vertex, or NULL: flat shading */
    const float *uv1;            /* 2 per vertex: authored lightmap UVs (TEXCOORD_1), or NULL */
    size_t triangle_count;       /* at most 16 Mi */
    const uint32_t *indices;     /* 3 per triangle, counter-clockwise front faces */
    const uint32_t *triangle_materials; /* one per triangle, or NULL: each object's material */
    size_t material_count;
    const lbk_bake_material *materials; /* at least one */
    size_t object_count;         /* 0: one object named `name` holding every triangle */
    const lbk_bake_object *objects;
    size_t light_count;
    const lbk_bake_light *lights;
    float sky[3];                /* uniform sky radiance in nits (lbk_sky) [0: none] */
    size_t combination_count;    /* lbk_combinations: pairs of door / light set names */
    const char *const (*combinations)[2];
} lbk_bake_scene;

/* ---- baking ------------------------------------------------------------------------------ */

typedef struct lbk_bake_output lbk_bake_output;

/* Bakes a .gltf / .glb file (spec/authoring.md). desc may be NULL (defaults). */
LBK_BAKE_API lbk_result lbk_bake_from_file(const char *path, const lbk_bake_desc *desc, lbk_bake_output **out);
/* Bakes an in-memory scene description. desc may be NULL (defaults). */
LBK_BAKE_API lbk_result lbk_bake_from_scene(const lbk_bake_scene *scene, const lbk_bake_desc *desc,
                                            lbk_bake_output **out);
LBK_BAKE_API void lbk_bake_output_free(lbk_bake_output *out);

/* The container: its sections are in this writer (owned by the output). A caller may add
 * sections of its own before serialising it. */
LBK_BAKE_API lbk_writer *lbk_bake_output_writer(lbk_bake_output *out);
/* The container's bytes, allocated with desc->allocator; free them with lbk_free(allocator, *bytes). */
LBK_BAKE_API lbk_result lbk_bake_output_container(lbk_bake_output *out, void **bytes, size_t *size);
/* Writes the container atomically (a temporary file beside path, fsync, rename): on failure
 * nothing is left at path. Same bytes as lbk_bake_output_container. */
LBK_BAKE_API lbk_result lbk_bake_output_write_file(lbk_bake_output *out, const char *path);

/* ---- the report -------------------------------------------------------------------------- */

/* One progressive pass of the base bake (the samples of REPT and of the JSON report). */
typedef struct lbk_bake_pass {
    int pass;                    /* 0-based */
    double seconds;              /* since the transport started, wall clock */
    double samples_per_receiver; /* cumulative gather samples per texel/probe, both halves */
    double est_rel_rmse;         /* estimated relative RMSE after this pass */
    int bounces;                 /* explicit bounces before the analytic tail */
} lbk_bake_pass;

typedef struct lbk_bake_phase_time {
    lbk_bake_phase phase;
    double seconds;
} lbk_bake_phase_time;

/* Totals of the base bake's transport. */
typedef struct lbk_bake_transport {
    double seconds;
    int passes;
    uint64_t rays;               /* every ray traced */
    int bounces;                 /* explicit bounces of the last pass */
    double bounce_ratio_q;       /* per-bounce energy ratio used for the analytic tail */
    double tail_fraction;        /* share of the indirect energy from the tail */
    uint64_t cache_cells;
    uint64_t nonfinite_dropped;  /* NaN/Inf samples dropped (0 in every test) */
    uint64_t texel_channels_saturated; /* above R11G11B10F's largest value × the LMAP scale */
    uint64_t texel_channels_flushed;   /* lit but below its smallest step: stored 0 */
    double est_rel_rmse;         /* the final estimate */
} lbk_bake_transport;

/* The radiometric scale of each lighting section written (spec §5.7); 0: section absent. */
typedef struct lbk_bake_scales {
    float lmap, glg, llg, octp;
} lbk_bake_scales;

typedef struct lbk_bake_counts {
    uint64_t objects, texels, pages, glg_probes, llgs, llg_probes;
    uint32_t light_sets;         /* DLS sets, door states and combinations included */
    uint32_t doors;
    uint64_t file_bytes;         /* the container as baked */
} lbk_bake_counts;

/* Estimated relative RMSE per receiver class (0 for a class the bake has none of): lightmap
 * texels (irradiance), GLG and LLG probes (fluence), and both probe classes together. */
typedef struct lbk_bake_class_errors {
    double texels, glg, llg, probes;
} lbk_bake_class_errors;

/* The OCTP probe volume (--octahedral; 0 everywhere when none was written). */
typedef struct lbk_bake_octp {
    uint32_t probes, inside, no_nearby, relocated; /* all; inactive; marked; moved off the grid */
    double rel_rmse;     /* estimated relative RMSE of the irradiance texels (two halves) */
    double rays;         /* gather rays per probe (both halves, all passes) */
} lbk_bake_octp;

/* The estimate of what a denoised bake delivers (lbk_bake_report.denoised; all 0 when the bake
 * was not denoised): the noise the filter leaves (also the part correlated between receivers),
 * from each of the transport's two halves filtered by weights built from that half alone, and
 * the bias it adds, from the halves through the denoiser's own weights (bake/denoise/DENOISE.md
 * §What the report says). LLG probes are not filtered: errors.llg is the base estimate's. */
typedef struct lbk_bake_denoised {
    lbk_bake_class_errors errors;   /* √(noise² + bias²) per class, relative as REPT's */
    double texel_noise, texel_bias; /* the two parts of errors.texels */
    double glg_noise, glg_bias;     /* the two parts of errors.glg */
    double seconds;                 /* estimating it (one more pass of the filter) */
    /* (1.6) which classes are stored filtered: --denoise auto keeps the unfiltered result of a
     * class (then its error is the transport's, bias 0) where filtering would not lower it */
    int texels_filtered, glg_filtered;
} lbk_bake_denoised;

/* One transport run of the light sets and doors (a light set, a door open or closed, a
 * combination, the doors-closed reference), with its own final estimate. A door state's or a
 * combination's stored contribution is a difference of such runs: its error is larger. */
typedef struct lbk_bake_set_run {
    const char *label;           /* as in the bake's messages, e.g. "light set 'A'" */
    double est_rel_rmse;         /* over all its receivers */
    lbk_bake_class_errors classes;
    double seconds;
} lbk_bake_set_run;

/* A stored light set, door state or combination and the estimated error of its contribution
 * as stored (appended in 1.6; bake/sets/SETS.md, "Error of each stored set"): its two halves —
 * for a door state or combination, the same difference of the runs' halves as of their
 * results — through the base's denoising weights, or unfiltered. Relative to the RMS of the
 * contribution itself, so a door's difference, small where the door changes little, reads
 * large where the run estimates read small. The guided door estimator's open sets have none. */
typedef struct lbk_bake_set_estimate {
    const char *name;            /* the set's name in the DLS section */
    uint32_t set;                /* its index in the DLS section's set table */
    uint32_t kind;               /* lbk_dls_set_kind (lbk/dls.h) */
    int denoised;                /* 1: through the denoiser's weights (then bias may be > 0) */
    lbk_bake_denoised error;     /* as the base's denoised estimate; seconds: its share of the pass */
} lbk_bake_set_estimate;

/* A lightmapped object's estimated error as stored (appended in 1.9): the bake's texel estimate
 * (REPT's, the denoised one where the texels were denoised) taken over the object's texels
 * alone, relative to the RMS of their irradiance. The level's figure is dominated by its large
 * bright surfaces; a small or dark object's own error can be many times larger. Pooled over
 * all objects (weights value2) the noise parts give the level's figure. */
typedef struct lbk_bake_object_estimate {
    const char *name;            /* the scene object's name */
    uint32_t object;             /* scene object index (OBJS order) */
    uint32_t texels;             /* its texel receivers */
    double rel_rmse;             /* √(noise² + bias²) */
    double noise, bias;          /* bias: what the denoiser moved beyond noise (0 unfiltered) */
    double value2;               /* Σ of its texels' squared irradiance luminance (pooling weight) */
} lbk_bake_object_estimate;

/* A lightmapped object's error measured by the path check (appended in 1.10): a few of its
 * texels traced by unbiased paths (no cache, every hit continued at its exact point) and
 * compared with what is stored there. rel_rmse estimates the object's whole error — noise,
 * denoiser bias and what the cache gets wrong alike in both halves (light through a slab thinner
 * than a cell) — relative to the RMS of its irradiance, from the checked texels alone; low / high
 * are its value at ∓ one standard error of the checks' spread. The object's estimate
 * (lbk_bake_object_estimate.rel_rmse) is the larger of this and the noise estimate. */
typedef struct lbk_bake_object_check {
    uint32_t receivers;          /* texels checked (0: none; then the other fields are 0) */
    double rel_rmse, low, high;
} lbk_bake_object_check;

/* An LLG prop's estimated error (appended in 1.11): the LLG class estimate (errors.llg) taken
 * over one object — its probes' noise (the transport's two halves over the grid's probes,
 * relative to the RMS of their fluence/4) and the fit's residual at its vertex targets less
 * their noise (relative to their mean irradiance), each relative as the class's is. The class
 * figure pools the grids; a prop whose lattice cannot follow its lighting (2 cm dividers in a
 * 30 cm cubby) carries more of it than the others. */
typedef struct lbk_bake_llg_estimate {
    const char *name;            /* the scene object's name */
    uint32_t object;             /* scene object index (OBJS order) */
    uint32_t targets;            /* its vertex targets (0: none fitted; then fit is 0) */
    double rel_rmse;             /* √(noise² + fit²) */
    double noise, fit;
} lbk_bake_llg_estimate;

/* The path check over the level (appended in 1.10; zero when it did not run). */
typedef struct lbk_bake_check {
    uint32_t receivers;          /* texels checked, every object */
    uint32_t samples;            /* paths per checked texel */
    uint64_t rays;               /* rays the paths traced (not in the transport's totals) */
    double rel_rmse;             /* the objects' measured errors pooled as the texel estimate pools
                                    (each weighted by Σ E² of its texels) */
} lbk_bake_check;

/* What lbk_bake_report_write_json writes (spec/bake-report-json.md), as data. */
typedef struct lbk_bake_report {
    size_t size;                 /* sizeof(lbk_bake_report) of the library that filled it */
    const char *input;           /* the path baked, or the scene description's name */
    lbk_bake_preset preset;
    uint64_t seed;
    uint32_t status;             /* why the transport stopped: an lbk_bake_status (lbk/report.h) */
    double target_error;         /* the target used (the preset's when the desc left it 0) */
    double time_limit;
    const lbk_bake_pass *passes; /* one per pass, in order */
    size_t pass_count;
    lbk_bake_transport transport;
    lbk_bake_scales scales;
    lbk_bake_counts counts;
    const lbk_bake_phase_time *phases; /* the phases run, in order */
    size_t phase_count;
    double seconds;              /* the whole bake call */
    /* appended after the first version of this struct: read only when size covers them */
    lbk_bake_class_errors errors;        /* the base bake's final estimate per class */
    const lbk_bake_class_errors *pass_errors; /* per pass, parallel to passes */
    const lbk_bake_set_run *set_runs;    /* every light-set and door run, in order */
    size_t set_run_count;
    /* appended with the OCTP probe volume: read only when size covers them */
    lbk_bake_octp octp;
    /* appended in 1.5 (the denoised bake's own estimate): read only when size covers it */
    lbk_bake_denoised denoised;
    /* appended in 1.6: read only when size covers it */
    uint32_t octp_levels;        /* clip levels of the OCTP volume (0: none written) */
    /* appended in 1.6 (each stored set's estimate): read only when size covers them */
    const lbk_bake_set_estimate *set_estimates; /* in DLS set order; sets without one are left out */
    size_t set_estimate_count;
    /* appended in 1.9 (each lightmapped object's estimate): read only when size covers them */
    const lbk_bake_object_estimate *object_estimates; /* in scene object order */
    size_t object_estimate_count;
    /* appended in 1.10: memory */
    const uint64_t *phase_peak_rss; /* parallel to phases: the process's peak resident set size at
                                   the phase's end, bytes; a high-water mark since the process
                                   started (getrusage ru_maxrss), so it never falls and includes
                                   what the caller held before the bake; NULL: not measured */
    /* appended in 1.10 (the path check): read only when size covers them */
    const lbk_bake_object_check *object_checks; /* parallel to object_estimates; NULL: none */
    lbk_bake_check check;
    /* appended in 1.11 (each LLG prop's estimate): read only when size covers them */
    const lbk_bake_llg_estimate *llg_estimates; /* in scene object order */
    size_t llg_estimate_count;
} lbk_bake_report;

/* Owned by the output, valid until lbk_bake_output_free. */
LBK_BAKE_API const lbk_bake_report *lbk_bake_output_report(const lbk_bake_output *out);
/* The report as JSON text (schema lbk-bake-report/1), NUL-terminated, allocated with
 * `allocator` (NULL: malloc); free with lbk_free(allocator, *text). `container_path` is the
 * "output" field: where the caller wrote the container (NULL: ""). */
LBK_BAKE_API lbk_result lbk_bake_report_json(const lbk_bake_report *report, const char *container_path,
                                             const lbk_allocator *allocator, char **text, size_t *size);
/* The same text (plus a newline) into json_path. */
LBK_BAKE_API lbk_result lbk_bake_report_write_json(const lbk_bake_report *report, const char *container_path,
                                                   const char *json_path);

/* "import", "layout", "light", "sets", "write"; "unknown" otherwise. */
LBK_BAKE_API const char *lbk_bake_phase_name(lbk_bake_phase phase);
/* "fast", "high"; "unknown" otherwise. */
LBK_BAKE_API const char *lbk_bake_preset_name(lbk_bake_preset preset);

#ifdef __cplusplus
}
#endif
#endif
