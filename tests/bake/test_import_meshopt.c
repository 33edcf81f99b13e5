/* EXT_meshopt_compression as gltfpack and glTF-Transform write it: a 5 x 5 grid (25 vertices,
 * 32 triangles) encoded here with meshoptimizer's own encoders (positions as float3 attributes,
 * normals through the OCTAHEDRAL filter at 8 bits, indices as TRIANGLES or INDICES streams) imports
 * to the same grid stored plainly: positions bit for bit (through the EXPONENTIAL filter: within
 * its mantissa), the vertices in the same order, the triangles in the same order (a TRIANGLES
 * stream may rotate a triangle's corners), normals within the octahedral filter's precision. With
 * the extension required and no fallback buffer; only used with a fallback buffer that has no uri
 * (.gltf and .glb, gltfpack's output); with a fallback holding other bytes (the compressed view
 * wins). Before the extension was decoded, the required case was refused. Truncated or swapped
 * streams, impossible counts, ranges outside the buffer, strides a filter cannot have and unknown
 * modes are refused naming the bufferView. The compressed grid bakes through lbk_bake_from_file. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


#include <meshoptimizer.h>

#include "scene/import.h"
#include "scene/scene.h"
#include "support/import_fixtures.h"

enum { GN = 5, NV = GN * GN, NT = (GN - 1) * (GN - 1) * 2, NI = NT * 3 };

static float g_pos[NV * 3], g_nrm[NV * 4];
static unsigned int g_idx[NI];

/* The grid: heights and normals vary per vertex so that every byte lane of the streams moves. */
static void make_grid(void)
{
    for (int j = 0; j < GN; j++)
        for (int i = 0; i < GN; i++) {
            int v = j * GN + i;
            g_pos[v * 3 + 0] = 0.5f * (float)i;
            g_pos[v * 3 + 1] = 0.1f * (float)((i * j) % 3) + 0.013f * (float)v;
            g_pos[v * 3 + 2] = -0.5f * (float)j;
            double n[3] = {0.4 * sin(0.7 * v), 1.0, 0.4 * cos(1.3 * v)};
            double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int c = 0; c < 3; c++) g_nrm[v * 4 + c] = (float)(n[c] / l);
            g_nrm[v * 4 + 3] = 0.0f;
        }
    int k = 0;
    for (int j = 0; j + 1 < GN; j++)
        for (int i = 0; i + 1 < GN; i++) {
            unsigned a = (unsigned)(j * GN + i), b = a + 1, c = a + GN, d = c + 1;
            unsigned t[6] = {a, c, b, b, c, d};
            for (int q = 0; q < 6; q++) g_idx[k++] = t[q];
        }
}

/* The compressed streams, each 4-byte aligned in one buffer. */
typedef struct {
    unsigned char bytes[4096];
    size_t len;
    size_t off[3], size[3]; /* positions, normals, indices */
    int exp_pos;            /* positions through the EXPONENTIAL filter (16-bit mantissas) */
} streams;

static void put(streams *s, int k, const unsigned char *data, size_t n)
{
    s->off[k] = s->len;
    s->size[k] = n;
    assert_true(s->len + n + 4 <= sizeof s->bytes);
    memcpy(s->bytes + s->len, data, n);
    s->len += (n + 3) & ~(size_t)3;
}

/* sequence = 0: the indices as a TRIANGLES stream of uint16, 1: an INDICES stream of uint32.
 * exp_pos: the positions through the EXPONENTIAL filter, as gltfpack -vpf writes them. */
static void encode(streams *s, int sequence, int exp_pos)
{
    unsigned char tmp[2048];
    memset(s, 0, sizeof *s);
    s->exp_pos = exp_pos;
    uint32_t pos[NV * 3];
    if (exp_pos) meshopt_encodeFilterExp(pos, NV, 12, 16, g_pos);
    else memcpy(pos, g_pos, sizeof pos);
    size_t n = meshopt_encodeVertexBuffer(tmp, sizeof tmp, pos, NV, 12);
    assert_true(n > 0);
    put(s, 0, tmp, n);
    signed char oct[NV * 4];
    meshopt_encodeFilterOct(oct, NV, 4, 8, g_nrm);
    n = meshopt_encodeVertexBuffer(tmp, sizeof tmp, oct, NV, 4);
    assert_true(n > 0);
    put(s, 1, tmp, n);
    n = sequence ? meshopt_encodeIndexSequence(tmp, sizeof tmp, g_idx, NI)
                 : meshopt_encodeIndexBuffer(tmp, sizeof tmp, g_idx, NI);
    assert_true(n > 0);
    put(s, 2, tmp, n);
}

