/* Built by `make test` against an installed copy of liblbkbake with pkg-config only (once with
 * liblbkbake.so, once with liblbkbake.a), including nothing of lbk but lbk/bake.h (and the lbk
 * headers it pulls in). It describes one small level in memory — a room, a block with its own
 * texel density, a prop in a local light grid, an emissive panel in a light set, a door and a
 * point light — and checks:
 *
 *   - the in-memory bake reports progress (phases in order, fractions in [0, 1], the error
 *     estimate from the first pass on) and gives a container whose bytes equal its file;
 *   - a bake cancelled from the progress callback, in each phase, returns LBK_ERR_CANCELLED,
 *     no output, no error message, and writes nothing;
 *   - byte identity with the command line: the same level written as a glTF file and baked by
 *     the installed `lbk bake` gives exactly the bytes lbk_bake_from_file gives for that file;
 *     and the in-memory description gives the same container except META, section for section
 *     (META carries the source's hash and name: a file's bytes and base name there, the
 *     description's hash and name here). The in-memory bake runs on 1 thread, the others on 2:
 *     thread count changes nothing. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <lbk/bake.h>

#ifndef LBK_CLI
#define LBK_CLI "lbk"
#endif
#ifndef LBK_BAKE_PC_VERSION
#define LBK_BAKE_PC_VERSION "" /* the Makefile passes pkg-config --modversion lbk-bake */
#endif

/* ---- the level, as plain data ------------------------------------------------------------- */

#define MAX_V 256
#define MAX_T 256

static float pos[3 * MAX_V];
static uint32_t idx[3 * MAX_T];
static size_t nv, nt;
static lbk_bake_object objects[8];
static size_t n_obj;

static uint32_t vertex(const float p[3])
{
    memcpy(&pos[3 * nv], p, 3 * sizeof(float));
    return (uint32_t)nv++;
}

/* p0..p3 counter-clockwise seen from the front: two triangles */
static void quad(const float p0[3], const float p1[3], const float p2[3], const float p3[3])
{
    uint32_t a = vertex(p0), b = vertex(p1), c = vertex(p2), d = vertex(p3);
    uint32_t t[6] = {a, b, c, a, c, d};
    memcpy(&idx[3 * nt], t, sizeof t);
    nt += 2;
}

static void box(const float mn[3], const float mx[3], int inward)
{
    float c[8][3];
    for (int i = 0; i < 8; i++) {
        c[i][0] = i & 1 ? mx[0] : mn[0];
        c[i][1] = i & 2 ? mx[1] : mn[1];
        c[i][2] = i & 4 ? mx[2] : mn[2];
    }
    static const int f[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (int k = 0; k < 6; k++) {
        if (inward) quad(c[f[k][0]], c[f[k][3]], c[f[k][2]], c[f[k][1]]);
        else quad(c[f[k][0]], c[f[k][1]], c[f[k][2]], c[f[k][3]]);
    }
}

static lbk_bake_object *begin_object(const char *name, uint32_t material, lbk_bake_lighting lighting)
{
    lbk_bake_object *o = &objects[n_obj++];
    memset(o, 0, sizeof *o);
    o->name = name;
    o->first_triangle = (uint32_t)nt;
    o->material = material;
    o->lighting = lighting;
    return o;
}

static void end_object(lbk_bake_object *o) { o->triangle_count = (uint32_t)nt - o->first_triangle; }

static const lbk_bake_material materials[] = {
    {"wall", {0.6f, 0.6f, 0.6f}, {0, 0, 0}, 0},
    {"block", {0.4f, 0.5f, 0.625f}, {0, 0, 0}, 0},
    {"lamp", {0.5f, 0.5f, 0.5f}, {1, 1, 1}, 1},
};
static lbk_bake_light light = {"bulb", LBK_BAKE_LIGHT_POINT, {20, 20, 20}, {0, 2.5f, 1}, {0, 0, 0}, 0, 0, 0, NULL};
static lbk_bake_scene scene;

static void build_level(void)
{
    lbk_bake_object *o = begin_object("room", 0, LBK_BAKE_LIGHTING_LIGHTMAP);
    box((const float[3]){-2, 0, -2}, (const float[3]){2, 3, 2}, 1);
    end_object(o);
    o = begin_object("block", 1, LBK_BAKE_LIGHTING_LIGHTMAP);
    o->texel_density = 12;
    box((const float[3]){-1, 0, -1}, (const float[3]){0, 1, 0}, 0);
    end_object(o);
    o = begin_object("prop", 1, LBK_BAKE_LIGHTING_LLG);
    box((const float[3]){1, 0, 1}, (const float[3]){1.25f, 0.25f, 1.25f}, 0);
    end_object(o);
    o = begin_object("panel", 2, LBK_BAKE_LIGHTING_NONE);
    o->light_set = "lamp";
    quad((const float[3]){0.5f, 2.9f, -1}, (const float[3]){0.5f, 2.9f, -0.5f}, (const float[3]){1, 2.9f, -0.5f},
         (const float[3]){1, 2.9f, -1});
    end_object(o);
    o = begin_object("partition", 1, LBK_BAKE_LIGHTING_LIGHTMAP);
    o->door = "d1";
    quad((const float[3]){-2, 0, 0.5f}, (const float[3]){-1.25f, 0, 0.5f}, (const float[3]){-1.25f, 2, 0.5f},
         (const float[3]){-2, 2, 0.5f});
    end_object(o);
    memset(&scene, 0, sizeof scene);
    scene.name = "room";
    scene.vertex_count = nv;
    scene.positions = pos;
    scene.triangle_count = nt;
    scene.indices = idx;
    scene.material_count = sizeof materials / sizeof materials[0];
    scene.materials = materials;
    scene.object_count = n_obj;
    scene.objects = objects;
    scene.light_count = 1;
    scene.lights = &light;
}

/* ---- the same level as glTF (what tests/support/gltf_writer does, with stdio only) ---------- */

static char *base64(const unsigned char *d, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * ((n + 2) / 3) + 1);
    size_t o = 0;
    for (size_t i = 0; out && i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) | (i + 2 < n ? d[i + 2] : 0);
        out[o++] = tab[v >> 18 & 63];
        out[o++] = tab[v >> 12 & 63];
        out[o++] = i + 1 < n ? tab[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? tab[v & 63] : '=';
    }
    if (out) out[o] = 0;
    return out;
}

