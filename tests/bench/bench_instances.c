/* bench_instances — many objects per frame on llvmpipe (issue 18 items 3
 * and 10, and its Goal on instanced frusta):
 *
 *  cpu   CPU µs per instance to issue N draws of one object: N meso_rt_draw
 *        calls against one meso_rt_draw_instanced of N instances (and a
 *        meso_rt_draw_list of N items), under MESO_STATE_RESTORE and
 *        MESO_STATE_HOST_OWNS, for a mesh, a shell and a frusta object.
 *        Timed: the calls alone (glFinish before, untimed after), with
 *        every instance behind the camera (llvmpipe shades vertices inside
 *        the draw call; nothing is rasterised), small objects (the
 *        cube_no_bottom mesh and shell, the saguaro), so it is the
 *        submission cost plus the vertex work; median of 15.
 *  goal  "1000 instanced frusta objects cost at most 2x the GPU time of one
 *        object with the same total frusta": a saguaro (tests/data/
 *        saguaro.skel, `--relief bricks:64`) drawn as 1000 instances on a
 *        40 x 25 grid, against ONE object baked from a skeleton holding the
 *        same 1000 saguaros at the same places (so both images are the
 *        same, and so are the pixels shaded), and 1000 separate draws.
 *        GPU time: wall time from before the call to after glFinish
 *        (glFinish before too), median of 7 rounds, the three cases
 *        interleaved within each round so that load from other jobs on the
 *        machine falls on all three alike — llvmpipe has no timer queries
 *        worth trusting, and the draw calls' own CPU time is included on
 *        every side.
 *  field the cactus field's frame time at 1, 10, 100, 1000 objects: each
 *        saguaro its own pose slot, all slots re-posed every frame
 *        (meso_rt_frusta_set_pose_slot), then one instanced draw; median
 *        of 7 frames, glFinish included; the posing's share beside.
 *
 * Output: one CSV (section, case, n, value, unit). 320 x 240 pixels.
 * usage: bench_instances RESULTS_CSV MESOBAKE DATA_DIR */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_clock.h"
#include "meso_rt.h"

enum { W = 320, H = 240, RUNS = 7, GRID_X = 40, GRID_Z = 25, GOAL_N = GRID_X * GRID_Z };
#define SPACING 4.0

static meso_egl* egl;
static test_fbo fbo;
static FILE* csv;
static char dir[64];

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static double median(double* v, int n)
{
    qsort(v, (size_t)n, sizeof(double), cmp_double);
    return v[n / 2];
}

static void die(const char* what)
{
    fprintf(stderr, "bench_instances: %s\n", what);
    exit(1);
}

static meso_rt* make_rt(meso_rt_state_policy policy)
{
    meso_rt* rt = NULL;
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .state_policy = policy, .prepare = 1},
                       &rt) != MESO_OK)
        die("cannot create a libmeso context");
    return rt;
}

static void bake(const char* mesobake, const char* name, const char* args)
{
    char cmd[8192];
    snprintf(cmd, sizeof(cmd), "'%s' %s -o '%s/%s.meso' >/dev/null 2>&1", mesobake, args, dir, name);
    if (system(cmd) != 0)
        die(cmd);
}

static meso_rt_object load(meso_rt* rt, const char* name)
{
    char path[256];
    snprintf(path, sizeof(path), "%s/%s.meso", dir, name);
    meso_file* f = NULL;
    meso_error e;
    meso_object_record rec;
    uint32_t n = 0;
    meso_rt_object o = {0};
    if (meso_file_open_path(path, NULL, &f, &e) != MESO_OK || meso_file_objects(f, &rec, 1, &n, &e) != MESO_OK ||
        n != 1 || meso_rt_load_object(rt, f, rec.id, &o) != MESO_OK)
        die(path);
    meso_file_close(f);
    return o;
}

/* The view of the whole grid: from above one long side, looking down. */
static void camera(meso_rt_draw_desc* d)
{
    const double cx = 0.5 * (GRID_X - 1) * SPACING, cz = 0.5 * (GRID_Z - 1) * SPACING;
    const double eye[3] = {cx, 70.0, cz + 95.0}, at[3] = {cx, 0.0, cz}, up[3] = {0, 1, 0};
    meso_camera_look_at(d->view, eye, at, up);
    meso_camera_perspective(d->proj, 0.9, (double)W / H, 1.0, 400.0);
}

/* Instance i at grid cell i, turned about y (the same placement the
 * one-object bake uses, without the turn there: see the goal). */
