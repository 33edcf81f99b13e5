/* Wall-clock time for progress, reports and benchmarks; never for anything that goes into a file. */
#ifndef BK_CLOCK_H
#define BK_CLOCK_H

double bk_now(void); /* monotonic seconds since an arbitrary origin */

#endif
