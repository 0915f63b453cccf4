/* bench_frusta_standin_cost — is a frusta object's tessellated stand-in
 * cheaper to draw than its native level where libmeso switches to it?
 * (issue 14, Deliver 1: "at coarse error a polygon tessellation, where it
 * is cheaper"; bake/frusta_standin.h builds it, chosen by its error.)
 *
 * Each bundled skeleton (tests/data: saguaro.skel, vine.skel and the SWC
 * neurons) is baked by mesobake with a brick relief (--relief bricks:32)
 * and without one. T is its first mesh level (the tessellation), N the
 * native level before it. The camera looks at the object's centre from
 * where T's error projects to 1 pixel at the nearest point of the object's
 * bounding sphere (so a draw at pixel_error 1 switches to T there: the
 * nearest distance T is drawn at, where it covers the most pixels and
 * costs the native level the most). There, level N and level T are each
 * drawn from the file cut at their prefix_bytes (pixel_error -1: the finest
 * that has arrived), 320 x 240, one llvmpipe render thread
 * (LP_NUM_THREADS=1 unless set), glFinish either side: the median of 9
 * draws after 2 warm-up draws. Also the level a pixel_error 1 draw picks
 * there, the pixels level N covers, T's triangles, level N's frusta and
 * balls, and the pixels estimated from T's surface area A (a convex body's
 * mean projected area is A / 4, Cauchy) over T's error squared.
 * Output: CSV skeleton,relief,native_level,native_frusta,native_balls,
 * native_ms,standin_level,standin_ms,standin_triangles,covered_px,
 * px_estimate,picked_level.
 * usage: bench_frusta_standin_cost RESULTS_CSV MESOBAKE DATA_DIR WORK_DIR */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_clock.h"
#include "meso_rt.h"
#include "prefix_io.h"

enum { W = 320, H = 240, REPS = 9 };

static test_fbo fbo;

static void die(const char* what)
{
    fprintf(stderr, "bench_frusta_standin_cost: %s\n", what);
    exit(1);
}

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

/* Median ms of REPS draws of `obj` (after 2 warm-ups); *covered its pixels. */
static double time_draw(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* d, int* covered)
{
    double ms[REPS];
    for (int r = -2; r < REPS; ++r) {
        test_fbo_clear(&fbo, 0, 0, 0);
        fbo.Finish();
        const double t0 = meso_seconds();
        if (meso_rt_draw(rt, obj, d) != MESO_OK)
            die("draw failed");
        fbo.Finish();
        if (r >= 0)
            ms[r] = 1e3 * (meso_seconds() - t0);
    }
    qsort(ms, REPS, sizeof ms[0], cmp_double);
    static float depth[W * H];
    test_fbo_read(&fbo, NULL, depth);
    *covered = 0;
    for (int i = 0; i < W * H; ++i)
        *covered += depth[i] < 1.0f;
    return ms[REPS / 2];
}

static meso_rt_object load_cut(meso_rt* rt, const uint8_t* data, size_t size, uint64_t limit, meso_file** f,
                               prefix_io* c)
{
    *c = (prefix_io){data, limit};
    const meso_io io = {.read_fn = prefix_read_pending, .size = size, .user = c};
    meso_rt_object obj = {0};
    if (meso_file_open_io(&io, NULL, f, NULL) != MESO_OK || meso_rt_load_object_levels(rt, *f, 1, &obj) != MESO_OK)
        die("cannot load a cut file");
    return obj;
}

static uint8_t* read_file(const char* path, size_t* n)
{
    FILE* f = fopen(path, "rb");
    if (!f)
        die(path);
    fseek(f, 0, SEEK_END);
    *n = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t* b = malloc(*n ? *n : 1);
    if (!b || fread(b, 1, *n, f) != *n)
        die(path);
    fclose(f);
    return b;
}

