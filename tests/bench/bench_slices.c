/* bench_slices — Figure 12 of papers/volume-textures-lp-averaged-shells.md
 * (§5) recreated on llvmpipe (issue #19): the `icospheres` volume in a
 * unit-cube shell (tests/common/slices_scene.h), rendered by
 * MESO_SHELL_SLICES with no interpolation, normal interpolation and the
 * paper's texture-coordinate interpolation, and by smooth ray casting, each
 * measured against the exact CPU reference (runtime/reference).
 *
 *  slices.csv        method, knob, value, ms/frame, coverage mismatch, hit
 *                    error (px), colour MAE, normal error mean and median
 *                    (deg), fastest ms: the slice count swept 4..64 for each variant,
 *                    the ray caster's error bound (error_px) 0.25..16 and
 *                    its step limit (max_steps) 4..64;
 *  slices_angle.csv  the same errors as the view leaves the slices' normal
 *                    (elevation 90° = looking along the directors) for
 *                    texcoord@16, none@64 (slices along the view's family,
 *                    the default; _levels: always the levels) and smooth
 *                    ray casting;
 *  slices_fig12.png  side by side: no interpolation at 64 slices, normal
 *                    and texture-coordinate interpolation at 16, smooth ray
 *                    casting, and the exact reference;
 *  slices_thin.csv   a thin shell (the bundled sphere, 12 % thick, the
 *                    domes height field, 640x480): texcoord@16 and none@32
 *                    sliced along the view's family and along the levels at
 *                    60° and 10° elevation - what the view's family costs
 *                    (twice the vertices a prism) where the levels do well;
 *  slices_axis.png   at 15° elevation, texcoord@16 sliced along the view's
 *                    family and along the levels, and the exact reference.
 *
 * usage: bench_slices RESULTS_DIR [quick]   (quick: 200x200, fewer points)
 * Image 400x400 (the paper's is 800x800; llvmpipe on 2 shared cores).
 * Timing: median of 11 draws after a warm-up draw, each ended by glFinish.
 * Normal error: slices_scene.h (six draws with lights along ±x, ±y, ±z). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "adapters.h"
#include "bench_gl.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_rt.h"
#include "shell_reference.h"
#include "slices_scene.h"

enum { FRAMES = 11 };

static const char* const interp_names[MESO_SLICE_INTERP_COUNT] = {"texcoord", "normal", "none"};

typedef struct row {
    double ms, ms_min;
    metrics m;
    normal_error n;
} row;

/* Median ms of FRAMES draws (after one warm-up), glFinish-timed; *min the
 * fastest (the machine is shared: the median moves with the load). */
static double median_ms(bench* b, meso_rt_object obj, const meso_rt_draw_desc* d, double* min)
{
    double ms[FRAMES];
    for (int r = 0; r <= FRAMES; ++r) {
        test_fbo_clear(&b->fbo, 0, 0, 0);
        b->fbo.Finish();
        const double t0 = 1e3 * meso_seconds();
        if (meso_rt_draw(b->rt, obj, d) != MESO_OK) {
            fprintf(stderr, "bench_slices: draw failed\n");
            exit(1);
        }
        b->fbo.Finish();
        if (r > 0)
            ms[r - 1] = 1e3 * meso_seconds() - t0;
    }
    qsort(ms, FRAMES, sizeof(double), cmp_double);
    *min = ms[0];
    return ms[FRAMES / 2];
}

static row measure(bench* b, meso_rt_object obj, meso_rt_draw_desc d, const meso_ref_image* ref, uint8_t* rgba,
                   float* depth)
{
    memcpy(d.view, b->view, sizeof(d.view));
    memcpy(d.proj, b->proj, sizeof(d.proj));
    row r;
    r.ms = median_ms(b, obj, &d, &r.ms_min);
    test_fbo_clear(&b->fbo, 0, 0, 0);
    CHECK(meso_rt_draw(b->rt, obj, &d) == MESO_OK);
    test_fbo_read(&b->fbo, rgba, depth);
    r.m = compare(rgba, depth, ref, d.view, d.proj, b->cam.fovy, NULL);
    r.n = normal_error_deg(b->rt, &b->fbo, obj, d, ref, rgba, depth);
    return r;
}

