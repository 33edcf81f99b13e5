/* lbk bake's progress: a bar with phase, percent and ETA on a terminal, plain lines otherwise
 * (logs, CI), nothing with --quiet. Writes to stderr; stdout stays for results. The library
 * reports progress and messages through callbacks (lbk/bake.h); this is how the CLI shows them. */
#ifndef LBK_CLI_PROGRESS_H
#define LBK_CLI_PROGRESS_H

#include <stdio.h>

typedef struct cli_progress {
    FILE *out;          /* NULL: silent */
    int tty;            /* redraw one line in place */
    double start;       /* monotonic seconds at creation */
    double phase_start;
    char phase[48];
    int last_decile;    /* plain mode: print at each 10% */
    double last_draw;
} cli_progress;

void cli_progress_init(cli_progress *p, int quiet);
/* Starts a phase ("import", "layout", "light", "sets", "write"). */
void cli_progress_phase(cli_progress *p, const char *phase);
/* fraction in [0,1] of the current phase. */
void cli_progress_update(cli_progress *p, double fraction);
/* A line that must not be overwritten by the bar (warnings, report samples). */
void cli_progress_note(cli_progress *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void cli_progress_done(cli_progress *p);

#endif
