/* The glTF corpus (shared/gltf_corpus/, SOURCES.md there: public sample and test models as
 * exporters and other importers' suites have them): every file either imports with exactly the
 * triangles its accessors describe, or is refused with a message that names what lbk does not
 * take (from an allowed list per file); none crashes or hangs. The triangles are counted here
 * independently of the importer, from the JSON (a GLB's JSON chunk): the default scene's node
 * tree, each mesh instance's primitives, TRIANGLES n/3, TRIANGLE_STRIP and _FAN n-2, points and
 * lines none, n the indices' count or else POSITION's. With $LBK (make test: the ASan CLI) the
 * importable ones are also baked at a tiny budget under a 60 s timeout and must exit 0, and
 * the refused ones must be refused by the CLI with the same message. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "scene/import.h"
#include "scene/scene.h"

typedef struct {
    const char *file;   /* under the corpus folder */
    const char *refuse; /* NULL: imports; else a part of the refusal's message */
    int bake;           /* 1: baked through $LBK (0: import only, the bake being minutes under ASan) */
} corpus_case;

/* What each file is and does (shared/gltf_corpus/SOURCES.md says where it is from). */
static const corpus_case kCases[] = {
    {"2CylinderEngine-Draco/2CylinderEngine.gltf", NULL, 0},          /* Draco, 67 nodes, mm-sized */
    {"AnimatedMorphCube/glTF/AnimatedMorphCube.gltf", NULL, 1},       /* morph targets: the base mesh */
    {"AnimatedMorphSphere/glTF/AnimatedMorphSphere.gltf", NULL, 1},
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_00.gltf", "no triangles", 1}, /* points */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_01.gltf", "no triangles", 1}, /* lines */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_02.gltf", "no triangles", 1}, /* line loop */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_03.gltf", "no triangles", 1}, /* line strip */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_04.gltf", NULL, 1},           /* strip */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_05.gltf", NULL, 1},           /* fan */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_06.gltf", NULL, 1},
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_07.gltf", "no triangles", 1},
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_08.gltf", "no triangles", 1},
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_09.gltf", "no triangles", 1},
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_10.gltf", "no triangles", 1},
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_11.gltf", NULL, 1}, /* indexed strip */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_12.gltf", NULL, 1}, /* indexed fan */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_13.gltf", NULL, 1}, /* uint32 indices */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_14.gltf", NULL, 1}, /* uint8 */
    {"AssetGenerator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_15.gltf", NULL, 1}, /* uint16 */
    {"Box01/box01.glb", NULL, 1},
    {"BoxBadNormals/BoxBadNormals.glb", NULL, 1},
    {"BoxTexcoords/boxTexcoords.gltf", NULL, 1},              /* TEXCOORD_1 */
    {"BoxTextured/BoxTextured.gltf", NULL, 1},                /* interleaved (byteStride), .bin + PNG */
    {"BoxTextured-Binary/BoxTextured.glb", NULL, 1},          /* GLB, image in a bufferView */
    {"BoxTextured-Embedded/BoxTextured.gltf", NULL, 1},       /* data URIs */
    {"BoxTextured-SpecGloss/BoxTextured.gltf", NULL, 1},      /* KHR_materials_pbrSpecularGlossiness */
    {"BoxVertexColors/BoxVertexColors.gltf", NULL, 1},        /* COLOR_0 */
    {"BoxWithInfinites/BoxWithInfinites.glb", "NaN or infinite", 1},
    {"Cameras/Cameras.gltf", NULL, 1},
    {"ClearCoatTest/ClearCoatTest.gltf", NULL, 0},            /* KHR_materials_clearcoat, 27 objects */
    {"CubeImageUriSpaces/CubeImageUriSpaces.gltf", NULL, 1},  /* an image URI with spaces */
    {"IndexOutOfRange/AllIndicesOutOfRange.gltf", "but there are 24 vertices", 1},
    {"IndexOutOfRange/IndexOutOfRange.gltf", "but there are 24 vertices", 1},
    {"MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf", NULL, 1},
    {"RecursiveNodes/RecursiveNodes.gltf", "reached twice in the scene graph", 1},
    {"SimpleMorph/glTF/SimpleMorph.gltf", NULL, 1},
    {"SimpleSkin/quad_skin.glb", NULL, 1},                    /* skin: the mesh as authored */
    {"SimpleSkin/simple_skin.gltf", NULL, 1},
    {"SimpleSparseAccessor/SimpleSparseAccessor.gltf", "sparse accessors are not supported", 1},
    {"SparseMorphCube/singleBlendshapeCube_sparse.glb", NULL, 1}, /* sparse morph target only */
    {"TexcoordCrash/texcoord_crash.gltf", NULL, 1},
    {"TextureTransformTest/TextureTransformTest.gltf", NULL, 1}, /* KHR_texture_transform */
    {"TwoBoxes-glTF1/TwoBoxes.gltf", "lbk reads glTF 2.0 only", 1},
};

