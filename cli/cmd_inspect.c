/* lbk inspect FILE [--json]: memory per level. Per section the bytes on disk, decoded and
 * GPU-resident; header, table and padding bytes so that the disk column adds up exactly to the
 * file size; then the level statistics laid out like Table 1 of seed 001. */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/options.h"
#include "tools/common/bake_data.h"
#include "tools/inspect/report.h"
#include "lbk/container.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lbk inspect FILE [--json] [--budget SIZE|FILE] [--max-memory SIZE]\n"
            "\n"
            "Memory per level: for each section the bytes on disk, decoded bytes and GPU-resident\n"
            "bytes, plus header, table and padding bytes (the disk column adds up to the file size),\n"
            "then the level statistics of seed 001 Table 1 (lightmap texels, LLG probes, GLG probes,\n"
            "dynamic light sets, doors, memory without and with DLS).\n"
            "\n"
            "With --json also the GPU memory of every object (lightmap texels, LLG probes, the light-set\n"
            "entries that touch it) and of every light set, for a pipeline to chart per revision.\n"
            "\n"
            "  --json           one JSON document (schema \"lbk-inspect/1\", spec/inspect-json.md)\n"
            "  --budget SIZE    a build gate: fail when the level's GPU memory exceeds SIZE (e.g. 48MiB)\n"
            "  --budget FILE    ... or the limits of a budget file: total, per section type, per object,\n"
            "                   per light set (spec/inspect-json.md \"Budget files\"); every item over its\n"
            "                   limit is named\n"
            CLI_MAX_MEMORY_HELP
            "  --help           this text\n"
            "\n"
            "exit codes: 0 ok (within budget), 1 over budget, 2 usage, 3 I/O error, 4 not a readable\n"
            "            container (run lbk validate; --budget and per-object numbers need a valid one),\n"
            "            5 internal\n");
}

/* 1234567 → "1,234,567" */
static const char *grouped(uint64_t v, char buf[32])
{
    char tmp[32];
    int n = snprintf(tmp, sizeof tmp, "%" PRIu64, v), o = 0;
    for (int i = 0; i < n; i++) {
        buf[o++] = tmp[i];
        if ((n - i - 1) % 3 == 0 && i != n - 1) buf[o++] = ',';
    }
    buf[o] = '\0';
    return buf;
}

/* Table 1 gives MB; small levels read better in kB or bytes. Decimal units. */
static void human_bytes(uint64_t v, char *buf, size_t n)
{
    if (v < 10000) snprintf(buf, n, "%" PRIu64 " B", v);
    else if (v < 10000000) snprintf(buf, n, "%.1f kB", (double)v / 1e3);
    else snprintf(buf, n, "%.1f MB", (double)v / 1e6);
}