/* plain.bin: float positions, float normals, uint16 indices, as any exporter writes them. */
static void write_plain(void)
{
    unsigned char buf[NV * 12 * 2 + NI * 2];
    for (int v = 0; v < NV; v++) memcpy(buf + NV * 12 + v * 12, g_nrm + v * 4, 12);
    memcpy(buf, g_pos, NV * 12);
    for (int i = 0; i < NI; i++) {
        uint16_t x = (uint16_t)g_idx[i];
        memcpy(buf + NV * 24 + i * 2, &x, 2);
    }
    imp_write_file("plain.bin", buf, sizeof buf);
}

static const char *kPlainGltf =
    "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"plain.bin\",\"byteLength\":792}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":300},{\"buffer\":0,\"byteOffset\":300,"
    "\"byteLength\":300},{\"buffer\":0,\"byteOffset\":600,\"byteLength\":192}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":25,\"type\":\"VEC3\"},"
    "{\"bufferView\":1,\"componentType\":5126,\"count\":25,\"type\":\"VEC3\"},"
    "{\"bufferView\":2,\"componentType\":5123,\"count\":96,\"type\":\"SCALAR\"}],"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2}]}],"
    "\"nodes\":[{\"name\":\"grid\",\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}";

/* The compressed glTF's JSON. buffer 0 holds the streams (uri `bin`, or the GLB's BIN chunk when
 * NULL); buffer 1 is the fallback, 792 bytes laid out as plain.bin (`fallback_uri`, or none).
 * `required`: the extension in extensionsRequired. `trunc`: bytes cut from the positions' stream
 * length. `sequence`: the indices as an INDICES stream of uint32 (else TRIANGLES of uint16). */
static void meshopt_json(char *out, size_t n, const streams *s, const char *bin, const char *fallback_uri,
                         int required, size_t trunc, int sequence)
{
    char b0[128], b1[160];
    if (bin) snprintf(b0, sizeof b0, "{\"uri\":\"%s\",\"byteLength\":%zu}", bin, s->len);
    else snprintf(b0, sizeof b0, "{\"byteLength\":%zu}", s->len);
    snprintf(b1, sizeof b1, "{%s%s%s\"byteLength\":%d,\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}}",
             fallback_uri ? "\"uri\":\"" : "", fallback_uri ? fallback_uri : "", fallback_uri ? "\"," : "",
             sequence ? 984 : 792);
    const int isz = sequence ? 4 : 2;
    snprintf(out, n,
             "{\"asset\":{\"version\":\"2.0\"},"
             "\"extensionsUsed\":[\"EXT_meshopt_compression\",\"KHR_mesh_quantization\"],"
             "\"extensionsRequired\":[%s\"KHR_mesh_quantization\"],"
             "\"buffers\":[%s,%s],"
             "\"bufferViews\":["
             "{\"name\":\"pos\",\"buffer\":1,\"byteOffset\":0,\"byteLength\":300,\"byteStride\":12,\"extensions\":"
             "{\"EXT_meshopt_compression\":{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":12,"
             "\"count\":25,\"mode\":\"ATTRIBUTES\"%s}}},"
             "{\"name\":\"nrm\",\"buffer\":1,\"byteOffset\":300,\"byteLength\":100,\"byteStride\":4,\"extensions\":"
             "{\"EXT_meshopt_compression\":{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":4,"
             "\"count\":25,\"mode\":\"ATTRIBUTES\",\"filter\":\"OCTAHEDRAL\"}}},"
             "{\"name\":\"idx\",\"buffer\":1,\"byteOffset\":600,\"byteLength\":%d,\"extensions\":"
             "{\"EXT_meshopt_compression\":{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"byteStride\":%d,"
             "\"count\":96,\"mode\":\"%s\"}}}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":25,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5120,\"normalized\":true,\"count\":25,\"type\":\"VEC3\"},"
             "{\"bufferView\":2,\"componentType\":%d,\"count\":96,\"type\":\"SCALAR\"}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2}]}],"
             "\"nodes\":[{\"name\":\"grid\",\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
             required ? "\"EXT_meshopt_compression\"," : "", b0, b1, s->off[0], s->size[0] - trunc,
             s->exp_pos ? ",\"filter\":\"EXPONENTIAL\"" : "", s->off[1],
             s->size[1], 96 * isz, s->off[2], s->size[2], isz, sequence ? "INDICES" : "TRIANGLES",
             sequence ? 5125 : 5123);
}