static void reference(const meso_ref_shell* rs, const bench* b, meso_ref_image* img)
{
    meso_ref_view v = {.width = scene_w, .height = scene_h, .samples_per_prism = 512};
    for (int i = 0; i < 16; ++i)
        v.view[i] = b->view[i], v.proj[i] = b->proj[i];
    CHECK(meso_ref_render(rs, &v, img) == MESO_OK);
}

static meso_rt_draw_desc slices(meso_slice_interp interp, int n)
{
    return (meso_rt_draw_desc){.shell = {.technique = MESO_SHELL_SLICES, .slices = n, .slice_interp = interp}};
}

static void put_row(FILE* f, const char* method, const char* knob, double value, row r)
{
    fprintf(f, "%s,%s,%g,%.3f,%.5f,%.4f,%.5f,%.3f,%.3f,%.3f\n", method, knob, value, r.ms, r.m.coverage_mismatch,
            r.m.hit_err_px, r.m.colour_mae, r.n.mean_deg, r.n.median_deg, r.ms_min);
    printf("%-9s %-9s %6g  %8.2f ms (min %.2f)  coverage %.4f  hit %.3f px  colour %.4f  normal mean %.2f median %.2f deg\n",
           method, knob, value, r.ms, r.ms_min, r.m.coverage_mismatch, r.m.hit_err_px, r.m.colour_mae, r.n.mean_deg,
           r.n.median_deg);
}

/* The n draws of ds, then the reference, side by side into path. */
static void strip_png(bench* b, meso_rt_object obj, const meso_rt_draw_desc* ds, int n, const meso_ref_image* ref,
                      uint8_t* rgba, const char* path)
{
    const int S = scene_w, cols = n + 1;
    uint8_t* strip = malloc((size_t)cols * S * S * 4);
    for (int k = 0; k < cols; ++k) {
        if (k < n) {
            meso_rt_draw_desc d = ds[k];
            memcpy(d.view, b->view, sizeof(d.view));
            memcpy(d.proj, b->proj, sizeof(d.proj));
            test_fbo_clear(&b->fbo, 0, 0, 0);
            CHECK(meso_rt_draw(b->rt, obj, &d) == MESO_OK);
            test_fbo_read(&b->fbo, rgba, NULL);
        } else {
            for (size_t i = 0; i < (size_t)S * S; ++i) {
                for (int c = 0; c < 3; ++c)
                    rgba[4 * i + (size_t)c] =
                        ref->coverage[i] ? (uint8_t)lround(255.0 * fmin(ref->rgb[3 * i + (size_t)c], 1.0)) : 0;
                rgba[4 * i + 3] = 255;
            }
        }
        for (int y = 0; y < S; ++y)
            memcpy(strip + ((size_t)y * cols * S + (size_t)k * S) * 4, rgba + (size_t)y * S * 4, (size_t)S * 4);
    }
    char why[256];
    CHECK(meso_png_write_rgba8(path, strip, cols * S, S, 1, why, sizeof(why)) == 0);
    free(strip);
}

