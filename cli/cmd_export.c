/* lbk export: pages, planes, objects and probes as EXR/PNG/CSV/JSON, or the level as glTF. */
#include <stdio.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/options.h"
#include "tools/common/output_guard.h"
#include "tools/convert/export.h"
#include "tools/convert/gltf_export.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lbk export IN.lbk [--exr DIR] [--png DIR] [--per-object] [--gltf OUT.glb --scene SCENE] [--max-memory SIZE] [-q]\n"
            "       (at least one of --exr, --png, --gltf)\n"
            "\n"
            "Units: irradiance in lux-like units (lm/m^2); probe SH in radiance (nits, cd/m^2). Images are\n"
            "linear float EXR (ZIP, 32-bit) with row 0 at the top, x right: texel (x, y) of a page.\n"
            "\n"
            "  --exr DIR      per page NNN (3+ digits, from 000):\n"
            "                   page_NNN.exr          R,G,B = decoded irradiance along the surface normal (+Z)\n"
            "                                         (edit this one; lbk convert --from-exr DIR imports it)\n"
            "                   page_NNN.dominant.exr R,G,B = irradiance for a normal along the stored highlight\n"
            "                                         direction (the brightest the texel gets)\n"
            "                   page_NNN.ahd.exr      the raw AHD planes: plane0.R/G/B (R11G11B10F, exact) and\n"
            "                                         plane1.R/G/B/A (ratio, direction x, y, z bytes / 255)\n"
            "                   page_NNN.error.exr    Y = the per-texel error map's relative error (-1: no estimate),\n"
            "                                         only for a bake with --error-map (TERR; .error.png with --png)\n"
            "                 and for an OCTP probe volume (--octahedral), per clip level L:\n"
            "                   octp_level_L.exr       R,G,B = the probes' 4x4 irradiance texels (lux), probe\n"
            "                                         (x, y, z) the tile (x, y + dims_y*z); inactive probes 0\n"
            "                   octp_level_L.depth.exr m1, m2 = the 12x12 depth moments (m, m^2), same tiles\n"
            "  --png DIR      page_NNN.png tone-mapped previews of page_NNN.exr: one exposure for all pages,\n"
            "                 1 / (99th percentile of Rec.709 luminance over all texels), then sRGB, 8 bits\n"
            "  --per-object   also DIR/objects/III_name.exr (and .png): each lightmapped object's rectangle cut out\n"
            "                 of its page: pixel (i, j) is page texel (rect_x + i, rect_y + j) (III = the object's\n"
            "                 index in the object table); where that texel lies on the mesh is given by the LMUV\n"
            "                 section (spec/container.md 16), not by the object's TEXCOORD_1 alone\n"
            "  both dirs get probes.csv and probes.json (GLG and LLG probes: position, irradiance at the six\n"
            "  axis normals, the SH9 coefficients) and glg_top.png (top view looking down -Y: x right,\n"
            "  z down; tetra edges grey; probes coloured black-blue-cyan-green-yellow-red by luminance of\n"
            "  their mean irradiance, red = 99th percentile, white above)\n"
            "  --gltf OUT.glb the level as glTF 2.0 (binary), read again from --scene SCENE.gltf|.glb (the file it\n"
            "                 was baked from; checked object by object): one node per object, world-space geometry,\n"
            "                 TEXCOORD_1 = normalised page uv on every lightmapped primitive (vertices split where\n"
            "                 generated charts split); beside it OUT.lightmap_NNN.exr (R,G,B irradiance along the\n"
            "                 normal, lux), OUT.lightmap_NNN.ahd.exr (raw AHD planes), OUT.lightmap_NNN.png\n"
            "                 (preview) and OUT.lightmap_NNN.emissive.png (the lightmap as the emissive texture that\n"
            "                 stock glTF loaders draw: radiance albedo * E / pi in nits, tools/convert/README.md\n"
            "                 \"In engines\"); GLG and LLG probes as accessors named in the extras\n"
            "                 (tools/convert/README.md \"glTF export\")\n"
            "  -q, --quiet    no summary\n"
            CLI_MAX_MEMORY_HELP
            "  -h, --help     this text\n"
            "\n"
            "exit codes: 0 written, 2 usage, 3 I/O error (read or write), 4 the input is not a valid container\n"
            "            (or --scene cannot be read or is not the scene it was baked from),\n"
            "            5 internal error\n");
}

/* The outputs may replace neither the container nor the scene or its files, nor a device; the
 * guard stays active while the export writes its folders' files (output_guard.h). */
static int check_outputs(tl_guard *guard, const char *in, const tl_export_options *o, const tl_gltf_options *g)
{
    if (tl_guard_input(guard, in, "the container") || (g->scene && tl_guard_scene(guard, g->scene, NULL)))
        return LBK_EXIT_INTERNAL;
    const char *outs[] = {"--gltf", g->output, NULL, NULL};
    int rc = cli_check_outputs("export", guard, outs);
    char err[TL_ERR_LEN];
    if (!rc && ((o->exr_dir && tl_guard_output_dir(guard, o->exr_dir, NULL, "--exr", err)) ||
                (o->png_dir && tl_guard_output_dir(guard, o->png_dir, NULL, "--png", err)))) {
        fprintf(stderr, "lbk export: %s\n", err);
        rc = LBK_EXIT_USAGE;
    }
    if (!rc) tl_guard_activate(guard);
    return rc;
}

