/*
 * meso_clock.h — the one monotonic clock every layer times itself with
 * (bake stages, the programs' -v lines and reports, tests and benchmarks).
 * Internal, header-only. Timings never enter a .meso file.
 */
#ifndef MESO_CLOCK_H
#define MESO_CLOCK_H

#include <time.h>

/* Seconds on CLOCK_MONOTONIC: only differences mean anything. */
static inline double meso_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif /* MESO_CLOCK_H */
