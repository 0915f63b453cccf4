/* bench_draw_cpu — the CPU cost of one meso_rt_draw call, per object kind
 * (issue 18 item 2: "measured CPU µs per draw before and after").
 *
 * The smallest objects, baked with mesobake into a temporary directory: a
 * tetrahedron as a MESH, as a shell (bricks:32, MESO_SHELL_SMOOTH) and as
 * CELLS (2 tiles of 16^3), and the bundled one-frustum SWC as FRUSTA,
 * drawn into an 8 x 8 framebuffer. Small, because llvmpipe shades
 * vertices in the calling thread (a 4608-triangle torus cost 1.4 ms per
 * mesh draw, 13 ms per shell draw): with a few triangles the time is
 * libmeso's and the driver's per-call work. Per kind: WARM draws (the first
 * compiles the shaders) and a glFinish, then --runs (15) runs of --draws
 * (2000) draws each,
 * timed around the batch of meso_rt_draw calls alone (no glFinish inside
 * the batch; one after each run, outside the timing). The CSV row holds
 * the median µs per draw over the runs and the fastest and slowest run by
 * the wall clock (meso_seconds), and the median by the calling thread's
 * CPU time: the wall clock also counts the thread waiting for llvmpipe's
 * rasteriser threads (their queue fills) and for other processes on the
 * cores, so on a loaded machine the thread's CPU time is the steadier
 * before/after figure.
 *
 * GL calls per draw: a second libmeso context on the same GL context is
 * created through a get_proc_address that hands out counting wrappers for
 * the state queries (glGet{Integer,Boolean,Float,Double,Integer64}v,
 * glGetIntegeri_v, glIsEnabled, glIsEnabledi), glGetUniformLocation and
 * glGetError, and every other entry point unwrapped; COUNT_DRAWS draws of
 * the object after a warm-up give the mean calls per draw. The timed
 * context never goes through the wrappers.
 *
 * usage: bench_draw_cpu OUT.csv MESOBAKE TEST_DATA_DIR [--label L] [--runs R] [--draws N]
 * Rows of other labels in OUT.csv are kept, rows of label L replaced, so
 * "before" and "after" rows of a change can live in one file.
 */
#include <GL/glcorearb.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "camera.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_clock.h"
#include "meso_rt.h"

enum { WARM = 50, COUNT_DRAWS = 20, MAX_RUNS = 101, VIEWPORT = 8 };

static void fail(const char* what)
{
    fprintf(stderr, "bench_draw_cpu: %s\n", what);
    exit(1);
}

/* >>counting get_proc_address ---------------------------------------------- */

static unsigned long n_gets, n_uniform_lookups, n_geterror;

#define REAL(type, name) static type real_##name;
REAL(PFNGLGETINTEGERVPROC, GetIntegerv)
REAL(PFNGLGETBOOLEANVPROC, GetBooleanv)
REAL(PFNGLGETFLOATVPROC, GetFloatv)
REAL(PFNGLGETDOUBLEVPROC, GetDoublev)
REAL(PFNGLGETINTEGER64VPROC, GetInteger64v)
REAL(PFNGLGETINTEGERI_VPROC, GetIntegeri_v)
REAL(PFNGLISENABLEDPROC, IsEnabled)
REAL(PFNGLISENABLEDIPROC, IsEnabledi)
REAL(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)
REAL(PFNGLGETERRORPROC, GetError)
#undef REAL

/* glGet<T>v(pname, T* data) */
#define COUNT_GET(n, T)                               \
    static void APIENTRY count_##n(GLenum p, T* v)    \
    {                                                 \
        ++n_gets;                                     \
        real_##n(p, v);                               \
    }
COUNT_GET(GetIntegerv, GLint)
COUNT_GET(GetBooleanv, GLboolean)
COUNT_GET(GetFloatv, GLfloat)
COUNT_GET(GetDoublev, GLdouble)
COUNT_GET(GetInteger64v, GLint64)
#undef COUNT_GET
static void APIENTRY count_GetIntegeri_v(GLenum p, GLuint i, GLint* v)
{
    ++n_gets;
    real_GetIntegeri_v(p, i, v);
}
static GLboolean APIENTRY count_IsEnabled(GLenum cap)
{
    ++n_gets;
    return real_IsEnabled(cap);
}
static GLboolean APIENTRY count_IsEnabledi(GLenum cap, GLuint i)
{
    ++n_gets;
    return real_IsEnabledi(cap, i);
}
static GLint APIENTRY count_GetUniformLocation(GLuint program, const GLchar* name)
{
    ++n_uniform_lookups;
    return real_GetUniformLocation(program, name);
}
static GLenum APIENTRY count_GetError(void)
{
    ++n_geterror;
    return real_GetError();
}

