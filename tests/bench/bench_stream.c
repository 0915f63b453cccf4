/* bench_stream — time to first image of a large .meso file streamed from a
 * slow reader (issue 14, Deliver 6 and the Goal "a streamed 100 MB file
 * shows its first image after at most its first 2 % of bytes").
 *
 * The file: a bumpy torus of 2 x SIDE^2 triangles (SIDE 1050: 2.2 M
 * triangles, ~105 MB), written as OBJ into WORK_DIR and baked by
 * `mesobake mesh` with its default levels (meshoptimizer chain, errors
 * measured). A generated mesh, because no bundled mesh is near 100 MB; the
 * bumps (amplitude 1 % of the tube) keep the simplifier from collapsing it
 * for free.
 *
 * The stream: the file is held in memory and "arrives" at RATE MB/s from
 * the moment the reader is opened: a read of bytes not yet arrived answers
 * MESO_IO_PENDING (meso_io, meso_file.h). The host loop is the plain one:
 * meso_file_open_io and meso_rt_load_object_levels are retried until they
 * no longer answer MESO_ERR_PENDING, then one meso_rt_draw a frame asking
 * for the finest level (pixel_error < 0; at 1 px the torus, which fills
 * most of a 320 x 240 view, wants level 6 since errors are projected at
 * the nearest point of a level's box, 1.58 away where its bounding sphere
 * was 0.86), synchronous loads (meso_rt_desc.stream_requests 0); its
 * parts (mesobake's default) each want their level 0.
 *
 * Measured, on the clock from the first byte:
 *   first_image_s / _arrived / _share   the first frame with a covered pixel,
 *                 and how many bytes had arrived then (of the file);
 *   first_image_read   bytes libmeso had read for the object by then;
 *   level_L_s / level_L_arrived         the first frame that drew level L;
 *   frame_ms_median / frame_ms_max      frame times (a synchronous load's
 *                 read and upload land in the frame that wants the level);
 * then the same stream through stream requests, uploads at 4 MB a call:
 *   req_gl_ms_median / _max   the GL thread's time a frame (draw, give,
 *                 upload; the requests' reads and decodes, run on the same
 *                 thread here, are timed apart: req_run_s_total);
 *   req_upload_ms_max / req_upload_bytes_max  the largest upload call: a
 *                 level larger than what is left of a call's budget goes
 *                 up over several calls (rt_transfer.c), a part level whole;
 *   req_level_0_s             when level 0 was drawn;
 * and the same at 256 KB a call (rows ending in _256k).
 * Output: one CSV (metric, value).
 * usage: bench_stream RESULTS_CSV MESOBAKE WORK_DIR [SIDE [MB_PER_S]] */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "camera.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_clock.h"
#include "meso_rt.h"

enum { W = 320, H = 240, MAX_LEVELS = 16 };

static void die(const char* what)
{
    fprintf(stderr, "bench_stream: %s\n", what);
    exit(1);
}

static FILE* csv;

static void row(const char* metric, double v)
{
    fprintf(csv, "%s,%.6g\n", metric, v);
    printf("  %-24s %.6g\n", metric, v);
    fflush(csv);
}

/* R = 1, r = 0.3 with bumps of 0.01 r... along both angles. */
static void write_torus(const char* path, int side)
{
    FILE* f = fopen(path, "w");
    if (!f)
        die(path);
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const double u = 2 * M_PI * i / side, v = 2 * M_PI * j / side;
            const double r = 0.3 + 0.01 * sin(13 * u) * sin(17 * v);
            fprintf(f, "v %.6f %.6f %.6f\n", (1 + r * cos(v)) * cos(u), (1 + r * cos(v)) * sin(u), r * sin(v));
        }
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const int a = i * side + j + 1, b = ((i + 1) % side) * side + j + 1;
            const int c = ((i + 1) % side) * side + (j + 1) % side + 1, d = i * side + (j + 1) % side + 1;
            fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, c, a, c, d);
        }
    if (fclose(f) != 0)
        die(path);
}

