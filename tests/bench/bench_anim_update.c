/* bench_anim_update — the cost of animating a shell's texture function
 * (papers/volume-textures-lp-averaged-shells.md §6, the boiling textures;
 * issue 19): meso_rt_shell_set_texture replacing a W³ U8 density volume and
 * its (W/2)³ U8 distance map, for W = 64 and 128, and
 * meso_rt_shell_set_time switching between the stored frames of a baked
 * `boil:64 --frames 8` sequence (the same upload from the object's own
 * host copy). Each update is followed by glFinish, so the time includes the
 * driver finishing the upload; median, min and max over RUNS updates after
 * 3 warm-ups, on whatever GL the EGL context gives (llvmpipe in CI). A
 * driver may defer work to the first draw that samples a new texture, so
 * each case is also timed as update + one 16 x 16 draw, next to the same
 * draw without an update ("draw only").
 *
 * Shape updates (meso_rt_shell_update; `res` is the vertex count, `bytes`
 * the vertex texels uploaded) on a bake of spot_uv with the bricks height
 * field: the directors scaled by 1 +- 1 %, alternately, so the walk's
 * welded neighbours are kept and the folding test runs again
 * (rt_prism_walk.c). With MESO_BENCH_LEVEL0=1 the textures have no mip
 * levels (MESO_FILTER_LEVEL0): what the uploads cost without building them.
 *
 * usage: bench_anim_update OUT.csv MESOBAKE TEST_DATA_DIR
 */
#include <GL/glcorearb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "camera.h"
#include "gl_fbo.h"
#include "meso_clock.h"
#include "meso_rt.h"
#include "shell_reference.h"

enum { RUNS = 25, WARM = 3 };

static meso_rt_draw_desc draw_desc;
static meso_rt* rt_g;
static meso_rt_object obj_g;
static PFNGLFINISHPROC finish_g;

/* One update (k-th), as the caller defines it. */
typedef void (*update_fn)(int k, void* user);

/* Times RUNS calls of `update` (after WARM), each alone and each followed
 * by one draw, into t_update and t_draw (seconds). */
static void time_updates(update_fn update, void* user, double* t_update, double* t_draw)
{
    for (int pass = 0; pass < 2; ++pass)
        for (int k = 0; k < WARM + RUNS; ++k) {
            finish_g();
            const double t0 = meso_seconds();
            if (update)
                update(k, user);
            if (pass == 1 && meso_rt_draw(rt_g, obj_g, &draw_desc) != MESO_OK) {
                fprintf(stderr, "bench_anim_update: draw failed\n");
                exit(1);
            }
            finish_g();
            if (k >= WARM)
                (pass ? t_draw : t_update)[k - WARM] = meso_seconds() - t0;
        }
}

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static void fail(const char* what)
{
    fprintf(stderr, "bench_anim_update: %s\n", what);
    exit(1);
}

/* Median, min, max of t[0..n) in ms (sorts t). */
static void report(FILE* csv, const char* what, uint32_t w, size_t bytes, double* t, int n)
{
    qsort(t, (size_t)n, sizeof(double), cmp_double);
    const double med = n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
    printf("%-34s res %5u  %9zu bytes  median %7.2f ms  min %7.2f  max %7.2f  (%d updates)\n", what, w, bytes,
           1e3 * med, 1e3 * t[0], 1e3 * t[n - 1], n);
    fprintf(csv, "%s,%u,%zu,%d,%.3f,%.3f,%.3f\n", what, w, bytes, n, 1e3 * med, 1e3 * t[0], 1e3 * t[n - 1]);
}

typedef struct volumes {
    uint8_t* vol[2];
    uint8_t* dist[2];
    uint32_t w;
} volumes;