static void write_gltf(const char *name, const streams *s, const char *fallback_uri, int required, size_t trunc,
                       int sequence)
{
    char json[4096];
    imp_write_file("mo.bin", s->bytes, s->len);
    meshopt_json(json, sizeof json, s, "mo.bin", fallback_uri, required, trunc, sequence);
    imp_write_text(name, json);
}

static void le32(unsigned char *p, uint32_t x)
{
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(x >> (8 * i));
}

/* gltfpack's usual output: a GLB whose BIN chunk is buffer 0, the fallback buffer without uri. */
static void write_glb(const char *name, const streams *s)
{
    char json[4096];
    meshopt_json(json, sizeof json, s, NULL, NULL, 0, 0, 0);
    size_t jl = strlen(json), jp = (jl + 3) & ~(size_t)3, bp = (s->len + 3) & ~(size_t)3;
    size_t total = 12 + 8 + jp + 8 + bp;
    unsigned char *g = calloc(1, total);
    assert_non_null(g);
    memcpy(g, "glTF", 4);
    le32(g + 4, 2);
    le32(g + 8, (uint32_t)total);
    le32(g + 12, (uint32_t)jp);
    memcpy(g + 16, "JSON", 4);
    memset(g + 20, ' ', jp);
    memcpy(g + 20, json, jl);
    le32(g + 20 + jp, (uint32_t)bp);
    memcpy(g + 24 + jp, "BIN\0", 4);
    memcpy(g + 28 + jp, s->bytes, s->len);
    imp_write_file(name, g, total);
    free(g);
}

static void import_ok(const char *name, bk_scene *s)
{
    char err[1024];
    int rc = imp_import_tmp(name, s, NULL, err, sizeof err);
    if (rc) printf("%s: %s\n", name, err);
    assert_int_equal(rc, 0);
}

/* The same triangles in the same order: exactly for an INDICES stream, and up to a rotation of
 * each triangle's corners (winding kept) for a TRIANGLES stream, whose encoder rotates triangles
 * to share edges with the previous ones. */
static void assert_same_tris(const bk_scene *plain, const bk_scene *mo, int rotated_ok)
{
    int rotated = 0;
    for (size_t t = 0; t < mo->tri_count; t++) {
        const uint32_t *a = plain->tris + 3 * t, *b = mo->tris + 3 * t;
        int r = 0;
        while (r < 3 && !(b[r] == a[0] && b[(r + 1) % 3] == a[1] && b[(r + 2) % 3] == a[2])) r++;
        assert_true(r < 3);
        rotated += r != 0;
    }
    if (!rotated_ok) assert_int_equal(rotated, 0);
    printf("triangles rotated by the index codec: %d of %zu\n", rotated, mo->tri_count);
}

/* Normals within the octahedral filter's 8-bit precision (a cell of the 8-bit grid spans
 * 2/127 = 0.016 of u or v), and not equal: the filter is lossy, so equal normals would mean the
 * plain (fallback) view was read. */
static void assert_normals_close(const bk_scene *plain, const bk_scene *mo)
{
    double worst = 0;
    for (size_t v = 0; v < mo->vertex_count * 3; v++) {
        double d = fabs((double)mo->normals[v] - (double)plain->normals[v]);
        if (d > worst) worst = d;
    }
    printf("octahedral normals: max component error %.5f\n", worst);
    assert_true(worst < 0.016);
    assert_true(worst > 0);
}

