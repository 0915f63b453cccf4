/* libmeso's passes (meso_rt_draw_desc.pass: forward, depth, G-buffer) and
 * shading hook (meso_rt_desc.shading_hook), issue 18 item 4, on llvmpipe,
 * for every kind: a mesh, shells (smooth, curved, tetra, segment only,
 * slices MESO_SLICE_NONE), relief-mapped frusta and cells (first hit and
 * reflection), all baked by mesobake (argv[1]) from bundled data.
 *
 * The target is the host's G-buffer: two RGBA32F colour attachments (draw
 * buffers 0 and 1) and a 32-bit float depth buffer. Expectations, each
 * independent of the runtime's shaders:
 *  - depth: the depth pass's and the G-buffer pass's depth buffers equal
 *    the forward pass's bit for bit (same fragments, same gl_FragDepth), and
 *    the depth pass leaves the colour attachments as cleared and counts the
 *    same ray-cast fragments and hits as forward (stats, OpenGL 4.3); under
 *    reversed-Z too, over the pixels standard depth covers;
 *  - albedo: where hit, rgb = desc->albedo exactly (cells: the constant
 *    colour map's sRGB texel decoded with the sRGB formula, within 2e-3);
 *    a = 1 for meshes and cells, in [0.25, 1] for shells and frusta;
 *  - normals: unit (within 1e-4) and, against the exact CPU references'
 *    shading normals (runtime/reference: shell_reference.h,
 *    frustum_reference.h, cell_reference.h) turned to face the viewer and
 *    into world space, at pixels whose 3x3 neighbourhood the reference
 *    covers: median angle <= 0.25 degrees, 90th percentile <= 2 degrees
 *    (measured at most 0.03 and 0.62, shells; the GL hit lies up to a
 *    quarter pixel from the reference's and normals turn fast at brick
 *    edges); a mirrored model (x -> -x) gives the mirrored normals. Not
 *    compared: tetra shells (the reference maps with the smooth Phi, the
 *    tetrahedra differ by design), slices (slice points, not the surface),
 *    segment-only shells (no surface) and meshes (no reference);
 *  - deferred = forward: the built-in formula meso_rt.h states,
 *    albedo.rgb * albedo.a * (0.15 + 0.85 max(0, n . l)) (meshes |n . l|),
 *    recomputed from the G-buffer, equals the forward image within 2e-6 per
 *    channel (measured <= 2e-7: float rounding, the shaders light in object
 *    space);
 *  - the hook: with a host uniform block (MesoHook at binding point 3)
 *    selecting n * 0.5 + 0.5, the forward image equals the G-buffer's normal
 *    attachment within 1e-6; selecting albedo, equals albedo.rgb * albedo.a;
 *    selecting v * 0.5 + 0.5, v equals the unit direction from the hit
 *    (unprojected from the depth buffer) to the eye within 1e-5 (measured
 *    2e-7); the hooked draw's depth equals the forward one's bit for bit;
 *  - refused: a hook that does not compile, alone (checked first) or with a
 *    kind's shader (a name clash), fails meso_rt_create with MESO_ERR_GL and
 *    SHADER_COMPILE_FAILED naming the hook; two-pass slices in the depth pass
 *    give MESO_ERR_UNSUPPORTED; the colour mask comes back;
 *  - a frusta colour map (mesobake frusta --relief-color): the G-buffer
 *    albedo against the source PNG at the analytic relief coordinates of
 *    each pixel's hit, mean error <= 2/255 in sRGB (test_frusta_color);
 *  - cells coloured from a glTF's base-colour texture (mesobake cells
 *    --colour from-mesh): the albedo against the texture at the nearest
 *    box point, mean <= 2/255 away from the box's edges
 *    (test_cells_from_mesh).
 * MESO_TEST_PNG is not used: the numbers are printed per case. */
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cell_reference.h"
#include "egl_context.h"
#include "frustum_reference.h"
#include "gl_gbuffer.h"
#include "gl_log.h"
#include "meso_bake.h"
#include "meso_rt.h"
#include "png_io.h"
#include "shell_reference.h"
#include "shell_scene.h"

enum { W = 128, H = 96 };

typedef gbuffer_gl pgl;

#define HOOK_BINDING 3u
/* The hook under test: a mix of normal, albedo and view direction chosen by
 * the host through its uniform block. */
static const char* const hook_src =
    "layout(std140) uniform MesoHook { vec4 hook_mix; };\n"
    "vec3 meso_shade(vec3 albedo, vec3 n_world, vec3 p_world, vec3 v_world)\n"
    "{\n"
    "    return hook_mix.x * (n_world * 0.5 + 0.5) + hook_mix.y * albedo + hook_mix.z * (v_world * 0.5 + 0.5);\n"
    "}";

typedef struct ctx {
    meso_rt *rt, *hooked;
    pgl gl;
    GLuint fbo, rb[3], ubo;
    float *c0, *c1, *depth; /* attachment 0, 1 (RGBA), depth */
    float *fwd, *fwd_depth;
    log_capture log;
    const char* mesobake;
    char dir[64];
} ctx;

static const float sentinel[4] = {0.25f, 0.5f, 0.75f, 1.0f};
static const float zero4[4] = {0.0f, 0.0f, 0.0f, 0.0f};

static void target_create(ctx* c)
{
    gbuffer_create(&c->gl, W, H, &c->fbo, c->rb);
    pgl* gl = &c->gl;
    gl->GenBuffers(1, &c->ubo);
    gl->BindBuffer(GL_UNIFORM_BUFFER, c->ubo);
    gl->BufferData(GL_UNIFORM_BUFFER, 16, zero4, GL_DYNAMIC_DRAW);
    gl->BindBufferBase(GL_UNIFORM_BUFFER, HOOK_BINDING, c->ubo);
    const size_t n = (size_t)W * H;
    c->c0 = malloc(sizeof(float) * 4 * n);
    c->c1 = malloc(sizeof(float) * 4 * n);
    c->fwd = malloc(sizeof(float) * 4 * n);
    c->depth = malloc(sizeof(float) * n);
    c->fwd_depth = malloc(sizeof(float) * n);
}