static void grid_model(int i, double turn, float m[16])
{
    const double x = (i % GRID_X) * SPACING, z = (i / GRID_X) * SPACING, c = cos(turn), s = sin(turn);
    memset(m, 0, 16 * sizeof(float));
    m[0] = (float)c, m[2] = (float)-s, m[5] = 1.0f, m[8] = (float)s, m[10] = (float)c;
    m[12] = (float)x, m[14] = (float)z, m[15] = 1.0f;
}

static void result(const char* section, const char* name, int n, double value, const char* unit)
{
    fprintf(csv, "%s,%s,%d,%.4f,%s\n", section, name, n, value, unit);
    fflush(csv);
    printf("%-6s %-44s n=%-5d %10.3f %s\n", section, name, n, value, unit);
}

/* >>cpu ----------------------------------------------------------------------- */

static void cpu_case(meso_rt* rt, meso_rt_object o, const meso_rt_draw_desc* d, const char* kind,
                     const char* policy, int n)
{
    meso_rt_instance* inst = calloc((size_t)n, sizeof(*inst));
    meso_rt_draw_item* items = calloc((size_t)n, sizeof(*items));
    for (int i = 0; i < n; ++i) {
        grid_model(i, 0.1 * i, inst[i].model);
        inst[i].model[14] += 1000.0f; /* behind the camera */
        items[i].object = o;
        memcpy(items[i].model, inst[i].model, sizeof(items[i].model));
    }
    enum { CPU_RUNS = 15 };
    double t_sep[CPU_RUNS], t_inst[CPU_RUNS], t_list[CPU_RUNS];
    for (int r = 0; r <= CPU_RUNS; ++r) { /* run 0 warms up; the three interleaved */
        test_fbo_clear(&fbo, 0, 0, 0);
        fbo.Finish();
        double t0 = meso_seconds();
        for (int i = 0; i < n; ++i) {
            meso_rt_draw_desc di = *d;
            memcpy(di.model, inst[i].model, sizeof(di.model));
            if (meso_rt_draw(rt, o, &di) != MESO_OK)
                die("draw");
        }
        const double sep = meso_seconds() - t0;
        fbo.Finish();
        t0 = meso_seconds();
        if (meso_rt_draw_instanced(rt, o, d, inst, (uint32_t)n) != MESO_OK)
            die("instanced draw");
        const double ins = meso_seconds() - t0;
        fbo.Finish();
        t0 = meso_seconds();
        if (meso_rt_draw_list(rt, items, (uint32_t)n, d) != MESO_OK)
            die("list");
        const double lst = meso_seconds() - t0;
        fbo.Finish();
        if (r > 0) {
            t_sep[r - 1] = sep;
            t_inst[r - 1] = ins;
            t_list[r - 1] = lst;
        }
    }
    char name[96];
    snprintf(name, sizeof(name), "%s %s separate meso_rt_draw", kind, policy);
    result("cpu", name, n, 1e6 * median(t_sep, CPU_RUNS) / n, "us/instance");
    snprintf(name, sizeof(name), "%s %s meso_rt_draw_instanced", kind, policy);
    result("cpu", name, n, 1e6 * median(t_inst, CPU_RUNS) / n, "us/instance");
    snprintf(name, sizeof(name), "%s %s meso_rt_draw_list", kind, policy);
    result("cpu", name, n, 1e6 * median(t_list, CPU_RUNS) / n, "us/item");
    free(inst);
    free(items);
}

static void bench_cpu(const char* mesobake, const char* data)
{
    char args[4200];
    snprintf(args, sizeof(args), "mesh -i '%s/cube_no_bottom.obj'", data);
    bake(mesobake, "mesh", args);
    snprintf(args, sizeof(args), "shell -i '%s/cube_no_bottom.obj' --texture bricks:32 -j 2", data);
    bake(mesobake, "shell", args);
    static const meso_rt_state_policy policies[2] = {MESO_STATE_RESTORE, MESO_STATE_HOST_OWNS};
    static const char* const policy_names[2] = {"restore", "host-owns"};
    for (int p = 0; p < 2; ++p) {
        meso_rt* rt = make_rt(policies[p]);
        meso_rt_draw_desc d = {0};
        camera(&d);
        d.viewport[2] = W, d.viewport[3] = H; /* no viewport query per draw */
        const char* names[3] = {"mesh", "shell", "frusta"};
        for (int k = 0; k < 3; ++k) {
            meso_rt_object o = load(rt, names[k]);
            cpu_case(rt, o, &d, names[k], policy_names[p], 100);
            meso_rt_release_object(rt, o);
        }
        meso_rt_destroy(rt);
    }
}

