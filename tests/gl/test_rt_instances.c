/* Many objects per frame (issue 18 item 3) on llvmpipe, with objects baked
 * by the real mesobake (argv[1]): meso_rt_draw_instanced against separate
 * meso_rt_draw calls with the same models, for every kind and ray caster
 * (mesh; shells smooth, curved, tetra, segment-only; frusta with relief;
 * cells), frusta pose slots against separate objects posed with
 * meso_rt_frusta_set_pose, animated shells at one time against
 * meso_rt_shell_set_time, meso_rt_draw_list in three orders of its items
 * against the separate draws (and the GL state it restores), and the
 * refusals: a non-similarity instance (the log names its index), a pose
 * slot the object lacks, mirrored and unmirrored instances together, count
 * 0 and NULL instances, slices, instances at different frames.
 *
 * The expectation is independent of the instancing code: separate draws
 * through the single-draw path, whose images the other GL tests hold to
 * the CPU references. Colour and depth must be equal bit for bit (the
 * instance data are the very floats a single draw sets as uniforms), but
 * for one thing with shells: smooth and curved shells draw their prisms
 * sorted along the view axis in object space (hull rejection, rt_shell.c),
 * one order for all the instances of an instanced draw (its first's), and
 * where two prisms' hits tie at exactly the same depth the order drawn
 * picks whose colour shows; such pixels (depth bit for bit equal, colour
 * not) are allowed, at most 1 in 500 of those covered (measured: 1 or 2). */
#include "test_util.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "gl_fbo.h"
#include "gl_log.h"
#include "meso_rt.h"
#include "test_need.h"


enum { W = 128, H = 96, N = 5 };

typedef struct ctx {
    meso_rt* rt;
    test_fbo fbo;
    const char* mesobake;
    char dir[64];
    log_capture log;
    meso_rt_draw_desc desc;
    uint8_t *rgba[2];
    float* depth[2];
} ctx;

static void bake(ctx* c, const char* name, const char* args)
{
    char cmd[8192];
    snprintf(cmd, sizeof(cmd), "'%s' %s -o '%s/%s.meso' 2>'%s/%s.log' >/dev/null", c->mesobake, args, c->dir, name,
             c->dir, name);
    need(system(cmd) == 0, "bake failed: %s", cmd);
}

static meso_rt_object load(ctx* c, const char* name)
{
    char path[256];
    snprintf(path, sizeof(path), "%s/%s.meso", c->dir, name);
    meso_file* f = NULL;
    meso_error e;
    need(meso_file_open_path(path, NULL, &f, &e) == MESO_OK, "%s", e.message);
    meso_object_record rec;
    uint32_t n = 0;
    CHECK(meso_file_objects(f, &rec, 1, &n, &e) == MESO_OK && n == 1);
    meso_rt_object o = {0};
    need(meso_rt_load_object(c->rt, f, rec.id, &o) == MESO_OK, "load %s: %s", name, c->log.message);
    meso_file_close(f);
    return o;
}

/* Model matrix: translate(t) · rotate(axis, angle) · scale(s) · translate(-centre),
 * so the object's box centre lands at t and its largest side is 2s. */
static void model_of(ctx* c, meso_rt_object o, const double t[3], const double axis[3], double angle, double s,
                     int mirror, float m[16])
{
    float lo[3], hi[3];
    CHECK(meso_rt_object_bounds(c->rt, o, lo, hi) == MESO_OK);
    double size = 0, ctr[3];
    for (int k = 0; k < 3; ++k) {
        size = fmax(size, (double)hi[k] - lo[k]);
        ctr[k] = 0.5 * ((double)hi[k] + lo[k]);
    }
    const double sc = 2.0 * s / size;
    double a[3] = {axis[0], axis[1], axis[2]};
    const double l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int k = 0; k < 3; ++k)
        a[k] /= l;
    const double cs = cos(angle), sn = sin(angle), ic = 1 - cs;
    double r[3][3] = {{cs + a[0] * a[0] * ic, a[0] * a[1] * ic - a[2] * sn, a[0] * a[2] * ic + a[1] * sn},
                      {a[1] * a[0] * ic + a[2] * sn, cs + a[1] * a[1] * ic, a[1] * a[2] * ic - a[0] * sn},
                      {a[2] * a[0] * ic - a[1] * sn, a[2] * a[1] * ic + a[0] * sn, cs + a[2] * a[2] * ic}};
    if (mirror)
        for (int row = 0; row < 3; ++row)
            r[row][0] = -r[row][0];
    memset(m, 0, 16 * sizeof(float));
    for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row)
            m[4 * col + row] = (float)(sc * r[row][col]);
    for (int row = 0; row < 3; ++row) {
        double v = t[row];
        for (int col = 0; col < 3; ++col)
            v -= sc * r[row][col] * ctr[col];
        m[12 + row] = (float)v;
    }
    m[15] = 1.0f;
}

