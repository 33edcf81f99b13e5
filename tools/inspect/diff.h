/* Comparing the lighting of two bakes (lbk diff). The metric, matching rules and JSON schema
 * are documented in spec/diff-json.md; cmd_diff.c is the command line around this. */
#ifndef LBK_TOOLS_DIFF_H
#define LBK_TOOLS_DIFF_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "tools/common/bake_data.h"
#include "tools/inspect/diff_noise.h"

#define TL_DIFF_SCHEMA_VERSION 3

typedef enum tl_diff_status {
    TL_DIFF_SAME = 0,    /* present in both, equal within tolerance */
    TL_DIFF_CHANGED = 1, /* present in both, differs */
    TL_DIFF_ADDED = 2,   /* only in B */
    TL_DIFF_REMOVED = 3  /* only in A */
} tl_diff_status;
const char *tl_diff_status_name(int status); /* "same", "changed", "added", "removed" */

/* Error statistics of one comparison (texels of an object or page, probes of a grid, entries of a
 * light set). A sample is a texel or probe; its error is the largest absolute difference of the
 * decoded irradiance over the channels and the sample normals; it is over the tolerance when
 * error > abs_tol + rel_tol × (largest |A value| over the same channels and normals). */
typedef struct tl_err_stats {
    uint64_t count;        /* samples compared */
    uint64_t over;         /* samples over the tolerance */
    double max_abs;        /* largest sample error */
    double sum_abs;        /* Σ sample error (mean = sum_abs / count) */
    double sum_sq_diff;    /* Σ over samples, channels and normals of (B − A)² */
    double sum_sq_ref;     /* Σ of A² over the same */
    uint32_t max_x, max_y; /* where max_abs is (texel coordinates, or probe index in max_x) */
    int has_region;        /* over > 0: bounding box of the samples over tolerance */
    uint32_t x0, y0, x1, y1; /* inclusive */
} tl_err_stats;

double tl_err_mean(const tl_err_stats *s);
/* One sample of `values` numbers (A and B): its error is the largest |B − A|; over the tolerance
 * when error > abs_tol + rel_tol × max |A|; NaN in B counts as over. Returns 1 when over. */
int tl_err_add(tl_err_stats *s, const float *a, const float *b, size_t values, double abs_tol, double rel_tol,
               uint32_t x, uint32_t y, float *err_out);
/* sqrt(sum_sq_diff / sum_sq_ref); 0 when both are 0; +Inf when only A is all zero. */
double tl_err_rel_rmse(const tl_err_stats *s);

/* How lighting differences become a verdict. */
typedef enum tl_diff_mode {
    TL_DIFF_MODE_TOLERANCE = 0, /* a sample differs when its error exceeds abs_tol + rel_tol × ref
                                   (exact with both 0) */
    TL_DIFF_MODE_NOISE = 1,     /* an item differs when its change exceeds the noise of the two bakes
                                   (diff_noise.h); needs REPT in both, else tolerance */
    TL_DIFF_MODE_AUTO = 2       /* noise when both bakes carry REPT, else tolerance (lbk diff's default) */
} tl_diff_mode;
const char *tl_diff_mode_name(int mode); /* "tolerance", "noise" */

typedef struct tl_diff_options {
    double abs_tol; /* ≥ 0; default 0 */
    double rel_tol; /* ≥ 0; default 0 */
    int keep_error_maps; /* keep per-page error images for heatmaps */
    int mode;            /* tl_diff_mode */
    double false_alarm;  /* noise mode: α per item; 0: TL_NOISE_DEFAULT_FALSE_ALARM */
} tl_diff_options;

typedef struct tl_diff_section {
    uint32_t type;
    int status;             /* same: identical decoded bytes; changed: bytes differ (informational) */
    uint64_t a_decoded, b_decoded;
} tl_diff_section;

typedef struct tl_diff_param {
    char key[LBK_META_MAX_KEY + 1];
    char *a, *b; /* NULL when absent on that side */
    int status;
} tl_diff_param;