static const char *lighting_name(lbk_bake_lighting l)
{
    return l == LBK_BAKE_LIGHTING_LIGHTMAP ? "lightmap" : l == LBK_BAKE_LIGHTING_LLG ? "llg" : l == LBK_BAKE_LIGHTING_NONE ? "none" : "auto";
}

/* Each object a node with one non-indexed triangle primitive (the importer flat-shades both
 * forms alike); floats as %.9g, which reads back to the same float. */
static int write_gltf(const char *path)
{
    static float corners[9 * MAX_T];
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) memcpy(&corners[9 * t + 3 * k], &pos[3 * idx[3 * t + k]], 3 * sizeof(float));
    char *b64 = base64((const unsigned char *)corners, 9 * nt * sizeof(float));
    FILE *f = fopen(path, "w");
    if (!f || !b64) return -1;
    fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_lights_punctual\"],\"scene\":0,\n");
    fprintf(f, "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"point\",\"color\":[1,1,1],\"intensity\":%.9g}]}},\n",
            light.color[0]);
    fprintf(f, "\"scenes\":[{\"nodes\":[");
    for (size_t i = 0; i <= n_obj; i++) fprintf(f, "%s%zu", i ? "," : "", i);
    fprintf(f, "]}],\n\"materials\":[");
    for (size_t i = 0; i < sizeof materials / sizeof materials[0]; i++) {
        const lbk_bake_material *m = &materials[i];
        fprintf(f, "%s{\"name\":\"%s\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[%.9g,%.9g,%.9g,1],\"metallicFactor\":0},"
                   "\"emissiveFactor\":[%.9g,%.9g,%.9g],\"doubleSided\":%s}",
                i ? "," : "", m->name, m->base_color[0], m->base_color[1], m->base_color[2], m->emission[0], m->emission[1],
                m->emission[2], m->double_sided ? "true" : "false");
    }
    fprintf(f, "],\n\"nodes\":[");
    for (size_t i = 0; i < n_obj; i++) {
        const lbk_bake_object *o = &objects[i];
        fprintf(f, "{\"name\":\"%s\",\"mesh\":%zu,\"extras\":{\"lbk_lighting\":\"%s\"", o->name, i, lighting_name(o->lighting));
        if (o->texel_density > 0) fprintf(f, ",\"lbk_texel_density\":%.9g", o->texel_density);
        if (o->light_set) fprintf(f, ",\"lbk_light_set\":\"%s\"", o->light_set);
        if (o->door) fprintf(f, ",\"lbk_door\":\"%s\"", o->door);
        fprintf(f, "}},\n");
    }
    fprintf(f, "{\"name\":\"%s\",\"translation\":[%.9g,%.9g,%.9g],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}],\n",
            light.name, light.position[0], light.position[1], light.position[2]);
    fprintf(f, "\"meshes\":[");
    for (size_t i = 0; i < n_obj; i++)
        fprintf(f, "%s{\"primitives\":[{\"attributes\":{\"POSITION\":%zu},\"material\":%u,\"mode\":4}]}", i ? "," : "", i,
                objects[i].material);
    fprintf(f, "],\n\"accessors\":[");
    for (size_t i = 0; i < n_obj; i++) {
        const lbk_bake_object *o = &objects[i];
        float mn[3] = {1e30f, 1e30f, 1e30f}, mx[3] = {-1e30f, -1e30f, -1e30f};
        for (size_t k = 9 * (size_t)o->first_triangle; k < 9 * (size_t)(o->first_triangle + o->triangle_count); k++) {
            if (corners[k] < mn[k % 3]) mn[k % 3] = corners[k];
            if (corners[k] > mx[k % 3]) mx[k % 3] = corners[k];
        }
        fprintf(f, "%s{\"bufferView\":%zu,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\",\"min\":[%.9g,%.9g,%.9g],"
                   "\"max\":[%.9g,%.9g,%.9g]}",
                i ? "," : "", i, 3 * o->triangle_count, mn[0], mn[1], mn[2], mx[0], mx[1], mx[2]);
    }
    fprintf(f, "],\n\"bufferViews\":[");
    for (size_t i = 0; i < n_obj; i++)
        fprintf(f, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}", i ? "," : "",
                36 * (size_t)objects[i].first_triangle, 36 * (size_t)objects[i].triangle_count);
    fprintf(f, "],\n\"buffers\":[{\"byteLength\":%zu,\"uri\":\"data:application/octet-stream;base64,%s\"}]}\n", 36 * nt, b64);
    free(b64);
    return fclose(f) ? -1 : 0;
}

