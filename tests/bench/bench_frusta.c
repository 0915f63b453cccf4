/* bench_frusta — libmeso frusta objects (issue #7) on llvmpipe: the cost of
 * animating and drawing.
 *
 *  bench_frusta.csv, one row per skeleton size (fields of N/10 cacti of 10
 *  segments each, with joints, branch points and balls, baked in memory
 *  with mesobake's own code; cacti_swc below):
 *    pose_us_per_1000      meso_frusta_pose alone (planes, centres, radii,
 *                          u frames; formats/frusta_pose.c) per 1000 frusta
 *    cpu_us_per_1000       the CPU part of meso_rt_frusta_set_pose: the pose
 *                          plus the §2.6 bounding pyramids and the texels
 *    set_pose_us_per_1000  meso_rt_frusta_set_pose with its upload
 *                          (glBufferSubData of 256 bytes per primitive),
 *                          glFinish included
 *    draw_ms, draw_relief_ms  one meso_rt_draw at 800x600 with the field
 *                          filling the view, plain and relief-mapped (depth
 *                          5% of the radius, a 64x64 map), glFinish included
 *    fragments_per_px, steps_per_fragment  from the shaders' counters
 *  Timings: the minimum of 5 batches (draws: of 3) after a warm-up — the
 *  machines this runs on are shared, and the minimum is the least
 *  disturbed run; CPU batches are 2-100 calls, the sway that makes the
 *  poses is timed alone and subtracted.
 *
 * usage: bench_frusta RESULTS_DIR [quick]   (quick: sizes up to 1000)
 * The CSV is also printed on stdout. */
#include "meso_clock.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "egl_context.h"
#include "frusta_pose.h"
#include "frusta_scene.h"
#include "camera.h"
#include "gl_fbo.h"
#include "meso_rt.h"
#include "png_io.h"
#include "rt_internal.h" /* mesoi_frusta_pose_host: set_pose without the upload */

