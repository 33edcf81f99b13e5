/* Memory budgets as a build gate (lbk inspect --budget SIZE|FILE): a platform's limits on the GPU
 * memory of a level — in total, per section type, per object and per light set — checked against
 * a bake; every item over its limit is named. The file format is in spec/inspect-json.md
 * "Budget files"; tools/inspect/budgets/ holds examples. */
#ifndef LBK_INSPECT_BUDGET_H
#define LBK_INSPECT_BUDGET_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */
#include "tools/inspect/memory.h"

#define TL_BUDGET_MAX_RULES 64

typedef struct tl_budget_rule {
    char name[128];   /* section type code, object or light set name; "" for `default` */
    uint64_t limit;   /* bytes */
} tl_budget_rule;

typedef struct tl_budget {
    char name[64];                 /* `name =`, or the SIZE given */
    int has_total;
    uint64_t total;                /* GPU bytes of the whole level (every section) */
    tl_budget_rule sections[TL_BUDGET_MAX_RULES]; size_t section_count;  /* by type; "" = default */
    tl_budget_rule objects[TL_BUDGET_MAX_RULES]; size_t object_count;    /* by name; "" = default */
    tl_budget_rule sets[TL_BUDGET_MAX_RULES]; size_t set_count;          /* by name; "" = default */
} tl_budget;

/* "64MiB", "65536", "1.5 GB" → bytes (B, kB/KB = 1000, KiB = 1024, MB, MiB, GB, GiB; case of the
 * unit letters as written). Returns 0 or -1. */
int tl_budget_parse_size(const char *s, uint64_t *out);
/* Parses budget text (`origin` names it in errors). Returns 0 or -1 with err naming file and line. */
int tl_budget_parse(const char *text, size_t size, const char *origin, tl_budget *out, char err[TL_ERR_LEN]);
/* SIZE (a total) or a file path. */
int tl_budget_load(const char *size_or_file, tl_budget *out, char err[TL_ERR_LEN]);

typedef enum tl_budget_kind { TL_BUDGET_TOTAL = 0, TL_BUDGET_SECTION, TL_BUDGET_OBJECT, TL_BUDGET_LIGHT_SET } tl_budget_kind;
const char *tl_budget_kind_name(int kind); /* "total", "section", "object", "light_set" */

typedef struct tl_budget_violation {
    int kind;          /* tl_budget_kind */
    char name[128];    /* section type, object or set name; "" for the total */
    uint64_t bytes, limit;
} tl_budget_violation;

typedef struct tl_budget_result {
    tl_budget_violation *violations; size_t violation_count;
    size_t checked;    /* items that had a limit */
} tl_budget_result;

/* The level's numbers: GPU bytes per section type (gpu_bytes[i] of types[i]) and per object/set. */
typedef struct tl_budget_level {
    uint64_t total;
    const uint32_t *types; const uint64_t *gpu_bytes; size_t section_count;
    const tl_level_memory *memory; /* NULL: no per-object numbers (the file did not validate) */
} tl_budget_level;

/* Every limit against the level. Returns 0, or -1 when out of memory. */
int tl_budget_check(const tl_budget *b, const tl_budget_level *level, tl_budget_result *out);
void tl_budget_result_free(tl_budget_result *r);

#endif
