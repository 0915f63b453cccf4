/* bench_lod_scene — levels of detail in a scene (issue 14, Deliver 6), on
 * llvmpipe: 64 objects of every kind the bundled data bakes (meshes with
 * levels, shells, cells, frusta), each at its own distance from 1x to 100x
 * its size (log-spaced) and spread across the view, drawn through
 * meso_rt_load_object_levels.
 *
 * For each setting — the finest level everywhere (pixel_error < 0) and
 * pixel_error 0.5, 1, 2, 4, 8, 16 — a fresh context draws 3 warm-up frames
 * (the levels are read and uploaded in the first), then:
 *   ms         wall time of one frame of the 64 draws, glFinish before and
 *              after: the median of 15 frames, 5 in each of 3 rounds over
 *              all the settings (one round's frames, in a fresh context);
 *   ms_alone   the same frames with each draw timed alone (glFinish either
 *              side) and summed: the draws' own cost, without llvmpipe's
 *              overlap of one draw's vertex work with the last one's
 *              rasterisation, which moves the whole frame's time between
 *              builds that draw the same (README);
 *   steps_px   shader steps per covered pixel (one counted frame, untimed;
 *              0 where the context cannot count; meshes count none);
 *   resident   file bytes of the uploaded levels (meso_rt_levels_state);
 *   gpu_resident  what they hold on the GPU, the memory budget's unit
 *              (meso_rt_budget_state);
 *   read       file bytes read for them (every level uploaded so far);
 *   mae        mean absolute difference, 0..255 per channel over all
 *              pixels, from the finest levels rendered at 2x2 the pixels
 *              and box-filtered (the supersampled reference);
 *   bad_px     share of pixels whose largest channel differs by > 16.
 * Plus, per file, the bytes a stream must deliver before every object of
 * it can draw (its objects' coarsest prefix_bytes) against its size.
 *
 * Output: one CSV (section, setting, metric, value). 320 x 240 pixels, on
 * one llvmpipe render thread (LP_NUM_THREADS=1 unless set: see main).
 * With PNG: the scene at 1 px beside the level each pixel's object drew
 * (white the finest, then blue, green, yellow, orange, magenta, violet, grey
 * for 7 and coarser).
 * With MESO_BENCH_OBJECTS=T in the environment it prints, instead, each
 * object's distance, level drawn, resident bytes, draw time (alone,
 * median of 5), ray-casting fragments, steps per fragment and (shells) hull
 * fragments rejected before their ray cast (one counted frame; 0 where not
 * counted: meshes) at pixel error T (what a setting's bytes and time are
 * made of) and writes only the stream rows; MESO_BENCH_NO_HULL_REJECT=1
 * draws the shells without the rejection.
 * usage: bench_lod_scene RESULTS_CSV MESOBAKE DATA_DIR WORK_DIR [PNG] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_clock.h"
#include "meso_rt.h"
#include "png_io.h"

enum { W = 320, H = 240, N = 64, FRAMES = 5, ROUNDS = 3, SETTINGS = 7 };

static test_fbo fbo;
static FILE* csv;
static const char* work;

static void die(const char* what)
{
    fprintf(stderr, "bench_lod_scene: %s\n", what);
    exit(1);
}

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

/* The scene's files: name, mesobake arguments (DATA is replaced). */
typedef struct scene_file {
    const char* name;
    const char* args;
} scene_file;
static const scene_file files[] = {
    {"spot", "mesh -i DATA/spot_uv.obj"},
    {"wingnut", "mesh -i DATA/wingnut.obj"},
    {"torus", "mesh -i DATA/torus.obj"},
    {"blub", "mesh -i DATA/blub_fish_low_resolution.obj"},
    {"shell", "shell -i DATA/spot_uv.obj --texture bricks:64 --thickness-rel 0.02 -j 2"},
    {"cells", "cells -i DATA/spot_low_resolution.obj"},
    {"frusta", "frusta -i DATA/saguaro.skel --relief bricks:64"},
};
enum { FILES = sizeof files / sizeof files[0] };