/* The compressed import equals the plain one: the same vertices in the same order, positions bit
 * for bit (exp_pos = 0) or within one step of the EXPONENTIAL filter's 16-bit signed mantissa
 * (15 bits of magnitude), shared by a vertex's three components: under max|p| * 2^-15 (measured
 * 2.6e-5 of max|p|, and not 0: the plain view was not read). */
static void assert_same_grid(const bk_scene *plain, const bk_scene *mo, int rotated_ok, int exp_pos)
{
    assert_int_equal(mo->vertex_count, plain->vertex_count);
    assert_int_equal(mo->tri_count, plain->tri_count);
    assert_int_equal(mo->tri_count, NT);
    assert_memory_equal(mo->vertex_source, plain->vertex_source, plain->vertex_count * sizeof(uint32_t));
    if (!exp_pos) {
        assert_memory_equal(mo->positions, plain->positions, plain->vertex_count * 3 * sizeof(float));
    } else {
        double worst = 0;
        for (size_t v = 0; v < mo->vertex_count; v++) {
            const float *p = plain->positions + 3 * v, *q = mo->positions + 3 * v;
            double m = fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2])));
            for (int c = 0; c < 3; c++) {
                double d = fabs((double)q[c] - (double)p[c]);
                assert_true(d <= m * ldexp(1.0, -15));
                if (m > 0 && d / m > worst) worst = d / m;
            }
        }
        printf("exponential positions: max error %.3g of the vertex's largest component\n", worst);
        assert_true(worst > 0);
    }
    assert_same_tris(plain, mo, rotated_ok);
    assert_normals_close(plain, mo);
}

static void test_required_no_fallback(void **state)
{
    (void)state;
    make_grid();
    write_plain();
    imp_write_text("plain.gltf", kPlainGltf);
    streams s;
    encode(&s, 0, 0);
    write_gltf("req.gltf", &s, NULL, 1, 0, 0);
    bk_scene plain, mo;
    import_ok("plain.gltf", &plain);
    import_ok("req.gltf", &mo);
    assert_same_grid(&plain, &mo, 1, 0);
    bk_scene_free(&mo);
    /* INDICES (an index sequence, uint32) decodes to the same triangles */
    encode(&s, 1, 0);
    write_gltf("seq.gltf", &s, NULL, 1, 0, 1);
    import_ok("seq.gltf", &mo);
    assert_same_grid(&plain, &mo, 0, 0);
    bk_scene_free(&mo);
    /* positions through the EXPONENTIAL filter */
    encode(&s, 0, 1);
    write_gltf("exp.gltf", &s, NULL, 1, 0, 0);
    import_ok("exp.gltf", &mo);
    assert_same_grid(&plain, &mo, 1, 1);
    bk_scene_free(&mo);
    bk_scene_free(&plain);
}

static void test_used_with_fallback(void **state)
{
    (void)state;
    make_grid();
    write_plain();
    imp_write_text("plain.gltf", kPlainGltf);
    streams s;
    encode(&s, 0, 0);
    bk_scene plain, mo;
    import_ok("plain.gltf", &plain);
    /* the fallback buffer without uri (gltfpack's), only used */
    write_gltf("used.gltf", &s, NULL, 0, 0, 0);
    import_ok("used.gltf", &mo);
    assert_same_grid(&plain, &mo, 1, 0);
    bk_scene_free(&mo);
    /* the same as a GLB: the uri-less fallback is not mistaken for the BIN chunk */
    write_glb("used.glb", &s);
    import_ok("used.glb", &mo);
    assert_same_grid(&plain, &mo, 1, 0);
    bk_scene_free(&mo);
    /* a fallback with data of its own (all zero here): the compressed view is decoded instead */
    unsigned char zero[792] = {0};
    imp_write_file("zero.bin", zero, sizeof zero);
    write_gltf("fb.gltf", &s, "zero.bin", 0, 0, 0);
    import_ok("fb.gltf", &mo);
    assert_same_grid(&plain, &mo, 1, 0);
    for (size_t i = 0; i < mo.input_count; i++) assert_null(strstr(mo.inputs[i].path, "zero.bin"));
    bk_scene_free(&mo);
    bk_scene_free(&plain);
}