/* N instances spread over the view, partly overlapping, each turned and
 * scaled differently. */
static void spread(ctx* c, meso_rt_object o, meso_rt_instance* inst, int count)
{
    memset(inst, 0, sizeof(*inst) * (size_t)count);
    for (int i = 0; i < count; ++i) {
        const double t[3] = {-1.6 + 0.8 * i, 0.25 * ((i % 3) - 1), -0.3 * (i % 2)};
        const double axis[3] = {0.3 + 0.1 * i, 1.0, 0.2 * i - 0.4};
        model_of(c, o, t, axis, 0.7 * i - 1.0, 0.45 + 0.07 * i, 0, inst[i].model);
    }
}

static void render_begin(ctx* c)
{
    test_fbo_clear(&c->fbo, 0.1f, 0.2f, 0.3f);
}

static void render_end(ctx* c, int which)
{
    c->fbo.Finish();
    test_fbo_read(&c->fbo, c->rgba[which], c->depth[which]);
}

static long covered(const float* z)
{
    long n = 0;
    for (int i = 0; i < W * H; ++i)
        n += z[i] < 1.0f;
    return n;
}

/* Images 0 and 1 equal, bit for bit, and something drawn; with `ties`
 * (shells), up to 1 in 500 covered pixels may differ in colour alone. */
static void same(ctx* c, const char* what, int ties)
{
    long diff = 0, tied = 0;
    for (size_t i = 0; i < (size_t)W * H * 4; ++i)
        diff += c->rgba[0][i] != c->rgba[1][i];
    for (size_t i = 0; i < (size_t)W * H; ++i)
        tied += memcmp(c->rgba[0] + 4 * i, c->rgba[1] + 4 * i, 4) != 0;
    const long cov = covered(c->depth[0]);
    const int zdiff = memcmp(c->depth[0], c->depth[1], sizeof(float) * W * H) != 0;
    need((diff == 0 || (ties && tied <= cov / 500)) && !zdiff, "%s: %ld colour bytes differ%s", what, diff,
         zdiff ? ", depth differs" : "");
    need(cov > 200, "%s: only %ld pixels covered", what, cov);
    if (diff)
        printf("ok   %s (%ld px covered, identical but %ld px at tied depths)\n", what, cov, tied);
    else
        printf("ok   %s (%ld px covered, identical)\n", what, cov);
}

static int is_shell(ctx* c, meso_rt_object o)
{
    uint32_t nv = 0;
    return meso_rt_shell_info(c->rt, o, &nv, NULL) == MESO_OK && nv > 0;
}

/* Image 0: the instances drawn one by one with meso_rt_draw. */
static void draw_separately(ctx* c, meso_rt_object o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                            int count, const char* what)
{
    render_begin(c);
    for (int i = 0; i < count; ++i) {
        meso_rt_draw_desc di = *d;
        memcpy(di.model, inst[i].model, sizeof(di.model));
        need(meso_rt_draw(c->rt, o, &di) == MESO_OK, "%s: draw %d: %s", what, i, c->log.message);
    }
    render_end(c, 0);
}

