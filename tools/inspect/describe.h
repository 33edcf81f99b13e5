/* Per-section describers for `lbk inspect`: each reads one section's decoded bytes through its
 * view and fills the numbers the memory report needs. One function per section, in
 * describe_<section>.c, so each section's owner can refine its own. */
#ifndef LBK_INSPECT_DESCRIBE_H
#define LBK_INSPECT_DESCRIBE_H

#include <stddef.h>
#include <stdint.h>

typedef struct inspect_stats {
    int parsed;         /* the section's view accepted the bytes (0: only generic numbers) */
    uint64_t gpu_bytes; /* payload arrays a renderer uploads (spec/inspect-json.md); 0 for CPU-only */
    /* level statistics, summed over sections (zero where a section does not apply) */
    uint64_t lm_texels, lm_pages;
    uint64_t glg_probes, glg_tetrahedra;
    uint64_t llg_grids, llg_probes, llg_vertices;
    uint64_t octp_probes;
    uint64_t objects;
    uint64_t dls_light_sets, dls_sets, dls_clusters, dls_payload_bytes, dls_ancillary_bytes;
    uint64_t doors, door_states;
    /* TERR (format 1.4): texels, those with an estimate, the median and 90th percentile of the
     * relative error over those (0 without) */
    int terr_present, terr_denoised;
    uint64_t terr_texels, terr_estimated;
    double terr_median, terr_p90;
    char detail[200];   /* one line of section-specific numbers for the text report */
} inspect_stats;

typedef void (*inspect_describe_fn)(const uint8_t *data, size_t size, inspect_stats *out);

void inspect_describe_meta(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_rept(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_objs(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_lmap(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_glg(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_llg(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_octp(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_dls(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_door(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_lmuv(const uint8_t *data, size_t size, inspect_stats *out);
void inspect_describe_terr(const uint8_t *data, size_t size, inspect_stats *out);

/* log2 of a lighting section's scale (a power of two, spec/container.md §5.7). */
int inspect_scale_log2(float scale);

/* The describer of a section type; NULL for types this build does not know. */
inspect_describe_fn inspect_describer(uint32_t type);

#endif
