/* lbk convert: console-ready packs from a profile. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cJSON.h>

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
            "usage: lbk convert IN.lbk -o OUT.lbk --profile NAME|FILE [--from-exr DIR] [--max-memory SIZE] [--json] [-q]\n"
            "       lbk convert --list-profiles\n"
            "\n"
            "Repacks a container for a platform: section alignment, per-section compression (none for\n"
            "hardware decompressors and zero-copy upload, zstd otherwise), which sections ship (packs drop\n"
            "META provenance and the REPT bake report) and the lightmap page layout (row pitch, page\n"
            "alignment). Profiles are files: tools/convert/profiles/README.md documents the format.\n"
            "The output is validated before it is written (atomically); the same input and profile always\n"
            "give the same bytes. A profile that block-encodes the lightmap (BC6H, ASTC) is checked by\n"
            "decoding what was encoded: the summary gives the pack's error against the input (luminance\n"
            "and colour, mean / p99 / max, all texels, chart seams and the worst objects) and whether it\n"
            "meets the goal mean <= 1 %%, p99 <= 5 %% (tools/convert/profiles/README.md \"Pack error\").\n"
            "\n"
            "  -o, --output OUT.lbk   the pack to write (required)\n"
            "  --profile NAME|FILE    a profile name (found: %s)\n"
            "                         or a .profile file path; names are looked up in $LBK_PROFILE_PATH,\n"
            "                         <lbk dir>/../tools/convert/profiles, <lbk dir>/../share/lbk/profiles, ./tools/convert/profiles\n"
            "  --from-exr DIR         import edited lightmap pages written by `lbk export --exr DIR`:\n"
            "                         page_NNN.exr (R,G,B = irradiance along +Z) replaces plane 0 of page NNN;\n"
            "                         page_NNN.ahd.exr (plane1.R/G/B/A), when present, replaces plane 1\n"
            "  --list-profiles        print the profiles found on the search path and exit\n"
            "  --json                 the summary as one JSON document on stdout (schema \"lbk-convert/1\",\n"
            "                         spec/inspect-json.md), per object errors included\n"
            CLI_MAX_MEMORY_HELP
            "  -q, --quiet            no summary on stdout\n"
            "  -h, --help             this text\n"
            "\n"
            "exit codes: 0 written, 2 usage (incl. a bad or unknown profile), 3 I/O error,\n"
            "            4 unusable input (invalid container, bad EXR page), 5 internal error\n",
            known[0] ? known : "none");
}

static const char *compression_name(uint32_t c) { return c == LBK_COMPRESSION_ZSTD ? "zstd" : "none"; }

static void print_summary(const char *in, const char *out, const char *exr_dir, const tl_profile *profile,
                          const tl_convert_report *rep)
{
    printf("%s -> %s with profile %s (alignment %u)\n", in, out, profile->name, profile->alignment);
    printf("  %-4s  %-12s %12s  %12s  %s\n", "sect", "action", "in bytes", "out bytes", "decoded");
    for (uint32_t i = 0; i < rep->section_count; i++) {
        const tl_convert_section *s = &rep->sections[i];
        char t[5];
        lbk_fourcc_string(s->type, t);
        char action[24];
        if (s->dropped) snprintf(action, sizeof action, "dropped");
        else snprintf(action, sizeof action, "%s%s", compression_name(s->compression), s->relaid ? "+layout" : "");
        printf("  %-4s  %-12s %12llu  %12llu  %llu\n", t, action, (unsigned long long)s->in_stored,
               (unsigned long long)s->out_stored, (unsigned long long)(s->dropped ? 0 : s->out_decoded));
    }
    printf("  file  %-12s %12llu  %12llu\n", "", (unsigned long long)rep->in_size, (unsigned long long)rep->out_size);
    if (exr_dir) printf("  imported %u page(s) from %s\n", rep->pages_imported, exr_dir);
    if (profile->lmap_format[0] || profile->lmap_format[1])
        printf("  lightmap planes %s + %s: block-encoded in %.2f s\n", tl_lmap_format_name(0, profile->lmap_format[0]),
               tl_lmap_format_name(1, profile->lmap_format[1]), rep->encode_seconds);
}

static void print_part(const char *what, const tl_pack_part *p)
{
    if (!p->lum.samples) return;
    printf("    %-14s luminance %6.2f %% / %6.2f %% / %6.2f %%   colour %.4f / %.4f / %.4f\n", what,
           100 * p->lum.mean, 100 * p->lum.p99, 100 * p->lum.max, p->colour.mean, p->colour.p99, p->colour.max);
}

/* Objects by descending luminance p99 (ties: by index). */
static const tl_pack_error *sort_pe;
static int by_p99(const void *a, const void *b)
{
    const tl_pack_object_error *x = &sort_pe->objects[*(const uint32_t *)a], *y = &sort_pe->objects[*(const uint32_t *)b];
    if (x->all.lum.p99 != y->all.lum.p99) return x->all.lum.p99 < y->all.lum.p99 ? 1 : -1;
    return (x->object > y->object) - (x->object < y->object);
}