/* Separate draws (image 0) against one instanced draw (image 1). */
static void instanced_vs_separate(ctx* c, meso_rt_object o, const meso_rt_draw_desc* d, const char* what)
{
    meso_rt_instance inst[N];
    spread(c, o, inst, N);
    draw_separately(c, o, d, inst, N, what);
    render_begin(c);
    need(meso_rt_draw_instanced(c->rt, o, d, inst, N) == MESO_OK, "%s: instanced: %s", what, c->log.message);
    render_end(c, 1);
    same(c, what, is_shell(c, o));
}

/* A swaying pose: each node moved sideways by its height times `amp`. */
static void sway(const float* rest, uint32_t nodes, double amp, float* out)
{
    for (uint32_t n = 0; n < nodes; ++n) {
        const double y = rest[3 * n + 1];
        out[3 * n] = (float)(rest[3 * n] + amp * y * y);
        out[3 * n + 1] = rest[3 * n + 1];
        out[3 * n + 2] = (float)(rest[3 * n + 2] + 0.5 * amp * y * y);
    }
}

static void test_pose_slots(ctx* c)
{
    meso_rt_object a = load(c, "frusta"), sep[3] = {a, load(c, "frusta"), load(c, "frusta")};
    uint32_t nodes = 0;
    CHECK(meso_rt_frusta_info(c->rt, a, NULL, &nodes) == MESO_OK && nodes > 1);
    float* rest = malloc(sizeof(float) * 3 * nodes);
    float* pose = malloc(sizeof(float) * 3 * nodes);
    CHECK(meso_rt_frusta_rest_pose(c->rt, a, rest, NULL, nodes) == MESO_OK);
    float lo[3], hi[3];
    CHECK(meso_rt_object_bounds(c->rt, a, lo, hi) == MESO_OK);
    const double hgt = hi[1] - lo[1];
    CHECK(meso_rt_frusta_pose_slots(c->rt, a, 3) == MESO_OK);
    /* Two poses in sequence for slot 2 (frames carry over between poses). */
    for (int step = 0; step < 2; ++step)
        for (uint32_t s = 0; s < 3; ++s) {
            sway(rest, nodes, (0.15 + 0.1 * s + 0.05 * step) / hgt, pose);
            if (s == 1 && step == 1)
                continue;
            need(meso_rt_frusta_set_pose_slot(c->rt, a, s, pose, nodes) == MESO_OK, "slot %u: %s", s,
                 c->log.message);
            need(meso_rt_frusta_set_pose(c->rt, sep[s], pose, nodes) == MESO_OK, "pose: %s", c->log.message);
        }
    meso_rt_instance inst[3];
    spread(c, a, inst, 3);
    render_begin(c);
    for (uint32_t s = 0; s < 3; ++s) {
        meso_rt_draw_desc di = c->desc;
        memcpy(di.model, inst[s].model, sizeof(di.model));
        CHECK(meso_rt_draw(c->rt, sep[s], &di) == MESO_OK);
        inst[s].pose_slot = s;
    }
    render_end(c, 0);
    render_begin(c);
    need(meso_rt_draw_instanced(c->rt, a, &c->desc, inst, 3) == MESO_OK, "%s", c->log.message);
    render_end(c, 1);
    same(c, "frusta pose slots = separate objects posed with meso_rt_frusta_set_pose", 0);

    /* Growing keeps the slots, a new one copies slot 0; shrinking drops. */
    CHECK(meso_rt_frusta_pose_slots(c->rt, a, 4) == MESO_OK);
    inst[2].pose_slot = 3;
    c->log.errors = 0;
    CHECK(meso_rt_draw_instanced(c->rt, a, &c->desc, inst, 3) == MESO_OK);
    CHECK(meso_rt_frusta_pose_slots(c->rt, a, 2) == MESO_OK);
    CHECK(meso_rt_draw_instanced(c->rt, a, &c->desc, inst, 3) == MESO_ERR_INVALID_ARG);
    need(strstr(c->log.message, "instance 2") && strstr(c->log.message, "pose slot 3"), "log: %s", c->log.message);
    CHECK(meso_rt_frusta_set_pose_slot(c->rt, a, 2, pose, nodes) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_frusta_pose_slots(c->rt, a, 0) == MESO_ERR_INVALID_ARG);
    printf("ok   pose slots grow, shrink, refuse slot 3 of 2 and 0 slots\n");
    for (int s = 0; s < 3; ++s)
        meso_rt_release_object(c->rt, sep[s]);
    free(rest);
    free(pose);
}

