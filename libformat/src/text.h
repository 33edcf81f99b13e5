/* Private helpers for the string blobs of META and OBJS, and a sort with a context. */
#ifndef LBK_TEXT_H
#define LBK_TEXT_H

#include "internal.h"

/* Well-formed UTF-8 (no overlong forms, no surrogates, ≤ U+10FFFF) without any NUL byte. */
bool lbk_utf8_valid(const uint8_t *s, size_t n);

/* Bytewise order of two strings; a proper prefix sorts first. */
int lbk_bytes_cmp(const uint8_t *a, size_t an, const uint8_t *b, size_t bn);

/* Stable merge sort of `count` uint32 indices with a caller comparison. `scratch` holds count
 * entries. */
typedef int (*lbk_index_cmp)(void *ctx, uint32_t a, uint32_t b);
void lbk_sort_indices(uint32_t *idx, uint32_t *scratch, size_t count, lbk_index_cmp cmp, void *ctx);

#endif