/* Clears (colour to the sentinel, depth to 1), draws, reads all back. */
static meso_result draw(ctx* c, meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* d)
{
    pgl* gl = &c->gl;
    const float one = 1.0f;
    gl->ClearBufferfv(GL_COLOR, 0, sentinel);
    gl->ClearBufferfv(GL_COLOR, 1, sentinel);
    gl->ClearBufferfv(GL_DEPTH, 0, &one);
    const meso_result r = meso_rt_draw(rt, obj, d);
    gl->ReadBuffer(GL_COLOR_ATTACHMENT0);
    gl->ReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, c->c0);
    gl->ReadBuffer(GL_COLOR_ATTACHMENT1);
    gl->ReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, c->c1);
    gl->ReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, c->depth);
    return r;
}

/* >>cases ------------------------------------------------------------------ */

typedef struct pcase {
    const char* name;
    meso_object_kind kind;
    meso_rt_draw_desc d;  /* knobs; view/proj filled from the camera */
    int ref_normals;      /* compare normals against the reference */
    int recompute;        /* forward = the built-in formula from the G-buffer */
    double albedo[3];     /* expected albedo.rgb; all zero: desc->albedo */
    float model[16];      /* all zero: identity */
} pcase;

typedef struct loaded {
    meso_rt_object obj, obj_hooked;
    meso_object_kind kind;
    meso_ref_shell shell;
    meso_ref_frusta frusta;
    meso_ref_cells cells;
    double lo[3], hi[3];
} loaded;

static const char* bake(ctx* c, const char* name, const char* cmd_args)
{
    static char path[256];
    snprintf(path, sizeof(path), "%s/%s.meso", c->dir, name);
    char cmd[1200];
    snprintf(cmd, sizeof(cmd), "'%s' %s -o '%s' >/dev/null 2>&1", c->mesobake, cmd_args, path);
    CHECK_MSG(system(cmd) == 0, "bake failed: %s", cmd);
    return path;
}

static loaded load(ctx* c, const char* path)
{
    loaded l;
    memset(&l, 0, sizeof(l));
    meso_error err;
    meso_object_record rec;
    meso_file* f = open_single_object(path, &rec, l.lo, l.hi);
    l.kind = (meso_object_kind)rec.kind;
    CHECK_MSG(meso_rt_load_object(c->rt, f, rec.id, &l.obj) == MESO_OK, "%s", c->log.message);
    CHECK_MSG(meso_rt_load_object(c->hooked, f, rec.id, &l.obj_hooked) == MESO_OK, "%s", c->log.message);
    if (l.kind == MESO_OBJECT_SHELL)
        CHECK(meso_ref_shell_load(f, rec.id, &l.shell, &err) == MESO_OK);
    if (l.kind == MESO_OBJECT_FRUSTA)
        CHECK(meso_ref_frusta_load(f, rec.id, &l.frusta, &err) == MESO_OK);
    if (l.kind == MESO_OBJECT_CELLS)
        CHECK(meso_ref_cells_load(f, rec.id, &l.cells, &err) == MESO_OK);
    meso_file_close(f);
    return l;
}

static void unload(ctx* c, loaded* l)
{
    meso_rt_release_object(c->rt, l->obj);
    meso_rt_release_object(c->hooked, l->obj_hooked);
    if (l->kind == MESO_OBJECT_SHELL)
        meso_ref_shell_free(&l->shell);
    if (l->kind == MESO_OBJECT_FRUSTA)
        meso_ref_frusta_free(&l->frusta);
    if (l->kind == MESO_OBJECT_CELLS)
        meso_ref_cells_free(&l->cells);
}

static camera view_box(const loaded* l, const double dir[3])
{
    return camera_view_box(l->lo, l->hi, dir, 0.7, 1.0, 0.01);
}

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return x < y ? -1 : x > y;
}

/* Unit world-space direction of pixel (x, y)'s ray through inv = (proj view)^-1. */
static void pixel_ray(const double inv[16], int x, int y, double rd[3])
{
    double a[3], b[3];
    unproject(inv, x, y, 0.0, a);
    unproject(inv, x, y, 0.5, b);
    double l = 0;
    for (int k = 0; k < 3; ++k) {
        rd[k] = b[k] - a[k];
        l += rd[k] * rd[k];
    }
    for (int k = 0; k < 3; ++k)
        rd[k] /= sqrt(l);
}

static void mat_dir(const float m[16], const double v[3], double out[3])
{
    double l = 0;
    for (int r = 0; r < 3; ++r) {
        out[r] = m[r] * v[0] + m[4 + r] * v[1] + m[8 + r] * v[2];
        l += out[r] * out[r];
    }
    for (int r = 0; r < 3; ++r)
        out[r] /= sqrt(l);
}