/* Instances at one time and at different times (frames) against
 * meso_rt_shell_set_time before each separate draw. */
static void test_shell_time(ctx* c)
{
    meso_rt_object o = load(c, "anim"), ref = load(c, "anim");
    enum { NT = 5 };
    meso_rt_instance inst[NT];
    spread(c, o, inst, NT);
    for (int pass = 0; pass < 2; ++pass) {
        /* pass 0: all at frame 2 of 4 (8 fps); pass 1: frames 2, 0, 3, 2, 1 */
        static const double times[2][NT] = {{0.25, 0.26, 0.27, 0.28, 0.29}, {0.25, 0.0, 0.4, 0.3, 0.13}};
        render_begin(c);
        for (int i = 0; i < NT; ++i) {
            inst[i].has_time = 1;
            inst[i].time = times[pass][i];
            CHECK(meso_rt_shell_set_time(c->rt, ref, inst[i].time) == MESO_OK);
            meso_rt_draw_desc di = c->desc;
            memcpy(di.model, inst[i].model, sizeof(di.model));
            CHECK(meso_rt_draw(c->rt, ref, &di) == MESO_OK);
        }
        render_end(c, 0);
        render_begin(c);
        need(meso_rt_draw_instanced(c->rt, o, &c->desc, inst, NT) == MESO_OK, "%s", c->log.message);
        render_end(c, 1);
        uint32_t shown = 0;
        CHECK(meso_rt_shell_anim_info(c->rt, o, NULL, NULL, &shown) == MESO_OK);
        need(shown == (pass ? 3u : 2u), "shown frame %u after the draw", shown);
        same(c, pass ? "animated shell instances at frames 2 0 3 2 1 = set_time + separate draws"
                     : "animated shell instances at one frame = set_time + separate draws",
             1);
    }
    inst[3].time = NAN;
    CHECK(meso_rt_draw_instanced(c->rt, o, &c->desc, inst, NT) == MESO_ERR_INVALID_ARG);
    need(strstr(c->log.message, "instance 3: NaN time") != NULL, "log: %s", c->log.message);
    printf("ok   NaN time refused: %s\n", c->log.message);
    meso_rt_release_object(c->rt, o);
    meso_rt_release_object(c->rt, ref);
}