static int export_main(int argc, char **argv, tl_guard *guard)
{
    const char *in = NULL;
    tl_export_options o = {NULL, NULL, 0};
    tl_gltf_options g = {NULL, NULL, NULL, 0};
    int quiet = 0;
    uint64_t max_memory = 0;
    for (int i = 1; i < argc; i++) {
        const int mm = cli_max_memory_option("export", argc, argv, &i, &max_memory);
        if (mm < 0) return LBK_EXIT_USAGE;
        if (mm) continue;
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return LBK_EXIT_OK;
        } else if (!strcmp(a, "--per-object")) {
            o.per_object = 1;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            quiet = 1;
        } else if (!strcmp(a, "--exr") || !strcmp(a, "--png")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "lbk export: %s needs a directory\n", a);
                return LBK_EXIT_USAGE;
            }
            const char **dst = !strcmp(a, "--exr") ? &o.exr_dir : &o.png_dir;
            if (*dst) {
                fprintf(stderr, "lbk export: %s given twice\n", a);
                return LBK_EXIT_USAGE;
            }
            *dst = argv[++i];
        } else if (!strcmp(a, "--gltf") || !strcmp(a, "--scene")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "lbk export: %s needs a file\n", a);
                return LBK_EXIT_USAGE;
            }
            const char **dst = !strcmp(a, "--gltf") ? &g.output : &g.scene;
            if (*dst) {
                fprintf(stderr, "lbk export: %s given twice\n", a);
                return LBK_EXIT_USAGE;
            }
            *dst = argv[++i];
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk export: unknown option '%s' (see lbk export --help)\n", a);
            return LBK_EXIT_USAGE;
        } else if (!in) {
            in = a;
        } else {
            fprintf(stderr, "lbk export: more than one input\n");
            return LBK_EXIT_USAGE;
        }
    }
    if (!in || (!o.exr_dir && !o.png_dir && !g.output)) {
        fprintf(stderr, "lbk export: need IN.lbk and --exr DIR, --png DIR and/or --gltf OUT.glb (see lbk export --help)\n");
        return LBK_EXIT_USAGE;
    }
    if (!g.output != !g.scene) {
        fprintf(stderr, "lbk export: --gltf and --scene go together (the container holds no geometry)\n");
        return LBK_EXIT_USAGE;
    }
    int guarded = check_outputs(guard, in, &o, &g);
    if (guarded) return guarded;
    char err[TL_ERR_LEN];
    tl_bake b;
    tl_open_status st = tl_bake_open_file_capped(in, max_memory, &b, err);
    if (st != TL_OPEN_OK) {
        fprintf(stderr, "lbk export: %s\n", err);
        return st == TL_OPEN_IO ? LBK_EXIT_IO : st == TL_OPEN_INVALID ? LBK_EXIT_INPUT : LBK_EXIT_INTERNAL;
    }
    tl_export_stats s;
    int rc = o.exr_dir || o.png_dir ? tl_export(&b, &o, &s, err) : 0;
    if (rc) {
        tl_bake_close(&b);
        fprintf(stderr, "lbk export: %s\n", err);
        return LBK_EXIT_IO;
    }
    if (!quiet && (o.exr_dir || o.png_dir))
        printf("%s: %u EXR, %u PNG, %u listing files (preview exposure %.6g)\n", in, s.exr_files, s.png_files,
               s.text_files, s.exposure);
    if (g.output) {
        const char *base = strrchr(in, '/');
        g.container = base ? base + 1 : in;
        tl_gltf_stats gs;
        rc = tl_gltf_export(&b, &g, &gs, err);
        if (rc) {
            tl_bake_close(&b);
            fprintf(stderr, "lbk export: %s\n", err);
            return rc == TL_GLTF_IO ? LBK_EXIT_IO : rc == TL_GLTF_INPUT ? LBK_EXIT_INPUT : LBK_EXIT_INTERNAL;
        }
        if (!quiet)
            printf("%s: %u nodes, %u primitives (%u lightmapped: %u authored, %u generated), %llu triangles, %llu "
                   "vertices; %u pages (%u EXR, %u PNG, preview exposure %.6g)\n",
                   g.output, gs.nodes, gs.primitives, gs.lightmapped, gs.authored, gs.generated,
                   (unsigned long long)gs.triangles, (unsigned long long)gs.vertices, gs.pages, gs.exr_files,
                   gs.png_files, gs.exposure);
    }
    tl_bake_close(&b);
    return LBK_EXIT_OK;
}

int lbk_cmd_export(int argc, char **argv) { return cli_run_guarded("export", export_main, argc, argv); }
