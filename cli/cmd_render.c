/* lbk render: a view of a baked level through liblbk's runtime API (tools/render). */
#include <math.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/options.h"
#include "tools/common/output_guard.h"
#include "tools/render/render.h"

#define MAX_NAMED 64
#define MAX_SPHERES 256

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lbk render SCENE.gltf|.glb LEVEL.lbk -o VIEW.exr [--png VIEW.png] [options]\n"
            "\n"
            "A reference renderer: geometry from SCENE (the file LEVEL was baked from, checked object by\n"
            "object), lighting from LEVEL only: lightmaps (LMUV coordinates, bilinear, AHD decoded for the\n"
            "shading normal), LLG grids with per-vertex self-visibility, the GLG for dynamic objects\n"
            "(lbk_lighting \"none\") and test spheres, each along the shading normal: the material's normal\n"
            "map applied where it has one (normalTexture, with TANGENT or tangents derived from TEXCOORD_0).\n"
            "Radiance L = albedo * E / pi + emission, in nits (E in lux); rays that leave the level see the\n"
            "sky. Output: linear float EXR (R, G, B).\n"
            "\n"
            "  -o FILE.exr             the view\n"
            "  --png FILE.png          also an sRGB preview (exposure 1 / 99th percentile of luminance)\n"
            "  --camera N              the glTF's camera N (default: camera 0 if the file has one, else a\n"
            "                          view from inside the level's bounds near +z towards their centre, or\n"
            "                          from outside them at +z when that spot is inside a closed object)\n"
            "  --look-from X,Y,Z       a camera of your own (with --look-at; --up default 0,1,0)\n"
            "  --look-at X,Y,Z\n"
            "  --up X,Y,Z\n"
            "  --fov DEG               vertical field of view of --look-from (default 60)\n"
            "  --size WxH              image size (default 160x120)\n"
            "  --samples N             N x N stratified rays per pixel, box filter (default 2)\n"
            "  --set NAME=W            weight of light set NAME (default 1: on, as in the scene); repeatable\n"
            "  --door NAME=W           openness of door NAME, 0 closed .. 1 open (default 0: as the scene's\n"
            "                          geometry; a door at 1 is not drawn); repeatable\n"
            "  --probe-spheres LIST    white test spheres lit from the GLG: X,Y,Z,R[:X,Y,Z,R...]\n"
            "  --sky R,G,B             sky radiance seen by rays that leave the level (default: the scene's;\n"
            "                          pass the --sky the level was baked with)\n"
            "  --seams FILE.exr        chart-boundary mask of the view (channels lightmapped, seam) for the bench\n"
            "  --threads N             default: all cores\n"
            CLI_MAX_MEMORY_HELP
            "  -q, --quiet             no summary\n"
            "  -h, --help              this text\n"
            "\n"
            "exit codes: 0 written, 2 usage (also an unknown light set, door or camera), 3 I/O error,\n"
            "            4 unusable input (a scene that is not the one LEVEL was baked from), 5 internal error\n");
}

static int parse_floats(const char *s, float *v, int n)
{
    for (int i = 0; i < n; i++) {
        char *end;
        v[i] = strtof(s, &end);
        if (end == s || !isfinite(v[i]) || (i + 1 < n ? *end != ',' : *end != '\0')) return -1;
        s = end + 1;
    }
    return 0;
}

static int parse_named(const char *s, tl_weight *w)
{
    const char *eq = strrchr(s, '=');
    char *end;
    if (!eq || eq == s) return -1;
    w->weight = strtof(eq + 1, &end);
    if (end == eq + 1 || *end || !isfinite(w->weight)) return -1;
    char *name = malloc((size_t)(eq - s) + 1);
    if (!name) return -1;
    memcpy(name, s, (size_t)(eq - s));
    name[eq - s] = '\0';
    w->name = name;
    return 0;
}