static void print_pack_error(const tl_pack_error *pe)
{
    const int met = tl_pack_error_meets(&pe->all.lum, TL_PACK_GOAL_MEAN, TL_PACK_GOAL_P99);
    printf("  pack error against the input, %llu texels x 5 normals (mean / p99 / max; luminance |dY|/Y,\n"
           "  colour |d(r,g)| of the chromaticity):\n",
           (unsigned long long)pe->texels);
    print_part("all texels", &pe->all);
    print_part("seam texels", &pe->seam);
    if (pe->shared_block_texels) print_part("shared blocks", &pe->shared);
    uint32_t *order = malloc(((size_t)pe->object_count + 1) * sizeof *order);
    const uint32_t worst = pe->object_count < 5 ? pe->object_count : 5;
    if (order && worst) {
        for (uint32_t i = 0; i < pe->object_count; i++) order[i] = i;
        sort_pe = pe;
        qsort(order, pe->object_count, sizeof *order, by_p99);
        printf("    worst objects (luminance p99):");
        for (uint32_t k = 0; k < worst; k++)
            printf("%s %s %.2f %%", k ? "," : "", pe->objects[order[k]].name, 100 * pe->objects[order[k]].all.lum.p99);
        printf("\n");
    }
    free(order);
    printf("  goal mean <= %g %%, p99 <= %g %%: %s\n", 100 * TL_PACK_GOAL_MEAN, 100 * TL_PACK_GOAL_P99,
           met ? "met" : "NOT met");
}

static cJSON *stats_json(const tl_pack_stats *s)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "samples", (double)s->samples);
    cJSON_AddNumberToObject(j, "mean", s->mean);
    cJSON_AddNumberToObject(j, "p99", s->p99);
    cJSON_AddNumberToObject(j, "max", s->max);
    return j;
}

static cJSON *part_json(const tl_pack_part *p)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddItemToObject(j, "luminance", stats_json(&p->lum));
    cJSON_AddItemToObject(j, "colour", stats_json(&p->colour));
    return j;
}

static cJSON *pack_error_json(const tl_pack_error *pe)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "texels", (double)pe->texels);
    cJSON_AddNumberToObject(j, "luminance_floor", pe->y_floor);
    cJSON_AddNumberToObject(j, "shared_block_texels", (double)pe->shared_block_texels);
    cJSON_AddItemToObject(j, "all", part_json(&pe->all));
    cJSON_AddItemToObject(j, "seam", part_json(&pe->seam));
    cJSON_AddItemToObject(j, "shared_blocks", part_json(&pe->shared));
    cJSON *goal = cJSON_AddObjectToObject(j, "goal");
    cJSON_AddNumberToObject(goal, "mean", TL_PACK_GOAL_MEAN);
    cJSON_AddNumberToObject(goal, "p99", TL_PACK_GOAL_P99);
    cJSON_AddBoolToObject(goal, "met", tl_pack_error_meets(&pe->all.lum, TL_PACK_GOAL_MEAN, TL_PACK_GOAL_P99));
    cJSON *objs = cJSON_AddArrayToObject(j, "objects");
    for (uint32_t i = 0; i < pe->object_count; i++) {
        const tl_pack_object_error *o = &pe->objects[i];
        cJSON *oj = cJSON_CreateObject();
        cJSON_AddNumberToObject(oj, "object", o->object);
        cJSON_AddStringToObject(oj, "name", o->name);
        cJSON_AddNumberToObject(oj, "texels", (double)o->texels);
        cJSON_AddItemToObject(oj, "all", part_json(&o->all));
        cJSON_AddItemToObject(oj, "seam", part_json(&o->seam));
        cJSON_AddItemToArray(objs, oj);
    }
    return j;
}