static void run_case(ctx* c, const loaded* l, const pcase* pc, const camera* cam)
{
    meso_rt_draw_desc d = pc->d;
    camera_matrices(cam, d.view, d.proj);
    memcpy(d.model, pc->model, sizeof(d.model));
    const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const float* model = d.model[0] == 0.0f && d.model[5] == 0.0f ? identity : d.model;
    const size_t n = (size_t)W * H;

    /* forward */
    meso_rt_draw_stats fwd_stats, depth_stats;
    d.pass = MESO_PASS_FORWARD;
    d.stats = &fwd_stats;
    CHECK_MSG(draw(c, c->rt, l->obj, &d) == MESO_OK, "%s: %s", pc->name, c->log.message);
    memcpy(c->fwd, c->c0, sizeof(float) * 4 * n);
    memcpy(c->fwd_depth, c->depth, sizeof(float) * n);
    long covered = 0;
    for (size_t i = 0; i < n; ++i)
        covered += c->fwd_depth[i] < 1.0f;
    CHECK_MSG(covered > 200, "%s: only %ld pixels covered", pc->name, covered);

    /* depth: the same depth buffer, colour untouched */
    d.pass = MESO_PASS_DEPTH;
    d.stats = &depth_stats;
    CHECK(draw(c, c->rt, l->obj, &d) == MESO_OK);
    d.stats = NULL;
    CHECK_MSG(memcmp(c->depth, c->fwd_depth, sizeof(float) * n) == 0, "%s: depth pass depth differs", pc->name);
    /* The same ray-cast fragments and hits (the work counters, OpenGL 4.3). */
    CHECK(depth_stats.supported == fwd_stats.supported);
    CHECK_MSG(depth_stats.fragments == fwd_stats.fragments && depth_stats.hits == fwd_stats.hits,
              "%s: depth pass counted %llu fragments %llu hits, forward %llu %llu", pc->name,
              (unsigned long long)depth_stats.fragments, (unsigned long long)depth_stats.hits,
              (unsigned long long)fwd_stats.fragments, (unsigned long long)fwd_stats.hits);
    for (size_t i = 0; i < 4 * n; ++i)
        CHECK_MSG(c->c0[i] == sentinel[i % 4] && c->c1[i] == sentinel[i % 4], "%s: depth pass wrote colour",
                  pc->name);
    GLboolean mask[4] = {0, 0, 0, 0};
    c->gl.GetBooleanv(GL_COLOR_WRITEMASK, mask);
    CHECK(mask[0] && mask[1] && mask[2] && mask[3]); /* MESO_STATE_RESTORE put it back */

    /* G-buffer */
    d.pass = MESO_PASS_GBUFFER;
    CHECK(draw(c, c->rt, l->obj, &d) == MESO_OK);
    CHECK_MSG(memcmp(c->depth, c->fwd_depth, sizeof(float) * n) == 0, "%s: G-buffer depth differs", pc->name);
    double want[3];
    const int desc_albedo = pc->albedo[0] == 0.0 && pc->albedo[1] == 0.0 && pc->albedo[2] == 0.0;
    const int unset = d.albedo[0] == 0.0f && d.albedo[1] == 0.0f && d.albedo[2] == 0.0f;
    static const float default_albedo[3] = {0.80f, 0.74f, 0.66f}; /* meso_rt.h */
    for (int k = 0; k < 3; ++k)
        want[k] = !desc_albedo ? pc->albedo[k] : unset ? (double)default_albedo[k] : (double)d.albedo[k];
    const int occ = pc->kind == MESO_OBJECT_SHELL || pc->kind == MESO_OBJECT_FRUSTA;
    double light[3] = {0.3, 0.8, 0.5}, ll = sqrt(0.98);
    for (int k = 0; k < 3; ++k)
        light[k] /= ll;
    double mvp[16] = {0}, inv[16], iv[16], v16[16];
    for (int a = 0; a < 4; ++a)
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k)
                mvp[4 * a + r] += (double)d.proj[4 * k + r] * (double)d.view[4 * a + k];
    for (int i = 0; i < 16; ++i)
        v16[i] = d.view[i];
    CHECK(invert4(mvp, inv) && invert4(v16, iv));
    const double eye[3] = {iv[12], iv[13], iv[14]};
    double max_recompute = 0.0, max_albedo = 0.0;
    for (size_t i = 0; i < n; ++i) {
        if (!(c->depth[i] < 1.0f))
            continue;
        const float* a = c->c0 + 4 * i;
        double nn[3], len = 0, dot = 0;
        for (int k = 0; k < 3; ++k) {
            max_albedo = fmax(max_albedo, fabs(a[k] - want[k]));
            nn[k] = 2.0 * c->c1[4 * i + k] - 1.0;
            len += nn[k] * nn[k];
            dot += nn[k] * light[k];
        }
        CHECK_MSG(fabs(sqrt(len) - 1.0) <= 1e-4, "%s: normal length %g", pc->name, sqrt(len));
        CHECK_MSG(occ ? a[3] >= 0.25f - 1e-6f && a[3] <= 1.0f + 1e-6f : a[3] == 1.0f, "%s: albedo.a %g", pc->name,
                  (double)a[3]);
        if (pc->recompute) {
            const double lam = pc->kind == MESO_OBJECT_MESH ? fabs(dot) : fmax(0.0, dot);
            for (int k = 0; k < 3; ++k)
                max_recompute =
                    fmax(max_recompute, fabs(a[k] * a[3] * (0.15 + 0.85 * lam) - (double)c->fwd[4 * i + k]));
        }
    }
    CHECK_MSG(max_albedo <= (desc_albedo ? 0.0 : 2e-3), "%s: albedo off by %g", pc->name, max_albedo);
    CHECK_MSG(max_recompute <= 2e-6, "%s: deferred vs forward %g", pc->name, max_recompute);

    /* normals against the reference */
    double med = 0, p90 = 0;
    long compared = 0;
    if (pc->ref_normals) {
        meso_ref_view v = {.width = W, .height = H, .samples_per_prism = 256,
                           .curved = pc->d.shell.technique == MESO_SHELL_CURVED};
        for (int i = 0; i < 16; ++i) {
            v.view[i] = d.view[i];
            v.proj[i] = d.proj[i];
            v.model[i] = d.model[i];
        }
        meso_ref_image img;
        if (l->kind == MESO_OBJECT_SHELL)
            CHECK(meso_ref_render(&l->shell, &v, &img) == MESO_OK);
        else if (l->kind == MESO_OBJECT_FRUSTA)
            CHECK(meso_ref_frusta_render(&l->frusta, &v, &img) == MESO_OK);
        else
            CHECK(meso_ref_cells_render(&l->cells, &v, &(meso_ref_cells_opts){.mode = (int)d.cells.mode}, &img) ==
                  MESO_OK);
        double* ang = malloc(sizeof(double) * n);
        for (int y = 1; y + 1 < H; ++y)
            for (int x = 1; x + 1 < W; ++x) {
                const size_t i = (size_t)y * W + x;
                int inside = c->depth[i] < 1.0f;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                        inside &= img.coverage[(size_t)(y + dy) * W + (size_t)(x + dx)] != 0;
                if (!inside)
                    continue;
                const double nobj[3] = {img.normal[3 * i], img.normal[3 * i + 1], img.normal[3 * i + 2]};
                double nw[3], rd[3], dot = 0, ndot = 0;
                mat_dir(model, nobj, nw); /* a similarity: mat3(model) turns normals */
                pixel_ray(inv, x, y, rd);
                for (int k = 0; k < 3; ++k)
                    dot += nw[k] * rd[k];
                const double s = l->kind == MESO_OBJECT_CELLS || dot <= 0.0 ? 1.0 : -1.0;
                for (int k = 0; k < 3; ++k)
                    ndot += s * nw[k] * (2.0 * c->c1[4 * i + k] - 1.0);
                ang[compared++] = acos(fmax(-1.0, fmin(1.0, ndot))) * 180.0 / M_PI;
            }
        meso_ref_image_free(&img);
        CHECK_MSG(compared > 200, "%s: %ld pixels to compare normals", pc->name, compared);
        qsort(ang, (size_t)compared, sizeof(double), cmp_double);
        med = ang[compared / 2];
        p90 = ang[compared * 9 / 10];
        free(ang);
        CHECK_MSG(med <= 0.25 && p90 <= 2.0, "%s: normals off the reference: median %.3f, 90%% %.3f degrees",
                  pc->name, med, p90);
    }

    /* the hook: normal, albedo, view direction through the host's block */
    double hook_err[3] = {0, 0, 0};
    static const float mixes[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
    const int hooked = !(pc->kind == MESO_OBJECT_SHELL && pc->d.shell.technique == MESO_SHELL_SEGMENT_ONLY) &&
                       !(pc->kind == MESO_OBJECT_CELLS && pc->d.cells.mode != MESO_CELLS_FIRST_HIT);
    for (int m = 0; hooked && m < 3; ++m) {
        c->gl.BindBuffer(GL_UNIFORM_BUFFER, c->ubo);
        c->gl.BufferData(GL_UNIFORM_BUFFER, 16, mixes[m], GL_DYNAMIC_DRAW);
        d.pass = MESO_PASS_GBUFFER;
        CHECK(draw(c, c->rt, l->obj, &d) == MESO_OK);
        float* gb = malloc(sizeof(float) * 8 * n);
        memcpy(gb, c->c0, sizeof(float) * 4 * n);
        memcpy(gb + 4 * n, c->c1, sizeof(float) * 4 * n);
        d.pass = MESO_PASS_FORWARD;
        CHECK_MSG(draw(c, c->hooked, l->obj_hooked, &d) == MESO_OK, "%s", c->log.message);
        CHECK_MSG(memcmp(c->depth, c->fwd_depth, sizeof(float) * n) == 0, "%s: hooked depth differs", pc->name);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const size_t i = (size_t)y * W + x;
                if (!(c->depth[i] < 1.0f))
                    continue;
                double p[3], e[3], el = 0;
                if (m == 2) {
                    unproject(inv, x, y, c->depth[i], p);
                    for (int k = 0; k < 3; ++k) {
                        e[k] = eye[k] - p[k];
                        el += e[k] * e[k];
                    }
                }
                for (int k = 0; k < 3; ++k) {
                    const double expect = m == 0   ? gb[4 * n + 4 * i + k]
                                          : m == 1 ? (double)gb[4 * i + k] * gb[4 * i + 3]
                                                   : e[k] / sqrt(el) * 0.5 + 0.5;
                    hook_err[m] = fmax(hook_err[m], fabs(c->c0[4 * i + k] - expect));
                }
            }
        free(gb);
    }
    CHECK_MSG(hook_err[0] <= 1e-6 && hook_err[1] <= 1e-6 && hook_err[2] <= 1e-5,
              "%s: hook off by %g (normal) %g (albedo) %g (view)", pc->name, hook_err[0], hook_err[1], hook_err[2]);
    printf("%-18s covered %5ld  hits %6llu  depth passes bit-equal  albedo err %.1e  deferred-forward %.1e  normals vs reference "
           "(%ld px): median %.3f deg, 90%% %.3f deg  hook err %.1e %.1e %.1e\n",
           pc->name, covered, (unsigned long long)fwd_stats.hits, max_albedo, max_recompute, compared, med, p90, hook_err[0], hook_err[1], hook_err[2]);
}