static int parse_spheres(const char *s, tl_sphere *sp, size_t *n)
{
    char buf[4096];
    if (strlen(s) >= sizeof buf) return -1;
    strcpy(buf, s);
    for (char *save = NULL, *tok = strtok_r(buf, ":", &save); tok; tok = strtok_r(NULL, ":", &save)) {
        float v[4];
        if (*n >= MAX_SPHERES || parse_floats(tok, v, 4) || !(v[3] > 0)) return -1;
        sp[*n] = (tl_sphere){{v[0], v[1], v[2]}, v[3]};
        (*n)++;
    }
    return *n ? 0 : -1;
}

typedef struct args {
    const char *scene, *level, *exr, *png, *seams;
    tl_guard guard;
    int camera, have_from, have_at, quiet;
    float fov;
    tl_render_options o;
    tl_weight sets[MAX_NAMED], doors[MAX_NAMED];
    tl_sphere spheres[MAX_SPHERES];
} args;

static int bad(const char *what, const char *value)
{
    fprintf(stderr, "lbk render: bad %s '%s' (see lbk render --help)\n", what, value);
    return LBK_EXIT_USAGE;
}

/* WxH, both strict positive integers up to 16384. */
static int parse_size(const char *v, int *w, int *h)
{
    const char *x = strchr(v, 'x');
    char wbuf[16];
    unsigned long long a, b;
    if (!x || (size_t)(x - v) >= sizeof wbuf) return -1;
    memcpy(wbuf, v, (size_t)(x - v));
    wbuf[x - v] = 0;
    if (!cli_parse_uint(wbuf, 1, 16384, &a) || !cli_parse_uint(x + 1, 1, 16384, &b)) return -1;
    *w = (int)a, *h = (int)b;
    return 0;
}

static int parse(int argc, char **argv, args *a)
{
    unsigned long long u;
    a->camera = -1;
    a->fov = 60.0f;
    a->o.camera.up[1] = 1.0f;
    for (int i = 1; i < argc; i++) {
        const char *k = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        const int takes = k[0] == '-' && strcmp(k, "-q") && strcmp(k, "--quiet") && strcmp(k, "-h") && strcmp(k, "--help");
        if (takes && !v) return bad("option without a value", k);
        if (!strcmp(k, "-h") || !strcmp(k, "--help")) return usage(stdout), -1;
        else if (!strcmp(k, "-q") || !strcmp(k, "--quiet")) a->quiet = 1;
        else if (!strcmp(k, "-o")) a->exr = v;
        else if (!strcmp(k, "--png")) a->png = v;
        else if (!strcmp(k, "--seams")) a->seams = v, a->o.seams = 1;
        else if (!strcmp(k, "--camera")) { if (!cli_parse_uint(v, 0, INT_MAX, &u)) return bad("camera", v); a->camera = (int)u; }
        else if (!strcmp(k, "--look-from")) { if (parse_floats(v, a->o.camera.from, 3)) return bad("position", v); a->have_from = 1; }
        else if (!strcmp(k, "--look-at")) { if (parse_floats(v, a->o.camera.at, 3)) return bad("position", v); a->have_at = 1; }
        else if (!strcmp(k, "--up")) { if (parse_floats(v, a->o.camera.up, 3)) return bad("direction", v); }
        else if (!strcmp(k, "--fov")) { if (parse_floats(v, &a->fov, 1) || !(a->fov > 0 && a->fov < 178)) return bad("field of view", v); }
        else if (!strcmp(k, "--size")) { if (parse_size(v, &a->o.width, &a->o.height)) return bad("size", v); }
        else if (!strcmp(k, "--samples")) { if (!cli_parse_uint(v, 1, 64, &u)) return bad("samples", v); a->o.samples = (int)u; }
        else if (!strcmp(k, "--threads")) { if (!cli_parse_uint(v, 0, 1024, &u)) return bad("threads", v); a->o.threads = (int)u; }
        else if (!strcmp(k, "--max-memory")) {
            int mm = cli_max_memory_option("render", argc, argv, &i, &a->o.max_decoded_bytes);
            if (mm < 0) return LBK_EXIT_USAGE;
            continue;
        }
        else if (!strcmp(k, "--sky")) { if (parse_floats(v, a->o.sky, 3) || a->o.sky[0] < 0 || a->o.sky[1] < 0 || a->o.sky[2] < 0) return bad("sky", v); a->o.sky_override = 1; }
        else if (!strcmp(k, "--set")) { if (a->o.set_count >= MAX_NAMED || parse_named(v, &a->sets[a->o.set_count++])) return bad("light set weight", v); }
        else if (!strcmp(k, "--door")) { if (a->o.door_count >= MAX_NAMED || parse_named(v, &a->doors[a->o.door_count++])) return bad("door weight", v); }
        else if (!strcmp(k, "--probe-spheres")) { if (parse_spheres(v, a->spheres, &a->o.sphere_count)) return bad("probe spheres", v); }
        else if (k[0] == '-') return bad("option", k);
        else if (!a->scene) { a->scene = k; continue; }
        else if (!a->level) { a->level = k; continue; }
        else return bad("extra argument", k);
        if (takes) i++;
    }
    if (!a->scene || !a->level || !a->exr) return bad("command line", "need SCENE LEVEL.lbk -o VIEW.exr");
    if (a->have_from != a->have_at) return bad("camera", "--look-from and --look-at go together");
    if (a->have_from && a->camera >= 0) return bad("camera", "--camera or --look-from, not both");
    a->o.sets = a->sets, a->o.doors = a->doors, a->o.spheres = a->spheres;
    return 0;
}