static int print_json(const char *in, const char *out, const tl_profile *profile, const tl_convert_report *rep,
                      const tl_pack_error *pe)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "schema", "lbk-convert/1");
    cJSON_AddStringToObject(j, "input", in);
    cJSON_AddStringToObject(j, "output", out);
    cJSON_AddStringToObject(j, "profile", profile->name);
    cJSON_AddNumberToObject(j, "alignment", profile->alignment);
    cJSON_AddNumberToObject(j, "in_bytes", (double)rep->in_size);
    cJSON_AddNumberToObject(j, "out_bytes", (double)rep->out_size);
    cJSON *secs = cJSON_AddArrayToObject(j, "sections");
    for (uint32_t i = 0; i < rep->section_count; i++) {
        const tl_convert_section *s = &rep->sections[i];
        char t[5];
        lbk_fourcc_string(s->type, t);
        cJSON *sj = cJSON_CreateObject();
        cJSON_AddStringToObject(sj, "type", t);
        cJSON_AddBoolToObject(sj, "dropped", s->dropped);
        cJSON_AddStringToObject(sj, "compression", s->dropped ? "none" : compression_name(s->compression));
        cJSON_AddBoolToObject(sj, "relaid", s->relaid);
        cJSON_AddNumberToObject(sj, "in_stored", (double)s->in_stored);
        cJSON_AddNumberToObject(sj, "out_stored", (double)s->out_stored);
        cJSON_AddNumberToObject(sj, "out_decoded", (double)(s->dropped ? 0 : s->out_decoded));
        cJSON_AddItemToArray(secs, sj);
    }
    cJSON_AddNumberToObject(j, "pages_imported", rep->pages_imported);
    if (profile->lmap_format[0] || profile->lmap_format[1]) {
        cJSON *lm = cJSON_AddObjectToObject(j, "lightmap");
        cJSON_AddStringToObject(lm, "plane0", tl_lmap_format_name(0, profile->lmap_format[0]));
        cJSON_AddStringToObject(lm, "plane1", tl_lmap_format_name(1, profile->lmap_format[1]));
        cJSON_AddNumberToObject(lm, "encode_seconds", rep->encode_seconds);
    }
    if (pe) cJSON_AddItemToObject(j, "pack_error", pack_error_json(pe));
    else cJSON_AddNullToObject(j, "pack_error");
    if (rep->pack_error_skipped[0]) cJSON_AddStringToObject(j, "pack_error_skipped", rep->pack_error_skipped);
    char *text = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    if (!text) {
        fprintf(stderr, "lbk convert: out of memory\n");
        return LBK_EXIT_INTERNAL;
    }
    printf("%s\n", text);
    cJSON_free(text);
    return LBK_EXIT_OK;
}

int lbk_cmd_convert(int argc, char **argv)
{
    const time_t started = time(NULL); /* stale temporary files: older than a minute before this */
    const char *in = NULL, *out = NULL, *profile_arg = NULL, *exr_dir = NULL;
    int quiet = 0, json = 0;
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
        } else if (!strcmp(a, "--json")) {
            json = 1;
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
    tl_pack_error pe;
    memset(&pe, 0, sizeof pe);
    /* only a block-encoded lightmap can differ from the input's (other packs keep its texels), and
     * only a summary shows the difference (-q without --json skips the decoding) */
    const int block = profile.lmap_format[0] || profile.lmap_format[1];
    tl_convert_options opt = {.profile = &profile, .from_exr_dir = exr_dir, .max_decoded_bytes = max_memory,
                              .pack_error = block && (json || !quiet) ? &pe : NULL};
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
    int rc = LBK_EXIT_OK;
    if (tl_remove_stale_temps(out, started - 60, NULL, NULL) > 0)
        fprintf(stderr, "lbk convert: removed temporary files an interrupted write to %s left behind\n", out);
    if (tl_write_file_atomic(out, pack, pack_size, err)) {
        fprintf(stderr, "lbk convert: %s\n", err);
        rc = LBK_EXIT_IO;
    } else if (json) {
        rc = print_json(in, out, &profile, &rep, rep.pack_error_computed ? &pe : NULL);
    } else if (!quiet) {
        print_summary(in, out, exr_dir, &profile, &rep);
        if (rep.pack_error_computed) print_pack_error(&pe);
        else if (rep.pack_error_skipped[0]) printf("  pack error not measured: %s\n", rep.pack_error_skipped);
    }
    free(pack);
    tl_pack_error_free(&pe);
    return rc;
}
