/* See bake_file.h. */
#include "tests/support/bake_file.h"

#include <stdio.h>
#include <string.h>

typedef struct tb_err {
    char *text;
    size_t len;
} tb_err;

static void on_message(void *user, lbk_bake_severity severity, const char *message)
{
    tb_err *e = user;
    if (severity == LBK_BAKE_SEVERITY_ERROR && e->text && e->len) snprintf(e->text, e->len, "%s", message);
}

lbk_result tb_bake(const tb_job *job, lbk_bake_report *report, char *err, size_t err_len)
{
    const char *in = job->in, *out = job->out, *json = job->json;
    char dummy[1];
    tb_err e = {err && err_len ? err : dummy, err && err_len ? err_len : sizeof dummy};
    e.text[0] = 0;
    lbk_bake_desc d = job->d;
    d.size = sizeof d;
    d.message = on_message;
    d.user = &e;
    if (report) memset(report, 0, sizeof *report);
    lbk_bake_output *o = NULL;
    lbk_result r = lbk_bake_from_file(in, &d, &o);
    if (!r) {
        r = lbk_bake_output_write_file(o, out);
        if (r) snprintf(e.text, e.len, "writing %s: %s", out, lbk_result_message(r));
    }
    if (!r && json) {
        r = lbk_bake_report_write_json(lbk_bake_output_report(o), out, json);
        if (r) snprintf(e.text, e.len, "writing %s: %s", json, lbk_result_message(r));
    }
    if (!r && report) {
        *report = *lbk_bake_output_report(o);
        report->input = NULL;
        report->passes = NULL;
        report->phases = NULL; /* phase_count stays */
        report->pass_errors = NULL;
        report->set_runs = NULL; /* set_run_count stays: how many runs there were */
        report->set_estimates = NULL; /* set_estimate_count stays */
    }
    if (r && !e.text[0]) snprintf(e.text, e.len, "%s", lbk_result_message(r));
    lbk_bake_output_free(o);
    return r;
}