/* Reversed-Z (MESO_DEPTH_REVERSED, GL_GREATER, cleared to 0; proj with its
 * z row negated): the depth and G-buffer passes still write the forward
 * pass's depth buffer bit for bit, over the same pixels as standard depth. */
static void reversed_check(ctx* c, const loaded* l, const pcase* pc, const camera* cam)
{
    meso_rt_draw_desc d = pc->d;
    camera_matrices(cam, d.view, d.proj);
    CHECK(draw(c, c->rt, l->obj, &d) == MESO_OK); /* standard depth, forward: the coverage */
    memcpy(c->fwd_depth, c->depth, sizeof(float) * (size_t)W * H);
    for (int col = 0; col < 4; ++col)
        d.proj[4 * col + 2] = -d.proj[4 * col + 2];
    d.depth = MESO_DEPTH_REVERSED;
    d.depth_func = GL_GREATER;
    const size_t n = (size_t)W * H;
    float* first = malloc(sizeof(float) * n);
    long covered = 0;
    for (int p = 0; p < MESO_PASS_COUNT; ++p) {
        const float zero = 0.0f;
        c->gl.ClearBufferfv(GL_DEPTH, 0, &zero);
        d.pass = (meso_rt_pass)p;
        CHECK_MSG(meso_rt_draw(c->rt, l->obj, &d) == MESO_OK, "%s", c->log.message);
        c->gl.ReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, c->depth);
        if (p == 0) {
            memcpy(first, c->depth, sizeof(float) * n);
            for (size_t i = 0; i < n; ++i) {
                covered += c->depth[i] > 0.0f;
                CHECK_MSG((c->depth[i] > 0.0f) == (c->fwd_depth[i] < 1.0f), "%s reversed: coverage differs", pc->name);
            }
        }
        CHECK_MSG(memcmp(c->depth, first, sizeof(float) * n) == 0, "%s reversed: pass %d depth differs", pc->name, p);
    }
    printf("%-18s reversed-Z: %ld px, depth and G-buffer depth bit-equal to forward\n", pc->name, covered);
    free(first);
}

