/* bench_shell_render — shell ray casting on llvmpipe (issue #5):
 *
 *  table1.csv   the paper's Table 1 on a bundled mesh with a height field
 *               (spot + the `bricks` built-in, baked by mesobake): ms/frame
 *               and ray steps per covered pixel for segment-only, smooth,
 *               curved and tetra at 800x600, 640x480 and 1280x1024, half and
 *               double thickness (directors scaled through
 *               meso_rt_shell_update), 8x and 1/8 tiling (uv_scale), and
 *               the reference setup again without hull rejection
 *               (no_hull_reject: every hull fragment ray casts, issue 14)
 *               and without the walk (no_prism_walk: smooth prisms draw
 *               all their entry faces); fragments_per_px counts the
 *               ray-casting ones, rejected_per_px those stopped behind a
 *               hit found already;
 *  shell_render_error.csv  each technique against the exact reference
 *               (smooth and curved mappings) at 400x300;
 *  shell_render_sweep.csv  cost against error as the knobs move: error
 *               bound, step limit, fixed step without a distance map, and
 *               the distance-map resolution (files re-baked with --dist-res).
 *
 * usage: bench_shell_render RESULTS_DIR MESOBAKE DATA_DIR [quick | table]
 * (quick: 1 repetition, smaller sweep images, no re-bakes; table: Table 1 only)
 * Timing: median of 3 draws after a warm-up draw, glFinish included. The
 * counted steps come from the shaders' counters (OpenGL 4.3). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bench_gl.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_rt.h"
#include "shell_reference.h"
#include "shell_scene.h"

static const char* const tech_names[MESO_SHELL_TECHNIQUE_COUNT] = {
    [MESO_SHELL_SMOOTH] = "smooth", [MESO_SHELL_CURVED] = "curved", [MESO_SHELL_TETRA] = "tetra",
    [MESO_SHELL_SEGMENT_ONLY] = "segment"};
static const meso_shell_technique tech_order[4] = {MESO_SHELL_SEGMENT_ONLY, MESO_SHELL_SMOOTH, MESO_SHELL_CURVED,
                                                   MESO_SHELL_TETRA};

typedef struct timing {
    double ms, steps_per_px, frags_per_px, rejected_per_px;
    long covered;
} timing;

/* Draw 1 + reps times; median ms; steps/covered pixel from a stats draw. */
static timing time_draw(bench* b, meso_rt_object obj, meso_rt_draw_desc d, int reps, uint8_t* rgba, float* depth)
{
    const double median = bench_median_ms(b, obj, d, reps);
    memcpy(d.view, b->view, sizeof(d.view));
    memcpy(d.proj, b->proj, sizeof(d.proj));
    meso_rt_draw_stats st;
    d.stats = &st;
    test_fbo_clear(&b->fbo, 0, 0, 0);
    meso_rt_draw(b->rt, obj, &d);
    const size_t n = (size_t)b->fbo.w * (size_t)b->fbo.h;
    float* dep = depth ? depth : malloc(sizeof(float) * n);
    test_fbo_read(&b->fbo, rgba, dep);
    long covered = 0;
    for (size_t i = 0; i < n; ++i)
        covered += dep[i] < 1.0f;
    if (!depth)
        free(dep);
    timing t = {.ms = median, .covered = covered,
                .steps_per_px = covered ? (double)st.steps / (double)covered : 0.0,
                .frags_per_px = covered ? (double)st.fragments / (double)covered : 0.0,
                .rejected_per_px = covered ? (double)st.rejected / (double)covered : 0.0};
    return t;
}

static meso_rt_object load_object(bench* b, const char* path, meso_ref_shell* ref)
{
    meso_file* f = NULL;
    meso_error err;
    meso_rt_object obj = {0};
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK || meso_rt_load_object(b->rt, f, 1, &obj) != MESO_OK ||
        (ref && meso_ref_shell_load(f, 1, ref, &err) != MESO_OK)) {
        fprintf(stderr, "bench_shell_render: cannot load %s\n", path);
        exit(1);
    }
    meso_file_close(f);
    return obj;
}

static void bake(const char* mesobake, const char* data, const char* out, const char* extra)
{
    char cmd[2048];
    snprintf(cmd, sizeof(cmd),
             "%s shell -i %s/spot_low_resolution.obj -o %s --thickness-rel 0.04 --texture bricks --tiling 3,3 %s",
             mesobake, data, out, extra);
    fprintf(stderr, "== %s\n", cmd);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_shell_render: bake failed\n");
        exit(1);
    }
}