static uint8_t* read_all(const char* path, size_t* size)
{
    FILE* f = fopen(path, "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0)
        die(path);
    const long n = ftell(f);
    rewind(f);
    uint8_t* data = malloc(n > 0 ? (size_t)n : 1);
    if (n <= 0 || !data || fread(data, 1, (size_t)n, f) != (size_t)n)
        die(path);
    fclose(f);
    *size = (size_t)n;
    return data;
}

/* The slow reader: bytes arrive at `rate` per second from t0. */
typedef struct slow_io {
    const uint8_t* data;
    size_t size;
    double t0, rate;
} slow_io;

static uint64_t arrived(const slow_io* s)
{
    const double n = s->rate * (meso_seconds() - s->t0);
    return n >= (double)s->size ? s->size : (uint64_t)n;
}

static int slow_read(void* user, uint64_t off, void* dst, size_t n)
{
    const slow_io* s = user;
    if (off > s->size || n > s->size - off)
        return -1;
    const uint64_t a = arrived(s);
    if (off > a || n > a - off)
        return MESO_IO_PENDING;
    memcpy(dst, s->data + off, n);
    return 0;
}

static void sleep_ms(int ms)
{
    const struct timespec ts = {0, (long)ms * 1000000L};
    nanosleep(&ts, NULL);
}

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

/* Opens the streamed file and loads its object `id` into rt, each retried
 * while its bytes have not arrived. */
static meso_file* open_and_load(const meso_io* io, meso_rt* rt, uint32_t id, meso_rt_object* o)
{
    meso_file* f = NULL;
    meso_result r;
    while ((r = meso_file_open_io(io, NULL, &f, NULL)) == MESO_ERR_PENDING)
        sleep_ms(1);
    if (r != MESO_OK)
        die("open");
    while ((r = meso_rt_load_object_levels(rt, f, id, o)) == MESO_ERR_PENDING)
        sleep_ms(1);
    if (r != MESO_OK)
        die("load");
    return f;
}

/* One frame: a cleared framebuffer, the draw, frame end, glFinish; its ms. */
static double draw_frame(meso_rt* rt, meso_rt_object o, const meso_rt_draw_desc* d, test_fbo* fbo)
{
    const double t = meso_seconds();
    test_fbo_clear(fbo, 0, 0, 0);
    if (meso_rt_draw(rt, o, d) != MESO_OK)
        die("draw");
    meso_rt_frame_end(rt);
    fbo->Finish();
    return 1e3 * (meso_seconds() - t);
}

int main(int argc, char** argv)
{
    if (argc < 4 || argc > 6) {
        fprintf(stderr, "usage: bench_stream RESULTS_CSV MESOBAKE WORK_DIR [SIDE [MB_PER_S]]\n");
        return 2;
    }
    const int side = argc > 4 ? atoi(argv[4]) : 1050;
    const double rate = 1e6 * (argc > 5 ? atof(argv[5]) : 10.0);
    if (side < 8 || !(rate > 0))
        die("SIDE must be >= 8 and MB_PER_S > 0");
    char obj[1024], meso[1024], cmd[4096];
    snprintf(obj, sizeof obj, "%s/stream_torus.obj", argv[3]);
    snprintf(meso, sizeof meso, "%s/stream_torus.meso", argv[3]);
    write_torus(obj, side);
    snprintf(cmd, sizeof cmd, "'%s' mesh -i '%s' -o '%s' >/dev/null", argv[2], obj, meso);
    const double tb = meso_seconds();
    if (system(cmd) != 0)
        die(cmd);
    const double bake_s = meso_seconds() - tb;
    remove(obj);
    size_t size = 0;
    uint8_t* data = read_all(meso, &size);

    csv = fopen(argv[1], "w");
    if (!csv)
        die(argv[1]);
    fprintf(csv, "metric,value\n");
    row("triangles", 2.0 * side * side);
    row("file_bytes", (double)size);
    row("bake_s", bake_s);
    row("rate_bytes_per_s", rate);

    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof why);
    if (!egl)
        die(why);
    test_fbo fbo;
    if (!test_fbo_create(&fbo, W, H))
        die("fbo");
    meso_rt* rt = NULL;
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) != MESO_OK)
        die("libmeso context");

    slow_io s = {.data = data, .size = size, .rate = rate, .t0 = meso_seconds()};
    const meso_io io = {.read_fn = slow_read, .size = size, .user = &s};
    meso_file* f = NULL;
    meso_result r;
    while ((r = meso_file_open_io(&io, NULL, &f, NULL)) == MESO_ERR_PENDING)
        sleep_ms(1);
    if (r != MESO_OK)
        die("open");
    row("open_s", meso_seconds() - s.t0);
    meso_object_record rec;
    uint32_t count = 1;
    while ((r = meso_file_objects(f, &rec, 1, &count, NULL)) == MESO_ERR_PENDING)
        sleep_ms(1);
    if (r != MESO_OK || count < 1)
        die("objects");
    meso_rt_object o;
    while ((r = meso_rt_load_object_levels(rt, f, rec.id, &o)) == MESO_ERR_PENDING)
        sleep_ms(1);
    if (r != MESO_OK)
        die("load");
    meso_level_info li[MAX_LEVELS];
    uint32_t nl = 0;
    if (meso_file_levels(f, rec.id, li, MAX_LEVELS, &nl, NULL) != MESO_OK)
        die("levels");
    nl = nl < MAX_LEVELS ? nl : MAX_LEVELS;
    if (nl == 0)
        die("the baked file has no levels");
    row("levels", nl);
    row("coarsest_prefix_bytes", (double)li[nl - 1].prefix_bytes);

    meso_rt_draw_desc d = {0};
    const double eye[3] = {0, -2.2, 1.6}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    meso_camera_look_at(d.view, eye, at, up);
    meso_camera_perspective(d.proj, 40.0 * M_PI / 180.0, (double)W / H, 0.05, 100.0);
    d.pixel_error = -1.0f;
    d.light_dir[0] = 0.3f, d.light_dir[1] = 0.8f, d.light_dir[2] = 0.5f;
    for (int i = 0; i < 16; ++i)
        d.model[i] = i % 5 == 0 ? 1.0f : 0.0f;
    float* depth = malloc(sizeof(float) * W * H);
    double* frames = malloc(sizeof(double) * 100000);
    if (!depth || !frames)
        die("memory");
    int nframes = 0, first = 0, seen[MAX_LEVELS] = {0};
    const double limit = (double)size / rate + 120.0;
    for (;;) {
        const double ms = draw_frame(rt, o, &d, &fbo);
        if (nframes < 100000)
            frames[nframes++] = ms;
        meso_rt_levels_state ls;
        meso_rt_levels_state_get(rt, o, &ls);
        const double now = meso_seconds() - s.t0;
        if (!first) {
            test_fbo_read(&fbo, NULL, depth);
            size_t covered = 0;
            for (size_t p = 0; p < (size_t)W * H; ++p)
                covered += depth[p] < 1.0f;
            if (covered) {
                first = 1;
                const uint64_t a = arrived(&s);
                row("first_image_s", now);
                row("first_image_arrived", (double)a);
                row("first_image_share", (double)a / (double)size);
                row("first_image_read", (double)ls.bytes_read);
                row("first_image_level", ls.last_drawn);
                row("first_image_covered_px", (double)covered);
            }
        }
        if (ls.last_drawn >= 0 && ls.last_drawn < MAX_LEVELS && !seen[ls.last_drawn]) {
            seen[ls.last_drawn] = 1;
            char name[64];
            snprintf(name, sizeof name, "level_%d_s", ls.last_drawn);
            row(name, now);
            snprintf(name, sizeof name, "level_%d_arrived", ls.last_drawn);
            row(name, (double)arrived(&s));
        }
        if (ls.last_drawn == 0 || now > limit)
            break;
    }
    row("frames", nframes);
    qsort(frames, (size_t)nframes, sizeof(double), cmp_double);
    row("frame_ms_median", frames[nframes / 2]);
    row("frame_ms_max", frames[nframes - 1]);
    meso_rt_release_object(rt, o);
    meso_rt_destroy(rt);
    meso_file_close(f);
    const int ok = first && seen[0];

    /* The same stream through requests (meso_rt_desc.stream_requests): the
     * draw only files them; the host takes them, runs them (reads and
     * decodes: here on the GL thread too, timed apart, where a host would
     * use a worker), gives them back and uploads at UPLOAD_BUDGET bytes a
     * call. What the GL thread spends a frame (draw, give, upload) and the
     * largest single upload call, in ms and bytes against the budget.
     * Twice: at 4 MB a call, where each level fits a call, and at 256 KB,
     * where the larger whole levels go up over several calls
     * (rt_transfer.c); rows of the second pass end in "_256k". */
    static const uint64_t budgets[2] = {4 << 20, 256 << 10};
    int req_level0 = 1;
    for (int pass = 0; pass < 2; ++pass) {
        const uint64_t UPLOAD_BUDGET = budgets[pass];
        const char* sfx = pass ? "_256k" : "";
        char name[64];
        if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .stream_requests = 1}, &rt) !=
            MESO_OK)
            die("libmeso context");
        s.t0 = meso_seconds();
        f = open_and_load(&io, rt, rec.id, &o);
        double gl_max = 0.0, up_max = 0.0, run_total = 0.0, draw_max = 0.0;
        int draw_max_frame = 0;
        uint64_t up_bytes_max = 0;
        int req_frames = 0, level0 = 0;
        nframes = 0;
        for (;;) {
            const double t = meso_seconds(), draw_ms = draw_frame(rt, o, &d, &fbo);
            if (draw_ms > draw_max) {
                draw_max = draw_ms;
                draw_max_frame = req_frames;
            }
            meso_rt_request* reqs[16];
            const uint32_t taken = meso_rt_stream_take(rt, reqs, 16);
            const double tr = meso_seconds();
            for (uint32_t i = 0; i < taken; ++i)
                meso_rt_stream_run(reqs[i]);
            const double run_s = meso_seconds() - tr;
            run_total += run_s;
            meso_rt_stream_give(rt, reqs, taken);
            const double tu = meso_seconds();
            const uint64_t sent = meso_rt_stream_upload(rt, UPLOAD_BUDGET);
            fbo.Finish();
            const double up_ms = 1e3 * (meso_seconds() - tu), gl_ms = 1e3 * (meso_seconds() - t - run_s);
            up_max = up_ms > up_max ? up_ms : up_max;
            up_bytes_max = sent > up_bytes_max ? sent : up_bytes_max;
            gl_max = gl_ms > gl_max ? gl_ms : gl_max;
            if (nframes < 100000)
                frames[nframes++] = gl_ms;
            ++req_frames;
            meso_rt_levels_state ls;
            meso_rt_levels_state_get(rt, o, &ls);
            if (ls.last_drawn == 0) {
                level0 = 1;
                snprintf(name, sizeof name, "req_level_0_s%s", sfx);
                row(name, meso_seconds() - s.t0);
                break;
            }
            if (meso_seconds() - s.t0 > limit)
                break;
            if (!taken && !sent)
                sleep_ms(1);
        }
        req_level0 &= level0;
        qsort(frames, (size_t)nframes, sizeof(double), cmp_double);
        const struct {
            const char* metric;
            double v;
        } rows[] = {{"req_upload_budget_bytes", (double)UPLOAD_BUDGET}, {"req_frames", req_frames},
                    {"req_gl_ms_median", frames[nframes / 2]},          {"req_gl_ms_max", gl_max},
                    {"req_draw_ms_max", draw_max},                      {"req_draw_ms_max_frame", draw_max_frame},
                    {"req_upload_ms_max", up_max},                      {"req_upload_bytes_max", (double)up_bytes_max},
                    {"req_run_s_total", run_total}};
        for (size_t k = 0; k < sizeof rows / sizeof rows[0]; ++k) {
            snprintf(name, sizeof name, "%s%s", rows[k].metric, sfx);
            row(name, rows[k].v);
        }
        meso_rt_release_object(rt, o);
        meso_rt_destroy(rt);
        meso_file_close(f);
    }
    fclose(csv);
    free(frames);
    free(depth);
    test_fbo_destroy(&fbo);
    meso_egl_destroy(egl);
    free(data);
    return ok && req_level0 ? 0 : 1;
}
