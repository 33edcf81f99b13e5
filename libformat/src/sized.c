/* Size-tagged structs (the rule in lbk.h): a caller compiled against any liblbk release hands
 * in its own layout, and the library reads it as the current one. */
#include "internal.h"

lbk_result lbk_sized_in(void *dst, size_t dst_size, const void *src, size_t v1_size)
{
    memset(dst, 0, dst_size);
    if (!src) return LBK_OK; /* NULL options: every field at its default */
    size_t size;
    memcpy(&size, src, sizeof size);
    if (size == 0) size = v1_size; /* zero-initialised by a caller that did not set size */
    if (size < v1_size) return LBK_ERR_INVALID_ARGUMENT;
    /* A newer caller's fields that this library does not know must be unused (zero). */
    for (size_t i = dst_size; i < size; i++)
        if (((const uint8_t *)src)[i] != 0) return LBK_ERR_UNSUPPORTED_FEATURE;
    memcpy(dst, src, size < dst_size ? size : dst_size);
    memcpy(dst, &dst_size, sizeof dst_size); /* the copy is of the current layout */
    return LBK_OK;
}
