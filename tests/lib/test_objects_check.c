/* lbk_objects_geometry_check (lbk/objects.h, spec/container.md §8.3): an OBJS object against the
 * triangles a reader loaded. OBJS built here with the geometry hashes of two known meshes (a
 * triangle and an empty object): the meshes pass, -0 for +0 passes (the hash writes -0 as +0),
 * one changed coordinate, a triangle left out or another object's triangles are LBK_ERR_MISMATCH,
 * an index past the table LBK_ERR_NOT_FOUND, NULLs and a triangle count no memory holds
 * LBK_ERR_INVALID_ARGUMENT (refused before any read: ASan would see one). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "lbk/objects.h"

static const float tri2[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};

static void geometry_check(void **state)
{
    (void)state;
    const lbk_object objs[2] = {
        {.name = {"floor", 5}, .geometry_hash = lbk_objects_geometry_hash(tri2, 2),
         .representation = LBK_REPRESENTATION_LLG, .index = 0},
        {.name = {"empty", 5}, .geometry_hash = lbk_objects_geometry_hash(NULL, 0),
         .representation = LBK_REPRESENTATION_NONE}};
    void *bytes;
    size_t size;
    assert_int_equal(lbk_objects_build(objs, 2, NULL, &bytes, &size), LBK_OK);
    lbk_objects_view v;
    assert_int_equal(lbk_objects_open(bytes, size, &v), LBK_OK);
    assert_int_equal(lbk_objects_geometry_check(&v, 0, tri2, 2), LBK_OK);
    assert_int_equal(lbk_objects_geometry_check(&v, 1, NULL, 0), LBK_OK);
    float xyz[18];
    memcpy(xyz, tri2, sizeof xyz);
    xyz[0] = -0.0f;
    assert_int_equal(lbk_objects_geometry_check(&v, 0, xyz, 2), LBK_OK);
    xyz[4] = 0x1p-24f; /* one coordinate moved by 2^-24 */
    assert_int_equal(lbk_objects_geometry_check(&v, 0, xyz, 2), LBK_ERR_MISMATCH);
    assert_int_equal(lbk_objects_geometry_check(&v, 0, tri2, 1), LBK_ERR_MISMATCH);  /* a triangle left out */
    assert_int_equal(lbk_objects_geometry_check(&v, 1, tri2, 2), LBK_ERR_MISMATCH);  /* another object's */
    assert_int_equal(lbk_objects_geometry_check(&v, 2, tri2, 2), LBK_ERR_NOT_FOUND);
    assert_int_equal(lbk_objects_geometry_check(&v, UINT32_MAX, tri2, 2), LBK_ERR_NOT_FOUND);
    assert_int_equal(lbk_objects_geometry_check(NULL, 0, tri2, 2), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_objects_geometry_check(&v, 0, NULL, 2), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_objects_geometry_check(&v, 0, tri2, SIZE_MAX), LBK_ERR_INVALID_ARGUMENT);
    assert_int_equal(lbk_objects_geometry_check(&v, 0, tri2, SIZE_MAX / 36 + 1), LBK_ERR_INVALID_ARGUMENT);
    lbk_free(NULL, bytes);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(geometry_check)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
