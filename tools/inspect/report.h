/* lbk inspect's numbers for one container (spec/inspect-json.md): per section the bytes on disk,
 * decoded and GPU-resident, header, table and padding bytes (the disk column adds up to the file
 * size), the level statistics of seed 001 Table 1, and the JSON document `lbk inspect --json`
 * prints, which `lbk view` also puts in its page. */
#ifndef LBK_INSPECT_REPORT_H
#define LBK_INSPECT_REPORT_H

#include <stdint.h>

#include "lbk/container.h"
#include "tools/inspect/budget.h"
#include "tools/inspect/describe.h"
#include "tools/inspect/memory.h"

typedef struct tl_inspect_section {
    lbk_section_info info;
    char type[5];
    int known;       /* this build has a describer for the type */
    int readable;    /* section_data succeeded */
    lbk_result error;
    inspect_stats st;
} tl_inspect_section;

typedef struct tl_inspect_report {
    const char *path;
    const lbk_header_info *h;
    uint32_t count;
    tl_inspect_section rows[LBK_MAX_SECTIONS];
    uint64_t header_bytes, table_bytes, padding_bytes, disk_total, decoded_total, gpu_total;
    uint64_t memory_without_dls, memory_with_dls;
    inspect_stats level;
    int any_unreadable;
    const tl_level_memory *memory; /* per object / light set (a valid file), else NULL */
    const char *memory_error;
    const tl_budget *budget;       /* --budget, else NULL */
    const tl_budget_result *budget_result;
} tl_inspect_report;

/* Every section of an open reader described and summed into r (path: as the report names the
 * file; r->h points into the reader, which must outlive r). */
void tl_inspect_scan(lbk_reader *reader, const char *path, tl_inspect_report *r);
/* The "lbk-inspect/1" document of a report; NULL when out of memory. Free it with free(). */
char *tl_inspect_json(const tl_inspect_report *r);
/* The document of the file at path as `lbk inspect --json PATH` prints it (per-object memory
 * included; no budget): 0 and *json (free()), or -1 when the file cannot be read, some section
 * does not read, or out of memory. max_memory: the reader's decode cap (0: liblbk's default). */
int tl_inspect_file_json(const char *path, uint64_t max_memory, char **json);

#endif