typedef struct tl_diff_object {
    char name[128];          /* A's name (B's when added) */
    char name_b[128];        /* B's name when renamed, else "" */
    int status;
    int renamed, geometry_changed, representation_changed, rect_changed;
    uint64_t hash_a, hash_b;
    uint32_t repr_a, repr_b; /* lbk_representation; LBK_REPRESENTATION_COUNT_ when absent */
    uint32_t page_a, page_b; /* lightmap page / LLG grid index */
    uint32_t rect_a[4], rect_b[4]; /* x, y, w, h */
    int compared;            /* lighting was compared */
    int resampled;           /* B sampled at A's texel centres / probe positions (sizes differ) */
    tl_err_stats lighting;   /* texels (rect-local x, y) or LLG probes (index) */
    tl_noise_stats noise;    /* noise mode */
    int inputs_changed;      /* TL_INPUT_* bits from META scene.objects (provenance) */
    uint32_t index_a, index_b; /* OBJS record indices (of the sides present) */
} tl_diff_object;

/* What META says changed in an object's inputs. */
enum { TL_INPUT_GEOMETRY = 1, TL_INPUT_MATERIAL = 2, TL_INPUT_OPTIONS = 4 };

/* One difference of the inputs or options (META provenance, spec/container.md §6.2). */
typedef enum tl_change_kind {
    TL_CHANGE_OPTION = 0,   /* a bake.* option, or the writer */
    TL_CHANGE_FILE,         /* a file of input.files (by path) */
    TL_CHANGE_LIGHT,        /* a line of scene.lights (by name) */
    TL_CHANGE_MATERIAL,     /* a line of scene.materials (by name) */
    TL_CHANGE_OBJECT        /* an object's line of scene.objects */
} tl_change_kind;
const char *tl_change_kind_name(int kind); /* "option", "file", "light", "material", "object" */

typedef struct tl_diff_change {
    int kind;               /* tl_change_kind */
    int status;             /* changed, added, removed */
    char name[160];         /* option key, file path, light/material/object name */
    char *a, *b;            /* the values (a field list for lights/materials, a hash for files); NULL if absent */
    char *what;             /* one line: "sky 1,1,1 -> 1.2,1.2,1.2", "object Wall_03 material changed" */
} tl_diff_change;

typedef struct tl_diff_page {
    uint32_t index;
    int status;
    uint32_t wa, ha, wb, hb;
    int resized;              /* compared over the common region */
    tl_err_stats lighting;    /* page texel coordinates */
    float *error_map;         /* wa × ha sample errors (NaN: not compared), when keep_error_maps */
    uint8_t *over_map;        /* wa × ha: 1 where over tolerance */
} tl_diff_page;

typedef struct tl_diff_probes {
    int status;               /* of the GLG as a whole; same/changed/added/removed; -1 when in neither */
    uint32_t count_a, count_b;
    int resampled;            /* B sampled at A's probe positions (layouts differ) */
    tl_err_stats lighting;
    tl_noise_stats noise;
} tl_diff_probes;

/* The OCTP octahedral probes (spec/container.md §14), compared probe by probe when both have the
 * same layout: the same form, levels (origin, spacing, dims) or, for the list form, the same
 * probe positions. Irradiance: a sample is a probe, its values the 4×4 interior texels × RGB
 * (physical; the border only repeats them); depth: the 12×12 interior texels × (mean, mean²), in
 * metres, as stored. */
typedef struct tl_diff_octp {
    int status;               /* same/changed/added/removed; -1 when in neither */
    uint32_t count_a, count_b;
    uint32_t levels_a, levels_b; /* 0: list form */
    int comparable;           /* same layout: the probes were compared */
    uint32_t moved;           /* comparable volume: probes whose relocation offset differs */
    tl_err_stats lighting;    /* irradiance, decides with the tolerance or the noise */
    tl_err_stats depth;       /* depth moments; decides in tolerance mode only (no noise estimate) */
    tl_noise_stats noise;
    uint32_t states_a[3], states_b[3]; /* volume form: probes per LBK_OCTP_ACTIVE, _INSIDE, _NO_NEARBY */
    uint32_t state_changes;   /* comparable: probes whose state differs; decides in tolerance mode */
} tl_diff_octp;