static int report(const char *err, int status)
{
    fprintf(stderr, "lbk render: %s\n", err);
    return status == TL_RENDER_USAGE ? LBK_EXIT_USAGE : status == TL_RENDER_IO ? LBK_EXIT_IO
         : status == TL_RENDER_INPUT ? LBK_EXIT_INPUT : LBK_EXIT_INTERNAL;
}

/* No output may replace the container, the scene or a file the scene reads, or a device; the
 * guard stays active while the command writes (output_guard.h). */
static int check_outputs(args *a)
{
    if (tl_guard_input(&a->guard, a->level, "the container") || tl_guard_scene(&a->guard, a->scene, NULL))
        return LBK_EXIT_INTERNAL;
    const char *outs[] = {"-o", a->exr, "--png", a->png, "--seams", a->seams, NULL, NULL};
    int rc = cli_check_outputs("render", &a->guard, outs);
    if (!rc) tl_guard_activate(&a->guard);
    return rc;
}

static int run(int argc, char **argv, args *a)
{
    int rc = parse(argc, argv, a);
    if (rc) return rc < 0 ? LBK_EXIT_OK : rc;
    if ((rc = check_outputs(a))) return rc;
    char err[TL_ERR_LEN];
    if (a->have_from) {
        a->o.camera.yfov = a->fov * 3.14159265f / 180.0f;
    } else if ((rc = tl_gltf_camera(a->scene, a->camera < 0 ? 0 : a->camera, &a->o.camera, err))) {
        if (rc != TL_RENDER_USAGE || a->camera >= 0) return report(err, rc);
        /* no camera in the file: yfov stays 0, the default view */
    }
    tl_image im;
    if ((rc = tl_render(a->scene, a->level, &a->o, &im, err))) return report(err, rc);
    if (tl_image_write(&im, a->exr, a->png, err) || (a->seams && tl_image_write_seams(&im, a->seams, err))) {
        tl_image_free(&im);
        return report(err, TL_RENDER_IO);
    }
    const int n = a->o.samples ? a->o.samples : 2;
    if (!a->quiet) printf("%s: %dx%d, %d rays per pixel%s%s\n", a->exr, im.width, im.height, n * n, a->png ? ", preview " : "", a->png ? a->png : "");
    tl_image_free(&im);
    return LBK_EXIT_OK;
}

int lbk_cmd_render(int argc, char **argv)
{
    args *a = calloc(1, sizeof *a);
    if (!a) return LBK_EXIT_INTERNAL;
    tl_guard_init(&a->guard, "render");
    const int code = run(argc, argv, a);
    tl_guard_activate(NULL);
    tl_guard_free(&a->guard);
    for (size_t i = 0; i < a->o.set_count; i++) free((void *)a->sets[i].name);
    for (size_t i = 0; i < a->o.door_count; i++) free((void *)a->doors[i].name);
    free(a);
    return code;
}