static double srgb_decode(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

/* "CMD -i DATA/FILE EXTRA": a bake of bundled file FILE. */
static const char* args_with(char buf[512], const char* cmd, const char* file, const char* extra)
{
    snprintf(buf, 512, "%s -i '%s/%s' %s", cmd, MESO_TEST_DATA, file, extra);
    return buf;
}

static void test_kinds(ctx* c)
{
    static const double dir[3] = {0.3, 0.4, 1.0};
    char buf[512];

    loaded l = load(c, bake(c, "mesh", args_with(buf, "mesh", "sphere.obj", "")));
    camera cam = view_box(&l, dir);
    run_case(c, &l, &(pcase){.name = "mesh", .kind = MESO_OBJECT_MESH, .recompute = 1}, &cam);
    unload(c, &l);

    l = load(c, bake(c, "shell", args_with(buf, "shell", "sphere.obj", "--texture bricks:64 --tiling 2 -j 2")));
    cam = view_box(&l, dir);
    static const char* const tn[] = {"shell smooth", "shell curved", "shell tetra", "shell segment"};
    for (int t = 0; t < 4; ++t)
        run_case(c, &l,
                 &(pcase){.name = tn[t], .kind = MESO_OBJECT_SHELL, .d = {.shell = {.technique = t}},
                          .ref_normals = t != MESO_SHELL_SEGMENT_ONLY && t != MESO_SHELL_TETRA,
                          .recompute = t != MESO_SHELL_SEGMENT_ONLY},
                 &cam);
    reversed_check(c, &l, &(pcase){.name = "shell smooth", .kind = MESO_OBJECT_SHELL}, &cam);
    run_case(c, &l,
             &(pcase){.name = "shell mirrored", .kind = MESO_OBJECT_SHELL, .ref_normals = 1, .recompute = 1,
                      .d = {.albedo = {0.2f, 0.5f, 0.9f}}, .model = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
             &cam);
    run_case(c, &l,
             &(pcase){.name = "slices none", .kind = MESO_OBJECT_SHELL, .recompute = 1,
                      .d = {.shell = {.technique = MESO_SHELL_SLICES, .slice_interp = MESO_SLICE_NONE}}},
             &cam);
    meso_rt_draw_desc two = {.shell = {.technique = MESO_SHELL_SLICES}, .pass = MESO_PASS_DEPTH};
    camera_matrices(&cam, two.view, two.proj);
    CHECK(draw(c, c->rt, l.obj, &two) == MESO_ERR_UNSUPPORTED && c->log.last == MESO_LOGITEM_INVALID_ARGUMENT);
    unload(c, &l);

    l = load(c, bake(c, "frusta", args_with(buf, "frusta", "neurom_simple.swc", "--relief bricks:64")));
    cam = view_box(&l, dir);
    run_case(c, &l, &(pcase){.name = "frusta relief", .kind = MESO_OBJECT_FRUSTA, .ref_normals = 1, .recompute = 1},
             &cam);
    reversed_check(c, &l, &(pcase){.name = "frusta relief", .kind = MESO_OBJECT_FRUSTA}, &cam);
    run_case(c, &l,
             &(pcase){.name = "frusta mirrored", .kind = MESO_OBJECT_FRUSTA, .ref_normals = 1, .recompute = 1,
                      .model = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
             &cam);
    unload(c, &l);

    /* Cells with one colour everywhere: albedo is its sRGB texel decoded. */
    enum { R = 16 };
    char raw[128];
    snprintf(raw, sizeof(raw), "%s/colour.raw", c->dir);
    FILE* f = fopen(raw, "wb");
    CHECK(f);
    static const uint8_t texel[4] = {200, 120, 60, 255};
    for (int i = 0; i < R * R * R; ++i)
        CHECK(fwrite(texel, 4, 1, f) == 1);
    CHECK(fclose(f) == 0);
    char args[512];
    snprintf(args, sizeof(args),
             "cells -i '%s/sphere.obj' --tiles 5 --tile-res %d --tile-map voronoi:8 --colour '%s:%d' -j 2",
             MESO_TEST_DATA, R, raw, R);
    l = load(c, bake(c, "cells", args));
    cam = view_box(&l, dir);
    pcase cells = {.name = "cells first hit", .kind = MESO_OBJECT_CELLS, .ref_normals = 1, .recompute = 1};
    for (int k = 0; k < 3; ++k)
        cells.albedo[k] = srgb_decode(texel[k] / 255.0);
    run_case(c, &l, &cells, &cam);
    reversed_check(c, &l, &cells, &cam);
    cells.name = "cells reflect";
    cells.recompute = 0; /* forward adds the reflections; the G-buffer holds the first hit */
    cells.d.cells = (meso_rt_cells_draw){.mode = MESO_CELLS_REFLECT, .bounces = 2};
    run_case(c, &l, &cells, &cam);
    unload(c, &l);
}

/* Draws `l` into the G-buffer from direction `dir`; inv = (proj view)^-1. */
static void gbuffer_view(ctx* c, const loaded* l, const double dir[3], double inv[16])
{
    const camera cam = view_box(l, dir);
    meso_rt_draw_desc d = {.pass = MESO_PASS_GBUFFER};
    camera_matrices(&cam, d.view, d.proj);
    CHECK(draw(c, c->rt, l->obj, &d) == MESO_OK);
    double mvp[16] = {0};
    for (int a = 0; a < 4; ++a)
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k)
                mvp[4 * a + r] += (double)d.proj[4 * k + r] * (double)d.view[4 * a + k];
    CHECK(invert4(mvp, inv));
}

/* >>frusta colour ------------------------------------------------------------
 * A colour map on frusta (mesobake frusta --relief-color, FORMAT.md §7.2
 * kind 4 COLR) against the source PNG: one straight cylinder (two tips, so
 * both planes are perpendicular to the axis and v = y / h), the G-buffer's
 * linear albedo at every pixel whose ray meets the lateral surface well
 * inside both ends and not at a grazing angle, against the PNG bilinear in
 * linear colour at the (s, t) computed here from the ray's analytic hit on
 * the cylinder and FORMAT.md's parametrisation (u from the FSEG frame, the
 * PNG's bottom row at t = 0). Compared in sRGB (0..255): mean error at most
 * 2 (issue 16's goal). */
enum { CW = 12, CH = 6 };

static double srgb_encode(double l)
{
    l = fmin(fmax(l, 0.0), 1.0);
    return l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1 / 2.4) - 0.055;
}

static void test_frusta_color(ctx* c)
{
    uint8_t png[CW * CH * 4]; /* rows top to bottom, as the file */
    for (int y = 0; y < CH; ++y)
        for (int x = 0; x < CW; ++x) {
            uint8_t* p = png + 4 * (y * CW + x);
            p[0] = (uint8_t)(30 + 18 * x);
            p[1] = (uint8_t)(220 - 30 * y);
            p[2] = (uint8_t)(128 + (int)lround(80 * sin(0.7 * x + 1.1 * y)));
            p[3] = 255;
        }
    char path[160], swc[160], args[512], why[256];
    snprintf(path, sizeof(path), "%s/colour.png", c->dir);
    CHECK_MSG(meso_png_write_rgba8(path, png, CW, CH, 0, why, (int)sizeof(why)) == 0, "%s", why);
    snprintf(swc, sizeof(swc), "%s/rod.swc", c->dir);
    FILE* f = fopen(swc, "w");
    CHECK(f && fputs("1 1 0 0 0 0.5 -1\n2 1 3 0.4 0.2 0.5 1\n", f) >= 0 && fclose(f) == 0);
    snprintf(args, sizeof(args), "frusta -i '%s' --relief-color '%s' --relief-repeat 2", swc, path);
    loaded l = load(c, bake(c, "frusta_colour", args));
    CHECK(l.frusta.seg_count == 1 && l.frusta.ball_count == 0 && l.frusta.color_w == CW);
    const meso_ref_frustum* sg = &l.frusta.segs[0];
    CHECK(fabs(sg->r0 - sg->r1) < 1e-6 && !(sg->twist != 0));

    static const double dir[3] = {0.2, 0.6, 1.0};
    double inv[16];
    gbuffer_view(c, &l, dir, inv);
    double ax[3], h = 0, fz[3];
    for (int k = 0; k < 3; ++k) {
        ax[k] = sg->c1[k] - sg->c0[k];
        h += ax[k] * ax[k];
    }
    h = sqrt(h);
    for (int k = 0; k < 3; ++k)
        ax[k] /= h;
    const double* fx = sg->frame_x;
    fz[0] = fx[1] * ax[2] - fx[2] * ax[1];
    fz[1] = fx[2] * ax[0] - fx[0] * ax[2];
    fz[2] = fx[0] * ax[1] - fx[1] * ax[0];
    double sum_err = 0, max_err = 0, sum_e = 0, sum_e2 = 0;
    long count = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + (size_t)x;
            if (!(c->depth[i] < 1.0f))
                continue;
            double o[3], rd[3], oq[3], dq[3];
            unproject(inv, x, y, 0.0, o);
            pixel_ray(inv, x, y, rd);
            double oy = 0, dy = 0;
            for (int k = 0; k < 3; ++k) {
                oy += (o[k] - sg->c0[k]) * ax[k];
                dy += rd[k] * ax[k];
            }
            double A = 0, B = 0, C = -sg->r0 * sg->r0;
            for (int k = 0; k < 3; ++k) {
                oq[k] = o[k] - sg->c0[k] - oy * ax[k];
                dq[k] = rd[k] - dy * ax[k];
                A += dq[k] * dq[k];
                B += 2 * oq[k] * dq[k];
                C += oq[k] * oq[k];
            }
            const double disc = B * B - 4 * A * C;
            if (!(disc > 0) || !(A > 0))
                continue;
            const double t = (-B - sqrt(disc)) / (2 * A), yy = oy + t * dy;
            double q[3], qn = 0, facing = 0;
            for (int k = 0; k < 3; ++k) {
                q[k] = oq[k] + t * dq[k];
                qn += q[k] * q[k];
            }
            qn = sqrt(qn);
            for (int k = 0; k < 3; ++k)
                facing -= rd[k] * q[k] / qn;
            if (!(yy > 0.03 * h && yy < 0.97 * h) || facing < 0.25)
                continue; /* near an end or grazing: the hit is sensitive to rounding there */
            double qx = 0, qz = 0;
            for (int k = 0; k < 3; ++k) {
                qx += q[k] * fx[k];
                qz += q[k] * fz[k];
            }
            double u = atan2(qx, qz) / (2 * M_PI) - sg->u_offset;
            u -= floor(u);
            const double st[2] = {u * sg->u_scale, sg->v_offset + yy / h * sg->v_scale};
            const int n[2] = {CW, CH};
            int i0[2], i1[2];
            double fr[2];
            for (int a = 0; a < 2; ++a) {
                const double xx = st[a] * n[a] - 0.5, fl = floor(xx);
                fr[a] = xx - fl;
                i0[a] = (((int)fl % n[a]) + n[a]) % n[a];
                i1[a] = (i0[a] + 1) % n[a];
            }
            for (int k = 0; k < 3; ++k) {
                /* texel row j (t) is the PNG's row CH - 1 - j */
#define TEX(ix, jt) srgb_decode(png[4 * ((CH - 1 - (jt)) * CW + (ix)) + k] / 255.0)
                const double lin = (1 - fr[1]) * ((1 - fr[0]) * TEX(i0[0], i0[1]) + fr[0] * TEX(i1[0], i0[1])) +
                                   fr[1] * ((1 - fr[0]) * TEX(i0[0], i1[1]) + fr[0] * TEX(i1[0], i1[1]));
#undef TEX
                const double want = 255 * srgb_encode(lin), got = 255 * srgb_encode(c->c0[4 * i + (size_t)k]);
                sum_err += fabs(want - got);
                max_err = fmax(max_err, fabs(want - got));
                sum_e += want;
                sum_e2 += want * want;
            }
            ++count;
        }
    const double mean = sum_err / (3.0 * (double)count), m1 = sum_e / (3.0 * (double)count);
    const double spread = sqrt(fmax(0.0, sum_e2 / (3.0 * (double)count) - m1 * m1));
    printf("frusta colour map: %ld pixels, error vs the source PNG mean %.3f / 255, max %.2f / 255 (colour spread "
           "%.1f)\n",
           count, mean, max_err, spread);
    CHECK_MSG(count > 1500, "only %ld pixels compared", count);
    CHECK_MSG(spread > 20, "the map's colours vary over the image (spread %.1f), so a constant cannot pass", spread);
    CHECK_MSG(mean <= 2.0, "frusta colour: mean error %.3f / 255 > 2", mean);
    unload(c, &l);
}

