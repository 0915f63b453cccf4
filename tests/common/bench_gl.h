/* bench_gl.h — what the GL benchmarks share (tests/bench/bench_*_render.c):
 * a wall clock, the headless framebuffer and camera of a scene, and the
 * median time of a draw. Header-only, bench code. */
#ifndef MESO_BENCH_GL_H
#define MESO_BENCH_GL_H

#include "meso_clock.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gl_fbo.h"
#include "meso_rt.h"
#include "shell_scene.h"


static inline int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

typedef struct bench {
    meso_rt* rt;
    test_fbo fbo;
    camera cam;
    float view[16], proj[16];
} bench;

/* The headless EGL context and a libmeso context on it; NULL (reason on
 * stderr, prefixed with `who`) on failure. */
static inline meso_egl* bench_gl_open(bench* b, const char* who)
{
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    if (!egl) {
        fprintf(stderr, "%s: %s\n", who, why);
        return NULL;
    }
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &b->rt) != MESO_OK) {
        fprintf(stderr, "%s: cannot create a libmeso context\n", who);
        meso_egl_destroy(egl);
        return NULL;
    }
    return egl;
}

/* A w x h framebuffer (replacing the last) and the camera's matrices for it. */
static inline void bench_set_size(bench* b, int w, int h)
{
    if (b->fbo.fbo)
        test_fbo_destroy(&b->fbo);
    scene_w = w, scene_h = h;
    if (!test_fbo_create(&b->fbo, w, h)) {
        fprintf(stderr, "bench: cannot create a %dx%d framebuffer\n", w, h);
        exit(1);
    }
    camera_matrices(&b->cam, b->view, b->proj);
}

/* Draws 1 + reps times (at most 9 timed) with the bench's view and
 * projection; returns the median ms of the timed draws, glFinish included. */
static inline double bench_median_ms(bench* b, meso_rt_object obj, meso_rt_draw_desc d, int reps)
{
    memcpy(d.view, b->view, sizeof(d.view));
    memcpy(d.proj, b->proj, sizeof(d.proj));
    double ms[9];
    reps = reps < 1 ? 1 : reps > 9 ? 9 : reps;
    for (int r = 0; r <= reps; ++r) {
        test_fbo_clear(&b->fbo, 0, 0, 0);
        b->fbo.Finish();
        const double t0 = (1e3 * meso_seconds());
        if (meso_rt_draw(b->rt, obj, &d) != MESO_OK) {
            fprintf(stderr, "bench: draw failed\n");
            exit(1);
        }
        b->fbo.Finish();
        if (r > 0)
            ms[r - 1] = (1e3 * meso_seconds()) - t0;
    }
    qsort(ms, (size_t)reps, sizeof(double), cmp_double);
    return ms[reps / 2];
}

#endif /* MESO_BENCH_GL_H */