/* ---- helpers ------------------------------------------------------------------------------- */

static char tmpdir[256], gltf_path[320], mem_path[320], lib_path[320], cli_path[320];

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/lbk-bake-check-%d", (int)getpid());
    if (mkdir(tmpdir, 0755)) return -1;
    snprintf(gltf_path, sizeof gltf_path, "%s/room.gltf", tmpdir);
    snprintf(mem_path, sizeof mem_path, "%s/memory.lbk", tmpdir);
    snprintf(lib_path, sizeof lib_path, "%s/library.lbk", tmpdir);
    snprintf(cli_path, sizeof cli_path, "%s/cli.lbk", tmpdir);
    build_level();
    return write_gltf(gltf_path);
}

static int teardown(void **state)
{
    (void)state;
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
    return system(cmd);
}

static void *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    void *buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) free(buf), buf = NULL;
    fclose(f);
    *size = (size_t)n;
    return buf;
}

static int entries(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) n += e->d_name[0] != '.';
    if (d) closedir(d);
    return n;
}

/* The bake options every bake here uses: seed 7, 64 samples. */
static lbk_bake_desc options(int threads)
{
    lbk_bake_desc d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.seed = 7;
    d.max_samples = 64;
    d.threads = threads;
    return d;
}

typedef struct watch {
    int calls, last_phase, errors, cancel_phase; /* cancel_phase < 0: never */
    double last_fraction, last_elapsed;
    int phase_seen[LBK_BAKE_PHASE_COUNT_];
    int estimate_before_pass, estimate_after_pass;
} watch;

static int on_progress(void *user, const lbk_bake_progress *p)
{
    watch *w = user;
    w->calls++;
    assert_true((int)p->phase >= w->last_phase && p->phase < LBK_BAKE_PHASE_COUNT_);
    assert_true(p->fraction >= 0 && p->fraction <= 1);
    assert_true(p->elapsed_seconds >= w->last_elapsed);
    if ((int)p->phase > w->last_phase) assert_true(p->fraction == 0); /* a phase starts at 0 */
    w->last_phase = (int)p->phase;
    w->last_elapsed = p->elapsed_seconds;
    w->phase_seen[p->phase] = 1;
    if (p->phase < LBK_BAKE_PHASE_LIGHT) w->estimate_before_pass += p->est_rel_rmse >= 0;
    if (p->phase > LBK_BAKE_PHASE_LIGHT) w->estimate_after_pass += p->est_rel_rmse > 0;
    return (int)p->phase == w->cancel_phase;
}