static meso_file* opened[FILES];
static meso_object_record recs[FILES];

static void bake_all(const char* mesobake, const char* data)
{
    for (int i = 0; i < FILES; ++i) {
        char args[1024], cmd[4096];
        const char* a = files[i].args;
        size_t n = 0;
        for (const char* p = a; *p && n + 512 < sizeof args;) /* DATA -> the data dir */
            if (!strncmp(p, "DATA", 4)) {
                n += (size_t)snprintf(args + n, sizeof args - n, "%s", data);
                p += 4;
            } else {
                args[n++] = *p++;
            }
        args[n] = 0;
        snprintf(cmd, sizeof cmd, "'%s' %s -o '%s/%s.meso' >/dev/null 2>&1", mesobake, args, work, files[i].name);
        if (system(cmd) != 0)
            die(cmd);
        char path[512];
        snprintf(path, sizeof path, "%s/%s.meso", work, files[i].name);
        if (meso_file_open_path(path, NULL, &opened[i], NULL) != MESO_OK)
            die(path);
        uint32_t count = 1;
        if (meso_file_objects(opened[i], &recs[i], 1, &count, NULL) != MESO_OK || count < 1)
            die("no object");
    }
}

/* Object k: file k mod FILES, at distance size * 100^(k/63) along a ray
 * spread over the view (golden-angle spiral in the image). */
static void place(int k, float model[16], int* file)
{
    *file = k % FILES;
    const meso_object_record* r = &recs[*file];
    double c[3], size = 0.0;
    for (int a = 0; a < 3; ++a) {
        c[a] = 0.5 * ((double)r->bbox_min[a] + r->bbox_max[a]);
        size = fmax(size, (double)r->bbox_max[a] - r->bbox_min[a]);
    }
    const double dist = 2.0 * pow(100.0, k / (double)(N - 1));
    const double ang = k * 2.39996, rad = 0.75 * sqrt((k + 0.5) / N);
    const double t = tan(0.5 * 40.0 * M_PI / 180.0);
    const double x = rad * cos(ang) * t * (double)W / H * dist, y = rad * sin(ang) * t * dist;
    const double s = 1.0 / size; /* every object 1 unit across */
    memset(model, 0, sizeof(float) * 16);
    model[0] = model[5] = model[10] = (float)s;
    model[15] = 1.0f;
    model[12] = (float)(x - s * c[0]);
    model[13] = (float)(y - s * c[1]);
    model[14] = (float)(-dist - s * c[2]);
}

static void camera(meso_rt_draw_desc* d)
{
    const double eye[3] = {0, 0, 0}, at[3] = {0, 0, -1}, up[3] = {0, 1, 0};
    meso_camera_look_at(d->view, eye, at, up);
    meso_camera_perspective(d->proj, 40.0 * M_PI / 180.0, (double)W / H, 0.05, 1000.0);
}

typedef struct scene {
    meso_rt* rt;
    meso_rt_object obj[N];
    float model[N][16];
} scene;

static void scene_load(scene* s)
{
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .prepare = 1}, &s->rt) != MESO_OK)
        die("libmeso context");
    for (int k = 0; k < N; ++k) {
        int fi;
        place(k, s->model[k], &fi);
        if (meso_rt_load_object_levels(s->rt, opened[fi], recs[fi].id, &s->obj[k]) != MESO_OK)
            die("load");
    }
}