typedef struct tl_diff_set {
    char name[128];
    int status;
    int meta_changed;                          /* kind, lights or members differ */
    int compared[LBK_DLS_SPACE_COUNT_];        /* 0: space absent on both sides or not comparable */
    int not_comparable[LBK_DLS_SPACE_COUNT_];  /* target spaces differ between A and B (layout changed) */
    tl_err_stats lighting[LBK_DLS_SPACE_COUNT_];
    tl_noise_stats noise[LBK_DLS_SPACE_COUNT_];
} tl_diff_set;

typedef struct tl_diff_door {
    char name[128];
    int status;
} tl_diff_door;

typedef struct tl_diff_result {
    double abs_tol, rel_tol;
    int mode;                 /* the mode used: tolerance or noise */
    const char *mode_reason;  /* why (auto mode): "both bakes carry REPT", "… has no REPT" */
    tl_noise_model noise;     /* noise mode */
    tl_diff_change *changes; size_t change_count; /* inputs and options that changed */
    tl_diff_section *sections; size_t section_count;
    tl_diff_param *params; size_t param_count;
    tl_diff_object *objects; size_t object_count;
    tl_diff_page *pages; size_t page_count;
    tl_diff_probes glg;
    tl_diff_octp octp;
    tl_diff_set *sets; size_t set_count;
    tl_diff_door *doors; size_t door_count;
    /* summary */
    uint32_t objects_added, objects_removed, objects_changed;
    uint32_t pages_changed, sets_changed, doors_changed, sections_changed, params_changed;
    uint64_t texels_over, probes_over;
    uint32_t items_beyond_noise; /* noise mode: objects, the GLG, OCTP and light-set spaces whose change exceeds the noise */
    int differ; /* the exit-code decision: lighting or structure differs (not META/REPT alone) */
} tl_diff_result;

/* The inputs and options that differ (META provenance) into result->changes, and each matched
 * object's inputs_changed (diff_provenance.c). Returns 0, or -1 when out of memory. */
int tl_diff_provenance(const tl_bake *a, const tl_bake *b, tl_diff_result *result);

/* OCTP part of tl_diff_run (diff_octp.c): fills result->octp, adds to probes_over and items_beyond_noise. */
void tl_diff_octp_run(const tl_bake *a, const tl_bake *b, double abs_tol, double rel_tol, const tl_noise_model *noise,
                      tl_diff_result *result);

/* Light-set part of tl_diff_run (diff_sets.c): each light set, door state and combination per
 * target space into result->sets, adds to texels_over, probes_over, items_beyond_noise and
 * sets_changed (noise NULL: tolerance mode). Returns 0, or -1 when out of memory. */
int tl_diff_sets_run(const tl_bake *a, const tl_bake *b, double abs_tol, double rel_tol, const tl_noise_model *noise,
                     tl_diff_result *result);
/* Door part of tl_diff_run (diff_sets.c): each door's placement and sets into result->doors.
 * Returns 0, or -1 when out of memory. */
int tl_diff_doors_run(const tl_bake *a, const tl_bake *b, tl_diff_result *result);
/* Both GLGs have the same probes at the same positions, so they line up by index. */
int tl_diff_glg_same_layout(const tl_bake *a, const tl_bake *b);

/* Compares two opened bakes. Returns 0, or -1 (out of memory; err says so). */
int tl_diff_run(const tl_bake *a, const tl_bake *b, const tl_diff_options *options, tl_diff_result *out,
                char err[TL_ERR_LEN]);
void tl_diff_free(tl_diff_result *result);

/* JSON text (schema spec/diff-json.md), malloc'ed. */
char *tl_diff_json(const tl_diff_result *result, const char *path_a, const char *path_b);
/* Human-readable report. */
void tl_diff_print(FILE *f, const tl_diff_result *result, int verbose);
/* Writes DIR/page_NNN.diff.png per page that was compared (needs keep_error_maps). */
int tl_diff_heatmaps(const tl_diff_result *result, const char *dir, char err[TL_ERR_LEN]);

#endif
