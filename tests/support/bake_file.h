/* Baking a glTF file through liblbkbake (lbk/bake.h) the way `lbk bake` does, for tests and
 * benches: quiet, the container written atomically (nothing on failure), optionally the JSON
 * report, the report's numbers kept. */
#ifndef TB_BAKE_FILE_H
#define TB_BAKE_FILE_H

#include <stddef.h>

#include "lbk/bake.h"

/* A bake as `lbk bake IN -o OUT [--json-report JSON]` with the options in d. */
typedef struct tb_job {
    const char *in, *out, *json;   /* glTF, container, JSON report (NULL: none) */
    lbk_bake_desc d;               /* its message/user fields are replaced */
} tb_job;

/* report (may be NULL) gets the report's numbers; its pointers are cleared (they die with the
 * output). err gets the ERROR message, or the result's text. Returns the bake's lbk_result, or
 * that of writing the container or the JSON. */
lbk_result tb_bake(const tb_job *job, lbk_bake_report *report, char *err, size_t err_len);

#endif