/* >>goal ---------------------------------------------------------------------- */

/* tests/data/saguaro.skel's node lines ("x y z radius [parent]"), GOAL_N
 * times, copy i moved to grid cell i, parents renumbered, roots explicit. */
static void write_grid_skel(const char* data, const char* path)
{
    char src[4200];
    snprintf(src, sizeof(src), "%s/saguaro.skel", data);
    FILE* in = fopen(src, "r");
    if (!in)
        die(src);
    double node[64][4];
    int parent[64], count = 0;
    char line[256];
    while (fgets(line, sizeof(line), in) && count < 64) {
        double v[4];
        int par = -1, got = sscanf(line, "%lf %lf %lf %lf %d", &v[0], &v[1], &v[2], &v[3], &par);
        if (line[0] == '#' || got < 4)
            continue;
        memcpy(node[count], v, sizeof(v));
        parent[count] = got == 5 ? par : count; /* 1-based; omitted: the previous line (0 for the first) */
        ++count;
    }
    fclose(in);
    FILE* out = fopen(path, "w");
    if (!out)
        die(path);
    fprintf(out, "# %d saguaros on a %d x %d grid (bench_instances)\n", GOAL_N, GRID_X, GRID_Z);
    for (int i = 0; i < GOAL_N; ++i)
        for (int k = 0; k < count; ++k)
            fprintf(out, "%.9g %.9g %.9g %.9g %d\n", node[k][0] + (i % GRID_X) * SPACING, node[k][1],
                    node[k][2] + (i / GRID_X) * SPACING, node[k][3], parent[k] ? parent[k] + i * count : 0);
    fclose(out);
}

/* Seconds of a glFinish-bracketed call. */
typedef meso_result (*draw_fn)(void* user);

static double gpu_seconds(draw_fn fn, void* user)
{
    test_fbo_clear(&fbo, 0, 0, 0);
    fbo.Finish();
    const double t0 = meso_seconds();
    if (fn(user) != MESO_OK)
        die("draw");
    fbo.Finish();
    return meso_seconds() - t0;
}

typedef struct goal_ctx {
    meso_rt* rt;
    meso_rt_object one, big;
    meso_rt_draw_desc d;
    meso_rt_instance* inst;
    int n;
} goal_ctx;

static meso_result draw_big(void* u)
{
    goal_ctx* g = u;
    return meso_rt_draw(g->rt, g->big, &g->d);
}

static meso_result draw_instanced(void* u)
{
    goal_ctx* g = u;
    return meso_rt_draw_instanced(g->rt, g->one, &g->d, g->inst, (uint32_t)g->n);
}

static meso_result draw_separate(void* u)
{
    goal_ctx* g = u;
    for (int i = 0; i < g->n; ++i) {
        meso_rt_draw_desc di = g->d;
        memcpy(di.model, g->inst[i].model, sizeof(di.model));
        const meso_result r = meso_rt_draw(g->rt, g->one, &di);
        if (r != MESO_OK)
            return r;
    }
    return MESO_OK;
}