static const char *corpus_dir(void)
{
    const char *d = getenv("LBK_GLTF_CORPUS");
    return d && *d ? d : "shared/gltf_corpus";
}

/* The file's JSON text (a GLB's first chunk), NUL-terminated; NULL when unreadable. */
static char *read_json(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = n > 0 ? malloc((size_t)n + 1) : NULL;
    if (!buf || fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        fclose(f);
        return NULL;
    }
    fclose(f);
    buf[n] = 0;
    if (n >= 20 && !memcmp(buf, "glTF", 4)) { /* header 12 B, then chunk length, type "JSON" */
        uint32_t len;
        memcpy(&len, buf + 12, 4);
        if (memcmp(buf + 16, "JSON", 4) || (long)len > n - 20) {
            free(buf);
            return NULL;
        }
        memmove(buf, buf + 20, len);
        buf[len] = 0;
    }
    return buf;
}

static long accessor_count(const cJSON *root, int acc)
{
    const cJSON *a = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "accessors"), acc);
    const cJSON *c = cJSON_GetObjectItem(a, "count");
    return cJSON_IsNumber(c) ? (long)c->valuedouble : 0;
}

static long mesh_triangles(const cJSON *root, int mesh)
{
    const cJSON *m = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "meshes"), mesh);
    long tris = 0;
    const cJSON *p;
    cJSON_ArrayForEach(p, cJSON_GetObjectItem(m, "primitives"))
    {
        const cJSON *mode = cJSON_GetObjectItem(p, "mode"), *ind = cJSON_GetObjectItem(p, "indices");
        const cJSON *pos = cJSON_GetObjectItem(cJSON_GetObjectItem(p, "attributes"), "POSITION");
        const int md = cJSON_IsNumber(mode) ? mode->valueint : 4;
        const long n = cJSON_IsNumber(ind) ? accessor_count(root, ind->valueint)
                       : cJSON_IsNumber(pos) ? accessor_count(root, pos->valueint) : 0;
        if (md == 4) tris += n / 3;
        else if ((md == 5 || md == 6) && n >= 3) tris += n - 2;
    }
    return tris;
}

/* The triangles under node n (depth-capped: a cyclic file is refused by the importer anyway). */
static long node_triangles(const cJSON *root, int n, int depth)
{
    const cJSON *node = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "nodes"), n);
    if (!node || depth > 64) return 0;
    const cJSON *mesh = cJSON_GetObjectItem(node, "mesh"), *c;
    long tris = cJSON_IsNumber(mesh) ? mesh_triangles(root, mesh->valueint) : 0;
    cJSON_ArrayForEach(c, cJSON_GetObjectItem(node, "children")) tris += node_triangles(root, c->valueint, depth + 1);
    return tris;
}

/* The default scene's triangles (scene, else scene 0); -1 when the JSON does not parse. */
static long file_triangles(const char *path)
{
    char *text = read_json(path);
    cJSON *root = text ? cJSON_Parse(text) : NULL;
    free(text);
    if (!root) return -1;
    const cJSON *sc = cJSON_GetObjectItem(root, "scene"), *n;
    const cJSON *scene = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "scenes"), cJSON_IsNumber(sc) ? sc->valueint : 0);
    long tris = 0;
    cJSON_ArrayForEach(n, cJSON_GetObjectItem(scene, "nodes")) tris += node_triangles(root, n->valueint, 0);
    cJSON_Delete(root);
    return tris;
}