static void on_message(void *user, lbk_bake_severity severity, const char *message)
{
    watch *w = user;
    if (severity == LBK_BAKE_SEVERITY_ERROR) {
        print_message("error: %s\n", message);
        w->errors++;
    }
}

static void watch_init(watch *w, lbk_bake_desc *d, int cancel_phase)
{
    memset(w, 0, sizeof *w);
    w->cancel_phase = cancel_phase;
    d->progress = on_progress;
    d->message = on_message;
    d->user = w;
}

/* ---- tests --------------------------------------------------------------------------------- */

static void test_in_memory_bake_with_progress(void **state)
{
    (void)state;
    lbk_bake_desc d = options(1);
    watch w;
    watch_init(&w, &d, -1);
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&scene, &d, &out), LBK_OK);
    assert_non_null(out);
    assert_int_equal(w.errors, 0);
    for (int p = 0; p < LBK_BAKE_PHASE_COUNT_; p++) assert_true(w.phase_seen[p]); /* sets: the lamp and the door */
    assert_int_equal(w.estimate_before_pass, 0);
    assert_true(w.estimate_after_pass > 0);

    const lbk_bake_report *r = lbk_bake_output_report(out);
    assert_string_equal(r->input, "room");
    assert_int_equal(r->counts.objects, 5);
    assert_int_equal(r->counts.doors, 1);
    assert_int_equal(r->counts.light_sets, 3); /* lamp, door d1 open and closed */
    assert_int_equal(r->counts.llgs, 1);
    assert_true(r->counts.texels > 0 && r->counts.glg_probes > 0);
    assert_true(r->pass_count >= 1 && r->passes[r->pass_count - 1].samples_per_receiver <= 64);
    assert_int_equal(r->status, LBK_BAKE_SAMPLE_LIMIT);
    assert_int_equal(r->phase_count, LBK_BAKE_PHASE_COUNT_);
    assert_true(r->scales.lmap > 0 && r->scales.glg > 0 && r->scales.llg > 0 && r->scales.octp == 0);

    assert_int_equal(lbk_bake_output_write_file(out, mem_path), LBK_OK);
    void *bytes;
    size_t size, fsize;
    assert_int_equal(lbk_bake_output_container(out, &bytes, &size), LBK_OK);
    void *file = read_all(mem_path, &fsize);
    assert_non_null(file);
    assert_int_equal(size, fsize);
    assert_int_equal(size, r->counts.file_bytes);
    assert_memory_equal(bytes, file, size);
    lbk_free(NULL, bytes);
    free(file);

    char json[400];
    snprintf(json, sizeof json, "%s/memory.json", tmpdir);
    assert_int_equal(lbk_bake_report_write_json(r, mem_path, json), LBK_OK);
    char *text = read_all(json, &fsize);
    assert_non_null(text);
    text[fsize] = 0;
    assert_non_null(strstr(text, "\"schema\":\t\"lbk-bake-report/1\""));
    assert_non_null(strstr(text, "\"input\":\t\"room\""));
    free(text);
    lbk_bake_output_free(out);
}

/* Cancelled at the first checkpoint of each phase in turn: a distinct result, no output, no
 * error message, nothing written. */
static void test_cancel_from_callback(void **state)
{
    (void)state;
    int before = entries(tmpdir);
    for (int ph = 0; ph < LBK_BAKE_PHASE_COUNT_; ph++) {
        lbk_bake_desc d = options(2);
        watch w;
        watch_init(&w, &d, ph);
        lbk_bake_output *out = (lbk_bake_output *)&w; /* must come back NULL */
        assert_int_equal(lbk_bake_from_scene(&scene, &d, &out), LBK_ERR_CANCELLED);
        assert_null(out);
        assert_int_equal(w.errors, 0);
        assert_int_equal(w.last_phase, ph); /* stopped where it was told */
        assert_int_equal(entries(tmpdir), before);
    }
    assert_string_equal(lbk_result_name(LBK_ERR_CANCELLED), "LBK_ERR_CANCELLED");
}

