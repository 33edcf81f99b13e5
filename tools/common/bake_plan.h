/* The plan of a distributed bake (bake/dist/DIST.md): a small JSON file naming the scene (path
 * and content hash), the bake options as `lbk bake` arguments, the output and the number of
 * units. Its hash stamps every part, so the merge refuses parts of another plan. */
#ifndef LBK_TOOLS_BAKE_PLAN_H
#define LBK_TOOLS_BAKE_PLAN_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */

#define TL_PLAN_MAX_OPTIONS 128

#define TL_PLAN_MAX_INPUTS 65536

/* A file the bake reads (lbk_bake_input): the plan's record of it, which units compare with
 * what their import read. */
typedef struct tl_plan_input {
    char path[256];
    char role[8];
    uint64_t bytes, xxh3;
} tl_plan_input;

typedef struct tl_plan {
    char *scene;                 /* absolute path */
    uint64_t scene_hash;         /* XXH64 of the scene file's bytes */
    size_t input_count;          /* every file the bake reads, in the order read */
    tl_plan_input *inputs;
    char *output;                /* the container the merge writes (as given) */
    uint32_t units;
    int option_count;
    char *options[TL_PLAN_MAX_OPTIONS]; /* `lbk bake` options that shape the bytes */
    uint64_t hash;               /* tl_plan_hash */
} tl_plan;

/* The plan's identity: the format, the scene's content hash, its files, the units and the
 * options. */
uint64_t tl_plan_hash(const tl_plan *p);
/* XXH64 of a file's bytes; 0 or -1 with err. */
int tl_file_hash(const char *path, uint64_t *hash, char err[TL_ERR_LEN]);
/* Writes the plan as JSON (atomically); reads and checks one (its stored hash must match). */
int tl_plan_write(const tl_plan *p, const char *path, char err[TL_ERR_LEN]);
int tl_plan_read(const char *path, tl_plan *p, char err[TL_ERR_LEN]);
void tl_plan_free(tl_plan *p);

#endif
