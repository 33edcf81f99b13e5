/* What the glTF import tests (tests/bake/test_import*.c) share: importing a scene of scenes/,
 * finding things in a bk_scene by name, a scratch directory per test binary run (the group
 * setup and teardown) with files written into it and imported from it, and the hand-made quad
 * glTF the tests splice JSON into. */
#ifndef LBK_TESTS_IMPORT_FIXTURES_H
#define LBK_TESTS_IMPORT_FIXTURES_H

#include <stddef.h>

#include "scene/import.h"
#include "scene/scene.h"

/* A scene of scenes/ (or $LBK_SCENES): a missing file fails the test, naming it. */
int imp_import_shared(const char *rel, bk_scene *s, bk_import_options *opt);
const bk_material *imp_find_material(const bk_scene *s, const char *name);
const bk_object *imp_find_object(const bk_scene *s, const char *name);
const bk_light *imp_find_light(const bk_scene *s, const char *name);
/* Emissive materials some triangle uses. */
size_t imp_emissive_materials_used(const bk_scene *s);
/* bk_scene_check passes (its message printed when not). */
void imp_assert_valid(const bk_scene *s);

/* The scratch directory (made by imp_setup_tmp, removed by imp_teardown_tmp: the group's
 * setup and teardown): the path of `name` in it, files written into it. */
void imp_tmp_path(char *out, size_t n, const char *name);
void imp_write_file(const char *name, const void *data, size_t len);
void imp_write_text(const char *name, const char *text);
/* Imports tmp/name; returns rc, error text in err. */
int imp_import_tmp(const char *name, bk_scene *s, const bk_import_options *opt, char *err, size_t n);
/* tmp/name fails to import with a message holding needle1 and needle2 (NULL: any) and the
 * file's name, and leaves the scene empty. */
void imp_expect_error(const char *name, const char *needle1, const char *needle2);
int imp_setup_tmp(void **state);
int imp_teardown_tmp(void **state);
/* tmp/name goes through the whole pipeline, as `lbk bake` (support/bake_file.h) at its smallest:
 * fast preset, seed 1, one thread, 8 samples, 4 texels per metre, no global light grid. Asserts
 * it succeeded (the baker's message when not) and wrote a non-empty tmp/out. */
void imp_bake_tmp(const char *name, const char *out);

/* quad.bin: 4 positions of a unit quad in the XY plane (z = 0), 6 uint16 indices, 4 +Z normals. */
void imp_write_quad_bin(void);
/* The same with the quad's four positions replaced (indices and normals kept). */
void imp_write_quad_bin_at(const float pos[12]);
/* A glTF over quad.bin: mesh 0 the quad (indexed, normals, material "grey"), mesh 1 its first
 * three positions (material "lamp", emissive); `nodes`, `scene_nodes` and `top` spliced in as
 * JSON text. */
void imp_write_quad_gltf(const char *name, const char *nodes, const char *scene_nodes, const char *top);
/* The quad alone (no normals, no material) with the scene's extras `scene_extras`. */
void imp_write_quad_gltf_scene_extras(const char *name, const char *nodes, const char *scene_nodes,
                                      const char *scene_extras);

#endif