int main(int argc, char** argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: bench_shell_render RESULTS_DIR MESOBAKE DATA_DIR [quick | table]\n");
        return 2;
    }
    const char *dir = argv[1], *mesobake = argv[2], *data = argv[3];
    const int quick = argc > 4 && !strcmp(argv[4], "quick");
    const int table_only = argc > 4 && !strcmp(argv[4], "table");
    char tmp[] = "/tmp/meso_bench_shell_XXXXXX";
    if (!mkdtemp(tmp))
        return 1;
    char path[1024], csv[1024];
    snprintf(path, sizeof(path), "%s/spot_bricks.meso", tmp);
    bake(mesobake, data, path, "");

    bench b = {0};
    meso_egl* egl = bench_gl_open(&b, "bench_shell_render");
    if (!egl)
        return 1;
    meso_ref_shell ref;
    meso_rt_object obj = load_object(&b, path, &ref);
    double ctr[3], rad = 0;
    for (int k = 0; k < 3; ++k) {
        ctr[k] = 0.5 * (ref.bbox_min[k] + ref.bbox_max[k]);
        rad += (ref.bbox_max[k] - ref.bbox_min[k]) * (ref.bbox_max[k] - ref.bbox_min[k]);
    }
    rad = 0.5 * sqrt(rad);
    const double yaw = 210 * M_PI / 180, pitch = 15 * M_PI / 180, dist = 2.4 * rad;
    b.cam = (camera){.eye = {ctr[0] + dist * cos(pitch) * sin(yaw), ctr[1] + dist * sin(pitch),
                             ctr[2] + dist * cos(pitch) * cos(yaw)},
                     .at = {ctr[0], ctr[1], ctr[2]}, .fovy = 0.7, .zn = 0.2 * rad, .zf = 10 * rad};
    const int reps = quick ? 1 : 3;

    /* --- Table 1 --------------------------------------------------------- */
    uint32_t nv = 0, layers = 0;
    meso_rt_shell_info(b.rt, obj, &nv, &layers);
    float* dirs = malloc(sizeof(float) * 3 * nv * layers);
    memcpy(dirs, ref.directors, sizeof(float) * 3 * nv * layers);
    float* scaled = malloc(sizeof(float) * 3 * nv * layers);
    snprintf(csv, sizeof(csv), "%s/table1.csv", dir);
    FILE* t1 = fopen(csv, "w");
    fprintf(t1, "test,technique,width,height,ms,steps_per_px,fragments_per_px,covered_px,rejected_per_px\n");
    struct row {
        const char* name;
        int w, h;
        double thick, tiling;
        int no_reject; /* 1: no hull rejection; 2: rejection without the walk */
    } rows[] = {{"reference setup", 800, 600, 1, 1, 0},    {"without rejection", 800, 600, 1, 1, 1},
                {"without the walk", 800, 600, 1, 1, 2},
                {"screen 640x480", 640, 480, 1, 1, 0},     {"screen 1280x1024", 1280, 1024, 1, 1, 0},
                {"half thickness", 800, 600, 0.5, 1, 0},   {"double thickness", 800, 600, 2, 1, 0},
                {"8x tiling", 800, 600, 1, 8, 0},          {"1/8 tiling", 800, 600, 1, 0.125, 0}};
    for (size_t r = 0; r < sizeof(rows) / sizeof(rows[0]); ++r) {
        bench_set_size(&b, rows[r].w, rows[r].h);
        for (size_t i = 0; i < 3 * (size_t)nv * layers; ++i)
            scaled[i] = (float)(dirs[i] * rows[r].thick);
        meso_rt_shell_update(b.rt, obj, NULL, scaled, nv);
        for (int t = 0; t < 4; ++t) {
            meso_rt_draw_desc d = {.shell = {.technique = tech_order[t], .uv_scale = (float)rows[r].tiling,
                                             .no_hull_reject = rows[r].no_reject == 1,
                                             .no_prism_walk = rows[r].no_reject == 2}};
            timing tm = time_draw(&b, obj, d, reps, NULL, NULL);
            fprintf(t1, "%s,%s,%d,%d,%.2f,%.2f,%.2f,%ld,%.2f\n", rows[r].name, tech_names[tech_order[t]],
                    rows[r].w, rows[r].h, tm.ms, tm.steps_per_px, tm.frags_per_px, tm.covered, tm.rejected_per_px);
            fprintf(stderr, "table1 %-18s %-8s %8.1f ms %7.1f steps/px %5.2f fragments/px %5.2f rejected/px\n",
                    rows[r].name, tech_names[tech_order[t]], tm.ms, tm.steps_per_px, tm.frags_per_px,
                    tm.rejected_per_px);
            fflush(t1);
        }
    }
    fclose(t1);
    meso_rt_shell_update(b.rt, obj, NULL, dirs, nv);
    uint8_t* rgba = NULL;
    float* depth = NULL;
    meso_ref_image refimg[2];
    memset(refimg, 0, sizeof(refimg));
    if (table_only)
        goto finish;

    /* --- error against the reference and the sweeps, at 400x300 ---------- */
    bench_set_size(&b, quick ? 200 : 400, quick ? 150 : 300);
    const size_t npx = (size_t)scene_w * scene_h;
    rgba = malloc(npx * 4);
    depth = malloc(sizeof(float) * npx);
    for (int cv = 0; cv < 2; ++cv) {
        meso_ref_view v = {.width = scene_w, .height = scene_h, .curved = cv, .samples_per_prism = 512};
        for (int i = 0; i < 16; ++i)
            v.view[i] = b.view[i], v.proj[i] = b.proj[i];
        const double t0 = meso_seconds();
        if (meso_ref_render(&ref, &v, &refimg[cv]) != MESO_OK)
            return 1;
        fprintf(stderr, "reference (%s) %dx%d: %.1f s\n", cv ? "curved" : "smooth", scene_w, scene_h,
                meso_seconds() - t0);
    }
    snprintf(csv, sizeof(csv), "%s/shell_render_sweep.csv", dir);
    FILE* sw = fopen(csv, "w");
    fprintf(sw, "technique,knob,value,ms,steps_per_px,off_px,coverage_mismatch,hit_err_px,colour_mae\n");