/* slices_thin.csv (see the header). */
static void thin_shell(bench* b, const char* dir, int quick)
{
    meso_mesh m;
    meso_error err;
    CHECK(meso_openmesh_read(MESO_TEST_DATA "/sphere.obj", &m, NULL, &err) == MESO_OK);
    planar_uvs(&m, 2.0);
    texture height = make_height(64);
    size_t size;
    uint8_t* file = shell_file(&m, 0.12, &height, 1, &size);
    meso_file* f = NULL;
    CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    CHECK(meso_rt_load_object(b->rt, f, 1, &obj) == MESO_OK);
    meso_ref_shell rs;
    CHECK(meso_ref_shell_load(f, 1, &rs, &err) == MESO_OK);
    meso_file_close(f);
    const int w = quick ? 320 : 640, h = quick ? 240 : 480;
    bench_set_size(b, w, h);
    uint8_t* rgba = malloc((size_t)w * h * 4);
    float* depth = malloc(sizeof(float) * (size_t)w * h);
    char path[1024];
    snprintf(path, sizeof(path), "%s/slices_thin.csv", dir);
    FILE* out = fopen(path, "w");
    CHECK(out);
    fprintf(out, "method,knob,value,ms,coverage_mismatch,hit_err_px,colour_mae,normal_mean_deg,normal_median_deg,"
                 "ms_min\n");
    static const double elevations[] = {60, 10};
    for (int e = 0; e < 2; ++e) {
        const double el = elevations[e] * M_PI / 180.0;
        b->cam = (camera){.at = {0, 0, 0}, .fovy = 0.75, .zn = 0.3, .zf = 10};
        b->cam.eye[0] = 2.2 * cos(el) * 0.6;
        b->cam.eye[2] = 2.2 * cos(el) * 0.8;
        b->cam.eye[1] = 2.2 * sin(el);
        camera_matrices(&b->cam, b->view, b->proj);
        meso_ref_image ref;
        reference(&rs, b, &ref);
        static const char* const names[4] = {"texcoord16", "texcoord16_levels", "none32", "none32_levels"};
        for (int k = 0; k < 4; ++k) {
            meso_rt_draw_desc d = slices(k < 2 ? MESO_SLICE_TEXCOORD : MESO_SLICE_NONE, k < 2 ? 16 : 32);
            d.shell.slice_axis = (k & 1) ? MESO_SLICE_AXIS_LEVELS : MESO_SLICE_AXIS_VIEW;
            put_row(out, names[k], "elevation_deg", elevations[e], measure(b, obj, d, &ref, rgba, depth));
        }
        put_row(out, "smooth", "elevation_deg", elevations[e],
                measure(b, obj, (meso_rt_draw_desc){0}, &ref, rgba, depth));
        meso_ref_image_free(&ref);
    }
    fclose(out);
    free(rgba);
    free(depth);
    meso_ref_shell_free(&rs);
    meso_rt_release_object(b->rt, obj);
    free(file);
    free(height.texels);
    meso_mesh_free(&m);
}