/* >>cells colour from the mesh -------------------------------------------------
 * mesobake cells --colour from-mesh (FORMAT.md §7.2 kind 3, the TX3D colour
 * grid) on tests/data/gltf/box.gltf (the unit box [-0.5, 0.5]^3, each face
 * mapped to uv [0, 1]^2 as make_gltf.py builds it, a 4 x 4 PNG texture and
 * a base-colour factor). At every G-buffer pixel whose hit p (unprojected
 * from the depth buffer) is inside the box and nearer to one face than to
 * any other by at least two grid spacings (away from the box's edges,
 * where the nearest face and so the colour jumps), the albedo against the
 * base colour at p's nearest box point: that face's uv, computed here from
 * make_gltf.py's face table, the texture bilinear in linear colour
 * (repeating, v = 0 its first row) times the factor. sRGB, mean <= 2/255. */
static void test_cells_from_mesh(ctx* c)
{
    enum { G = 64 };
    char path[512], args[700];
    snprintf(path, sizeof(path), "%s/gltf/box.gltf", MESO_TEST_DATA);
    snprintf(args, sizeof(args), "cells -i '%s' --tiles 4 --tile-res 16 --colour from-mesh:%d -j 2", path, G);
    loaded l = load(c, bake(c, "cells_from_mesh", args));
    CHECK(l.cells.grid[0] == G && l.cells.grid[1] == G && l.cells.grid[2] == G);
    meso_mesh m;
    meso_mesh_materials mats;
    meso_error err;
    CHECK_MSG(meso_bake_load_mesh_materials(path, NULL, &m, &mats, NULL, &err) == MESO_OK, "%s", err.message);
    CHECK(mats.material_count == 1 && mats.materials[0].rgba && mats.materials[0].width == 4);
    const meso_mesh_material* mt = &mats.materials[0];

    static const double dir[3] = {0.35, 0.5, 1.0};
    double inv[16];
    gbuffer_view(c, &l, dir, inv);
    /* make_gltf.py's faces: (normal axis, sign, u axis, v axis); u = p[ua] + 0.5, v = 0.5 - p[va]. */
    static const int faces[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 2, 0}, {1, 0, 2}, {2, 0, 1}, {2, 1, 0}};
    const double spacing = (double)l.cells.tiles[0] * l.cells.res * l.cells.voxel / G;
    double sum = 0, worst = 0, sum_all = 0;
    long count = 0, covered = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + (size_t)x;
            if (!(c->depth[i] < 1.0f))
                continue;
            double p[3];
            unproject(inv, x, y, c->depth[i], p);
            int best = -1;
            double d1 = 1e30, d2 = 1e30;
            for (int f = 0; f < 6; ++f) {
                const int axis = faces[f][0];
                const double dist = f % 2 == 0 ? 0.5 - p[axis] : p[axis] + 0.5;
                if (dist < d1) {
                    d2 = d1;
                    d1 = dist;
                    best = f;
                } else if (dist < d2) {
                    d2 = dist;
                }
            }
            const double uv[2] = {p[faces[best][1]] + 0.5, 0.5 - p[faces[best][2]]};
            double want[3];
            for (int k = 0; k < 3; ++k) {
                double xy[2], fr[2];
                int i0[2], i1[2];
                for (int a = 0; a < 2; ++a) {
                    xy[a] = uv[a] * 4 - 0.5;
                    const double fl = floor(xy[a]);
                    fr[a] = xy[a] - fl;
                    i0[a] = (((int)fl % 4) + 4) % 4;
                    i1[a] = (i0[a] + 1) % 4;
                }
#define TEXEL(tx, ty) srgb_decode(mt->rgba[4 * ((ty) * 4 + (tx)) + k] / 255.0)
                want[k] = mt->base_color_factor[k] *
                          ((1 - fr[1]) * ((1 - fr[0]) * TEXEL(i0[0], i0[1]) + fr[0] * TEXEL(i1[0], i0[1])) +
                           fr[1] * ((1 - fr[0]) * TEXEL(i0[0], i1[1]) + fr[0] * TEXEL(i1[0], i1[1])));
#undef TEXEL
            }
            double e = 0;
            for (int k = 0; k < 3; ++k)
                e += fabs(255 * srgb_encode(want[k]) - 255 * srgb_encode(c->c0[4 * i + (size_t)k])) / 3;
            ++covered;
            sum_all += e;
            if (!(d1 >= 0) || d2 - d1 < 2 * spacing)
                continue; /* outside the box, or near an edge */
            sum += e;
            worst = fmax(worst, e);
            ++count;
        }
    printf("cells from-mesh: %ld of %ld pixels away from the box's edges: error vs the texture mean %.3f / 255, "
           "max %.2f / 255; all %ld pixels: mean %.3f / 255\n",
           count, covered, sum / (double)count, worst, covered, sum_all / (double)covered);
    CHECK_MSG(count > 2000, "only %ld pixels compared", count);
    CHECK_MSG(sum / (double)count <= 2.0, "cells from-mesh: mean error %.3f / 255 > 2", sum / (double)count);
    meso_mesh_materials_free(&mats);
    meso_mesh_free(&m);
    unload(c, &l);
}

