/* The baker's clock: monotonic seconds, for phase times and time limits (never stored in a
 * container unless a timestamp is asked for). */
#ifndef BK_CLOCK_H
#define BK_CLOCK_H

double bk_now(void);

#endif
