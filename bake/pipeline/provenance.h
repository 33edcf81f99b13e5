/* Provenance: the META section of a bake (spec/container.md §6.2) — every option that can change
 * the bytes, every file the bake read with its hash, and per object, light and material the
 * inputs that made it, so `lbk diff` can say what changed between two bakes and why. */
#ifndef BK_PROVENANCE_H
#define BK_PROVENANCE_H

#include <stddef.h>

#include "bake/pipeline/pipeline.h"

/* Hashes a file the bake read outside import (the desc's sky EXR) and appends it to
 * scene->inputs under its base name. Returns 0, or -1 when it cannot be read or memory runs out. */
int bk_provenance_add_file(bk_scene *scene, const char *path, const char *role);

/* The META payload of this bake (lbk_meta_build's output; free with lbk_free(NULL, ·)). */
lbk_result bk_provenance_meta(const bk_pipeline *b, void **data, size_t *size);

#endif