int main(int argc, char** argv)
{
    if (argc != 5)
        die("usage: bench_frusta_standin_cost RESULTS_CSV MESOBAKE DATA_DIR WORK_DIR");
    if (!getenv("LP_NUM_THREADS"))
        setenv("LP_NUM_THREADS", "1", 1);
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof why);
    if (!egl)
        die(why);
    if (!test_fbo_create(&fbo, W, H))
        die("fbo");
    meso_rt* rt = NULL;
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) != MESO_OK)
        die("meso_rt_create");
    FILE* csv = fopen(argv[1], "w");
    if (!csv)
        die(argv[1]);
    fprintf(csv, "skeleton,relief,native_level,native_frusta,native_balls,native_ms,standin_level,standin_ms,"
                 "standin_triangles,covered_px,px_estimate,picked_level\n");
    static const char* skeletons[] = {"saguaro.skel",           "vine.skel",          "neurom_simple.swc",
                                      "neurom_fat_end.swc",     "neurom_Neuron.swc", "morphio_three_point_soma.swc",
                                      "morphio_soma_single_frustum.swc"};
    static const char* reliefs[] = {"--relief bricks:32", ""};
    for (size_t k = 0; k < sizeof skeletons / sizeof skeletons[0]; ++k)
        for (int r = 0; r < 2; ++r) {
            char path[1024], cmd[4096];
            snprintf(path, sizeof path, "%s/standin_cost.meso", argv[4]);
            snprintf(cmd, sizeof cmd, "'%s' frusta -i '%s/%s' %s -o '%s' >/dev/null 2>&1", argv[2], argv[3],
                     skeletons[k], reliefs[r], path);
            if (system(cmd) != 0)
                die(cmd);
            size_t size = 0;
            uint8_t* data = read_file(path, &size);
            meso_file* f = NULL;
            if (meso_file_open_memory(data, size, NULL, &f, NULL) != MESO_OK)
                die(path);
            meso_object_record rec;
            uint32_t n = 1;
            meso_level_info li[16];
            uint32_t levels = 0;
            if (meso_file_objects(f, &rec, 1, &n, NULL) != MESO_OK ||
                meso_file_levels(f, 1, li, 16, &levels, NULL) != MESO_OK)
                die("levels");
            uint32_t T = 1;
            while (T < levels && li[T].rec.form != MESO_LEVEL_MESH)
                ++T;
            if (T >= levels) {
                printf("%-32s %-18s no mesh level\n", skeletons[k], r ? "plain" : "relief bricks:32");
                meso_file_close(f);
                free(data);
                continue;
            }
            /* T's triangles and area, from its MESH; level N's frusta and balls */
            uint32_t tris = 0;
            double area = 0;
            const int32_t mi = meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)T);
            if (mi >= 0) {
                const meso_chunk_info* ci = meso_file_chunk(f, (uint32_t)mi);
                void* mb = malloc((size_t)ci->decoded_size);
                meso_mesh_view mv;
                if (mb && meso_file_read_chunk(f, (uint32_t)mi, mb, (size_t)ci->decoded_size, NULL) == MESO_OK &&
                    meso_mesh_parse(mb, (size_t)ci->decoded_size, &mv, NULL) == MESO_OK) {
                    tris = mv.layout.index_count / 3;
                    for (uint32_t q = 0; q < tris; ++q) {
                        const float* P[3] = {mv.positions + 3 * mv.indices[3 * q], mv.positions + 3 * mv.indices[3 * q + 1],
                                             mv.positions + 3 * mv.indices[3 * q + 2]};
                        double e1[3], e2[3];
                        for (int a = 0; a < 3; ++a) {
                            e1[a] = (double)P[1][a] - P[0][a];
                            e2[a] = (double)P[2][a] - P[0][a];
                        }
                        const double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2],
                                     z = e1[0] * e2[1] - e1[1] * e2[0];
                        area += 0.5 * sqrt(x * x + y * y + z * z);
                    }
                }
                free(mb);
            }
            const int32_t fi = meso_file_find_level(f, MESO_CHUNK_FRUS, 1, (uint16_t)(T - 1));
            const int32_t bi = meso_file_find_level(f, MESO_CHUNK_BALL, 1, (uint16_t)(T - 1));
            const uint32_t frusta = fi >= 0 ? meso_file_chunk(f, (uint32_t)fi)->dims[0] : 0;
            const uint32_t balls = bi >= 0 ? meso_file_chunk(f, (uint32_t)bi)->dims[0] : 0;
            meso_file_close(f);
            double c[3], R = 0;
            for (int a = 0; a < 3; ++a) {
                c[a] = 0.5 * ((double)rec.bbox_min[a] + rec.bbox_max[a]);
                R += 0.25 * pow((double)rec.bbox_max[a] - rec.bbox_min[a], 2);
            }
            R = sqrt(R);
            /* the nearest point at d_near: one pixel there is e_T */
            const double t = tan(0.5 * 40.0 * M_PI / 180.0);
            const double d_near = li[T].rec.error * H / (2.0 * t);
            const double dist = 1.02 * (d_near + R);
            meso_rt_draw_desc d = {.pixel_error = -1.0f};
            const double eye[3] = {c[0] + 0.6 * dist, c[1] + 0.2 * dist, c[2] + 0.77 * dist}, up[3] = {0, 1, 0};
            meso_camera_look_at(d.view, eye, c, up);
            meso_camera_perspective(d.proj, 40.0 * M_PI / 180.0, (double)W / H, 0.01 * R, dist + 4 * R);
            prefix_io cn, ct, cw;
            meso_file *fn = NULL, *ft = NULL, *fw = NULL;
            meso_rt_object on = load_cut(rt, data, size, li[T - 1].prefix_bytes, &fn, &cn);
            meso_rt_object ot = load_cut(rt, data, size, li[T].prefix_bytes, &ft, &ct);
            meso_rt_object ow = load_cut(rt, data, size, size, &fw, &cw);
            int pn = 0, pt = 0, pw = 0;
            const double msn = time_draw(rt, on, &d, &pn), mst = time_draw(rt, ot, &d, &pt);
            meso_rt_draw_desc d1 = d;
            d1.pixel_error = 1.0f;
            time_draw(rt, ow, &d1, &pw);
            meso_rt_levels_state sn, st, sw;
            meso_rt_levels_state_get(rt, on, &sn);
            meso_rt_levels_state_get(rt, ot, &st);
            meso_rt_levels_state_get(rt, ow, &sw);
            if (sn.last_drawn != (int)T - 1 || st.last_drawn != (int)T)
                die("the cut files did not draw their levels");
            /* Cauchy: a convex body's mean projected area is a quarter of its surface's */
            const double px_est = 0.25 * area / (li[T].rec.error * li[T].rec.error);
            printf("%-32s %-18s native level %u (%u frusta, %u balls) %7.2f ms, stand-in level %u (%u triangles) "
                   "%7.2f ms, %5d px (%5d px by T's area / 4); 1 px picks level %d\n",
                   skeletons[k], r ? "plain" : "relief bricks:32", T - 1, frusta, balls, msn, T, tris, mst, pn,
                   (int)px_est, sw.last_drawn);
            fflush(stdout);
            fprintf(csv, "%s,%s,%u,%u,%u,%.3f,%u,%.3f,%u,%d,%.0f,%d\n", skeletons[k], r ? "none" : "bricks:32", T - 1,
                    frusta, balls, msn, T, mst, tris, pn, px_est, sw.last_drawn);
            meso_rt_release_object(rt, on);
            meso_rt_release_object(rt, ot);
            meso_rt_release_object(rt, ow);
            meso_file_close(fn);
            meso_file_close(ft);
            meso_file_close(fw);
            free(data);
        }
    fclose(csv);
    meso_rt_destroy(rt);
    test_fbo_destroy(&fbo);
    meso_egl_destroy(egl);
    return 0;
}