#define MEASURE(TECH, KNOB, VALUE, DESC, OBJ)                                                                        \
    do {                                                                                                             \
        timing tm_ = time_draw(&b, OBJ, DESC, reps, rgba, depth);                                                    \
        metrics m_ = compare(rgba, depth, &refimg[(TECH) == MESO_SHELL_CURVED], b.view, b.proj, b.cam.fovy, NULL);   \
        fprintf(sw, "%s,%s,%g,%.2f,%.2f,%.5f,%.5f,%.4f,%.5f\n", tech_names[TECH], KNOB, (double)(VALUE), tm_.ms,     \
                tm_.steps_per_px, m_.off_pixel, m_.coverage_mismatch, m_.hit_err_px, m_.colour_mae);                 \
        fprintf(stderr, "sweep %-7s %-10s %-8g %8.1f ms %6.1f steps/px  off %.4f  cov %.4f  hit %.3f px  colour %.4f\n", \
                tech_names[TECH], KNOB, (double)(VALUE), tm_.ms, tm_.steps_per_px, m_.off_pixel,                     \
                m_.coverage_mismatch, m_.hit_err_px, m_.colour_mae);                                                 \
        fflush(sw);                                                                                                  \
    } while (0)
    const meso_shell_technique three[3] = {MESO_SHELL_SMOOTH, MESO_SHELL_CURVED, MESO_SHELL_TETRA};
    for (int t = 0; t < 3; ++t)
        MEASURE(three[t], "defaults", 0, ((meso_rt_draw_desc){.shell = {.technique = three[t]}}), obj);
    const float errs[] = {0.25f, 0.5f, 1, 2, 4, 8, 16, 64};
    for (int t = 0; t < 2; ++t)
        for (size_t i = 0; i < sizeof(errs) / sizeof(errs[0]); ++i)
            MEASURE(three[t], "error_px", errs[i],
                    ((meso_rt_draw_desc){.shell = {.technique = three[t], .error_px = errs[i]}}), obj);
    const int steps[] = {2, 4, 8, 12, 16, 24, 32, 64, 256};
    for (int t = 0; t < 3; ++t)
        for (size_t i = 0; i < sizeof(steps) / sizeof(steps[0]); ++i)
            MEASURE(three[t], "max_steps", steps[i],
                    ((meso_rt_draw_desc){.shell = {.technique = three[t], .max_steps = steps[i]}}), obj);
    const float fixed[] = {1.0f / 16, 1.0f / 32, 1.0f / 64, 1.0f / 128, 1.0f / 256, 1.0f / 512};
    for (int t = 0; t < 3; ++t)
        for (size_t i = 0; i < sizeof(fixed) / sizeof(fixed[0]); ++i)
            MEASURE(three[t], "fixed_step", fixed[i],
                    ((meso_rt_draw_desc){.shell = {.technique = three[t], .no_distance_map = 1,
                                                   .fixed_step = fixed[i], .max_steps = 4096}}),
                    obj);
    const char* const dres[] = {"4x4x4", "8x8x8", "16x16x8", "32x32x16", "64x64x32", "128x128x64"};
    for (size_t i = 0; i < sizeof(dres) / sizeof(dres[0]) && !quick; ++i) {
        char p2[1024], extra[64];
        snprintf(p2, sizeof(p2), "%s/spot_dist_%zu.meso", tmp, i);
        snprintf(extra, sizeof(extra), "--dist-res %s", dres[i]);
        bake(mesobake, data, p2, extra);
        meso_rt_object o2 = load_object(&b, p2, NULL);
        int cells = 1;
        for (const char* c = dres[i]; *c;) {
            cells *= atoi(c);
            while (*c && *c != 'x')
                ++c;
            if (*c)
                ++c;
        }
        for (int t = 0; t < 3; ++t)
            MEASURE(three[t], "dist_cells", cells,
                    ((meso_rt_draw_desc){.shell = {.technique = three[t], .max_steps = 4096}}), o2);
        meso_rt_release_object(b.rt, o2);
        unlink(p2);
    }
    fclose(sw);
finish:
    unlink(path);
    rmdir(tmp);
    meso_ref_image_free(&refimg[0]);
    meso_ref_image_free(&refimg[1]);
    meso_ref_shell_free(&ref);
    free(rgba);
    free(depth);
    free(dirs);
    free(scaled);
    meso_rt_release_object(b.rt, obj);
    test_fbo_destroy(&b.fbo);
    meso_rt_destroy(b.rt);
    meso_egl_destroy(egl);
    return 0;
}