static void test_broken_hook(void)
{
    log_capture log = {0};
    meso_rt* rt = NULL;
    const meso_result r = meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc,
                                                         .log_fn = on_log_error,
                                                         .log_user = &log,
                                                         .shading_hook = "vec3 meso_shade(vec3 a) { return oops; }"},
                                         &rt);
    CHECK(r == MESO_ERR_GL && rt == NULL);
    CHECK_MSG(log.last == MESO_LOGITEM_SHADER_COMPILE_FAILED && strstr(log.message, "shading hook"), "%d %s",
              (int)log.last, log.message);
    printf("broken hook refused: %.120s\n", log.message);
    /* One that compiles alone but clashes with the runtime's names: the first
     * kind's shader (the mesh's, built at create) fails, naming the hook. */
    memset(&log, 0, sizeof(log));
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc,
                                         .log_fn = on_log_error,
                                         .log_user = &log,
                                         .shading_hook = "float occlusion(float w) { return w; }\n"
                                                         "vec3 meso_shade(vec3 a, vec3 n, vec3 p, vec3 v) "
                                                         "{ return a * occlusion(0.5); }"},
                         &rt) == MESO_ERR_GL &&
          rt == NULL);
    CHECK_MSG(log.last == MESO_LOGITEM_SHADER_COMPILE_FAILED && strstr(log.message, "shading hook"), "%d %s",
              (int)log.last, log.message);
    printf("clashing hook refused: %.120s\n", log.message);
    /* A correct hook with every pass prepared up front. */
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error,
                                         .log_user = &log, .shading_hook = hook_src},
                         &rt) == MESO_OK);
    CHECK(meso_rt_prepare(rt, MESO_PREPARE_ALL_PASSES | MESO_PREPARE_STATS) == MESO_OK);
    CHECK(meso_rt_prepare(rt, 4u) == MESO_ERR_INVALID_ARG);
    meso_rt_destroy(rt);
}

