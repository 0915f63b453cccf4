/* bench_cells_render — cells objects (FORMAT.md §7.2 kind 3) ray traced by
 * libmeso on llvmpipe against the exact CPU reference
 * (runtime/reference/cell_reference.h), on the thesis's Figure 5.1 (top)
 * bunny: `mesobake cells --tile-res 64 --tiles 128 --tile-map voronoi:8`
 * (papers/cell-based-object-representation.md §5.2-5.3):
 *
 *  cells_render_step.csv   first hit: the thesis's linear search
 *               (Algorithm 3.1) at cells.step = R/16 .. R/512 tile-map voxels
 *               (its Table 5.4 steps 1/16 .. 1/512 of a tile), with the step
 *               fixed (cells.fixed_step = 1) and scaled by the angle to the
 *               base mesh (0), and meso's exact voxel traversal (step 0):
 *               median ms, steps per fragment (the shaders' counters), and
 *               the error against the exact reference: coverage mismatch,
 *               mean hit error in pixel footprints, the share of hits off by
 *               more than 1 px, colour MAE;
 *  cells_render_order.csv  reflection (§3.2.3) and refraction (§3.2.4) with
 *               0..3 bounces, exact traversal: ms, steps per fragment, colour
 *               MAE against the reference of the same order (correctness),
 *               and the reference's own change from order b to order 3 (mean
 *               and the share of pixels changing by more than 2/255: how
 *               much the higher orders still add, the thesis's "hardly
 *               visible").
 *
 * Views at 400x300: `full` (the whole bunny, 38 % of the frame) and
 * `close` (a close-up of its flank covering 99 % of the frame, Table 5.3
 * style). Pictures (GL, 400x300, a closer view where cells are a few pixels
 * wide): cells_first.png, cells_reflect.png and cells_refract.png (2
 * bounces). Timing: median of 3 draws after a warm-up, glFinish included;
 * the counts come from one more draw with stats (OpenGL 4.3). The
 * searches run with the default cells.max_steps (4096): with the angle rule
 * at steps of 1/4 voxel and below, grazing rays run out of steps and miss
 * (holes; 65536 steps remove them).
 * usage: bench_cells_render RESULTS_DIR MESOBAKE MESH [quick | pictures]
 * (MESH: meson's benchmark and run_benchmarks.sh pass the bundled
 * tests/data/spot_low_resolution.obj, run_benchmarks.sh $MESO_BENCH_MESH if
 * set; the checked-in results and pictures are of the thesis's Stanford
 * bunny, which cannot be bundled: its terms forbid commercial use)
 * (quick: the full view only, 3 step sizes, orders 0 and 3; pictures: the
 * three pictures only). MESO_TEST_PNG=DIR also writes each measured
 * image's GL, reference and difference PNGs (tests/common/shell_scene.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_gl.h"
#include "cell_reference.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_rt.h"
#include "png_io.h"
#include "shell_scene.h"

typedef struct timing {
    double ms, steps_per_frag;
    uint64_t fragments;
} timing;

/* Median ms of 3 draws after a warm-up, then one draw with stats whose
 * image is read back. */
static timing time_draw(bench* b, meso_rt_object obj, meso_rt_draw_desc d, uint8_t* rgba, float* depth)
{
    timing t = {.ms = bench_median_ms(b, obj, d, 3)};
    memcpy(d.view, b->view, sizeof(d.view));
    memcpy(d.proj, b->proj, sizeof(d.proj));
    meso_rt_draw_stats st = {0};
    d.stats = &st;
    test_fbo_clear(&b->fbo, 0, 0, 0);
    if (meso_rt_draw(b->rt, obj, &d) != MESO_OK) {
        fprintf(stderr, "bench_cells_render: draw failed\n");
        exit(1);
    }
    test_fbo_read(&b->fbo, rgba, depth);
    t.fragments = st.fragments;
    t.steps_per_frag = st.fragments ? (double)st.steps / (double)st.fragments : 0.0;
    return t;
}

