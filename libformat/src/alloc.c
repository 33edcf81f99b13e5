/* All library memory goes through these, so a caller's allocator sees every byte. */
#include <stdlib.h>

#include "internal.h"

static int has_custom(const lbk_allocator *a) { return a && a->alloc && a->free; }

void *lbk_alloc(const lbk_allocator *a, size_t size)
{
    if (size == 0) size = 1; /* a valid pointer for empty arrays keeps callers simple */
    return has_custom(a) ? a->alloc(a->user, size) : malloc(size);
}

void *lbk_calloc(const lbk_allocator *a, size_t count, size_t size)
{
    if (size != 0 && count > SIZE_MAX / size) return NULL;
    size_t bytes = count * size;
    void *p = lbk_alloc(a, bytes);
    if (p && bytes) memset(p, 0, bytes);
    return p;
}

void lbk_dealloc(const lbk_allocator *a, void *p)
{
    if (!p) return;
    if (has_custom(a)) a->free(a->user, p);
    else free(p);
}

void lbk_free(const lbk_allocator *allocator, void *ptr) { lbk_dealloc(allocator, ptr); }