static void print_text(const tl_inspect_report *r)
{
    char a[32], b[32], c[32];
    printf("%s: lbk container %u.%u, %u section%s, alignment %u, %s bytes\n\n", r->path, r->h->version_major,
           r->h->version_minor, r->count, r->count == 1 ? "" : "s", r->h->section_alignment,
           grouped(r->h->file_size, a));
    printf("%-8s %-5s %14s %14s %14s  %s\n", "section", "comp", "on disk", "decoded", "GPU", "detail");
    printf("%-8s %-5s %14s %14s %14s  %s\n", "header", "", grouped(r->header_bytes, a), "-", "-", "64-byte header");
    printf("%-8s %-5s %14s %14s %14s  %s\n", "table", "", grouped(r->table_bytes, a), "-", "-", "48 bytes per section");
    for (uint32_t i = 0; i < r->count; i++) {
        const tl_inspect_section *s = &r->rows[i];
        char detail[260];
        if (!s->readable) snprintf(detail, sizeof detail, "unreadable: %s", lbk_result_name(s->error));
        else if (!s->known) snprintf(detail, sizeof detail, "unknown optional section (skipped)");
        else if (!s->st.parsed) snprintf(detail, sizeof detail, "payload did not parse (run lbk validate); GPU unknown");
        else snprintf(detail, sizeof detail, "%s", s->st.detail);
        printf("%-8s %-5s %14s %14s %14s  %s%s\n", s->type, s->info.compression ? "zstd" : "none",
               grouped(s->info.stored_size, a), s->readable ? grouped(s->info.decoded_size, b) : "?",
               grouped(s->st.gpu_bytes, c), detail, (s->info.flags & LBK_SECTION_FLAG_REQUIRED) ? " [required]" : "");
    }
    printf("%-8s %-5s %14s %14s %14s  %s\n", "padding", "", grouped(r->padding_bytes, a), "-", "-",
           "zero bytes for section alignment");
    printf("%-8s %-5s %14s %14s %14s\n", "total", "", grouped(r->disk_total, a), grouped(r->decoded_total, b),
           grouped(r->gpu_total, c));
    printf("check: header + table + sections + padding = %s bytes %s file size %s bytes%s\n\n",
           grouped(r->disk_total, a), r->disk_total == r->h->file_size ? "==" : "!=", grouped(r->h->file_size, b),
           r->disk_total == r->h->file_size ? "" : "  MISMATCH");

    const inspect_stats *l = &r->level;
    printf("level statistics (as in seed 001, Table 1)\n");
    printf("%14s %14s %14s %8s %8s %18s %18s\n", "# LM texels", "# LLG probes", "# GLG probes", "# DLS", "# doors",
           "memory (no DLS)", "memory (DLS)");
    char m1[40], m2[40], d[32], e[32];
    human_bytes(r->memory_without_dls, m1, sizeof m1);
    human_bytes(r->memory_with_dls, m2, sizeof m2);
    snprintf(d, sizeof d, "%" PRIu64, l->dls_light_sets);
    snprintf(e, sizeof e, "%" PRIu64, l->doors);
    printf("%14s %14s %14s %8s %8s %18s %18s\n", grouped(l->lm_texels, a), grouped(l->llg_probes, b),
           grouped(l->glg_probes, c), d, e, m1, m2);
    printf("\n  lightmap pages %" PRIu64 ", LLG grids %" PRIu64 ", GLG tetrahedra %" PRIu64 ", octahedral probes %" PRIu64
           ", objects %" PRIu64 "\n",
           l->lm_pages, l->llg_grids, l->glg_tetrahedra, l->octp_probes, l->objects);
    printf("  DLS: %" PRIu64 " sets in all, %" PRIu64 " clusters, payload %s B, ancillary %s B; door states %" PRIu64
           "\n",
           l->dls_sets, l->dls_clusters, grouped(l->dls_payload_bytes, a), grouped(l->dls_ancillary_bytes, b),
           l->door_states);
    printf("  memory = GPU-resident bytes; \"no DLS\" leaves out the DLS and DOOR sections\n");
    if (r->budget) {
        const tl_budget_result *br = r->budget_result;
        printf("\nbudget %s: %zu limits checked, %s\n", r->budget->name, br->checked,
               br->violation_count ? "OVER BUDGET" : "within budget");
        for (size_t i = 0; i < br->violation_count; i++) {
            const tl_budget_violation *v = &br->violations[i];
            printf("  over budget: %s%s%s %s B > %s B (by %s B)\n", tl_budget_kind_name(v->kind), v->name[0] ? " " : "",
                   v->name, grouped(v->bytes, a), grouped(v->limit, b), grouped(v->bytes - v->limit, c));
        }
    }
}

static int print_json(const tl_inspect_report *r)
{
    char *text = tl_inspect_json(r);
    if (!text) return 0;
    puts(text);
    free(text);
    return 1;
}

