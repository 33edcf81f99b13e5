/* lbk export: pages, planes, objects and probes as EXR/PNG/CSV/JSON. */
#include <stdio.h>
#include <string.h>

#include "cli/cli.h"
#include "tools/convert/export.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lbk export IN.lbk [--exr DIR] [--png DIR] [--per-object] [-q]   (at least one of --exr, --png)\n"
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
            "  --png DIR      page_NNN.png tone-mapped previews of page_NNN.exr: one exposure for all pages,\n"
            "                 1 / (99th percentile of Rec.709 luminance over all texels), then sRGB, 8 bits\n"
            "  --per-object   also DIR/objects/III_name.exr (and .png): each lightmapped object's irradiance\n"
            "                 at its rectangle's resolution; pixel (i, j) is TEXCOORD_1 ((i+0.5)/w, (j+0.5)/h)\n"
            "                 (III = the object's index in the object table)\n"
            "  both dirs get probes.csv and probes.json (GLG and LLG probes: position, irradiance at the six\n"
            "  axis normals, the SH9 coefficients) and glg_top.png (top view looking down -Y: x right,\n"
            "  z down; tetra edges grey; probes coloured black-blue-cyan-green-yellow-red by luminance of\n"
            "  their mean irradiance, red = 99th percentile, white above)\n"
            "  -q, --quiet    no summary\n"
            "  -h, --help     this text\n"
            "\n"
            "exit codes: 0 written, 2 usage, 3 I/O error (read or write), 4 the input is not a valid container,\n"
            "            5 internal error\n");
}

int lbk_cmd_export(int argc, char **argv)
{
    const char *in = NULL;
    tl_export_options o = {NULL, NULL, 0};
    int quiet = 0;
    for (int i = 1; i < argc; i++) {
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
    if (!in || (!o.exr_dir && !o.png_dir)) {
        fprintf(stderr, "lbk export: need IN.lbk and --exr DIR and/or --png DIR (see lbk export --help)\n");
        return LBK_EXIT_USAGE;
    }
    char err[TL_ERR_LEN];
    tl_bake b;
    tl_open_status st = tl_bake_open_file(in, &b, err);
    if (st != TL_OPEN_OK) {
        fprintf(stderr, "lbk export: %s\n", err);
        return st == TL_OPEN_IO ? LBK_EXIT_IO : st == TL_OPEN_INVALID ? LBK_EXIT_INPUT : LBK_EXIT_INTERNAL;
    }
    tl_export_stats s;
    int rc = tl_export(&b, &o, &s, err);
    tl_bake_close(&b);
    if (rc) {
        fprintf(stderr, "lbk export: %s\n", err);
        return LBK_EXIT_IO;
    }
    if (!quiet)
        printf("%s: %u EXR, %u PNG, %u listing files (preview exposure %.6g)\n", in, s.exr_files, s.png_files,
               s.text_files, s.exposure);
    return LBK_EXIT_OK;
}