/* The reference with the bench's camera; seconds to stderr. */
static meso_ref_image reference(const bench* b, const meso_ref_cells* ref, int mode, int bounces, const char* what)
{
    meso_ref_view v = {.width = scene_w, .height = scene_h};
    for (int i = 0; i < 16; ++i)
        v.view[i] = b->view[i], v.proj[i] = b->proj[i];
    const meso_ref_cells_opts o = {.mode = mode, .bounces = bounces};
    meso_ref_image img;
    const double t0 = meso_seconds();
    if (meso_ref_cells_render(ref, &v, &o, &img) != MESO_OK) {
        fprintf(stderr, "bench_cells_render: reference failed\n");
        exit(1);
    }
    fprintf(stderr, "reference %s (mode %d, %d bounces) %dx%d: %.1f s\n", what, mode, bounces, scene_w, scene_h,
            meso_seconds() - t0);
    return img;
}

/* Looking at `at` from direction (yaw, pitch) at distance dist. */
static camera look(const double at[3], double yaw_deg, double pitch_deg, double dist, double zn, double zf)
{
    const double yaw = yaw_deg * M_PI / 180, pitch = pitch_deg * M_PI / 180;
    return (camera){.eye = {at[0] + dist * cos(pitch) * sin(yaw), at[1] + dist * sin(pitch),
                            at[2] + dist * cos(pitch) * cos(yaw)},
                    .at = {at[0], at[1], at[2]}, .fovy = 0.7, .zn = zn, .zf = zf};
}

/* Mean |a - b| over channels and the share of pixels with a channel
 * differing by more than 2/255, over pixels both images cover. */
static void ref_change(const meso_ref_image* a, const meso_ref_image* b, double* mae, double* share)
{
    const size_t n = (size_t)a->width * (size_t)a->height;
    double sum = 0;
    long both = 0, big = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!a->coverage[i] || !b->coverage[i])
            continue;
        ++both;
        double mx = 0;
        for (int k = 0; k < 3; ++k) {
            const double d = fabs((double)a->rgb[3 * i + (size_t)k] - (double)b->rgb[3 * i + (size_t)k]);
            sum += d;
            mx = fmax(mx, d);
        }
        big += mx > 2.0 / 255.0;
    }
    *mae = both ? sum / (3.0 * (double)both) : 0.0;
    *share = both ? (double)big / (double)both : 0.0;
}

/* The share of pixels covered by both whose colours differ by more than 0.1
 * in some channel (tests/gl/test_rt_cells.c's `colour bad`). */
static double colour_bad(const uint8_t* rgba, const float* depth, const meso_ref_image* img)
{
    const size_t n = (size_t)img->width * (size_t)img->height;
    long both = 0, bad = 0;
    for (size_t i = 0; i < n; ++i)
        if (img->coverage[i] && depth[i] < 1.0f) {
            ++both;
            int d = 0;
            for (int k = 0; k < 3; ++k)
                d |= fabs(rgba[4 * i + (size_t)k] / 255.0 - img->rgb[3 * i + (size_t)k]) > 0.1;
            bad += d;
        }
    return both ? (double)bad / (double)both : 0.0;
}

static void write_png(const char* dir, const char* name, const uint8_t* rgba)
{
    char path[1024], why[256];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    /* Rows come bottom first from glReadPixels: flip. */
    if (meso_png_write_rgba8(path, rgba, scene_w, scene_h, 1, why, (int)sizeof(why)) != 0)
        fprintf(stderr, "bench_cells_render: %s: %s\n", path, why);
    else
        fprintf(stderr, "wrote %s\n", path);
}

