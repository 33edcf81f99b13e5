/* Progress on long work: a bar with phase, percent and ETA on a terminal, plain lines
 * otherwise (logs, CI), nothing with --quiet. Writes to stderr; stdout stays for results. */
#ifndef BK_PROGRESS_H
#define BK_PROGRESS_H

#include "bake/util/clock.h" /* bk_now, for the callers that still reach it through here */

#include <stdio.h>

typedef struct bk_progress {
    FILE *out;          /* NULL: silent */
    int tty;            /* redraw one line in place */
    double start;       /* monotonic seconds at creation */
    double phase_start;
    char phase[48];
    int last_decile;    /* plain mode: print at each 10% */
    double last_draw;
} bk_progress;

void bk_progress_init(bk_progress *p, int quiet);
/* Starts a phase ("import", "uv", "probes", "bake", "encode", "write"). */
void bk_progress_phase(bk_progress *p, const char *phase);
/* fraction in [0,1] of the current phase. */
void bk_progress_update(bk_progress *p, double fraction);
/* A line that must not be overwritten by the bar (warnings, report samples). */
void bk_progress_note(bk_progress *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void bk_progress_done(bk_progress *p);

#endif