static void test_malformed(void **state)
{
    (void)state;
    make_grid();
    streams s;
    encode(&s, 0, 0);
    /* the positions' stream cut short by 9 bytes */
    write_gltf("trunc.gltf", &s, NULL, 1, 9, 0);
    imp_expect_error("trunc.gltf", "bufferView 0 \"pos\": EXT_meshopt_compression", "malformed or truncated");
    /* the streams bytes swapped: the normals' stream read as the positions' */
    s.off[0] = s.off[1];
    s.size[0] = s.size[1];
    write_gltf("swap.gltf", &s, NULL, 1, 0, 0);
    imp_expect_error("swap.gltf", "bufferView 0 \"pos\"", "malformed or truncated");
    /* a count the compressed bytes cannot hold (more than 128 bytes per compressed byte) */
    encode(&s, 0, 0);
    char json[4096], big[4200];
    meshopt_json(json, sizeof json, &s, "mo.bin", NULL, 1, 0, 0);
    const char *k = "\"count\":25,\"mode\":\"ATTRIBUTES\"}";
    char *c = strstr(json, k);
    assert_non_null(c);
    snprintf(big, sizeof big, "%.*s\"count\":2000000,\"mode\":\"ATTRIBUTES\"}%s", (int)(c - json), json, c + strlen(k));
    imp_write_text("count.gltf", big);
    imp_expect_error("count.gltf", "bufferView 0 \"pos\": EXT_meshopt_compression: count 2000000", "compressed bytes");
    /* the compressed range outside its buffer */
    s.off[2] = s.len;
    write_gltf("range.gltf", &s, NULL, 1, 0, 0);
    imp_expect_error("range.gltf", "bufferView 2 \"idx\"", "outside buffer 0");
    /* a stride the filter cannot have, and an unknown mode: refused before any decoding */
    encode(&s, 0, 0);
    meshopt_json(json, sizeof json, &s, "mo.bin", NULL, 1, 0, 0);
    k = "\"byteStride\":4,\"count\":25,\"mode\":\"ATTRIBUTES\",\"filter\":\"OCTAHEDRAL\"";
    c = strstr(json, k);
    assert_non_null(c);
    snprintf(big, sizeof big, "%.*s\"byteStride\":12,\"count\":25,\"mode\":\"ATTRIBUTES\",\"filter\":\"OCTAHEDRAL\"%s",
             (int)(c - json), json, c + strlen(k));
    imp_write_text("stride.gltf", big);
    imp_expect_error("stride.gltf", "bufferView 1 \"nrm\"", "byteStride 12 and count 25 do not fit");
    k = "\"mode\":\"TRIANGLES\"";
    c = strstr(json, k);
    assert_non_null(c);
    snprintf(big, sizeof big, "%.*s\"mode\":\"STRIPS\"%s", (int)(c - json), json, c + strlen(k));
    imp_write_text("mode.gltf", big);
    imp_expect_error("mode.gltf", "bufferView 2 \"idx\"", "unknown mode \"STRIPS\"");
}

/* The whole bake (lbk_bake_from_file, as lbk bake runs it) of the grid under a white sky, the
 * extension required and no fallback: it bakes, and writes a container. */
static void test_bake(void **state)
{
    (void)state;
    make_grid();
    streams s;
    encode(&s, 0, 1);
    char json[4096], sky[4200];
    imp_write_file("mo.bin", s.bytes, s.len);
    meshopt_json(json, sizeof json, &s, "mo.bin", NULL, 1, 0, 0);
    const char *k = "\"scenes\":[{\"nodes\":[0]}]";
    const char *c = strstr(json, k);
    assert_non_null(c);
    snprintf(sky, sizeof sky, "%.*s\"scenes\":[{\"nodes\":[0],\"extras\":{\"lbk_sky\":[1,1,1]}}]%s", (int)(c - json),
             json, c + strlen(k));
    imp_write_text("bake.gltf", sky);
    imp_bake_tmp("bake.gltf", "bake.lbk");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_required_no_fallback, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_used_with_fallback, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_malformed, imp_setup_tmp, imp_teardown_tmp),
        cmocka_unit_test_setup_teardown(test_bake, imp_setup_tmp, imp_teardown_tmp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