static void bench_goal(const char* mesobake, const char* data)
{
    char args[4200], skel[128];
    snprintf(skel, sizeof(skel), "%s/grid.skel", dir);
    write_grid_skel(data, skel);
    snprintf(args, sizeof(args), "frusta -i '%s/saguaro.skel' --relief bricks:64", data);
    bake(mesobake, "frusta", args);
    snprintf(args, sizeof(args), "frusta -i '%s' --relief bricks:64", skel);
    bake(mesobake, "grid", args);
    goal_ctx g = {.rt = make_rt(MESO_STATE_RESTORE), .n = GOAL_N};
    g.one = load(g.rt, "frusta");
    g.big = load(g.rt, "grid");
    uint32_t f1 = 0, fb = 0;
    meso_rt_frusta_info(g.rt, g.one, &f1, NULL);
    meso_rt_frusta_info(g.rt, g.big, &fb, NULL);
    printf("goal: one saguaro %u frusta, the grid object %u frusta\n", f1, fb);
    if (fb != f1 * GOAL_N)
        die("the grid object does not hold 1000 saguaros' frusta");
    camera(&g.d);
    g.inst = calloc(GOAL_N, sizeof(*g.inst));
    for (int i = 0; i < GOAL_N; ++i)
        grid_model(i, 0.0, g.inst[i].model);
    double t[3][RUNS];
    for (int r = 0; r <= RUNS; ++r) { /* round 0 warms up; the cases interleaved */
        const double a = gpu_seconds(draw_big, &g), b = gpu_seconds(draw_instanced, &g),
                     c = gpu_seconds(draw_separate, &g);
        if (r > 0)
            t[0][r - 1] = a, t[1][r - 1] = b, t[2][r - 1] = c;
    }
    const double big = 1e3 * median(t[0], RUNS), ins = 1e3 * median(t[1], RUNS), sep = 1e3 * median(t[2], RUNS);
    result("goal", "one object of 1000 saguaros (meso_rt_draw)", GOAL_N, big, "ms");
    result("goal", "1000 instances (meso_rt_draw_instanced)", GOAL_N, ins, "ms");
    result("goal", "1000 separate meso_rt_draw", GOAL_N, sep, "ms");
    result("goal", "ratio instanced / one object (goal <= 2)", GOAL_N, ins / big, "x");
    result("goal", "ratio separate / one object", GOAL_N, sep / big, "x");

    /* >>field: 1, 10, 100, 1000 swaying saguaros, each its own pose slot */
    uint32_t nodes = 0;
    meso_rt_frusta_info(g.rt, g.one, NULL, &nodes);
    float* rest = malloc(sizeof(float) * 3 * nodes);
    float* pose = malloc(sizeof(float) * 3 * nodes);
    meso_rt_frusta_rest_pose(g.rt, g.one, rest, NULL, nodes);
    static const int counts[4] = {1, 10, 100, 1000};
    for (int c = 0; c < 4; ++c) {
        const int n = counts[c];
        if (meso_rt_frusta_pose_slots(g.rt, g.one, (uint32_t)n) != MESO_OK)
            die("pose slots");
        for (int i = 0; i < n; ++i)
            g.inst[i].pose_slot = (uint32_t)i;
        g.n = n;
        double frame[RUNS], posing[RUNS];
        for (int r = 0; r <= RUNS; ++r) {
            test_fbo_clear(&fbo, 0, 0, 0);
            fbo.Finish();
            const double t0 = meso_seconds();
            for (int i = 0; i < n; ++i) {
                const double a = 0.02 * sin(0.7 * r + 0.37 * i);
                for (uint32_t k = 0; k < nodes; ++k) {
                    const double y = rest[3 * k + 1];
                    pose[3 * k] = (float)(rest[3 * k] + a * y * y);
                    pose[3 * k + 1] = rest[3 * k + 1];
                    pose[3 * k + 2] = rest[3 * k + 2];
                }
                if (meso_rt_frusta_set_pose_slot(g.rt, g.one, (uint32_t)i, pose, nodes) != MESO_OK)
                    die("pose");
            }
            const double t1 = meso_seconds();
            if (draw_instanced(&g) != MESO_OK)
                die("field draw");
            fbo.Finish();
            if (r > 0) {
                frame[r - 1] = meso_seconds() - t0;
                posing[r - 1] = t1 - t0;
            }
        }
        result("field", "frame (pose every slot + instanced draw)", n, 1e3 * median(frame, RUNS), "ms");
        result("field", "of which posing", n, 1e3 * median(posing, RUNS), "ms");
    }
    free(rest);
    free(pose);
    free(g.inst);
    meso_rt_destroy(g.rt);
}

int main(int argc, char** argv)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    if (argc != 4) {
        fprintf(stderr, "usage: bench_instances RESULTS_CSV MESOBAKE DATA_DIR\n");
        return 2;
    }
    char why[256];
    egl = meso_egl_create(why, sizeof(why));
    if (!egl)
        die(why);
    if (!test_fbo_create(&fbo, W, H))
        die("framebuffer");
    snprintf(dir, sizeof(dir), "/tmp/meso_bench_instances_XXXXXX");
    if (!mkdtemp(dir))
        die("temp dir");
    csv = fopen(argv[1], "w");
    if (!csv)
        die(argv[1]);
    fprintf(csv, "section,case,n,value,unit\n");
    bench_goal(argv[2], argv[3]); /* bakes the frusta bench_cpu uses too */
    bench_cpu(argv[2], argv[3]);
    fclose(csv);
    char cmd[128];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        return 1;
    test_fbo_destroy(&fbo);
    meso_egl_destroy(egl);
    return 0;
}