/* draw_list in three orders against the separate draws. */
static void test_list(ctx* c, const meso_rt_object* objs, int count)
{
    enum { MAXI = 12 };
    meso_rt_draw_item items[MAXI];
    meso_rt_instance inst[N];
    meso_rt_draw_desc knobs = c->desc;
    knobs.shell.technique = MESO_SHELL_CURVED;
    knobs.albedo[0] = 0.9f, knobs.albedo[1] = 0.3f, knobs.albedo[2] = 0.2f;
    int n = 0;
    memset(items, 0, sizeof(items));
    for (int i = 0; i < count; ++i)
        for (int rep = 0; rep < 2; ++rep) {
            meso_rt_instance one;
            const double t[3] = {-1.8 + 0.55 * (2 * i + rep), 0.5 * rep - 0.25, 0.0};
            const double axis[3] = {0.2, 1.0, 0.1 * i};
            model_of(c, objs[i], t, axis, 0.5 * i + rep, 0.4, 0, one.model);
            items[n].object = objs[i];
            memcpy(items[n].model, one.model, sizeof(one.model));
            items[n].knobs = rep && i == 1 ? &knobs : NULL; /* a curved, red shell */
            ++n;
        }
    spread(c, objs[0], inst, N); /* an instanced item too */
    for (int i = 0; i < N; ++i)
        inst[i].model[13] -= 0.9f;
    items[n].object = objs[0];
    items[n].instances = inst;
    items[n].instance_count = N;
    ++n;

    render_begin(c);
    for (int i = 0; i < n; ++i) {
        meso_rt_draw_desc d = items[i].knobs ? *items[i].knobs : c->desc;
        memcpy(d.model, items[i].model, sizeof(d.model));
        if (items[i].instances)
            for (uint32_t k = 0; k < items[i].instance_count; ++k) {
                memcpy(d.model, items[i].instances[k].model, sizeof(d.model));
                CHECK(meso_rt_draw(c->rt, items[i].object, &d) == MESO_OK);
            }
        else
            CHECK(meso_rt_draw(c->rt, items[i].object, &d) == MESO_OK);
    }
    render_end(c, 0);
    static const char* const orders[3] = {"given order", "reversed", "shuffled"};
    for (int ord = 0; ord < 3; ++ord) {
        meso_rt_draw_item list[MAXI];
        for (int i = 0; i < n; ++i)
            list[i] = items[ord == 0 ? i : ord == 1 ? n - 1 - i : (i * 5 + 3) % n];
        if (ord == 2) { /* (i * 5 + 3) % n is a permutation when gcd(5, n) = 1 */
            int seen[MAXI] = {0};
            for (int i = 0; i < n; ++i)
                CHECK(!seen[(i * 5 + 3) % n]++);
        }
        render_begin(c);
        /* Odd host state that must come back. */
        c->fbo.Finish();
        need(meso_rt_draw_list(c->rt, list, (uint32_t)n, &c->desc) == MESO_OK, "list: %s", c->log.message);
        render_end(c, 1);
        char what[96];
        snprintf(what, sizeof(what), "draw_list of %d items (%s) = separate draws", n, orders[ord]);
        same(c, what, 1); /* shells among the items */
    }
    CHECK(meso_rt_draw_list(c->rt, items, 0, &c->desc) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_draw_list(c->rt, NULL, 1, &c->desc) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_draw_list(c->rt, items, 1, NULL) == MESO_ERR_INVALID_ARG);
    meso_rt_draw_item bad = items[0];
    bad.instance_count = 2;
    bad.instances = NULL;
    CHECK(meso_rt_draw_list(c->rt, &bad, 1, &c->desc) == MESO_ERR_INVALID_ARG);
    printf("ok   draw_list refuses count 0, NULL items / common, instance_count without instances\n");
}

typedef void (*glgetiv_fn)(GLenum, GLint*);

/* The GL state around a list under MESO_STATE_RESTORE. */
static void test_list_state(ctx* c, const meso_rt_object* objs, int count)
{
    glgetiv_fn get_iv = (glgetiv_fn)meso_egl_proc("glGetIntegerv");
    void (*active)(GLenum) = (void (*)(GLenum))meso_egl_proc("glActiveTexture");
    void (*depth_func)(GLenum) = (void (*)(GLenum))meso_egl_proc("glDepthFunc");
    CHECK(get_iv && active && depth_func);
    active(GL_TEXTURE3);
    depth_func(GL_LEQUAL);
    GLint before[4], after[4];
    get_iv(GL_ACTIVE_TEXTURE, &before[0]);
    get_iv(GL_DEPTH_FUNC, &before[1]);
    get_iv(GL_CURRENT_PROGRAM, &before[2]);
    get_iv(GL_TEXTURE_BUFFER_BINDING, &before[3]);
    meso_rt_draw_item items[4];
    memset(items, 0, sizeof(items));
    for (int i = 0; i < count && i < 4; ++i)
        items[i].object = objs[i];
    CHECK(meso_rt_draw_list(c->rt, items, (uint32_t)(count < 4 ? count : 4), &c->desc) == MESO_OK);
    get_iv(GL_ACTIVE_TEXTURE, &after[0]);
    get_iv(GL_DEPTH_FUNC, &after[1]);
    get_iv(GL_CURRENT_PROGRAM, &after[2]);
    get_iv(GL_TEXTURE_BUFFER_BINDING, &after[3]);
    CHECK(memcmp(before, after, sizeof(before)) == 0);
    active(GL_TEXTURE0);
    depth_func(GL_LESS);
    printf("ok   draw_list restores active texture, depth function, program, texture buffer binding\n");
}