static void set_texture(int k, void* user)
{
    const volumes* v = user;
    const uint32_t w = v->w, d = w / 2;
    const meso_rt_shell_texture desc = {.kind = MESO_RT_TEXTURE_DENSITY,
                                        .dims = {w, w, w},
                                        .dtype = MESO_DTYPE_U8,
                                        .data = v->vol[k & 1],
                                        .dist_dims = {d, d, d},
                                        .dist_dtype = MESO_DTYPE_U8,
                                        .dist_data = v->dist[k & 1]};
    if (meso_rt_shell_set_texture(rt_g, obj_g, &desc) != MESO_OK)
        fail("meso_rt_shell_set_texture failed");
}

/* The stored frames of the bake (8 over boil's 2 s loop: 4 fps). */
typedef struct stored {
    uint32_t frames;
    float fps;
} stored;

static void set_time(int k, void* user)
{
    const stored* s = user;
    if (meso_rt_shell_set_time(rt_g, obj_g, ((uint32_t)k % s->frames + 0.5) / s->fps) != MESO_OK)
        fail("meso_rt_shell_set_time failed");
}

/* A shape for meso_rt_shell_update: the bake's directors, and a copy
 * changed per call. */
typedef struct shape {
    meso_ref_shell ref;
    float* directors;
} shape;

static void scale_directors(int k, void* user)
{
    shape* sh = user;
    const size_t n = 3 * (size_t)sh->ref.vertex_count * sh->ref.layers;
    const float f = k & 1 ? 1.01f : 0.99f;
    for (size_t i = 0; i < n; ++i)
        sh->directors[i] = f * sh->ref.directors[i];
    if (meso_rt_shell_update(rt_g, obj_g, NULL, sh->directors, sh->ref.vertex_count) != MESO_OK)
        fail("meso_rt_shell_update failed");
}