/* The scene's draw description at pixel error tau (the model is each object's). */
static meso_rt_draw_desc scene_desc(float tau)
{
    meso_rt_draw_desc d = {0};
    camera(&d);
    d.pixel_error = tau;
    d.light_dir[0] = 0.3f, d.light_dir[1] = 0.8f, d.light_dir[2] = 0.5f;
    /* MESO_BENCH_NO_HULL_REJECT=1: shells ray cast every hull fragment (what
     * the rejection saves, with MESO_BENCH_OBJECTS) */
    const char* nr = getenv("MESO_BENCH_NO_HULL_REJECT");
    d.shell.no_hull_reject = nr && atoi(nr) ? 1 : 0;
    /* MESO_BENCH_NO_WALK=1: every prism rasterises its entry faces (what
     * the walk, rt_prism_walk.c, saves) */
    const char* nw = getenv("MESO_BENCH_NO_WALK");
    d.shell.no_prism_walk = nw && atoi(nw) ? 1 : 0;
    return d;
}

static void scene_draw(scene* s, float tau, meso_rt_draw_stats* sum)
{
    meso_rt_draw_desc d = scene_desc(tau);
    test_fbo_clear(&fbo, 0.18f, 0.20f, 0.24f);
    meso_rt_draw_stats st;
    for (int k = 0; k < N; ++k) {
        memcpy(d.model, s->model[k], sizeof d.model);
        memset(&st, 0, sizeof st);
        d.stats = sum ? &st : NULL;
        if (meso_rt_draw(s->rt, s->obj[k], &d) != MESO_OK)
            die("draw");
        if (sum) {
            sum->supported |= st.supported;
            sum->steps += st.steps;
            sum->fragments += st.fragments;
        }
    }
    meso_rt_frame_end(s->rt);
}

static void scene_free(scene* s)
{
    meso_rt_destroy(s->rt);
}

static uint8_t reference[W * H * 4];

/* The finest levels at 2x2 the pixels, box-filtered. */
static void render_reference(void)
{
    test_fbo big;
    test_fbo_destroy(&fbo);
    if (!test_fbo_create(&big, 2 * W, 2 * H))
        die("fbo");
    scene s;
    scene_load(&s);
    meso_rt_draw_desc d = {0};
    (void)d;
    scene_draw(&s, -1.0f, NULL); /* into the big FBO (the draw takes the viewport from GL) */
    uint8_t* px = malloc((size_t)4 * 4 * W * H);
    if (!px)
        die("memory");
    test_fbo_read(&big, px, NULL);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 4; ++c) {
                int sum = 0;
                for (int j = 0; j < 2; ++j)
                    for (int i = 0; i < 2; ++i)
                        sum += px[((size_t)(2 * y + j) * 2 * W + 2 * x + i) * 4 + c];
                reference[((size_t)y * W + x) * 4 + c] = (uint8_t)((sum + 2) / 4);
            }
    free(px);
    scene_free(&s);
    test_fbo_destroy(&big);
    if (!test_fbo_create(&fbo, W, H))
        die("fbo");
}

static void row(const char* section, const char* setting, const char* metric, double v)
{
    fprintf(csv, "%s,%s,%s,%.6g\n", section, setting, metric, v);
    printf("  %-8s %-8s %-10s %.6g\n", section, setting, metric, v);
    fflush(csv);
}

/* The scene's picture for the README (PNG_PATH, when set): the frame at
 * the setting, and beside it which level each visible pixel's object drew
 * (the object drawn alone, its depth equal to the frame's). */
static const char* png_path;

