/* LMAP rewriting for convert. Waiting for the LMAP layout (lbk/lightmap.h) from the codec work:
 * until then the payload ships as baked and --from-exr is refused. */
#include "convert/lmap_layout.h"

#include <stdio.h>

#include "convert/convert.h"

int tl_lmap_rewrite(const void *lmap, size_t size, const tl_lmap_layout_options *options, void **out, size_t *out_size,
                    uint32_t *pages_imported, char err[TL_ERR_LEN])
{
    (void)lmap;
    (void)size;
    *out = NULL;
    *out_size = 0;
    *pages_imported = 0;
    if (options->from_exr_dir) {
        snprintf(err, TL_ERR_LEN, "--from-exr is not available yet in this build");
        return TL_CONVERT_UNSUPPORTED;
    }
    return TL_CONVERT_OK;
}