int main(int argc, char** argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: bench_cells_render RESULTS_DIR MESOBAKE MESH [quick | pictures]\n");
        return 2;
    }
    const char *dir = argv[1], *mesobake = argv[2], *mesh = argv[3];
    const int quick = argc > 4 && !strcmp(argv[4], "quick");
    const int pictures_only = argc > 4 && !strcmp(argv[4], "pictures");
    char tmp[] = "/tmp/meso_bench_cells_XXXXXX";
    if (!mkdtemp(tmp))
        return 1;
    char path[1024], cmd[4096], csv[1024];
    snprintf(path, sizeof(path), "%s/bunny_cells.meso", tmp);
    snprintf(cmd, sizeof(cmd), "'%s' cells -i '%s' -o '%s' --tile-res 64 --tiles 128 --tile-map voronoi:8 -j 2",
             mesobake, mesh, path);
    fprintf(stderr, "== %s\n", cmd);
    const double tb = meso_seconds();
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_cells_render: bake failed\n");
        return 1;
    }
    fprintf(stderr, "bake: %.1f s\n", meso_seconds() - tb);

    bench b = {0};
    meso_egl* egl = bench_gl_open(&b, "bench_cells_render");
    if (!egl)
        return 1;
    meso_file* f = NULL;
    meso_error err;
    meso_rt_object obj = {0};
    meso_ref_cells ref;
    meso_object_record rec;
    uint32_t nobj = 0;
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK || meso_file_objects(f, &rec, 1, &nobj, &err) != MESO_OK ||
        nobj != 1 || meso_rt_load_object(b.rt, f, rec.id, &obj) != MESO_OK ||
        meso_ref_cells_load(f, rec.id, &ref, &err) != MESO_OK) {
        fprintf(stderr, "bench_cells_render: cannot load %s\n", path);
        return 1;
    }
    meso_file_close(f);
    const uint32_t R = ref.res;
    double ctr[3], rad = 0;
    for (int k = 0; k < 3; ++k) {
        ctr[k] = 0.5 * ((double)rec.bbox_min[k] + (double)rec.bbox_max[k]);
        rad += 0.25 * ((double)rec.bbox_max[k] - rec.bbox_min[k]) * ((double)rec.bbox_max[k] - rec.bbox_min[k]);
    }
    rad = sqrt(rad);
    fprintf(stderr, "bunny: %u^3 tiles x %u^3 map, voxel %.3g, bounding radius %.3g\n", ref.tiles[0], R, ref.voxel,
            rad);

    /* Views: the whole bunny; a close-up of its flank filling the frame;
     * and for the pictures, its head and back where cells are a few
     * pixels wide. */
    const double flank[3] = {ctr[0] + 0.05 * rad, ctr[1] - 0.15 * rad, ctr[2] + 0.25 * rad};
    const double head[3] = {ctr[0] - 0.25 * rad, ctr[1] + 0.15 * rad, ctr[2] + 0.1 * rad};
    struct view {
        const char* name;
        camera cam;
    } views[] = {
        {"full", look(ctr, 30, 15, 1.8 * rad, 0.2 * rad, 10 * rad)},
        {"close", look(flank, 20, 10, 0.55 * rad, 0.05 * rad, 4 * rad)},
    };
    const int nviews = quick ? 1 : 2;
    const camera pic = look(head, 20, 20, 0.35 * rad, 0.05 * rad, 4 * rad);

    bench_set_size(&b, 400, 300);
    const size_t npx = (size_t)scene_w * scene_h;
    uint8_t* rgba = malloc(npx * 4);
    float* depth = malloc(sizeof(float) * npx);

    /* --- pictures for the README ----------------------------------------- */
    b.cam = pic;
    camera_matrices(&b.cam, b.view, b.proj);
    {
        const struct {
            const char* file;
            meso_cells_mode mode;
        } pics[] = {{"cells_first.png", MESO_CELLS_FIRST_HIT},
                    {"cells_reflect.png", MESO_CELLS_REFLECT},
                    {"cells_refract.png", MESO_CELLS_REFRACT}};
        for (size_t i = 0; i < sizeof(pics) / sizeof(pics[0]); ++i) {
            meso_rt_draw_desc d = {.cells = {.mode = pics[i].mode, .bounces = pics[i].mode ? 2 : 0}};
            memcpy(d.view, b.view, sizeof(d.view));
            memcpy(d.proj, b.proj, sizeof(d.proj));
            test_fbo_clear(&b.fbo, 0.16f, 0.17f, 0.19f);
            if (meso_rt_draw(b.rt, obj, &d) != MESO_OK)
                return 1;
            test_fbo_read(&b.fbo, rgba, depth);
            write_png(dir, pics[i].file, rgba);
            /* Checked against the reference (MESO_TEST_PNG=DIR: its image and the differences). */
            meso_ref_image img = reference(&b, &ref, (int)d.cells.mode, d.cells.bounces, "picture");
            char prefix[64];
            snprintf(prefix, sizeof(prefix), "cells_picture_%d", (int)d.cells.mode);
            const metrics m = compare(rgba, depth, &img, b.view, b.proj, b.cam.fovy, prefix);
            fprintf(stderr,
                    "  vs reference: coverage mismatch %.4f, hit error %.3f px (> 1 px: %.4f), colour MAE %.4f, "
                    "colour bad %.4f\n",
                    m.coverage_mismatch, m.hit_err_px, m.hit_gt1, m.colour_mae, colour_bad(rgba, depth, &img));
            meso_ref_image_free(&img);
        }
    }

    /* --- step sweep (first hit) ------------------------------------------ */
    if (pictures_only)
        goto done;
    snprintf(csv, sizeof(csv), "%s/cells_render_step.csv", dir);
    FILE* fs = fopen(csv, "w");
    snprintf(csv, sizeof(csv), "%s/cells_render_order.csv", dir);
    FILE* fo = fopen(csv, "w");
    if (!fs || !fo) {
        fprintf(stderr, "bench_cells_render: cannot write into %s\n", dir);
        return 1;
    }
    fprintf(fs, "view,search,cell_step_voxels,step_tiles,ms,steps_per_fragment,fragments,covered_gl,covered_ref,"
                "coverage_mismatch,hit_err_px,hit_gt1,colour_mae,colour_bad\n");
    fprintf(fo, "view,mode,bounces,ms,steps_per_fragment,fragments,coverage_mismatch,hit_err_px,colour_mae,colour_bad,"
                "ref_change_vs3_mae,ref_change_vs3_gt2,ref_seconds\n");
    const int divs_all[] = {16, 32, 64, 128, 256, 512}, divs_quick[] = {16, 64, 512};
    const int* divs = quick ? divs_quick : divs_all;
    const int ndivs = quick ? 3 : 6;
    for (int vi = 0; vi < nviews; ++vi) {
        b.cam = views[vi].cam;
        camera_matrices(&b.cam, b.view, b.proj);
        meso_ref_image img = reference(&b, &ref, MESO_REF_CELLS_FIRST_HIT, 0, views[vi].name);
        /* search 0: exact; 1: linear, fixed step; 2: linear, angle rule */
        for (int search = 0; search < 3; ++search)
            for (int di = 0; di < (search ? ndivs : 1); ++di) {
                meso_rt_draw_desc d = {0};
                if (search) {
                    d.cells.step = (float)R / (float)divs[di];
                    d.cells.fixed_step = search == 1;
                }
                const timing t = time_draw(&b, obj, d, rgba, depth);
                static const char* const names[3] = {"exact", "linear_fixed", "linear_angle"};
                char prefix[64]; /* MESO_TEST_PNG=DIR: GL, reference and difference images */
                snprintf(prefix, sizeof(prefix), "cells_%s_%s_%g", views[vi].name, names[search], (double)d.cells.step);
                const metrics m = compare(rgba, depth, &img, b.view, b.proj, b.cam.fovy, prefix);
                fprintf(fs, "%s,%s,%g,%g,%.2f,%.2f,%llu,%ld,%ld,%.5f,%.4f,%.5f,%.5f,%.5f\n", views[vi].name,
                        names[search], (double)d.cells.step, (double)d.cells.step / R, t.ms, t.steps_per_frag,
                        (unsigned long long)t.fragments, m.covered_gl, m.covered_ref, m.coverage_mismatch,
                        m.hit_err_px, m.hit_gt1, m.colour_mae, colour_bad(rgba, depth, &img));
                fprintf(stderr,
                        "%-5s %-12s step %6.3f vx: %7.1f ms  %6.1f steps/frag  cov %.4f  hit %.3f px  >1px %.4f  "
                        "colour %.4f\n",
                        views[vi].name, names[search], (double)d.cells.step, t.ms, t.steps_per_frag,
                        m.coverage_mismatch, m.hit_err_px, m.hit_gt1, m.colour_mae);
                fflush(fs);
            }
        meso_ref_image_free(&img);

        /* --- reflection and refraction orders 0..3 ------------------------ */
        const int modes[2] = {MESO_CELLS_REFLECT, MESO_CELLS_REFRACT};
        for (int mi = 0; mi < 2; ++mi) {
            meso_ref_image imgs[4];
            double secs[4];
            timing tim[4];
            metrics met[4];
            double bad[4];
            for (int bo = 0; bo <= 3; ++bo) {
                if (quick && bo != 0 && bo != 3)
                    continue;
                const double t0 = meso_seconds();
                imgs[bo] = reference(&b, &ref, modes[mi], bo, views[vi].name);
                secs[bo] = meso_seconds() - t0;
                meso_rt_draw_desc d = {.cells = {.mode = (meso_cells_mode)modes[mi], .bounces = bo}};
                tim[bo] = time_draw(&b, obj, d, rgba, depth);
                char prefix[64];
                snprintf(prefix, sizeof(prefix), "cells_%s_%s_%d", views[vi].name, mi ? "refract" : "reflect", bo);
                met[bo] = compare(rgba, depth, &imgs[bo], b.view, b.proj, b.cam.fovy, prefix);
                bad[bo] = colour_bad(rgba, depth, &imgs[bo]);
            }
            for (int bo = 0; bo <= 3; ++bo) {
                if (quick && bo != 0 && bo != 3)
                    continue;
                double mae = 0, share = 0;
                ref_change(&imgs[bo], &imgs[3], &mae, &share);
                const char* mname = mi ? "refract" : "reflect";
                fprintf(fo, "%s,%s,%d,%.2f,%.2f,%llu,%.5f,%.4f,%.5f,%.5f,%.5f,%.5f,%.2f\n", views[vi].name, mname,
                        bo, tim[bo].ms, tim[bo].steps_per_frag, (unsigned long long)tim[bo].fragments,
                        met[bo].coverage_mismatch, met[bo].hit_err_px, met[bo].colour_mae, bad[bo], mae, share,
                        secs[bo]);
                fprintf(stderr,
                        "%-5s %-7s %d: %7.1f ms  %6.1f steps/frag  colour MAE %.4f bad %.4f (cov %.4f)  ref change "
                        "to order 3: %.4f, %.4f of pixels > 2/255\n",
                        views[vi].name, mname, bo, tim[bo].ms, tim[bo].steps_per_frag, met[bo].colour_mae, bad[bo],
                        met[bo].coverage_mismatch, mae, share);
                meso_ref_image_free(&imgs[bo]);
            }
            fflush(fo);
        }
    }
    fclose(fs);
    fclose(fo);
done:

    unlink(path);
    rmdir(tmp);
    meso_ref_cells_free(&ref);
    free(rgba);
    free(depth);
    meso_rt_release_object(b.rt, obj);
    test_fbo_destroy(&b.fbo);
    meso_rt_destroy(b.rt);
    meso_egl_destroy(egl);
    return 0;
}
