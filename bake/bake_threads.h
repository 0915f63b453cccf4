/*
 * bake_threads.h — the OpenMP thread count every bake stage uses (internal).
 * threads <= 0 means all cores; without OpenMP everything runs on one
 * thread, and every stage gives the same result either way.
 */
#ifndef MESO_BAKE_THREADS_H
#define MESO_BAKE_THREADS_H

#ifdef _OPENMP
#include <omp.h>
#endif

static inline int meso_bake_thread_count(int threads)
{
#ifdef _OPENMP
    return threads > 0 ? threads : omp_get_max_threads();
#else
    (void)threads;
    return 1;
#endif
}

#endif /* MESO_BAKE_THREADS_H */
