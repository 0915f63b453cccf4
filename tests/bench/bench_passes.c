/* bench_passes.c — time per frame of libmeso's depth-only pass against the
 * forward pass (meso_rt_draw_desc.pass, issue 18 item 4) on llvmpipe: one
 * bundled object of each ray-cast kind, baked by mesobake, filling most of a
 * 512x512 view; the median of 9 timed draws after a warm-up, glFinish
 * included (bench_gl.h). The G-buffer pass is timed too, into the bench's
 * single RGBA8 attachment (its normal output has no attachment there, so
 * it costs what a two-attachment target would minus that write).
 *
 * Usage: bench_passes RESULTS_DIR MESOBAKE DATA_DIR — writes
 * RESULTS_DIR/passes.csv (object, forward_ms, depth_ms, gbuffer_ms,
 * depth_over_forward) and prints one line per object. */
#include "bench_gl.h"

#include <math.h>

#include "egl_context.h"

enum { SIZE = 512 };

typedef struct item {
    const char* name;
    const char *cmd, *input, *args; /* mesobake CMD -i DATA_DIR/INPUT ARGS */
    meso_rt_draw_desc d;
} item;

int main(int argc, char** argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: bench_passes RESULTS_DIR MESOBAKE DATA_DIR\n");
        return 1;
    }
    bench b;
    memset(&b, 0, sizeof(b));
    meso_egl* egl = bench_gl_open(&b, "bench_passes");
    if (!egl)
        return 1;
    char dir[] = "/tmp/meso_bench_passes_XXXXXX";
    if (!mkdtemp(dir))
        return 1;
    const item items[] = {
        {"shell smooth (spot, bricks)", "shell", "spot_uv.obj", "--texture bricks:128 -j 2", {.pass = 0}},
        {"shell curved (spot, bricks)", "shell", "spot_uv.obj", "--texture bricks:128 -j 2",
         {.shell = {.technique = MESO_SHELL_CURVED}}},
        {"frusta (neuron, bricks relief)", "frusta", "neurom_Neuron.swc", "--relief bricks:64", {.pass = 0}},
        {"cells (sphere, voronoi)", "cells", "sphere.obj", "--tiles 8 --tile-res 16 --tile-map voronoi:8 -j 2",
         {.pass = 0}},
    };
    char csv[4096];
    snprintf(csv, sizeof(csv), "%s/passes.csv", argv[1]);
    FILE* out = fopen(csv, "w");
    if (!out)
        return 1;
    fprintf(out, "object,forward_ms,depth_ms,gbuffer_ms,depth_over_forward\n");
    for (size_t i = 0; i < sizeof(items) / sizeof(items[0]); ++i) {
        char path[4200], cmd[9000];
        snprintf(path, sizeof(path), "%s/%zu.meso", dir, i);
        snprintf(cmd, sizeof(cmd), "'%s' %s -i '%s/%s' %s -o '%s' >/dev/null 2>&1", argv[2], items[i].cmd, argv[3],
                 items[i].input, items[i].args, path);
        if (system(cmd) != 0) {
            fprintf(stderr, "bench_passes: bake failed: %s\n", cmd);
            return 1;
        }
        meso_file* f = NULL;
        meso_error err;
        meso_object_record rec;
        uint32_t n = 0;
        meso_rt_object obj;
        if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK || meso_file_objects(f, &rec, 1, &n, &err) != MESO_OK ||
            n != 1 || meso_rt_load_object(b.rt, f, rec.id, &obj) != MESO_OK) {
            fprintf(stderr, "bench_passes: cannot load %s\n", path);
            return 1;
        }
        meso_file_close(f);
        double c[3], r = 0;
        for (int k = 0; k < 3; ++k) {
            c[k] = 0.5 * (rec.bbox_min[k] + rec.bbox_max[k]);
            r += 0.25 * (rec.bbox_max[k] - rec.bbox_min[k]) * (rec.bbox_max[k] - rec.bbox_min[k]);
        }
        r = sqrt(r);
        const double dist = r / sin(0.35);
        b.cam = (camera){.eye = {c[0] + 0.3 * dist, c[1] + 0.4 * dist, c[2] + 0.87 * dist},
                         .at = {c[0], c[1], c[2]},
                         .fovy = 0.7,
                         .zn = fmax(dist - 2 * r, 0.01 * dist),
                         .zf = dist + 2 * r};
        bench_set_size(&b, SIZE, SIZE);
        double ms[MESO_PASS_COUNT];
        for (int p = 0; p < MESO_PASS_COUNT; ++p) {
            meso_rt_draw_desc d = items[i].d;
            d.pass = (meso_rt_pass)p;
            ms[p] = bench_median_ms(&b, obj, d, 9);
        }
        printf("%-32s forward %8.2f ms  depth %8.2f ms  gbuffer %8.2f ms  depth/forward %.2f\n", items[i].name,
               ms[0], ms[1], ms[2], ms[1] / ms[0]);
        fprintf(out, "\"%s\",%.3f,%.3f,%.3f,%.3f\n", items[i].name, ms[0], ms[1], ms[2], ms[1] / ms[0]);
        meso_rt_release_object(b.rt, obj);
    }
    fclose(out);
    char rm[200];
    snprintf(rm, sizeof(rm), "rm -rf '%s'", dir);
    if (system(rm) != 0)
        return 1;
    test_fbo_destroy(&b.fbo);
    meso_rt_destroy(b.rt);
    meso_egl_destroy(egl);
    return 0;
}
