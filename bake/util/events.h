/* How the phases talk to whoever runs the bake: messages with a severity and progress with
 * cancellation. bake/pipeline routes them to the callbacks of lbk_bake_desc; a phase never
 * prints. A zero bk_events drops messages and never cancels. */
#ifndef BK_EVENTS_H
#define BK_EVENTS_H

#include "lbk/bake.h"

typedef struct bk_events {
    void (*message)(void *user, lbk_bake_severity severity, const char *text);
    /* fraction of the current phase; non-zero: the caller cancelled */
    int (*progress)(void *user, double fraction);
    void *user;
} bk_events;

void bk_events_say(const bk_events *ev, lbk_bake_severity severity, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* 0: go on; non-zero: cancelled (the caller returns LBK_ERR_CANCELLED). NULL ev: 0. */
int bk_events_progress(const bk_events *ev, double fraction);

#endif