int main(int argc, char** argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_slices RESULTS_DIR [quick]\n");
        return 2;
    }
    setvbuf(stdout, NULL, _IONBF, 0);
    const int quick = argc > 2 && !strcmp(argv[2], "quick");
    const int S = quick ? 200 : 400;
    bench b = {0};
    meso_egl* egl = bench_gl_open(&b, "bench_slices");
    if (!egl)
        return 1;
    b.cam = icospheres_camera();
    bench_set_size(&b, S, S);
    size_t size;
    uint8_t* file = icospheres_file(64, &size);
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    CHECK(meso_rt_load_object(b.rt, f, 1, &obj) == MESO_OK);
    meso_ref_shell rs;
    CHECK(meso_ref_shell_load(f, 1, &rs, &err) == MESO_OK);
    meso_file_close(f);
    meso_ref_image ref;
    reference(&rs, &b, &ref);
    uint8_t* rgba = malloc((size_t)S * S * 4);
    float* depth = malloc(sizeof(float) * S * S);

    char path[1024];
    snprintf(path, sizeof(path), "%s/slices.csv", argv[1]);
    FILE* out = fopen(path, "w");
    CHECK(out);
    fprintf(out, "method,knob,value,ms,coverage_mismatch,hit_err_px,colour_mae,normal_mean_deg,normal_median_deg,"
                 "ms_min\n");
    static const int counts[] = {4, 6, 8, 12, 16, 24, 32, 48, 64};
    static const int quick_counts[] = {4, 16, 64};
    const int nc = quick ? 3 : (int)(sizeof(counts) / sizeof(counts[0]));
    for (int v = MESO_SLICE_NONE; v >= MESO_SLICE_TEXCOORD; --v)
        for (int i = 0; i < nc; ++i) {
            const int n = quick ? quick_counts[i] : counts[i];
            put_row(out, interp_names[v], "slices", n,
                    measure(&b, obj, slices((meso_slice_interp)v, n), &ref, rgba, depth));
        }
    static const double errs[] = {0.25, 0.5, 1, 2, 4, 8, 16};
    for (int i = 0; i < (quick ? 3 : 7); ++i) {
        const meso_rt_draw_desc d = {.shell = {.technique = MESO_SHELL_SMOOTH, .error_px = (float)errs[i]}};
        put_row(out, "smooth", "error_px", errs[i], measure(&b, obj, d, &ref, rgba, depth));
    }
    static const int steps[] = {4, 8, 16, 32, 64};
    for (int i = 0; i < (quick ? 2 : 5); ++i) {
        const meso_rt_draw_desc d = {.shell = {.technique = MESO_SHELL_SMOOTH, .max_steps = steps[i]}};
        put_row(out, "smooth", "max_steps", steps[i], measure(&b, obj, d, &ref, rgba, depth));
    }
    fclose(out);

    /* Figure 12 side by side: none@64, normal@16, texcoord@16, smooth, reference. */
    {
        const meso_rt_draw_desc ds[4] = {slices(MESO_SLICE_NONE, 64), slices(MESO_SLICE_NORMAL, 16),
                                         slices(MESO_SLICE_TEXCOORD, 16),
                                         {.shell = {.technique = MESO_SHELL_SMOOTH}}};
        snprintf(path, sizeof(path), "%s/slices_fig12.png", argv[1]);
        strip_png(&b, obj, ds, 4, &ref, rgba, path);
    }

    /* The view angle. */
    snprintf(path, sizeof(path), "%s/slices_angle.csv", argv[1]);
    out = fopen(path, "w");
    CHECK(out);
    fprintf(out, "method,knob,value,ms,coverage_mismatch,hit_err_px,colour_mae,normal_mean_deg,normal_median_deg,"
                 "ms_min\n");
    static const double elevations[] = {90, 75, 60, 45, 30, 15};
    for (int e = 0; e < (quick ? 2 : 6); ++e) {
        b.cam = icospheres_camera_at(elevations[e]);
        camera_matrices(&b.cam, b.view, b.proj);
        meso_ref_image_free(&ref);
        reference(&rs, &b, &ref);
        put_row(out, "texcoord16", "elevation_deg", elevations[e],
                measure(&b, obj, slices(MESO_SLICE_TEXCOORD, 16), &ref, rgba, depth));
        put_row(out, "none64", "elevation_deg", elevations[e],
                measure(&b, obj, slices(MESO_SLICE_NONE, 64), &ref, rgba, depth));
        meso_rt_draw_desc lv = slices(MESO_SLICE_TEXCOORD, 16);
        lv.shell.slice_axis = MESO_SLICE_AXIS_LEVELS;
        put_row(out, "texcoord16_levels", "elevation_deg", elevations[e], measure(&b, obj, lv, &ref, rgba, depth));
        lv = slices(MESO_SLICE_NONE, 64);
        lv.shell.slice_axis = MESO_SLICE_AXIS_LEVELS;
        put_row(out, "none64_levels", "elevation_deg", elevations[e], measure(&b, obj, lv, &ref, rgba, depth));
        put_row(out, "smooth", "elevation_deg", elevations[e],
                measure(&b, obj, (meso_rt_draw_desc){0}, &ref, rgba, depth));
    }
    fclose(out);

    /* The slicing family at 15°: the view's family, the levels, reference. */
    {
        b.cam = icospheres_camera_at(15.0);
        camera_matrices(&b.cam, b.view, b.proj);
        meso_ref_image_free(&ref);
        reference(&rs, &b, &ref);
        meso_rt_draw_desc ds[2] = {slices(MESO_SLICE_TEXCOORD, 16), slices(MESO_SLICE_TEXCOORD, 16)};
        ds[1].shell.slice_axis = MESO_SLICE_AXIS_LEVELS;
        snprintf(path, sizeof(path), "%s/slices_axis.png", argv[1]);
        strip_png(&b, obj, ds, 2, &ref, rgba, path);
    }

    thin_shell(&b, argv[1], quick);

    free(rgba);
    free(depth);
    meso_ref_image_free(&ref);
    meso_ref_shell_free(&rs);
    meso_rt_release_object(b.rt, obj);
    free(file);
    test_fbo_destroy(&b.fbo);
    meso_rt_destroy(b.rt);
    meso_egl_destroy(egl);
    return 0;
}