/* Runs `$LBK bake` on path at a tiny budget under a 60 s timeout; returns the exit status
 * (124: timed out, 128 + n: killed by signal n) and leaves its output in log. */
static int cli_bake(const char *path, const char *log)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd,
             "timeout 60 %s bake '%s' -o /tmp/lbk_test_corpus_%d.lbk --samples 16 --texel-density 2 "
             "--texel-budget 4096 --max-probes 256 --max-bounces 1 --path-check off --sky 1,1,1 > '%s' 2>&1",
             getenv("LBK"), path, (int)getpid(), log);
    const int st = system(cmd);
    snprintf(cmd, sizeof cmd, "/tmp/lbk_test_corpus_%d.lbk", (int)getpid());
    unlink(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

static int file_has(const char *path, const char *needle)
{
    char *text = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    text = calloc(1, 1 << 20);
    size_t n = text ? fread(text, 1, (1 << 20) - 1, f) : 0;
    fclose(f);
    const int hit = n > 0 && strstr(text, needle) != NULL;
    free(text);
    return hit;
}

static void test_corpus(void **state)
{
    (void)state;
    const size_t n = sizeof kCases / sizeof kCases[0];
    int failures = 0, baked = 0, refused = 0;
    for (size_t i = 0; i < n; i++) {
        const corpus_case *c = &kCases[i];
        char path[1024], err[1024], log[256];
        snprintf(path, sizeof path, "%s/%s", corpus_dir(), c->file);
        if (access(path, R_OK) != 0) fail_msg("missing corpus file %s", path);
        const long want = file_triangles(path);
        bk_scene s;
        const int rc = bk_import_gltf(path, NULL, &s, err, sizeof err);
        int ok;
        if (!c->refuse) {
            ok = rc == 0 && want > 0 && (long)s.tri_count == want;
            if (!ok) printf("%s: rc %d (%s), %zu triangles imported, %ld in the file\n", c->file, rc, rc ? err : "",
                            rc ? (size_t)0 : s.tri_count, want);
        } else if (!strcmp(c->refuse, "no triangles")) {
            /* points and lines only: the import holds nothing (the file has no triangles either:
             * nothing was dropped), the bake refuses it */
            ok = rc == 0 && s.tri_count == 0 && want == 0;
            if (!ok) printf("%s: rc %d (%s), %zu triangles imported, %ld in the file, expected none\n", c->file, rc,
                            rc ? err : "", rc ? (size_t)0 : s.tri_count, want);
        } else {
            ok = rc != 0 && strstr(err, c->refuse);
            if (!ok) printf("%s: rc %d, message \"%s\", expected \"%s\" (%ld triangles in the file)\n", c->file, rc,
                            err, c->refuse, want);
        }
        if (rc == 0) bk_scene_free(&s);
        if (ok && c->bake && getenv("LBK")) {
            snprintf(log, sizeof log, "/tmp/lbk_test_corpus_%d.log", (int)getpid());
            const int st = cli_bake(path, log);
            ok = c->refuse ? st != 0 && st < 124 && file_has(log, c->refuse) : st == 0;
            if (!ok) {
                printf("%s: lbk bake exit %d%s; its output:\n", c->file, st, st == 124 ? " (timed out)" : "");
                fflush(stdout);
                char cmd[512];
                snprintf(cmd, sizeof cmd, "tail -n 5 '%s'", log);
                if (system(cmd) != 0) printf("(no output)\n");
            }
            unlink(log);
        }
        printf("%-62s %-7s %ld triangles%s\n", c->file, c->refuse ? "refused" : "imports", want,
               ok ? "" : "  FAILED");
        failures += !ok;
        baked += ok && !c->refuse && c->bake && getenv("LBK");
        refused += ok && c->refuse != NULL;
    }
    printf("corpus: %zu files, %d refused as expected, %d baked through lbk%s, %d failed\n", n, refused, baked,
           getenv("LBK") ? "" : " ($LBK unset: import only)", failures);
    assert_int_equal(failures, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_corpus),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
