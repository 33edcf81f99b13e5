/* lbk convert: console-ready packs from a profile. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli/cli.h"
#include "cli/options.h"
#include "tools/common/lmap_decode.h"
#include "tools/convert/convert.h"
#include "tools/common/file_util.h"
#include "tools/common/output_guard.h"

static void usage(FILE *f)
{
    char known[256];
    tl_profile_list(NULL, known, sizeof known);
    fprintf(f,
            "usage: lbk convert IN.lbk -o OUT.lbk --profile NAME|FILE [--from-exr DIR] [--max-memory SIZE] [-q]\n"
            "       lbk convert --list-profiles\n"
            "\n"
            "Repacks a container for a platform: section alignment, per-section compression (none for\n"
            "hardware decompressors and zero-copy upload, zstd otherwise), which sections ship (packs drop\n"
            "META provenance and the REPT bake report) and the lightmap page layout (row pitch, page\n"
            "alignment). Profiles are files: tools/convert/profiles/README.md documents the format.\n"
            "The output is validated before it is written (atomically); the same input and profile always\n"
            "give the same bytes.\n"
            "\n"
            "  -o, --output OUT.lbk   the pack to write (required)\n"
            "  --profile NAME|FILE    a profile name (found: %s)\n"
            "                         or a .profile file path; names are looked up in $LBK_PROFILE_PATH,\n"
            "                         <lbk dir>/../tools/convert/profiles, <lbk dir>/../share/lbk/profiles, ./tools/convert/profiles\n"
            "  --from-exr DIR         import edited lightmap pages written by `lbk export --exr DIR`:\n"
            "                         page_NNN.exr (R,G,B = irradiance along +Z) replaces plane 0 of page NNN;\n"
            "                         page_NNN.ahd.exr (plane1.R/G/B/A), when present, replaces plane 1\n"
            "  --list-profiles        print the profiles found on the search path and exit\n"
            CLI_MAX_MEMORY_HELP
            "  -q, --quiet            no summary on stdout\n"
            "  -h, --help             this text\n"
            "\n"
            "exit codes: 0 written, 2 usage (incl. a bad or unknown profile), 3 I/O error,\n"
            "            4 unusable input (invalid container, bad EXR page), 5 internal error\n",
            known[0] ? known : "none");
}

static const char *compression_name(uint32_t c) { return c == LBK_COMPRESSION_ZSTD ? "zstd" : "none"; }

int lbk_cmd_convert(int argc, char **argv)
{
    const time_t started = time(NULL); /* stale temporary files: older than a minute before this */
    const char *in = NULL, *out = NULL, *profile_arg = NULL, *exr_dir = NULL;
    int quiet = 0;
    uint64_t max_memory = 0;
    for (int i = 1; i < argc; i++) {
        const int mm = cli_max_memory_option("convert", argc, argv, &i, &max_memory);
        if (mm < 0) return LBK_EXIT_USAGE;
        if (mm) continue;
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return LBK_EXIT_OK;
        } else if (!strcmp(a, "--list-profiles")) {
            char known[1024];
            tl_profile_list(NULL, known, sizeof known);
            printf("%s\n", known);
            return LBK_EXIT_OK;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            quiet = 1;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--profile") || !strcmp(a, "--from-exr"))) {
            if (i + 1 >= argc) {
                fprintf(stderr, "lbk convert: %s needs a value\n", a);
                return LBK_EXIT_USAGE;
            }
            const char **dst = !strcmp(a, "--profile") ? &profile_arg : !strcmp(a, "--from-exr") ? &exr_dir : &out;
            if (*dst) {
                fprintf(stderr, "lbk convert: %s given twice\n", a);
                return LBK_EXIT_USAGE;
            }
            *dst = argv[++i];
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk convert: unknown option '%s' (see lbk convert --help)\n", a);
            return LBK_EXIT_USAGE;
        } else if (!in) {
            in = a;
        } else {
            fprintf(stderr, "lbk convert: more than one input ('%s' and '%s')\n", in, a);
            return LBK_EXIT_USAGE;
        }
    }
    if (!in || !out || !profile_arg) {
        fprintf(stderr, "lbk convert: need IN.lbk, -o OUT.lbk and --profile (see lbk convert --help)\n");
        return LBK_EXIT_USAGE;
    }
    tl_guard guard;
    tl_guard_init(&guard, "convert");
    const char *outs[] = {"-o", out, NULL, NULL};
    int guarded = tl_guard_input(&guard, in, "the container") || tl_guard_input(&guard, profile_arg, "the profile") ||
                          tl_guard_input_dir(&guard, exr_dir, "an EXR page of --from-exr")
                      ? LBK_EXIT_INTERNAL
                      : cli_check_outputs("convert", &guard, outs);
    tl_guard_free(&guard);
    if (guarded) return guarded;
    char err[TL_ERR_LEN];
    tl_profile profile;
    if (tl_profile_resolve(profile_arg, NULL, &profile, err)) {
        fprintf(stderr, "lbk convert: %s\n", err);
        return LBK_EXIT_USAGE;
    }
    void *in_bytes = NULL;
    size_t in_size = 0;
    if (tl_read_file(in, &in_bytes, &in_size, err)) {
        fprintf(stderr, "lbk convert: %s\n", err);
        return LBK_EXIT_IO;
    }
    tl_convert_options opt = {.profile = &profile, .from_exr_dir = exr_dir, .max_decoded_bytes = max_memory};
    void *pack = NULL;
    size_t pack_size = 0;
    tl_convert_report rep;
    tl_convert_status st = tl_convert_memory(in_bytes, in_size, &opt, &pack, &pack_size, &rep, err);
    free(in_bytes);
    if (st != TL_CONVERT_OK) {
        fprintf(stderr, "lbk convert: %s: %s\n", in, err);
        return st == TL_CONVERT_IO ? LBK_EXIT_IO
               : st == TL_CONVERT_BAD_INPUT || st == TL_CONVERT_BAD_EXR ? LBK_EXIT_INPUT
               : st == TL_CONVERT_UNSUPPORTED ? LBK_EXIT_INPUT
                                              : LBK_EXIT_INTERNAL;
    }
    if (tl_remove_stale_temps(out, started - 60, NULL, NULL) > 0)
        fprintf(stderr, "lbk convert: removed temporary files an interrupted write to %s left behind\n", out);
    if (tl_write_file_atomic(out, pack, pack_size, err)) {
        free(pack);
        fprintf(stderr, "lbk convert: %s\n", err);
        return LBK_EXIT_IO;
    }
    free(pack);
    if (!quiet) {
        printf("%s -> %s with profile %s (alignment %u)\n", in, out, profile.name, profile.alignment);
        printf("  %-4s  %-12s %12s  %12s  %s\n", "sect", "action", "in bytes", "out bytes", "decoded");
        for (uint32_t i = 0; i < rep.section_count; i++) {
            const tl_convert_section *s = &rep.sections[i];
            char t[5];
            lbk_fourcc_string(s->type, t);
            char action[24];
            if (s->dropped) snprintf(action, sizeof action, "dropped");
            else snprintf(action, sizeof action, "%s%s", compression_name(s->compression), s->relaid ? "+layout" : "");
            printf("  %-4s  %-12s %12llu  %12llu  %llu\n", t, action, (unsigned long long)s->in_stored,
                   (unsigned long long)s->out_stored, (unsigned long long)(s->dropped ? 0 : s->out_decoded));
        }
        printf("  file  %-12s %12llu  %12llu\n", "", (unsigned long long)rep.in_size, (unsigned long long)rep.out_size);
        if (exr_dir) printf("  imported %u page(s) from %s\n", rep.pages_imported, exr_dir);
        if (profile.lmap_format[0] || profile.lmap_format[1])
            printf("  lightmap planes %s + %s: block-encoded in %.2f s\n", tl_lmap_format_name(0, profile.lmap_format[0]),
                   tl_lmap_format_name(1, profile.lmap_format[1]), rep.encode_seconds);
    }
    return LBK_EXIT_OK;
}