int main(int argc, char** argv)
{
    if (argc != 4)
        fail("usage: bench_anim_update OUT.csv MESOBAKE TEST_DATA_DIR");
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    if (!egl)
        fail(why);
    PFNGLFINISHPROC Finish = (PFNGLFINISHPROC)meso_egl_proc("glFinish");
    test_fbo fbo;
    if (!test_fbo_create(&fbo, 16, 16))
        fail("no framebuffer");
    PFNGLGETSTRINGPROC GetString = (PFNGLGETSTRINGPROC)meso_egl_proc("glGetString");
    meso_rt* rt = NULL;
    /* MESO_BENCH_LEVEL0=1: textures without mip levels (what an upload
     * costs without building them) */
    const char* l0 = getenv("MESO_BENCH_LEVEL0");
    const meso_texture_filter filter = l0 && atoi(l0) ? MESO_FILTER_LEVEL0 : MESO_FILTER_MIPMAP;
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .texture_filter = filter}, &rt) !=
        MESO_OK)
        fail("meso_rt_create failed");
    char path[512], cmd[2048];
    snprintf(path, sizeof(path), "/tmp/bench_anim_update_%d.meso", (int)getpid());
    snprintf(cmd, sizeof(cmd),
             "'%s' shell -i '%s/torus.obj' --texture boil:64 --frames 8 -j 2 -o '%s' 2>/dev/null", argv[2], argv[3],
             path);
    if (system(cmd) != 0)
        fail("mesobake failed");
    meso_file* f = NULL;
    meso_error err;
    meso_rt_object obj;
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK || meso_rt_load_object(rt, f, 1, &obj) != MESO_OK)
        fail("loading the bake failed");
    meso_file_close(f);
    remove(path);
    FILE* csv = fopen(argv[1], "w");
    if (!csv)
        fail("cannot write the CSV");
    fprintf(csv, "# %s; glFinish after each update\nupdate,res,bytes,updates,median_ms,min_ms,max_ms\n",
            (const char*)GetString(GL_RENDERER));
    printf("GL renderer: %s\n", (const char*)GetString(GL_RENDERER));
    rt_g = rt;
    obj_g = obj;
    finish_g = Finish;
    float lo[3], hi[3];
    meso_rt_object_bounds(rt, obj, lo, hi);
    const double eye[3] = {0.0, 1.6 * hi[1] + 2.0 * hi[0], 2.0 * hi[2]}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    meso_camera_look_at(draw_desc.view, eye, at, up);
    meso_camera_perspective(draw_desc.proj, 0.8, 1.0, 0.05, 20.0);
    double t[RUNS], td[RUNS], t_none[RUNS], t_draw_only[RUNS];
    time_updates(NULL, NULL, t_none, t_draw_only);
    report(csv, "draw only (16x16)", 0, 0, t_draw_only, RUNS);
    static const uint32_t res[2] = {64, 128};
    for (int r = 0; r < 2; ++r) {
        const uint32_t w = res[r], d = w / 2;
        const size_t nv = (size_t)w * w * w, nd = (size_t)d * d * d;
        volumes v = {{malloc(nv), malloc(nv)}, {malloc(nd), malloc(nd)}, w};
        if (!v.vol[0] || !v.vol[1] || !v.dist[0] || !v.dist[1])
            fail("out of memory");
        for (int b = 0; b < 2; ++b) { /* two different contents, alternated */
            for (size_t i = 0; i < nv; ++i)
                v.vol[b][i] = (uint8_t)((i * 2654435761u) >> (24 + b));
            memset(v.dist[b], b ? 3 : 5, nd);
        }
        time_updates(set_texture, &v, t, td);
        report(csv, "set_texture", w, nv + nd, t, RUNS);
        report(csv, "set_texture + draw", w, nv + nd, td, RUNS);
        for (int b = 0; b < 2; ++b) {
            free(v.vol[b]);
            free(v.dist[b]);
        }
    }
    /* Stored frames: every call shows the next frame. */
    stored s = {0};
    meso_rt_shell_anim_info(rt, obj, &s.frames, &s.fps, NULL);
    time_updates(set_time, &s, t, td);
    report(csv, "set_time (stored frame)", 64, (size_t)64 * 64 * 64 + (size_t)32 * 32 * 32, t, RUNS);
    report(csv, "set_time + draw", 64, (size_t)64 * 64 * 64 + (size_t)32 * 32 * 32, td, RUNS);
    meso_rt_release_object(rt, obj);

    /* Shape updates on spot_uv (bricks). */
    snprintf(cmd, sizeof(cmd), "'%s' shell -i '%s/spot_uv.obj' --texture bricks:32 -j 2 -o '%s' 2>/dev/null",
             argv[2], argv[3], path);
    shape sh = {0};
    if (system(cmd) != 0)
        fail("mesobake failed");
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK || meso_rt_load_object(rt, f, 1, &obj) != MESO_OK ||
        meso_ref_shell_load(f, 1, &sh.ref, &err) != MESO_OK)
        fail("loading the spot bake failed");
    meso_file_close(f);
    remove(path);
    obj_g = obj;
    sh.directors = malloc(sizeof(float) * 3 * sh.ref.vertex_count * sh.ref.layers);
    if (!sh.directors)
        fail("out of memory");
    meso_rt_object_bounds(rt, obj, lo, hi);
    const double eye2[3] = {0.0, 0.5 * (lo[1] + hi[1]), 3.0 * hi[2]};
    meso_camera_look_at(draw_desc.view, eye2, at, up);
    const size_t texels = (size_t)32 * sh.ref.vertex_count;
    time_updates(scale_directors, &sh, t, td);
    report(csv, "shell_update (directors)", sh.ref.vertex_count, texels, t, RUNS);
    report(csv, "shell_update (directors) + draw", sh.ref.vertex_count, texels, td, RUNS);
    free(sh.directors);
    meso_ref_shell_free(&sh.ref);
    test_fbo_destroy(&fbo);
    fclose(csv);
    meso_rt_release_object(rt, obj);
    meso_rt_destroy(rt);
    meso_egl_destroy(egl);
    return 0;
}
