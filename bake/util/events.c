#include "bake/util/events.h"

#include <stdarg.h>
#include <stdio.h>

void bk_events_say(const bk_events *ev, lbk_bake_severity severity, const char *fmt, ...)
{
    if (!ev || !ev->message) return;
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    ev->message(ev->user, severity, text);
}

int bk_events_progress(const bk_events *ev, double fraction)
{
    return ev && ev->progress ? ev->progress(ev->user, fraction) : 0;
}