#define CHECK(x)                                                         \
    do {                                                                 \
        if (!(x)) {                                                      \
            fprintf(stderr, "bench_frusta: %s failed (line %d)\n", #x, __LINE__); \
            exit(1);                                                     \
        }                                                                \
    } while (0)


static double minimum(const double* v, int n)
{
    double m = v[0];
    for (int i = 1; i < n; ++i)
        m = v[i] < m ? v[i] : m;
    return m;
}

static uint64_t rng(uint64_t* s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * 2685821657736338717ULL;
}

static double uniform(uint64_t* s)
{
    return (double)(rng(s) >> 11) * (1.0 / 9007199254740992.0);
}

/* SWC text of a field of cacti (the paper's Figure 8 scene: "100
 * individually animated cacti"): ceil(segments / 10) plants on a square
 * grid, each a trunk of 6 segments and two arms of 2 segments (10 frusta,
 * 2 branch points with balls, 4 tips), randomly bent by up to ~15°. */
static char* cacti_swc(uint32_t segments, uint64_t seed)
{
    const uint32_t plants = (segments + 9) / 10, side = (uint32_t)ceil(sqrt((double)plants));
    char* text = malloc((size_t)plants * 11 * 96 + 1);
    CHECK(text != NULL);
    size_t len = 0;
    uint32_t id = 0;
    for (uint32_t k = 0; k < plants; ++k) {
        const double x0 = 3.0 * (k % side), z0 = 3.0 * (k / side);
        double p[11][3];
        int32_t parent[11];
        double rad[11];
        /* trunk 0..6 */
        for (int i = 0; i <= 6; ++i) {
            parent[i] = i - 1;
            rad[i] = 0.45 - 0.02 * i;
            p[i][0] = x0 + (i ? p[i - 1][0] - x0 + 0.25 * (uniform(&seed) - 0.5) : 0.0);
            p[i][1] = 1.0 * i;
            p[i][2] = z0 + (i ? p[i - 1][2] - z0 + 0.25 * (uniform(&seed) - 0.5) : 0.0);
        }
        /* arms from nodes 2 and 3, to opposite sides, then up */
        for (int a = 0; a < 2; ++a) {
            const int base = 2 + a, n1 = 7 + 2 * a, n2 = n1 + 1;
            const double ang = 6.283185307179586 * uniform(&seed) + a * 3.14159, dx = cos(ang), dz = sin(ang);
            parent[n1] = base;
            parent[n2] = n1;
            rad[n1] = 0.3;
            rad[n2] = 0.25;
            for (int c = 0; c < 3; ++c)
                p[n1][c] = p[base][c];
            p[n1][0] += 0.9 * dx, p[n1][1] += 0.35, p[n1][2] += 0.9 * dz;
            for (int c = 0; c < 3; ++c)
                p[n2][c] = p[n1][c];
            p[n2][0] += 0.15 * dx, p[n2][1] += 1.1, p[n2][2] += 0.15 * dz;
        }
        for (int i = 0; i < 11; ++i)
            len += (size_t)snprintf(text + len, 96, "%u 3 %.6f %.6f %.6f %.6f %d\n", id + (uint32_t)i + 1, p[i][0],
                                    p[i][1], p[i][2], rad[i], parent[i] >= 0 ? (int)id + parent[i] + 1 : -1);
        id += 11;
    }
    return text;
}

typedef struct scene {
    uint8_t* file;
    size_t size;
} scene;

/* The field baked in memory; with relief: depth 5% of the trunk radius
 * scale (0.05), a 64x64 map of domes (4x4 per tile). */
static scene bake(const char* swc, int relief)
{
    enum { N = 64 };
    uint8_t* tex = malloc((size_t)N * N);
    CHECK(tex != NULL);
    for (uint32_t j = 0; j < N; ++j)
        for (uint32_t i = 0; i < N; ++i) {
            const double s = fmod(4.0 * (i + 0.5) / N, 1.0) - 0.5, t = fmod(4.0 * (j + 0.5) / N, 1.0) - 0.5;
            const double r = sqrt(s * s + t * t);
            tex[(size_t)j * N + i] = (uint8_t)lround(255.0 * (r < 0.45 ? 0.2 + 0.8 * sqrt(1 - r * r / 0.2025) : 0.2));
        }
    const frusta_file_opts o = {.depth = relief ? 0.05 : 0.0, .u_repeat = 2, .relief = relief ? tex : NULL,
                                .relief_w = N, .relief_h = N};
    scene sc;
    sc.file = frusta_file(swc, &o, &sc.size);
    free(tex);
    return sc;
}

static meso_rt_object load(meso_rt* rt, const scene* sc)
{
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(sc->file, sc->size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    CHECK(meso_rt_load_object(rt, f, 1, &obj) == MESO_OK);
    meso_file_close(f);
    return obj;
}

/* Every node turned a little about its parent (about z), by `t`. */
static void sway(const float* rest, const int32_t* parent, uint32_t n, double t, float* out)
{
    for (uint32_t i = 0; i < n; ++i) {
        const int32_t p = parent[i];
        if (p < 0) {
            memcpy(out + 3 * (size_t)i, rest + 3 * (size_t)i, sizeof(float) * 3);
            continue;
        }
        const double a = 0.05 * sin(t + 0.3 * (double)i), c = cos(a), s = sin(a);
        const double dx = rest[3 * i] - rest[3 * p], dy = rest[3 * i + 1] - rest[3 * p + 1];
        out[3 * i] = (float)(out[3 * p] + c * dx - s * dy);
        out[3 * i + 1] = (float)(out[3 * p + 1] + s * dx + c * dy);
        out[3 * i + 2] = out[3 * p + 2] + (rest[3 * i + 2] - rest[3 * p + 2]);
    }
}

typedef struct draw_result {
    double ms, frags_per_px, steps_per_frag;
} draw_result;

/* MESO_BENCH_PNG=DIR: each timed image is written there as NAME.png. */
static draw_result time_draw(meso_rt* rt, test_fbo* fbo, meso_rt_object obj, int w, int h, const char* name)
{
    float lo[3], hi[3];
    CHECK(meso_rt_object_bounds(rt, obj, lo, hi) == MESO_OK);
    double c[3], r = 0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * (lo[k] + hi[k]);
        r += 0.25 * (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    r = sqrt(r);
    const double fovy = 0.7, dist = r / sin(fovy / 2);
    const double eye[3] = {c[0] + 0.45 * dist, c[1] + 0.55 * dist, c[2] + 0.70 * dist}, up[3] = {0, 1, 0};
    meso_rt_draw_desc d = {0};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, fovy, (double)w / h, 0.05 * dist, 3 * dist);
    meso_rt_draw_stats st;
    d.stats = &st;
    test_fbo_clear(fbo, 0, 0, 0);
    CHECK(meso_rt_draw(rt, obj, &d) == MESO_OK); /* warm-up, counters */
    draw_result res = {.frags_per_px = (double)st.fragments / ((double)w * h),
                       .steps_per_frag = st.fragments ? (double)st.steps / (double)st.fragments : 0.0};
    d.stats = NULL;
    double t[3];
    for (int i = 0; i < 3; ++i) {
        test_fbo_clear(fbo, 0, 0, 0);
        fbo->Finish();
        const double t0 = (1e6 * meso_seconds());
        CHECK(meso_rt_draw(rt, obj, &d) == MESO_OK);
        fbo->Finish();
        t[i] = ((1e6 * meso_seconds()) - t0) / 1e3;
    }
    res.ms = minimum(t, 3);
    if (getenv("MESO_BENCH_PNG")) {
        uint8_t* px = malloc((size_t)w * h * 4);
        char path[4096], why[128];
        CHECK(px != NULL);
        test_fbo_read(fbo, px, NULL);
        snprintf(path, sizeof(path), "%s/%s.png", getenv("MESO_BENCH_PNG"), name);
        meso_png_write_rgba8(path, px, w, h, 1, why, sizeof(why));
        free(px);
    }
    return res;
}

int main(int argc, char** argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_frusta RESULTS_DIR [quick]\n");
        return 1;
    }
    const int quick = argc > 2 && !strcmp(argv[2], "quick");
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    CHECK(egl != NULL);
    const int W = 800, H = 600;
    test_fbo fbo;
    CHECK(test_fbo_create(&fbo, W, H));
    meso_rt* rt = NULL;
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
    char path[4096];
    snprintf(path, sizeof(path), "%s/bench_frusta.csv", argv[1]);
    FILE* csv = fopen(path, "w");
    CHECK(csv != NULL);
    const char* header = "segments,balls,nodes,pose_us_per_1000,cpu_us_per_1000,set_pose_us_per_1000,draw_ms,"
                         "draw_relief_ms,fragments_per_px,steps_per_fragment,relief_steps_per_fragment\n";
    fputs(header, csv);
    fputs(header, stdout);
    const uint32_t sizes[] = {100, 1000, 10000};
    const int nsizes = quick ? 2 : 3;
    for (int si = 0; si < nsizes; ++si) {
        char* swc = cacti_swc(sizes[si], 0x5eed + (uint64_t)si);
        scene plain = bake(swc, 0), relief = bake(swc, 1);
        free(swc);
        meso_rt_object obj = load(rt, &plain);
        uint32_t nf = 0, nn = 0;
        CHECK(meso_rt_frusta_info(rt, obj, &nf, &nn) == MESO_OK);
        float* rest = malloc(sizeof(float) * 3 * nn);
        float* pos = malloc(sizeof(float) * 3 * nn);
        int32_t* parent = malloc(sizeof(int32_t) * nn);
        CHECK(rest && pos && parent && meso_rt_frusta_rest_pose(rt, obj, rest, parent, nn) == MESO_OK);

        /* The pose rebuild alone, on host records decoded from the file. */
        meso_frustum_rec* recs;
        meso_frustum_ball_rec* balls;
        uint32_t nrec, nball;
        frusta_file_records(plain.file, plain.size, &recs, &nrec, &balls, &nball);
        CHECK(nrec == nf);
        const int reps = 5;
        double tp[5], tc[5], ts[5];
        const int inner = sizes[si] >= 10000 ? 2 : sizes[si] >= 1000 ? 10 : 100; /* calls per timing */
        for (int r = -1; r < reps; ++r) {
            double t0 = (1e6 * meso_seconds());
            for (int i = 0; i < inner; ++i) {
                sway(rest, parent, nn, 0.1 * (r * inner + i), pos);
                CHECK(meso_frusta_pose(recs, nf, balls, nball, pos, nn) == 0);
            }
            const double a = ((1e6 * meso_seconds()) - t0) / inner;
            t0 = (1e6 * meso_seconds());
            for (int i = 0; i < inner; ++i) {
                sway(rest, parent, nn, 0.1 * (r * inner + i), pos);
                CHECK(mesoi_frusta_pose_host(rt, obj, pos, nn) == MESO_OK);
            }
            const double b = ((1e6 * meso_seconds()) - t0) / inner;
            fbo.Finish();
            t0 = (1e6 * meso_seconds());
            for (int i = 0; i < inner; ++i) {
                sway(rest, parent, nn, 0.1 * (r * inner + i), pos);
                CHECK(meso_rt_frusta_set_pose(rt, obj, pos, nn) == MESO_OK);
            }
            fbo.Finish();
            const double c = ((1e6 * meso_seconds()) - t0) / inner;
            if (r >= 0)
                tp[r] = a, tc[r] = b, ts[r] = c;
        }
        /* The sway itself is in all three; subtract it. */
        double tsw[5];
        for (int r = 0; r < reps; ++r) {
            const double t0 = (1e6 * meso_seconds());
            for (int i = 0; i < inner; ++i)
                sway(rest, parent, nn, 0.1 * i, pos);
            tsw[r] = ((1e6 * meso_seconds()) - t0) / inner;
        }
        const double sw = minimum(tsw, reps), per = 1000.0 / nf;
        const double pose_us = (minimum(tp, reps) - sw) * per, cpu_us = (minimum(tc, reps) - sw) * per,
                     set_us = (minimum(ts, reps) - sw) * per;
        CHECK(meso_rt_frusta_set_pose(rt, obj, rest, nn) == MESO_OK);
        char name[64];
        snprintf(name, sizeof(name), "frusta_%u", nf);
        draw_result dp = time_draw(rt, &fbo, obj, W, H, name);
        meso_rt_release_object(rt, obj);
        obj = load(rt, &relief);
        snprintf(name, sizeof(name), "frusta_%u_relief", nf);
        draw_result dr = time_draw(rt, &fbo, obj, W, H, name);
        meso_rt_release_object(rt, obj);
        char row[512];
        snprintf(row, sizeof(row), "%u,%u,%u,%.1f,%.1f,%.1f,%.1f,%.1f,%.2f,%.1f,%.1f\n", nf, nball, nn, pose_us,
                 cpu_us, set_us, dp.ms, dr.ms, dp.frags_per_px, dp.steps_per_frag, dr.steps_per_frag);
        fputs(row, csv);
        fputs(row, stdout);
        free(recs);
        free(balls);
        free(rest);
        free(pos);
        free(parent);
        free(plain.file);
        free(relief.file);
    }
    fclose(csv);
    meso_rt_destroy(rt);
    test_fbo_destroy(&fbo);
    meso_egl_destroy(egl);
    return 0;
}