static void test_refusals(ctx* c, meso_rt_object mesh, meso_rt_object shell)
{
    meso_rt_instance inst[3];
    spread(c, mesh, inst, 3);
    inst[2].model[0] *= 2.0f; /* stretched along x */
    CHECK(meso_rt_draw_instanced(c->rt, mesh, &c->desc, inst, 3) == MESO_ERR_INVALID_ARG);
    need(strstr(c->log.message, "instance 2: model matrix is not") != NULL, "log: %s", c->log.message);
    printf("ok   non-similarity instance refused: %s\n", c->log.message);
    spread(c, mesh, inst, 3);
    const double t[3] = {0, 0, 0}, axis[3] = {0, 1, 0};
    model_of(c, mesh, t, axis, 0.3, 0.5, 1, inst[1].model);
    CHECK(meso_rt_draw_instanced(c->rt, shell, &c->desc, inst, 3) == MESO_ERR_INVALID_ARG);
    need(strstr(c->log.message, "instance 1 is mirrored") != NULL, "log: %s", c->log.message);
    CHECK(meso_rt_draw_instanced(c->rt, mesh, &c->desc, inst, 0) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_draw_instanced(c->rt, mesh, &c->desc, NULL, 3) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_draw_instanced(c->rt, mesh, NULL, inst, 3) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_draw_instanced(c->rt, (meso_rt_object){0}, &c->desc, inst, 3) == MESO_ERR_INVALID_ARG);
    meso_rt_draw_desc d = c->desc;
    d.shell.technique = MESO_SHELL_SLICES;
    CHECK(meso_rt_draw_instanced(c->rt, shell, &d, inst, 1) == MESO_ERR_UNSUPPORTED);
    printf("ok   refused: mirrored mix, count 0, NULL instances / desc, stale handle, slices\n");

    /* All mirrored is fine, and equals the separate (mirrored) draws. */
    for (int i = 0; i < N && i < 3; ++i) {
        const double ti[3] = {-1.2 + 1.2 * i, 0, 0};
        model_of(c, shell, ti, axis, 0.4 * i, 0.5, 1, inst[i].model);
    }
    draw_separately(c, shell, &c->desc, inst, 3, "mirrored");
    render_begin(c);
    CHECK(meso_rt_draw_instanced(c->rt, shell, &c->desc, inst, 3) == MESO_OK);
    render_end(c, 1);
    same(c, "mirrored shell instances = separate mirrored draws", 1);
}

/* The passes and the shading hook see each instance's model in their
 * fragment stages (world normals, world points): depth-only and G-buffer
 * (albedo attachment and depth) instanced = separate draws, and forward
 * with hooks that paint the world normal and the world point. */
static void test_passes(ctx* c, const meso_rt_object* objs)
{
    static const char* const kinds[4] = {"mesh", "shell", "frusta", "cells"};
    for (int k = 0; k < 4; ++k)
        for (int pass = MESO_PASS_DEPTH; pass <= MESO_PASS_GBUFFER; ++pass) {
            meso_rt_draw_desc d = c->desc;
            d.pass = (meso_rt_pass)pass;
            char what[96];
            snprintf(what, sizeof(what), "%s %s pass: instanced = separate draws", kinds[k],
                     pass == MESO_PASS_DEPTH ? "depth" : "G-buffer");
            instanced_vs_separate(c, objs[k], &d, what);
        }
    static const char* const hooks[2] = {
        "vec3 meso_shade(vec3 a, vec3 n, vec3 p, vec3 v) { return 0.5 + 0.5 * n; }\n",
        "vec3 meso_shade(vec3 a, vec3 n, vec3 p, vec3 v) { return fract(0.7 * p + 0.5); }\n"};
    static const char* const names[4] = {"mesh", "shell", "frusta", "cells"};
    meso_rt* plain = c->rt;
    for (int h = 0; h < 2; ++h) {
        CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error,
                                             .log_user = &c->log, .shading_hook = hooks[h]},
                             &c->rt) == MESO_OK);
        for (int k = 0; k < 4; ++k) {
            const meso_rt_object o = load(c, names[k]);
            char what[96];
            snprintf(what, sizeof(what), "%s, hook painting the world %s: instanced = separate draws", kinds[k],
                     h ? "point" : "normal");
            instanced_vs_separate(c, o, &c->desc, what);
            meso_rt_release_object(c->rt, o);
        }
        meso_rt_destroy(c->rt);
    }
    c->rt = plain;
}