int lbk_cmd_inspect(int argc, char **argv)
{
    const char *path = NULL, *budget_arg = NULL;
    int json = 0;
    uint64_t max_memory = 0;
    for (int i = 1; i < argc; i++) {
        const int mm = cli_max_memory_option("inspect", argc, argv, &i, &max_memory);
        if (mm < 0) return LBK_EXIT_USAGE;
        if (mm) continue;
        if (!strcmp(argv[i], "--json")) json = 1;
        else if (!strcmp(argv[i], "--budget")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "lbk inspect: --budget needs a SIZE or a FILE\n");
                return LBK_EXIT_USAGE;
            }
            budget_arg = argv[++i];
        }
        else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return LBK_EXIT_OK;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "lbk inspect: unknown option '%s'\n", argv[i]);
            usage(stderr);
            return LBK_EXIT_USAGE;
        } else if (path) {
            fprintf(stderr, "lbk inspect: one FILE only ('%s' and '%s')\n", path, argv[i]);
            return LBK_EXIT_USAGE;
        } else {
            path = argv[i];
        }
    }
    if (!path) {
        usage(stderr);
        return LBK_EXIT_USAGE;
    }
    static tl_budget budget;
    char err[TL_ERR_LEN];
    if (budget_arg && tl_budget_load(budget_arg, &budget, err)) {
        fprintf(stderr, "lbk inspect: %s\n", err);
        return LBK_EXIT_USAGE;
    }
    lbk_reader *reader;
    errno = 0;
    lbk_read_options ro = LBK_READ_OPTIONS_INIT;
    ro.max_decoded_bytes = max_memory;
    lbk_result res = lbk_reader_open_file(path, &ro, &reader);
    if (res == LBK_ERR_IO) {
        fprintf(stderr, "lbk inspect: %s: %s\n", path, errno ? strerror(errno) : lbk_result_message(res));
        return LBK_EXIT_IO;
    }
    if (res == LBK_ERR_OUT_OF_MEMORY) {
        fprintf(stderr, "lbk inspect: out of memory\n");
        return LBK_EXIT_INTERNAL;
    }
    if (res != LBK_OK) {
        fprintf(stderr, "lbk inspect: %s: not a readable container: %s (%s); run 'lbk validate %s'\n", path,
                lbk_result_name(res), lbk_result_message(res), path);
        return LBK_EXIT_INPUT;
    }

    static tl_inspect_report r; /* large (64 rows); one per process */
    tl_inspect_scan(reader, path, &r);

    /* per object and light set: needs the views, so a file that validates */
    tl_bake bake;
    tl_level_memory mem;
    int have_mem = 0;
    if (json || budget_arg) {
        tl_open_status st = tl_bake_open_file_capped(path, max_memory, &bake, err);
        if (st == TL_OPEN_OK) {
            if (tl_level_memory_get(&bake, &mem) == 0) have_mem = 1, r.memory = &mem;
            else r.memory_error = "out of memory";
            tl_bake_close(&bake);
        } else {
            r.memory_error = "the file does not validate (run lbk validate)";
        }
    }
    tl_budget_result br = {0};
    uint32_t types[LBK_MAX_SECTIONS];
    uint64_t gpu[LBK_MAX_SECTIONS];
    if (budget_arg) {
        for (uint32_t i = 0; i < r.count; i++) types[i] = r.rows[i].info.type, gpu[i] = r.rows[i].st.gpu_bytes;
        tl_budget_level lv = {r.memory_with_dls, types, gpu, r.count, r.memory};
        if (!r.memory) {
            fprintf(stderr, "lbk inspect: %s: %s; a budget needs a valid container\n", path, r.memory_error);
            lbk_reader_close(reader);
            return LBK_EXIT_INPUT;
        }
        if (tl_budget_check(&budget, &lv, &br)) {
            fprintf(stderr, "lbk inspect: out of memory\n");
            lbk_reader_close(reader);
            if (have_mem) tl_level_memory_free(&mem);
            return LBK_EXIT_INTERNAL;
        }
        r.budget = &budget;
        r.budget_result = &br;
    }

    int ok = 1;
    if (json) ok = print_json(&r);
    else print_text(&r);
    lbk_reader_close(reader);
    if (have_mem) tl_level_memory_free(&mem);
    const int over = br.violation_count > 0;
    tl_budget_result_free(&br);
    if (!ok) {
        fprintf(stderr, "lbk inspect: out of memory\n");
        return LBK_EXIT_INTERNAL;
    }
    if (r.any_unreadable) {
        fprintf(stderr, "lbk inspect: %s: some sections could not be read; run 'lbk validate %s'\n", path, path);
        return LBK_EXIT_INPUT;
    }
    if (over) {
        if (json) fprintf(stderr, "lbk inspect: %s: over budget %s\n", path, budget.name);
        return LBK_EXIT_NEGATIVE;
    }
    return LBK_EXIT_OK;
}