/* eglGetProcAddress, except that the entry points above come back as their
 * counting wrapper (the real one kept for it to call). */
static meso_gl_fn counting_proc(const char* name)
{
    meso_gl_fn real = meso_egl_proc(name);
    if (!real)
        return NULL;
#define WRAP(n)                                 \
    if (!strcmp(name, "gl" #n)) {               \
        memcpy(&real_##n, &real, sizeof(real)); \
        return (meso_gl_fn)count_##n;           \
    }
    WRAP(GetIntegerv)
    WRAP(GetBooleanv)
    WRAP(GetFloatv)
    WRAP(GetDoublev)
    WRAP(GetInteger64v)
    WRAP(GetIntegeri_v)
    WRAP(IsEnabled)
    WRAP(IsEnabledi)
    WRAP(GetUniformLocation)
    WRAP(GetError)
#undef WRAP
    return real;
}

/* >>measuring -------------------------------------------------------------- */

typedef struct kind {
    const char* name;    /* the CSV's `kind` */
    const char* command; /* mesobake command */
    int tetra;           /* 1: the input is the tetrahedron below, 0: `input` in TEST_DATA_DIR */
    const char* input;
    const char* options; /* more mesobake options */
} kind;

/* The smallest closed mesh: the geometry a draw sends through llvmpipe's
 * vertex stage (which runs in the calling thread) is then next to nothing,
 * so the time is libmeso's and the driver's per-call overhead. */
static const char tetra_obj[] = "v 1 1 1\nv 1 -1 -1\nv -1 1 -1\nv -1 -1 1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";

static const kind kinds[] = {
    {"mesh", "mesh", 1, NULL, ""},
    {"shell_smooth", "shell", 1, NULL, "--texture bricks:32 -j 2"},
    {"frusta", "frusta", 0, "morphio_soma_single_frustum.swc", ""},
    {"cells", "cells", 1, NULL, "--tiles 2 --tile-res 16 -j 2"},
};
enum { KIND_COUNT = sizeof(kinds) / sizeof(kinds[0]) };

typedef struct result {
    double median_us, min_us, max_us; /* wall clock */
    double cpu_median_us;             /* the calling thread's CPU time */
    double gets, uniform_lookups, geterror; /* per draw */
    int covered;                            /* pixels the object covers */
} result;

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

/* Median of t[0..n) (sorts t). */
static double median(double* t, int n)
{
    qsort(t, (size_t)n, sizeof(double), cmp_double);
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

/* CPU time of the calling thread: the draw calls' own work, without the
 * time the thread waits or is descheduled, and without llvmpipe's
 * rasteriser threads (vertex shading runs in the calling thread). */
static double thread_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static meso_rt_object load(meso_rt* rt, const char* path)
{
    meso_file* f = NULL;
    meso_error err;
    meso_rt_object obj = {0};
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK)
        fail(err.message);
    meso_object_record rec;
    uint32_t count = 0;
    if (meso_file_objects(f, &rec, 1, &count, &err) != MESO_OK || count < 1)
        fail("the bake has no object");
    if (meso_rt_load_object(rt, f, rec.id, &obj) != MESO_OK)
        fail("meso_rt_load_object failed");
    meso_file_close(f);
    return obj;
}

/* A camera two radii from the object's centre, looking at it. */
static meso_rt_draw_desc draw_desc_for(meso_rt* rt, meso_rt_object obj)
{
    float lo[3], hi[3];
    meso_rt_object_bounds(rt, obj, lo, hi);
    double c[3], r = 0.0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)lo[k] + hi[k]);
        r += 0.25 * ((double)hi[k] - lo[k]) * ((double)hi[k] - lo[k]);
    }
    r = sqrt(r);
    const double eye[3] = {c[0] + 1.0 * r, c[1] + 1.1 * r, c[2] + 1.3 * r}, up[3] = {0, 1, 0};
    meso_rt_draw_desc d = {0};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, 0.9, 1.0, 0.1 * r, 6.0 * r);
    return d;
}

static void draw(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* d)
{
    if (meso_rt_draw(rt, obj, d) != MESO_OK)
        fail("meso_rt_draw failed");
}