static void write_picture(scene* s, float tau, const uint8_t* img, const float* depth)
{
    static const uint8_t palette[8][3] = {{240, 240, 240}, {80, 160, 255}, {80, 200, 120}, {250, 200, 60},
                                          {240, 120, 60},  {200, 70, 160}, {140, 90, 220}, {120, 120, 120}};
    uint8_t* out = malloc((size_t)4 * 2 * W * H);
    float* alone = malloc(sizeof(float) * W * H);
    if (!out || !alone)
        die("memory");
    for (int y = 0; y < H; ++y) {
        memcpy(out + (size_t)y * 2 * W * 4, img + (size_t)y * W * 4, (size_t)W * 4);
        for (int x = 0; x < W; ++x) {
            uint8_t* o = out + ((size_t)y * 2 * W + W + x) * 4;
            o[0] = 24, o[1] = 26, o[2] = 30, o[3] = 255;
        }
    }
    meso_rt_draw_desc d = {0};
    camera(&d);
    d.pixel_error = tau;
    for (int k = 0; k < N; ++k) {
        meso_rt_levels_state ls;
        meso_rt_levels_state_get(s->rt, s->obj[k], &ls);
        if (ls.last_drawn < 0)
            continue;
        test_fbo_clear(&fbo, 0, 0, 0);
        memcpy(d.model, s->model[k], sizeof d.model);
        if (meso_rt_draw(s->rt, s->obj[k], &d) != MESO_OK)
            die("draw");
        test_fbo_read(&fbo, NULL, alone);
        const uint8_t* c = palette[ls.last_drawn < 7 ? ls.last_drawn : 7];
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const size_t p = (size_t)y * W + x;
                if (alone[p] < 1.0f && alone[p] == depth[p]) {
                    uint8_t* o = out + ((size_t)y * 2 * W + W + x) * 4;
                    o[0] = c[0], o[1] = c[1], o[2] = c[2];
                }
            }
    }
    meso_rt_frame_end(s->rt);
    char why[256];
    if (meso_png_write_rgba8(png_path, out, 2 * W, H, 1, why, sizeof why) != 0)
        die(why);
    printf("  wrote %s\n", png_path);
    free(out);
    free(alone);
}

/* One frame at `tau` with each draw timed alone (glFinish either side), in
 * scene order so the depth buffer holds the nearer objects: object k's ms
 * into out[k * stride]; returns their sum. */
static double frame_alone(scene* s, float tau, double* out, int stride)
{
    meso_rt_draw_desc d = scene_desc(tau);
    test_fbo_clear(&fbo, 0.18f, 0.20f, 0.24f);
    double sum = 0.0;
    for (int k = 0; k < N; ++k) {
        memcpy(d.model, s->model[k], sizeof d.model);
        fbo.Finish();
        const double t0 = meso_seconds();
        if (meso_rt_draw(s->rt, s->obj[k], &d) != MESO_OK)
            die("draw");
        fbo.Finish();
        const double ms = 1e3 * (meso_seconds() - t0);
        if (out)
            out[(size_t)k * (size_t)stride] = ms;
        sum += ms;
    }
    meso_rt_frame_end(s->rt);
    return sum;
}

/* FRAMES frames' ms at `tau`, in a fresh context after 3
 * warm-up frames (the levels are read and uploaded in the first); then
 * FRAMES more with each draw timed alone (glFinish either side), summed
 * over the frame (alone[]). */
static void time_setting(float tau, double ms[FRAMES], double alone[FRAMES])
{
    scene s;
    scene_load(&s);
    for (int i = 0; i < 3; ++i)
        scene_draw(&s, tau, NULL);
    for (int i = 0; i < FRAMES; ++i) {
        fbo.Finish();
        const double t0 = meso_seconds();
        scene_draw(&s, tau, NULL);
        fbo.Finish();
        ms[i] = 1e3 * (meso_seconds() - t0);
    }
    for (int i = 0; i < FRAMES; ++i)
        alone[i] = frame_alone(&s, tau, NULL, 0);
    scene_free(&s);
}

/* Every metric but ms (the same in every run: the levels a setting picks
 * and the image do not depend on time) and ms, the median of the timed
 * frames of every round. */
