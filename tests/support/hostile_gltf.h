/* The hostile-glTF campaign (issue 39): a generator that writes each hostile scene into a
 * folder, with what its import must say. tests/bake/test_import_limits.c imports every case
 * through bk_import_gltf and checks the message; tests/tools/test_hostile_cli.c runs `lbk bake`
 * (the ASan build in make test) on every case and wants exit 4 (LBK_EXIT_INPUT), no crash and
 * no sanitizer report. Case 0, "baseline", is the template every other case breaks: it must
 * import (and bake), so a broken template cannot pass as a refusal. */
#ifndef LBK_TESTS_HOSTILE_GLTF_H
#define LBK_TESTS_HOSTILE_GLTF_H

#include <stddef.h>

typedef struct hg_case {
    const char *name;   /* the scene is written as <name>.gltf (or .glb) */
    const char *needle; /* what the import error must hold; NULL for the baseline (it imports) */
    int (*write)(const char *dir, const char *name, char *path, size_t n);
} hg_case;

/* The cases, case 0 the baseline. */
const hg_case *hg_cases(size_t *count);

/* Writes case c into dir (its buffers, images, FIFOs, links too); its scene's path into path.
 * Returns 0, or -1 when a file cannot be made (the case is then skipped: a missing input, say). */
int hg_write(const char *dir, const hg_case *c, char *path, size_t n);

/* `count` nodes into dir/name: empty nodes `{}` (chain 0), or a chain, each node the only child
 * of the one before it (chain 1); the quad mesh on node 0. Returns the JSON's size, 0 on error. */
size_t hg_write_nodes(const char *dir, const char *name, size_t count, int chain);

#endif