static result measure(meso_rt* rt, meso_rt* rt_count, const char* path, test_fbo* fbo, int runs, int draws)
{
    result res = {0};
    const meso_rt_object obj = load(rt, path);
    const meso_rt_draw_desc d = draw_desc_for(rt, obj);
    for (int i = 0; i < WARM; ++i)
        draw(rt, obj, &d);
    /* The object must cover pixels, or the fragment work of a real draw is missed. */
    test_fbo_clear(fbo, 0, 0, 0);
    draw(rt, obj, &d);
    float depth[VIEWPORT * VIEWPORT];
    test_fbo_read(fbo, NULL, depth);
    for (int i = 0; i < VIEWPORT * VIEWPORT; ++i)
        res.covered += depth[i] < 1.0f;
    if (!res.covered)
        fail("the object covers no pixel");
    double us[MAX_RUNS], cpu[MAX_RUNS];
    for (int r = 0; r < runs; ++r) {
        test_fbo_clear(fbo, 0, 0, 0);
        fbo->Finish();
        const double c0 = thread_seconds(), t0 = meso_seconds();
        for (int i = 0; i < draws; ++i)
            draw(rt, obj, &d);
        const double t1 = meso_seconds();
        cpu[r] = 1e6 * (thread_seconds() - c0) / draws;
        us[r] = 1e6 * (t1 - t0) / draws;
        fbo->Finish();
    }
    res.median_us = median(us, runs);
    res.min_us = us[0];
    res.max_us = us[runs - 1];
    res.cpu_median_us = median(cpu, runs);
    meso_rt_release_object(rt, obj);

    const meso_rt_object cobj = load(rt_count, path);
    for (int i = 0; i < 3; ++i) /* shaders compile and uniforms are first looked up here */
        draw(rt_count, cobj, &d);
    fbo->Finish();
    n_gets = n_uniform_lookups = n_geterror = 0;
    for (int i = 0; i < COUNT_DRAWS; ++i)
        draw(rt_count, cobj, &d);
    res.gets = (double)n_gets / COUNT_DRAWS;
    res.uniform_lookups = (double)n_uniform_lookups / COUNT_DRAWS;
    res.geterror = (double)n_geterror / COUNT_DRAWS;
    meso_rt_release_object(rt_count, cobj);
    fbo->Finish();
    return res;
}

/* >>CSV -------------------------------------------------------------------- */

static const char* const csv_header =
    "label,kind,median_us,min_us,max_us,cpu_median_us,runs,draws_per_run,gets_per_draw,uniform_lookups_per_draw,"
    "geterror_per_draw,viewport,load1,gl_renderer\n";

/* Rewrites `path`: its rows of other labels, then this run's. */
static void write_csv(const char* path, const char* label, const result* res, int runs, int draws, double load1,
                      const char* renderer)
{
    char* keep = NULL;
    size_t keep_len = 0;
    FILE* old = fopen(path, "r");
    if (old) {
        char line[1024];
        const size_t ll = strlen(label);
        while (fgets(line, sizeof(line), old)) {
            if (line[0] == '#' || !strncmp(line, "label,", 6) || line[0] == '\n')
                continue;
            if (!strncmp(line, label, ll) && line[ll] == ',')
                continue;
            const size_t n = strlen(line);
            char* grown = realloc(keep, keep_len + n + 1);
            if (!grown)
                fail("out of memory");
            keep = grown;
            memcpy(keep + keep_len, line, n + 1);
            keep_len += n;
        }
        fclose(old);
    }
    FILE* f = fopen(path, "w");
    if (!f)
        fail("cannot write the CSV");
    fprintf(f, "# tests/bench/bench_draw_cpu.c: CPU microseconds per meso_rt_draw call (wall clock around a batch of\n"
               "# draws, no glFinish inside), median/min/max over the runs; GL state queries, uniform look-ups\n"
               "# and glGetError calls per draw; load1: the machine's 1-minute load average at the start (the wall\n"
               "# clock suffers when other work shares the cores). Rows are replaced per label (--label).\n");
    fputs(csv_header, f);
    if (keep)
        fputs(keep, f);
    for (int k = 0; k < KIND_COUNT; ++k)
        fprintf(f, "%s,%s,%.2f,%.2f,%.2f,%.2f,%d,%d,%.1f,%.1f,%.1f,%dx%d,%.2f,\"%s\"\n", label, kinds[k].name,
                res[k].median_us, res[k].min_us, res[k].max_us, res[k].cpu_median_us, runs, draws, res[k].gets, res[k].uniform_lookups, res[k].geterror,
                VIEWPORT, VIEWPORT, load1, renderer);
    fclose(f);
    free(keep);
}

