/* Small containers built from fixed content, shared by the container, corruption and golden
 * tests. Every byte is a function of the content below, so files built here are reproducible. */
#ifndef LBK_TEST_CONTAINER_FIXTURE_H
#define LBK_TEST_CONTAINER_FIXTURE_H

#include <stddef.h>
#include <stdint.h>

#include "lbk/container.h"

/* A valid container with META, REPT (zstd), OBJS and an unknown optional section 'XTRA':
 * 4 sections, only sections the container helper owns, so other validators cannot change its
 * verdict. alignment 0: default. Caller frees *out with free(). Returns 0 on success. */
int fixture_small_container(uint32_t alignment, void **out, size_t *size);

/* The fixed section payloads used above (builders' output), for golden comparisons. */
int fixture_meta(void **out, size_t *size);
int fixture_report(void **out, size_t *size);
int fixture_objects(void **out, size_t *size);
extern const uint8_t fixture_xtra[40];

/* After a test edits header or table fields: recompute table and header checksums. */
void fixture_fix_checksums(uint8_t *file);

#endif