static void bench_setting(float tau, const char* name, const double* ms, const double* alone, int count)
{
    scene s;
    scene_load(&s);
    for (int i = 0; i < 4; ++i)
        scene_draw(&s, tau, NULL);
    uint8_t* img = malloc((size_t)4 * W * H);
    float* depth = malloc(sizeof(float) * W * H);
    if (!img || !depth)
        die("memory");
    test_fbo_read(&fbo, img, depth); /* the last timed frame */
    double abs_sum = 0.0;
    size_t bad = 0;
    for (size_t p = 0; p < (size_t)W * H; ++p) {
        int worst = 0;
        for (int c = 0; c < 3; ++c) {
            const int dlt = abs((int)img[4 * p + c] - (int)reference[4 * p + c]);
            abs_sum += dlt;
            worst = dlt > worst ? dlt : worst;
        }
        bad += worst > 16;
    }
    meso_rt_draw_stats sum = {0};
    scene_draw(&s, tau, &sum);
    test_fbo_read(&fbo, NULL, depth);
    size_t covered = 0;
    for (size_t p = 0; p < (size_t)W * H; ++p)
        covered += depth[p] < 1.0f;
    meso_rt_budget_state bs;
    meso_rt_budget_state_get(s.rt, &bs);
    uint64_t read = 0, resident = 0;
    int level_sum = 0;
    for (int k = 0; k < N; ++k) {
        meso_rt_levels_state ls;
        meso_rt_levels_state_get(s.rt, s.obj[k], &ls);
        read += ls.bytes_read;
        resident += ls.bytes_resident;
        level_sum += ls.last_drawn;
    }
    row("scene", name, "ms", ms[count / 2]);
    row("scene", name, "ms_alone", alone[count / 2]);
    row("scene", name, "steps_px", sum.supported && covered ? (double)sum.steps / (double)covered : 0.0);
    row("scene", name, "frags_px", sum.supported && covered ? (double)sum.fragments / (double)covered : 0.0);
    row("scene", name, "resident", (double)resident);
    row("scene", name, "gpu_resident", (double)bs.bytes_resident);
    row("scene", name, "read", (double)read);
    row("scene", name, "mae", abs_sum / (3.0 * W * H));
    row("scene", name, "bad_px", (double)bad / ((double)W * H));
    row("scene", name, "mean_lod", (double)level_sum / N);
    if (png_path && tau == 1.0f) {
        test_fbo_read(&fbo, img, depth); /* the counted frame: same levels, same image */
        write_picture(&s, tau, img, depth);
    }
    free(img);
    free(depth);
    scene_free(&s);
}

/* MESO_BENCH_OBJECTS=T: each object's file, distance, level drawn and
 * bytes at pixel error T (after a few frames), to stdout; what a setting's
 * bytes and time are made of. */
static void objects_at(float tau)
{
    enum { REPEAT = 5 };
    scene s;
    scene_load(&s);
    for (int i = 0; i < 4; ++i)
        scene_draw(&s, tau, NULL);
    /* Each object's draw timed alone, REPEAT frames. */
    static double ms[N][REPEAT];
    for (int r = 0; r < REPEAT; ++r)
        frame_alone(&s, tau, &ms[0][r], REPEAT);
    meso_rt_draw_desc d = scene_desc(tau);
    /* One more frame, counted (untimed): each draw's fragments and steps. */
    static meso_rt_draw_stats st[N];
    test_fbo_clear(&fbo, 0.18f, 0.20f, 0.24f);
    for (int k = 0; k < N; ++k) {
        memcpy(d.model, s.model[k], sizeof d.model);
        d.stats = &st[k];
        if (meso_rt_draw(s.rt, s.obj[k], &d) != MESO_OK)
            die("draw");
    }
    d.stats = NULL;
    meso_rt_frame_end(s.rt);
    uint64_t total = 0;
    double total_ms = 0.0;
    printf("object  file     distance  lod  resident_bytes      ms  fragments  steps/fragment  rejected\n");
    for (int k = 0; k < N; ++k) {
        int fi;
        float model[16];
        place(k, model, &fi);
        meso_rt_levels_state ls;
        meso_rt_levels_state_get(s.rt, s.obj[k], &ls);
        total += ls.bytes_resident;
        qsort(ms[k], REPEAT, sizeof(double), cmp_double);
        total_ms += ms[k][REPEAT / 2];
        printf("%6d  %-7s  %8.2f  %3d  %14llu  %6.2f  %9llu  %14.1f  %8llu\n", k, files[fi].name,
               2.0 * pow(100.0, k / (double)(N - 1)), ls.last_drawn, (unsigned long long)ls.bytes_resident,
               ms[k][REPEAT / 2], (unsigned long long)st[k].fragments,
               st[k].fragments ? (double)st[k].steps / (double)st[k].fragments : 0.0,
               (unsigned long long)st[k].rejected);
    }
    printf("total %llu bytes, %.1f ms (medians of %d, summed) at %g px\n", (unsigned long long)total, total_ms, REPEAT,
           (double)tau);
    scene_free(&s);
}