int main(int argc, char** argv)
{
    const char* usage = "usage: bench_draw_cpu OUT.csv MESOBAKE TEST_DATA_DIR [--label L] [--runs R] [--draws N]";
    if (argc < 4)
        fail(usage);
    const char *label = "latest", *csv = argv[1], *mesobake = argv[2], *data = argv[3];
    int runs = 15, draws = 2000;
    for (int i = 4; i < argc; ++i) {
        if (!strcmp(argv[i], "--label") && i + 1 < argc)
            label = argv[++i];
        else if (!strcmp(argv[i], "--runs") && i + 1 < argc)
            runs = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--draws") && i + 1 < argc)
            draws = atoi(argv[++i]);
        else
            fail(usage);
    }
    if (!*label || strpbrk(label, ",\"\n") || runs < 1 || runs > MAX_RUNS || draws < 1)
        fail("a label without commas or quotes, 1..101 runs and at least one draw, please");

    double load1 = -1.0; /* -1: unknown */
    FILE* la = fopen("/proc/loadavg", "r");
    if (la) {
        if (fscanf(la, "%lf", &load1) != 1)
            load1 = -1.0;
        fclose(la);
    }
    char dir[] = "/tmp/bench_draw_cpu_XXXXXX";
    if (!mkdtemp(dir))
        fail("cannot make a temporary directory");
    char paths[KIND_COUNT][256], tetra[256];
    snprintf(tetra, sizeof(tetra), "%s/tetra.obj", dir);
    FILE* tf = fopen(tetra, "w");
    if (!tf || fputs(tetra_obj, tf) < 0 || fclose(tf) != 0)
        fail("cannot write the tetrahedron");
    for (int k = 0; k < KIND_COUNT; ++k) {
        char cmd[4096];
        snprintf(paths[k], sizeof(paths[k]), "%s/%s.meso", dir, kinds[k].name);
        const int n = snprintf(cmd, sizeof(cmd), "'%s' %s -i '%s%s%s' %s -o '%s' 2>/dev/null", mesobake,
                               kinds[k].command, kinds[k].tetra ? tetra : data, kinds[k].tetra ? "" : "/",
                               kinds[k].tetra ? "" : kinds[k].input, kinds[k].options, paths[k]);
        if (n < 0 || (size_t)n >= sizeof(cmd))
            fail("paths too long");
        if (system(cmd) != 0)
            fail(cmd);
    }

    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    if (!egl)
        fail(why);
    test_fbo fbo;
    if (!test_fbo_create(&fbo, VIEWPORT, VIEWPORT))
        fail("no framebuffer");
    PFNGLGETSTRINGPROC GetString = (PFNGLGETSTRINGPROC)meso_egl_proc("glGetString");
    const char* renderer = (const char*)GetString(GL_RENDERER);
    meso_rt *rt = NULL, *rt_count = NULL;
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) != MESO_OK ||
        meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = counting_proc}, &rt_count) != MESO_OK)
        fail("meso_rt_create failed");
    printf("GL renderer: %s; %dx%d viewport, %d runs of %d draws per kind; load average %.2f\n", renderer, VIEWPORT,
           VIEWPORT, runs, draws, load1);
    result res[KIND_COUNT];
    for (int k = 0; k < KIND_COUNT; ++k) {
        res[k] = measure(rt, rt_count, paths[k], &fbo, runs, draws);
        printf("%-13s median %7.2f us/draw (min %7.2f, max %7.2f), thread CPU %7.2f us/draw; per draw: %4.1f gets, "
               "%4.1f uniform look-ups, %4.1f glGetError; %d px\n",
               kinds[k].name, res[k].median_us, res[k].min_us, res[k].max_us, res[k].cpu_median_us, res[k].gets,
               res[k].uniform_lookups, res[k].geterror, res[k].covered);
        remove(paths[k]);
    }
    remove(tetra);
    rmdir(dir);
    write_csv(csv, label, res, runs, draws, load1, renderer);
    meso_rt_destroy(rt_count);
    meso_rt_destroy(rt);
    test_fbo_destroy(&fbo);
    meso_egl_destroy(egl);
    return 0;
}
