#include "cli/progress.h"

#include <stdarg.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void cli_progress_init(cli_progress *p, int quiet)
{
    memset(p, 0, sizeof *p);
    p->out = quiet ? NULL : stderr;
    p->tty = p->out && isatty(fileno(p->out));
    p->start = p->phase_start = now_seconds();
    p->last_decile = -1;
}

static void clear_line(cli_progress *p)
{
    if (p->tty) fputs("\r\033[K", p->out);
}

void cli_progress_phase(cli_progress *p, const char *phase)
{
    if (!p->out) return;
    if (p->tty && p->phase[0]) {
        clear_line(p);
        fprintf(p->out, "  %-8s done in %.1f s\n", p->phase, now_seconds() - p->phase_start);
    }
    snprintf(p->phase, sizeof p->phase, "%s", phase);
    p->phase_start = now_seconds();
    p->last_decile = -1;
    p->last_draw = 0;
    if (!p->tty) fprintf(p->out, "lbk bake: %s...\n", phase);
    fflush(p->out);
}

void cli_progress_update(cli_progress *p, double f)
{
    if (!p->out) return;
    if (!(f >= 0)) f = 0;
    if (f > 1) f = 1;
    double now = now_seconds();
    if (p->tty) {
        if (now - p->last_draw < 0.1 && f < 1) return; /* redraw at most 10 times a second */
        p->last_draw = now;
        double el = now - p->phase_start;
        char eta[32] = "--";
        if (f > 0.01) snprintf(eta, sizeof eta, "%.0f s", el * (1 - f) / f);
        int w = 30, filled = (int)(f * w + 0.5);
        char bar[31];
        for (int i = 0; i < w; i++) bar[i] = i < filled ? '#' : '.';
        bar[w] = 0;
        fprintf(p->out, "\r\033[K  %-8s [%s] %3.0f%%  ETA %s", p->phase, bar, f * 100, eta);
    } else {
        int dec = (int)(f * 10);
        if (dec <= p->last_decile) return;
        p->last_decile = dec;
        fprintf(p->out, "lbk bake: %s %d%% (%.1f s)\n", p->phase, dec * 10, now - p->phase_start);
    }
    fflush(p->out);
}

void cli_progress_note(cli_progress *p, const char *fmt, ...)
{
    if (!p->out) return;
    clear_line(p);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(p->out, fmt, ap);
    va_end(ap);
    fputc('\n', p->out);
    p->last_draw = 0;
    fflush(p->out);
}

void cli_progress_done(cli_progress *p)
{
    if (!p->out) return;
    if (p->tty && p->phase[0]) {
        clear_line(p);
        fprintf(p->out, "  %-8s done in %.1f s\n", p->phase, now_seconds() - p->phase_start);
    }
    fprintf(p->out, "lbk bake: finished in %.1f s\n", now_seconds() - p->start);
    fflush(p->out);
}
