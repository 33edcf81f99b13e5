/* Built by `make test` against an installed copy of liblbk (pkg-config, headers from
 * include/lbk/), once with liblbk.so and once with liblbk.a: proves that the install is usable
 * by an engine on its own — the headers are self-contained, the exported symbols are there and
 * the pkg-config flags link. Reads the committed golden container. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <lbk/container.h>
#include <lbk/lightmap_uv.h>
#include <lbk/meta.h>
#include <lbk/objects.h>
#include <lbk/validate.h>

static void test_golden_opens_and_validates(void **state)
{
    (void)state;
    lbk_validate_summary s;
    assert_int_equal(lbk_validate_file("tests/golden/small.lbk", NULL, NULL, NULL, &s), LBK_OK);
    assert_int_equal(s.fatal + s.errors, 0);
    /* the installed library is the one the installed headers describe */
    assert_int_equal(lbk_version_number(), LBK_LIBRARY_VERSION_NUMBER);
    assert_string_equal(lbk_version_string(), LBK_LIBRARY_VERSION_STRING);
    lbk_reader *r;
    const lbk_read_options ro = LBK_READ_OPTIONS_INIT;
    assert_int_equal(lbk_reader_open_file("tests/golden/small.lbk", &ro, &r), LBK_OK);
    assert_true(lbk_reader_section_count(r) >= 1);
    assert_int_equal(lbk_reader_header(r)->version_major, LBK_FORMAT_VERSION_MAJOR);
    const void *data;
    size_t size;
    assert_int_equal(lbk_reader_section_by_type(r, LBK_SECTION_META, &data, &size), LBK_OK);
    lbk_meta_view v;
    assert_int_equal(lbk_meta_open(data, size, &v), LBK_OK);
    assert_true(v.entry_count > 0);
    lbk_reader_close(r);
    assert_string_equal(lbk_result_name(LBK_ERR_CHECKSUM), "LBK_ERR_CHECKSUM");
}

/* The checks of a container against the caller's glTF (liblbk 1.5) are exported: one record of
 * one triangle, checked against its mesh and against a mesh with another corner; one object's
 * geometry hash against its triangle and another. */
static void test_gltf_checks_are_exported(void **state)
{
    (void)state;
    static const uint32_t remap[3] = {0, 1, 2}, idx[3] = {0, 1, 2};
    static const float xy[6] = {1, 1, 2, 1, 1, 2};
    const lbk_lmuv_primitive_desc pd = {.source_primitive = 0, .source_vertex_count = 3, .vertex_count = 3,
                                        .index_count = 3, .remap = remap, .indices = idx, .coords = xy};
    const lbk_lmuv_object_desc od = {.object = 0, .kind = LBK_LMUV_GENERATED, .source_node = 2, .primitive_count = 1,
                                     .primitives = &pd};
    void *bytes;
    size_t size;
    assert_int_equal(lbk_lmuv_build(&od, 1, NULL, &bytes, &size), LBK_OK);
    lbk_lmuv_view v;
    lbk_lmuv_object rec;
    assert_int_equal(lbk_lmuv_open(bytes, size, &v), LBK_OK);
    assert_int_equal(lbk_lmuv_get_object(&v, 0, &rec), LBK_OK);
    uint32_t corners[3] = {0, 1, 2};
    const lbk_lmuv_mesh_primitive mp = {.source_vertex_count = 3, .triangle_count = 1, .corners = corners};
    lbk_lmuv_mesh_desc mesh = LBK_LMUV_MESH_DESC_INIT;
    mesh.source_node = 2;
    mesh.primitive_count = 1;
    mesh.primitives = &mp;
    lbk_lmuv_check_detail d;
    assert_int_equal(lbk_lmuv_object_check(&v, &rec, &mesh, &d), LBK_OK);
    corners[2] = 1;
    assert_int_equal(lbk_lmuv_object_check(&v, &rec, &mesh, &d), LBK_ERR_MISMATCH);
    assert_string_equal(lbk_lmuv_check_code_name(d.code), "LBK_LMUV_CHECK_CORNER");
    lbk_free(NULL, bytes);
    static const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, other[9] = {0, 0, 0, 1, 0, 0, 0, 2, 0};
    const lbk_object ob = {.name = {"a", 1}, .geometry_hash = lbk_objects_geometry_hash(tri, 1),
                           .representation = LBK_REPRESENTATION_NONE};
    assert_int_equal(lbk_objects_build(&ob, 1, NULL, &bytes, &size), LBK_OK);
    lbk_objects_view ov;
    assert_int_equal(lbk_objects_open(bytes, size, &ov), LBK_OK);
    assert_int_equal(lbk_objects_geometry_check(&ov, 0, tri, 1), LBK_OK);
    assert_int_equal(lbk_objects_geometry_check(&ov, 0, other, 1), LBK_ERR_MISMATCH);
    lbk_free(NULL, bytes);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_golden_opens_and_validates),
                                       cmocka_unit_test(test_gltf_checks_are_exported)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
