/* Weak placeholders for section validators that have not landed yet; the real one in the
 * section's own file overrides it. Each owner deletes its line here when its validator lands. */
#include "internal.h"

#define LBK_WEAK_VALIDATOR(name) \
    __attribute__((weak)) void name(lbk_vctx *ctx, const uint8_t *data, size_t size) { (void)ctx; (void)data; (void)size; }