int main(int argc, char** argv)
{
    CHECK_MSG(argc == 2, "usage: test_rt_passes MESOBAKE");
    setvbuf(stdout, NULL, _IONBF, 0);
    scene_w = W;
    scene_h = H;
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    CHECK_MSG(egl != NULL, "%s", why);
    ctx c;
    memset(&c, 0, sizeof(c));
    c.mesobake = argv[1];
    test_temp_dir(c.dir, sizeof(c.dir), "rt_passes");
    /* MESO_FILTER_LEVEL0 (both): forward = shading the G-buffer holds only
     * while the forward pass shades one sample; with mip levels a minified
     * shell's forward pass averages shading taps over the pixel's footprint
     * and the G-buffer stores one filtered albedo and normal (meso_rt.h
     * meso_texture_filter; measured here: 0.36 apart on the spot shell). */
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error,
                                         .log_user = &c.log, .texture_filter = MESO_FILTER_LEVEL0},
                         &c.rt) == MESO_OK);
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error,
                                         .log_user = &c.log, .shading_hook = hook_src,
                                         .shading_hook_binding = HOOK_BINDING, .texture_filter = MESO_FILTER_LEVEL0},
                         &c.hooked) == MESO_OK);
    target_create(&c);
    test_broken_hook();
    test_kinds(&c);
    test_frusta_color(&c);
    test_cells_from_mesh(&c);
    meso_rt_destroy(c.rt);
    meso_rt_destroy(c.hooked);
    test_temp_dir_remove(c.dir);
    free(c.c0);
    free(c.c1);
    free(c.fwd);
    free(c.depth);
    free(c.fwd_depth);
    meso_egl_destroy(egl);
    printf("OK\n");
    return 0;
}