int main(int argc, char** argv)
{
    if (argc != 5 && argc != 6) {
        fprintf(stderr, "usage: bench_lod_scene RESULTS_CSV MESOBAKE DATA_DIR WORK_DIR [PNG]\n");
        return 2;
    }
    work = argv[4];
    png_path = argc == 6 ? argv[5] : NULL;
    /* One llvmpipe render thread, unless told otherwise: with the default
     * two beside the application thread (which runs llvmpipe's vertex
     * work) on this machine's two cores, the finest setting's frame (1.4 M
     * shell hull vertices) took either about 230 or about 340-440 ms from
     * run to run of the same binary, while its draws timed alone summed to
     * 255-268 ms; with one it took 496-525 ms in every run. */
    if (!getenv("LP_NUM_THREADS"))
        setenv("LP_NUM_THREADS", "1", 1);
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof why);
    if (!egl)
        die(why);
    if (!test_fbo_create(&fbo, W, H))
        die("fbo");
    csv = fopen(argv[1], "w");
    if (!csv)
        die(argv[1]);
    fprintf(csv, "section,setting,metric,value\n");
    bake_all(argv[2], argv[3]);
    for (int i = 0; i < FILES; ++i) {
        meso_level_info li[16];
        uint32_t n = 0;
        if (meso_file_levels(opened[i], recs[i].id, li, 16, &n, NULL) != MESO_OK)
            die("levels");
        const uint32_t last = (n < 16 ? n : 16) - 1;
        row("stream", files[i].name, "levels", n);
        row("stream", files[i].name, "file_bytes", (double)meso_file_size(opened[i]));
        row("stream", files[i].name, "first_image_bytes", (double)li[last].prefix_bytes);
        row("stream", files[i].name, "first_image_share",
            (double)li[last].prefix_bytes / (double)meso_file_size(opened[i]));
    }
    const char* objects = getenv("MESO_BENCH_OBJECTS");
    if (objects) {
        objects_at((float)atof(objects));
        return 0;
    }
    render_reference();
    /* Rounds over all settings, so that a slow spell of the machine
     * (llvmpipe shares its two cores with everything else) falls on every
     * setting alike rather than on one. */
    static const float taus[SETTINGS] = {-1.0f, 0.5f, 1.0f, 2.0f, 4.0f, 8.0f, 16.0f};
    static const char* const names[SETTINGS] = {"finest", "0.5", "1", "2", "4", "8", "16"};
    static double ms[SETTINGS][ROUNDS * FRAMES], alone[SETTINGS][ROUNDS * FRAMES];
    for (int round = 0; round < ROUNDS; ++round)
        for (int i = 0; i < SETTINGS; ++i)
            time_setting(taus[i], ms[i] + round * FRAMES, alone[i] + round * FRAMES);
    for (int i = 0; i < SETTINGS; ++i) {
        qsort(ms[i], ROUNDS * FRAMES, sizeof(double), cmp_double);
        qsort(alone[i], ROUNDS * FRAMES, sizeof(double), cmp_double);
        bench_setting(taus[i], names[i], ms[i], alone[i], ROUNDS * FRAMES);
    }
    fclose(csv);
    for (int i = 0; i < FILES; ++i)
        meso_file_close(opened[i]);
    test_fbo_destroy(&fbo);
    meso_egl_destroy(egl);
    return 0;
}
