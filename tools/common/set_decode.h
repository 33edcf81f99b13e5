/* The texel luminance each stored DLS set holds (spec/container.md §12), as liblbk's apply
 * gives it: what bench_sets and the tests measure a set's stored contribution with. */
#ifndef LBK_TOOLS_SET_DECODE_H
#define LBK_TOOLS_SET_DECODE_H

#include <stddef.h>
#include <stdint.h>

typedef struct tl_set_texels {
    char name[64];
    uint32_t set, kind; /* index in the DLS set table; lbk_dls_set_kind */
    double *lum;        /* per LMAP texel: luminance of the irradiance along the normal (lux) */
} tl_set_texels;

/* Every stored set of the container in `bytes` (up to max_sets; combinations of more than two
 * members are skipped), decoded on a black base by a runtime without the DOOR view, so that
 * every set takes its weight from the set weights, door states too: a set alone at weight 1,
 * and a combination as out(members on) − out(each member alone) + out(none), its weight being
 * the product of its members'. Returns 0, or -1 (a section missing or unreadable, out of
 * memory); free with tl_set_texels_free. */
int tl_set_texels_decode(const void *bytes, size_t size, tl_set_texels *sets, int max_sets, int *nsets, uint64_t *ntex);
void tl_set_texels_free(tl_set_texels *sets, int nsets);

/* Luminance of one AHD texel's irradiance along its normal (lux). */
double tl_texel_lum(uint32_t irradiance_z, const uint8_t rgba[4]);

/* √(Σ (x − y)² / Σ y²) over n values: the relative RMS difference of two decoded sets; 0 when y is 0. */
double tl_rel_rms(const double *x, const double *y, uint64_t n);

#endif