int main(int argc, char** argv)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    need(argc == 2, "usage: test_rt_instances MESOBAKE");
    ctx c = {.mesobake = argv[1]};
    test_temp_dir(c.dir, sizeof(c.dir), "rt_instances");
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    need(egl != NULL, "%s", why);
    CHECK(test_fbo_create(&c.fbo, W, H));
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error,
                                         .log_user = &c.log},
                         &c.rt) == MESO_OK);
    for (int k = 0; k < 2; ++k) {
        c.rgba[k] = malloc((size_t)W * H * 4);
        c.depth[k] = malloc(sizeof(float) * W * H);
    }
    const double eye[3] = {0.3, 1.4, 4.2}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    meso_camera_look_at(c.desc.view, eye, at, up);
    meso_camera_perspective(c.desc.proj, 0.9, (double)W / H, 0.1, 20.0);

    char args[4400];
    snprintf(args, sizeof(args), "mesh -i '%s'", test_data("torus.obj"));
    bake(&c, "mesh", args);
    snprintf(args, sizeof(args), "shell -i '%s' --texture bricks:32 --tiling 2 -j 2", test_data("spot_uv.obj"));
    bake(&c, "shell", args);
    snprintf(args, sizeof(args), "frusta -i '%s' --relief bricks:32", test_data("saguaro.skel"));
    bake(&c, "frusta", args);
    snprintf(args, sizeof(args), "cells -i '%s' --tile-map spheres:8:0.3 --tiles 3 --tile-res 16 -j 2", test_data("cube_no_bottom.obj"));
    bake(&c, "cells", args);
    snprintf(args, sizeof(args),
             "shell -i '%s' -j 2 --thickness-rel 0.12 --texture boil:16 --frames 4 --fps 8", test_data("torus.obj"));
    bake(&c, "anim", args);
    const meso_rt_object objs[4] = {load(&c, "mesh"), load(&c, "shell"), load(&c, "frusta"), load(&c, "cells")};

    instanced_vs_separate(&c, objs[0], &c.desc, "mesh: instanced = separate draws");
    static const char* const tech[4] = {"smooth", "curved", "tetra", "segment-only"};
    for (int t = 0; t < 4; ++t) {
        meso_rt_draw_desc d = c.desc;
        d.shell.technique = (meso_shell_technique)t;
        char what[64];
        snprintf(what, sizeof(what), "shell %s: instanced = separate draws", tech[t]);
        instanced_vs_separate(&c, objs[1], &d, what);
    }
    instanced_vs_separate(&c, objs[2], &c.desc, "frusta (relief): instanced = separate draws");
    instanced_vs_separate(&c, objs[3], &c.desc, "cells: instanced = separate draws");
    {
        meso_rt_draw_desc d = c.desc;
        d.cells.mode = MESO_CELLS_REFLECT;
        d.cells.bounces = 1;
        instanced_vs_separate(&c, objs[3], &d, "cells reflect: instanced = separate draws");
    }
    test_pose_slots(&c);
    test_shell_time(&c);
    test_list(&c, objs, 4);
    test_list_state(&c, objs, 4);
    test_refusals(&c, objs[0], objs[1]);
    test_passes(&c, objs);

    for (int i = 0; i < 4; ++i)
        meso_rt_release_object(c.rt, objs[i]);
    for (int k = 0; k < 2; ++k) {
        free(c.rgba[k]);
        free(c.depth[k]);
    }
    meso_rt_destroy(c.rt);
    test_fbo_destroy(&c.fbo);
    meso_egl_destroy(egl);
    test_temp_dir_remove(c.dir);
    printf("all instance tests passed\n");
    return 0;
}