static int contains(const void *hay, size_t n, const char *needle)
{
    size_t k = strlen(needle);
    for (size_t i = 0; i + k <= n; i++)
        if (!memcmp((const char *)hay + i, needle, k)) return 1;
    return 0;
}

static lbk_reader *open_reader(const char *path)
{
    lbk_reader *r = NULL;
    assert_int_equal(lbk_reader_open_file(path, NULL, &r), LBK_OK);
    return r;
}

static void test_same_bytes_as_lbk_bake(void **state)
{
    (void)state;
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s -q --seed 7 --samples 64 --threads 2", LBK_CLI, gltf_path, cli_path);
    assert_int_equal(system(cmd), 0);

    /* the glTF file through the library: every byte */
    lbk_bake_desc d = options(2);
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_file(gltf_path, &d, &out), LBK_OK);
    assert_int_equal(lbk_bake_output_write_file(out, lib_path), LBK_OK);
    lbk_bake_output_free(out);
    size_t na, nb;
    void *a = read_all(cli_path, &na), *b = read_all(lib_path, &nb);
    assert_non_null(a);
    assert_non_null(b);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    free(a), free(b);

    /* the in-memory description: every section but META and LMUV, which describe the source:
     * META names the file, LMUV maps lightmap UVs onto the glTF's own nodes, primitives and
     * vertices (spec §16), which a description does not have, so only the file's bake has it */
    lbk_reader *cli = open_reader(cli_path), *mem = open_reader(mem_path);
    uint32_t n = lbk_reader_section_count(cli), nm = lbk_reader_section_count(mem);
    assert_true(nm >= 8); /* META REPT OBJS LMAP GLG LLG DLS DOOR */
    int compared = 0;
    for (uint32_t i = 0, j = 0; i < n; i++) {
        lbk_section_info si, sm;
        assert_int_equal(lbk_reader_section_get(cli, i, &si), LBK_OK);
        if (si.type == LBK_SECTION_LMUV) continue;
        assert_true(j < nm);
        assert_int_equal(lbk_reader_section_get(mem, j, &sm), LBK_OK);
        assert_int_equal(si.type, sm.type);
        const void *pc, *pm;
        size_t sc, sz;
        assert_int_equal(lbk_reader_section_data(cli, i, &pc, &sc), LBK_OK);
        assert_int_equal(lbk_reader_section_data(mem, j++, &pm, &sz), LBK_OK);
        if (si.type == LBK_SECTION_META) {
            assert_true(contains(pc, sc, "room.gltf")); /* the file's name ... */
            assert_false(contains(pm, sz, "room.gltf")); /* ... the description's: "room" */
            continue;
        }
        assert_int_equal(sc, sz);
        assert_memory_equal(pc, pm, sc);
        compared++;
    }
    assert_int_equal(compared, (int)nm - 1);
    lbk_reader_close(cli);
    lbk_reader_close(mem);
}

/* The description's rules are checked: an index out of range is an unusable scene, named. */
static void test_bad_description_is_refused(void **state)
{
    (void)state;
    lbk_bake_scene bad = scene;
    uint32_t broken[3 * MAX_T];
    memcpy(broken, idx, 3 * nt * sizeof *broken);
    broken[7] = (uint32_t)nv;
    bad.indices = broken;
    lbk_bake_desc d = options(1);
    watch w;
    watch_init(&w, &d, -1);
    lbk_bake_output *out = NULL;
    assert_int_equal(lbk_bake_from_scene(&bad, &d, &out), LBK_ERR_BAD_INPUT);
    assert_null(out);
    assert_int_equal(w.errors, 1);
}

/* lbk-bake.pc states the version the installed header declares (it said 1.0.0 while the
 * header's structs had grown three minor versions). */
static void test_pc_version_is_the_header_version(void **state)
{
    (void)state;
    char want[32];
    snprintf(want, sizeof want, "%d.%d.%d", LBK_BAKE_LIBRARY_VERSION_MAJOR, LBK_BAKE_LIBRARY_VERSION_MINOR,
             LBK_BAKE_LIBRARY_VERSION_PATCH);
    assert_string_equal(LBK_BAKE_PC_VERSION, want);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pc_version_is_the_header_version),
        cmocka_unit_test(test_in_memory_bake_with_progress),
        cmocka_unit_test(test_cancel_from_callback),
        cmocka_unit_test(test_same_bytes_as_lbk_bake),
        cmocka_unit_test(test_bad_description_is_refused),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
