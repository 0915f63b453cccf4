/* libmeso in an engine's conventions (issue 18 items 1, 2, 5): every kind
 * — mesh, shell (smooth, curved, two-pass slices), frusta, cells — baked by
 * the real `mesobake` (argv[1]) from bundled data, drawn on llvmpipe under
 *
 *  - four depth set-ups: standard with a finite far plane (the reference),
 *    standard with an infinite far plane, reversed-Z with 0..1 clip depth
 *    (glClipControl) and an infinite far plane, and reversed-Z 0..1 with a
 *    finite one. Colour must be the reference's (the same rays), and each
 *    depth buffer, turned back into eye distance with its own projection's
 *    inverse, the reference's eye distance;
 *  - the host's depth function honoured: GL_GREATER against a cleared 0 in
 *    standard convention draws nothing; the draw leaves it set;
 *  - both state policies: MESO_STATE_HOST_OWNS gives the same image as
 *    MESO_STATE_RESTORE, and GL calls counted through a wrapping
 *    get_proc_address show what each draw asks GL: no uniform look-ups and
 *    no glGetError under either policy, no query at all under HOST_OWNS with
 *    the viewport given (two-pass slices: the draw framebuffer binding
 *    only), glGetError with check_gl_errors;
 *  - pre-warm: after meso_rt_prepare no draw compiles or links a shader
 *    (and without it the first draw does — the count can fail);
 *  - the host's GL error queue: an error the host raised before a load and
 *    a draw is still there after them;
 *  - the host's pixel-unpack state (row length, skips, alignment, a bound
 *    unpack buffer) neither corrupts uploads (images equal those loaded
 *    under GL's defaults) nor is changed by them;
 *  - model matrices: a mirroring one draws the mirror image (pixel columns
 *    flipped, light in the mirror plane; meshes under the host's back-face
 *    culling); a non-uniform scale is refused
 *    with MESO_ERR_INVALID_ARG and a logged reason;
 *  - a bad depth function is refused with nothing in the host's error
 *    queue; the host's colour mask survives depth-only draws and draw lists,
 *    its shader storage binding 0 a draw that counts work;
 *  - sRGB framebuffers: libmeso writes linear colour, so drawn into an
 *    GL_SRGB8_ALPHA8 target with GL_FRAMEBUFFER_SRGB on, each pixel decodes
 *    to the linear (RGBA8) render's value.
 * Tolerances (measured on llvmpipe, stated where asserted): the depth
 * set-ups change the float rounding of the unprojected rays, so a few
 * silhouette pixels may differ. */
#include "test_util.h"

#include <math.h>
#include <string.h>

#include "camera.h"
#include "egl_context.h"
#include "gl_fbo.h"
#include "meso_rt.h"

enum { W = 96, H = 72 };

#define EXTRA_GL(X)                                                                                                \
    X(PFNGLCLIPCONTROLPROC, ClipControl) X(PFNGLDEPTHFUNCPROC, DepthFunc) X(PFNGLGETINTEGERVPROC, GetIntegerv)       \
    X(PFNGLENABLEPROC, Enable) X(PFNGLGETERRORPROC, GetError) X(PFNGLPIXELSTOREIPROC, PixelStorei)                  \
    X(PFNGLGENBUFFERSPROC, GenBuffers) X(PFNGLBINDBUFFERPROC, BindBuffer) X(PFNGLBUFFERDATAPROC, BufferData)       \
    X(PFNGLDELETEBUFFERSPROC, DeleteBuffers) X(PFNGLDISABLEPROC, Disable)                                          \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus) X(PFNGLCULLFACEPROC, CullFace)                       \
    X(PFNGLGETBOOLEANVPROC, GetBooleanv) X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                               \
    X(PFNGLGETINTEGERI_VPROC, GetIntegeri_v)

typedef struct extra_gl {
#define M(t, n) t n;
    EXTRA_GL(M)
#undef M
} extra_gl;

/* >>counting GL ------------------------------------------------------------ */

/* The entry points counted: every query and lookup a draw could make. */
static struct {
    long get, is_enabled, get_error, uniform_location, compile, link;
} calls;
static PFNGLGETINTEGERVPROC real_get_integerv;
static PFNGLGETBOOLEANVPROC real_get_booleanv;
static PFNGLGETFLOATVPROC real_get_floatv;
static PFNGLISENABLEDPROC real_is_enabled;
static PFNGLGETERRORPROC real_get_error;
static PFNGLGETUNIFORMLOCATIONPROC real_uniform_location;
static PFNGLCOMPILESHADERPROC real_compile;
static PFNGLLINKPROGRAMPROC real_link;

static void APIENTRY count_get_integerv(GLenum p, GLint* v)
{
    ++calls.get;
    real_get_integerv(p, v);
}
static void APIENTRY count_get_booleanv(GLenum p, GLboolean* v)
{
    ++calls.get;
    real_get_booleanv(p, v);
}
static void APIENTRY count_get_floatv(GLenum p, GLfloat* v)
{
    ++calls.get;
    real_get_floatv(p, v);
}
static GLboolean APIENTRY count_is_enabled(GLenum cap)
{
    ++calls.is_enabled;
    return real_is_enabled(cap);
}
static GLenum APIENTRY count_get_error(void)
{
    ++calls.get_error;
    return real_get_error();
}
static GLint APIENTRY count_uniform_location(GLuint p, const GLchar* name)
{
    ++calls.uniform_location;
    return real_uniform_location(p, name);
}
static void APIENTRY count_compile(GLuint s)
{
    ++calls.compile;
    real_compile(s);
}
static void APIENTRY count_link(GLuint p)
{
    ++calls.link;
    real_link(p);
}

#define WRAP(name, real, counter)                           \
    if (!strcmp(n, name)) {                                 \
        meso_gl_fn f = meso_egl_proc(n);                    \
        memcpy(&real, &f, sizeof(f));                       \
        void (*c)(void) = (void (*)(void))counter;          \
        return c;                                           \
    }

static meso_gl_fn counting_proc(const char* n)
{
    WRAP("glGetIntegerv", real_get_integerv, count_get_integerv)
    WRAP("glGetBooleanv", real_get_booleanv, count_get_booleanv)
    WRAP("glGetFloatv", real_get_floatv, count_get_floatv)
    WRAP("glIsEnabled", real_is_enabled, count_is_enabled)
    WRAP("glGetError", real_get_error, count_get_error)
    WRAP("glGetUniformLocation", real_uniform_location, count_uniform_location)
    WRAP("glCompileShader", real_compile, count_compile)
    WRAP("glLinkProgram", real_link, count_link)
    return meso_egl_proc(n);
}

/* >>scene ------------------------------------------------------------------ */

enum { K_MESH, K_SHELL, K_CURVED, K_SLICES, K_FRUSTA, K_CELLS, K_COUNT };
static const char* const kind_name[K_COUNT] = {"mesh", "shell smooth", "shell curved", "shell slices",
                                               "frusta", "cells"};
static const char* const kind_file[K_COUNT] = {"mesh", "shell", "shell", "shell", "frusta", "cells"};

typedef struct ctx {
    const char* mesobake;
    char dir[256];
    test_fbo fbo;
    extra_gl gl;
    char log[1024];
} ctx;

static void on_log(void* user, meso_log_level level, meso_log_item item, const char* msg)
{
    (void)item;
    if (level == MESO_LOG_ERROR)
        snprintf((char*)user, 1024, "%s", msg ? msg : "");
}

static void bake_all(ctx* c)
{
    /* command, input (tests/data), output (in the temporary directory), options */
    static const char* const jobs[][4] = {
        {"mesh", "spot_low_resolution.obj", "mesh", ""},
        {"shell", "sphere.obj", "shell", "--thickness-rel 0.05 --texture bricks:64 -j 2"},
        {"frusta", "saguaro.skel", "frusta", "--relief bricks:64"},
        {"cells", "spot_low_resolution.obj", "cells", "-j 2"},
    };
    for (size_t i = 0; i < sizeof(jobs) / sizeof(jobs[0]); ++i) {
        char cmd[1400];
        snprintf(cmd, sizeof(cmd), "'%s' %s -i '%s/%s' -o '%s/%s.meso' %s >/dev/null 2>&1", c->mesobake, jobs[i][0],
                 MESO_TEST_DATA, jobs[i][1], c->dir, jobs[i][2], jobs[i][3]);
        if (system(cmd) != 0) {
            fprintf(stderr, "bake failed: %s\n", cmd);
            abort();
        }
    }
}

static meso_rt_object load(ctx* c, meso_rt* rt, int kind)
{
    char path[400];
    snprintf(path, sizeof(path), "%s/%s.meso", c->dir, kind_file[kind]);
    meso_file* f = NULL;
    meso_error err;
    assert(meso_file_open_path(path, NULL, &f, &err) == MESO_OK);
    meso_rt_object o = {0};
    assert(meso_rt_load_object(rt, f, 1, &o) == MESO_OK);
    meso_file_close(f);
    return o;
}

/* The four depth set-ups. */
enum { D_STANDARD, D_INFINITE, D_REVERSED_INFINITE, D_REVERSED, D_COUNT };
static const char* const depth_name[D_COUNT] = {"standard", "standard, infinite far", "reversed-Z 0..1, infinite far",
                                                "reversed-Z 0..1"};

typedef struct camera {
    double eye[3], at[3], zn, zf;
} camera;

static camera frame(meso_rt* rt, meso_rt_object o)
{
    float lo[3], hi[3];
    assert(meso_rt_object_bounds(rt, o, lo, hi) == MESO_OK);
    camera cam;
    double r = 0.0;
    for (int k = 0; k < 3; ++k) {
        cam.at[k] = 0.5 * (lo[k] + hi[k]);
        r += 0.25 * (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    r = sqrt(r);
    const double dir[3] = {0.0, 0.35, 1.0}, len = sqrt(1.0 + 0.35 * 0.35);
    for (int k = 0; k < 3; ++k)
        cam.eye[k] = cam.at[k] + 2.6 * r * dir[k] / len;
    cam.zn = 0.2 * r;
    cam.zf = 6.0 * r;
    return cam;
}

/* proj (column-major) for a set-up; see the file's header. */
static void projection(const camera* cam, int setup, float proj[16])
{
    const double f = 1.0 / tan(0.5 * 0.8), a = (double)W / H, n = cam->zn, zf = cam->zf;
    double m[16] = {0};
    m[0] = f / a;
    m[5] = f;
    m[11] = -1.0;
    switch (setup) {
    case D_STANDARD:
        m[10] = -(zf + n) / (zf - n);
        m[14] = -2.0 * zf * n / (zf - n);
        break;
    case D_INFINITE: /* ndc = 1 - 2n/d */
        m[10] = -1.0;
        m[14] = -2.0 * n;
        break;
    case D_REVERSED_INFINITE: /* ndc = n/d */
        m[10] = 0.0;
        m[14] = n;
        break;
    default: /* ndc = b/d - a: 1 at n, 0 at zf */
        m[10] = n / (zf - n);
        m[14] = n * zf / (zf - n);
        break;
    }
    for (int i = 0; i < 16; ++i)
        proj[i] = (float)m[i];
}

/* Eye distance d from window depth z (glDepthRange 0..1) for a set-up. */
static double eye_distance(const camera* cam, int setup, double z)
{
    const double n = cam->zn, zf = cam->zf;
    switch (setup) {
    case D_STANDARD: {
        const double zn = 2.0 * z - 1.0;
        return 2.0 * n * zf / (zf + n - zn * (zf - n));
    }
    case D_INFINITE: return 2.0 * n / (1.0 - (2.0 * z - 1.0));
    case D_REVERSED_INFINITE: return n / z;
    default: return (n * zf / (zf - n)) / (z + n / (zf - n));
    }
}

typedef struct image {
    uint8_t rgba[W * H * 4];
    float depth[W * H];
} image;

/* Clears for the set-up, draws with `d` (view/proj set by the caller)
 * and reads back. */
static meso_result render(ctx* c, meso_rt* rt, meso_rt_object o, int kind, int setup, meso_rt_draw_desc d,
                          image* out)
{
    const int reversed = setup >= D_REVERSED_INFINITE;
    c->gl.ClipControl(GL_LOWER_LEFT, reversed ? GL_ZERO_TO_ONE : GL_NEGATIVE_ONE_TO_ONE);
    const float clear_depth = reversed ? 0.0f : 1.0f;
    c->fbo.ClearColor(0.1f, 0.1f, 0.1f, 1.0f);
    c->fbo.Clear(GL_COLOR_BUFFER_BIT);
    c->fbo.ClearBufferfv(GL_DEPTH, 0, &clear_depth); /* glClearDepth is desktop only (gl_fbo.h) */
    c->gl.DepthFunc(reversed ? GL_GREATER : GL_LESS);
    d.depth = reversed ? MESO_DEPTH_REVERSED : MESO_DEPTH_STANDARD;
    d.clip_depth = reversed ? MESO_CLIP_DEPTH_ZERO_TO_ONE : MESO_CLIP_DEPTH_NEGATIVE_ONE_TO_ONE;
    if (kind == K_CURVED)
        d.shell.technique = MESO_SHELL_CURVED;
    if (kind == K_SLICES) {
        d.shell.technique = MESO_SHELL_SLICES;
        d.shell.slices = 24;
        d.shell.slice_interp = MESO_SLICE_TEXCOORD;
    }
    const meso_result r = meso_rt_draw(rt, o, &d);
    test_fbo_read(&c->fbo, out->rgba, out->depth);
    c->gl.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    c->gl.DepthFunc(GL_LESS);
    return r;
}

static meso_rt_draw_desc view_desc(const camera* cam, int setup)
{
    meso_rt_draw_desc d = {0};
    const double up[3] = {0, 1, 0};
    meso_camera_look_at(d.view, cam->eye, cam->at, up);
    projection(cam, setup, d.proj);
    return d;
}

/* Pixels whose coverage differs, and covered pixels whose colour differs by
 * more than 2/255 in a channel (rows of b mirrored when `flip`). */
static void compare(const image* a, const image* b, int flip, int* coverage, int* colour, int* covered)
{
    *coverage = *colour = *covered = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const int i = y * W + x, j = y * W + (flip ? W - 1 - x : x);
            const int ca = memcmp(a->rgba + 4 * i, (const uint8_t[]){26, 26, 26, 255}, 4) != 0;
            const int cb = memcmp(b->rgba + 4 * j, (const uint8_t[]){26, 26, 26, 255}, 4) != 0;
            *covered += ca;
            if (ca != cb) {
                ++*coverage;
                continue;
            }
            for (int k = 0; k < 3; ++k)
                if (abs((int)a->rgba[4 * i + k] - (int)b->rgba[4 * j + k]) > 2) {
                    ++*colour;
                    break;
                }
        }
}

/* >>tests ------------------------------------------------------------------ */

static image ref[K_COUNT], img;

static void depth_conventions(ctx* c, meso_rt* rt, meso_rt_object* objs, const camera* cams)
{
    for (int k = 0; k < K_COUNT; ++k) {
        assert(render(c, rt, objs[k], k, D_STANDARD, view_desc(&cams[k], D_STANDARD), &ref[k]) == MESO_OK);
        for (int s = D_INFINITE; s < D_COUNT; ++s) {
            assert(render(c, rt, objs[k], k, s, view_desc(&cams[k], s), &img) == MESO_OK);
            int coverage, colour, covered;
            compare(&ref[k], &img, 0, &coverage, &colour, &covered);
            double worst = 0.0;
            int depth_bad = 0;
            for (int i = 0; i < W * H; ++i) {
                const int hit_ref = ref[k].depth[i] < 1.0f, hit = s >= D_REVERSED_INFINITE ? img.depth[i] > 0.0f
                                                                                            : img.depth[i] < 1.0f;
                if (!hit_ref || !hit)
                    continue;
                const double d0 = eye_distance(&cams[k], D_STANDARD, ref[k].depth[i]);
                const double d1 = eye_distance(&cams[k], s, img.depth[i]);
                const double rel = fabs(d1 - d0) / d0;
                worst = fmax(worst, rel);
                depth_bad += rel > 1e-3;
            }
            fprintf(stderr, "    %-13s %-30s covered %4d, coverage differs %d, colour differs %d, depth worst %.1e (%d > 1e-3)\n",
                    kind_name[k], depth_name[s], covered, coverage, colour, worst, depth_bad);
            assert(covered > 300);
            /* The same rays. The ray casters: at most 0.5 % of the covered
             * pixels differ in colour (float rounding of the unprojected
             * rays moves a march sample across a brick's edge; measured:
             * 0-3 of ~1000), depth within 1e-3 of the distance at all but
             * as many (the hit is found to the march's tolerance, not
             * exactly; measured 0-4). Slices are rasterised polygons: which of two slice
             * fragments at equal depth wins follows the depth rounding, so
             * up to 2 % of pixels (measured 14-16 of 1111) may differ. */
            const int allowed = covered * (k == K_SLICES ? 20 : 5) / 1000;
            assert(coverage <= allowed && colour <= allowed && depth_bad <= allowed);
        }
        /* The host's function is honoured: GL_GREATER against a depth
         * cleared to 1 in the standard convention passes nothing. */
        static const float far = 1.0f;
        c->fbo.ClearColor(0.1f, 0.1f, 0.1f, 1.0f);
        c->fbo.Clear(GL_COLOR_BUFFER_BIT);
        c->fbo.ClearBufferfv(GL_DEPTH, 0, &far);
        c->gl.DepthFunc(GL_GREATER);
        meso_rt_draw_desc d = view_desc(&cams[k], D_STANDARD);
        if (k == K_SLICES) {
            d.shell.technique = MESO_SHELL_SLICES;
            d.shell.slice_interp = MESO_SLICE_TEXCOORD;
        }
        assert(meso_rt_draw(rt, objs[k], &d) == MESO_OK);
        test_fbo_read(&c->fbo, img.rgba, img.depth);
        int coverage, colour, covered;
        compare(&img, &img, 0, &coverage, &colour, &covered);
        GLint func = 0;
        c->gl.GetIntegerv(GL_DEPTH_FUNC, &func);
        assert(covered == 0 && func == GL_GREATER);
        c->gl.DepthFunc(GL_LESS);
    }
}

/* Draw k once to warm up, then once counted; returns the image. */
static void counted_draw(ctx* c, meso_rt* rt, meso_rt_object o, int k, const camera* cam, int give_viewport)
{
    meso_rt_draw_desc d = view_desc(cam, D_STANDARD);
    if (give_viewport) {
        d.viewport[2] = W;
        d.viewport[3] = H;
    }
    assert(render(c, rt, o, k, D_STANDARD, d, &img) == MESO_OK);
    memset(&calls, 0, sizeof(calls));
    assert(render(c, rt, o, k, D_STANDARD, d, &img) == MESO_OK);
}

static void state_policies(ctx* c, const camera* cams)
{
    for (int policy = 0; policy < 2; ++policy) {
        meso_rt* rt = NULL;
        const meso_rt_desc rd = {.gl_get_proc_address = counting_proc, .log_fn = on_log, .log_user = c->log,
                                 .state_policy = policy ? MESO_STATE_HOST_OWNS : MESO_STATE_RESTORE};
        assert(meso_rt_create(&rd, &rt) == MESO_OK);
        for (int k = 0; k < K_COUNT; ++k) {
            meso_rt_object o = load(c, rt, k);
            counted_draw(c, rt, o, k, &cams[k], 1);
            fprintf(stderr, "    %-10s %-13s per draw: %ld get, %ld is_enabled, %ld get_error, %ld uniform look-ups\n",
                    policy ? "host owns" : "restore", kind_name[k], calls.get, calls.is_enabled, calls.get_error,
                    calls.uniform_location);
            assert(calls.uniform_location == 0 && calls.get_error == 0 && calls.compile == 0);
            if (policy) {
                /* Nothing queried; two-pass slices read the framebuffer
                 * their last pass draws into. */
                assert(calls.get == (k == K_SLICES ? 1 : 0) && calls.is_enabled == 0);
            } else {
                assert(calls.get > 0); /* the counter sees the restore's queries */
            }
            int coverage, colour, covered;
            compare(&ref[k], &img, 0, &coverage, &colour, &covered);
            assert(coverage == 0 && colour == 0);
            meso_rt_release_object(rt, o);
        }
        meso_rt_destroy(rt);
        /* The host owns what the draws left: culling of front faces. */
        c->gl.Disable(GL_CULL_FACE);
    }
    /* check_gl_errors reads the queue. */
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = counting_proc, .check_gl_errors = 1}, &rt) ==
           MESO_OK);
    meso_rt_object o = load(c, rt, K_FRUSTA);
    counted_draw(c, rt, o, K_FRUSTA, &cams[K_FRUSTA], 1);
    assert(calls.get_error > 0);
    meso_rt_destroy(rt);
}

static void prewarm(ctx* c, const camera* cams)
{
    for (int warm = 0; warm < 2; ++warm) {
        meso_rt* rt = NULL;
        memset(&calls, 0, sizeof(calls));
        assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = counting_proc, .prepare = warm}, &rt) ==
               MESO_OK);
        const long built = calls.link;
        long during = 0;
        for (int k = 0; k < K_COUNT; ++k) {
            meso_rt_object o = load(c, rt, k);
            memset(&calls, 0, sizeof(calls));
            assert(render(c, rt, o, k, D_STANDARD, view_desc(&cams[k], D_STANDARD), &img) == MESO_OK);
            during += calls.compile + calls.link;
            meso_rt_release_object(rt, o);
        }
        fprintf(stderr, "    prepare %d: %ld programs linked at create, %ld compiles + links during first draws\n",
                warm, built, during);
        assert(warm ? during == 0 && built > 10 : during > 0);
        assert(meso_rt_prepare(rt, 0) == MESO_OK && meso_rt_prepare(rt, 0x80) == MESO_ERR_INVALID_ARG);
        meso_rt_destroy(rt);
    }
}

static void error_queue_and_unpack(ctx* c, const camera* cams)
{
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
    extra_gl* gl = &c->gl;
    /* Unpack state a host may leave behind, and an unpack buffer bound. */
    static const GLenum names[] = {GL_UNPACK_ALIGNMENT, GL_UNPACK_ROW_LENGTH, GL_UNPACK_IMAGE_HEIGHT,
                                   GL_UNPACK_SKIP_PIXELS, GL_UNPACK_SKIP_ROWS, GL_UNPACK_SKIP_IMAGES};
    static const GLint values[] = {8, 13, 5, 2, 1, 1};
    GLuint pbo = 0;
    gl->GenBuffers(1, &pbo);
    gl->BindBuffer(GL_PIXEL_UNPACK_BUFFER, pbo);
    gl->BufferData(GL_PIXEL_UNPACK_BUFFER, 4096, NULL, GL_STREAM_DRAW);
    for (int i = 0; i < 6; ++i)
        gl->PixelStorei(names[i], values[i]);
    for (int k = 0; k < K_COUNT; ++k) {
        const GLenum before = gl->GetError();
        if (before != GL_NO_ERROR)
            fprintf(stderr, "    before %s: 0x%04x pending\n", kind_name[k], before);
        assert(before == GL_NO_ERROR);
        gl->Enable(0x1234); /* the host's own mistake: GL_INVALID_ENUM pending */
        meso_rt_object o = load(c, rt, k);
        assert(render(c, rt, o, k, D_STANDARD, view_desc(&cams[k], D_STANDARD), &img) == MESO_OK);
        /* ReadPixels in render() does not touch errors of this kind either. */
        const GLenum e1 = gl->GetError(), e2 = gl->GetError();
        if (e1 != GL_INVALID_ENUM || e2 != GL_NO_ERROR)
            fprintf(stderr, "    %s: host error queue 0x%04x then 0x%04x\n", kind_name[k], e1, e2);
        assert(e1 == GL_INVALID_ENUM && e2 == GL_NO_ERROR);
        int coverage, colour, covered;
        compare(&ref[k], &img, 0, &coverage, &colour, &covered);
        fprintf(stderr, "    %-13s loaded under the host's unpack state: coverage differs %d, colour differs %d\n",
                kind_name[k], coverage, colour);
        assert(coverage == 0 && colour == 0);
        meso_rt_release_object(rt, o);
    }
    for (int i = 0; i < 6; ++i) {
        GLint v = 0;
        gl->GetIntegerv(names[i], &v);
        assert(v == values[i]);
        gl->PixelStorei(names[i], i == 0 ? 4 : 0);
    }
    GLint bound = 0;
    gl->GetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &bound);
    assert(bound == (GLint)pbo);
    gl->BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    gl->DeleteBuffers(1, &pbo);
    meso_rt_destroy(rt);
}

static void model_matrices(ctx* c, meso_rt* rt, meso_rt_object* objs, const camera* cams)
{
    for (int k = 0; k < K_COUNT; ++k) {
        if (k == K_CURVED || k == K_SLICES)
            continue;
        /* Eye on the z axis through the centre, light in the x = centre
         * plane: mirroring x about the centre mirrors the image. */
        camera cam = cams[k];
        cam.eye[0] = cam.at[0];
        meso_rt_draw_desc d = view_desc(&cam, D_STANDARD);
        d.light_dir[1] = 0.8f;
        d.light_dir[2] = 0.6f;
        /* Meshes keep the host's culling: back faces culled, which a
         * mirroring model must not turn into front faces. */
        if (k == K_MESH) {
            c->gl.Enable(GL_CULL_FACE);
            c->gl.CullFace(GL_BACK);
        }
        image plain;
        assert(render(c, rt, objs[k], k, D_STANDARD, d, &plain) == MESO_OK);
        for (int i = 0; i < 16; ++i)
            d.model[i] = i % 5 == 0 ? 1.0f : 0.0f;
        d.model[0] = -1.0f;
        d.model[12] = (float)(2.0 * cam.at[0]); /* x -> 2 cx - x */
        assert(render(c, rt, objs[k], k, D_STANDARD, d, &img) == MESO_OK);
        int coverage, colour, covered;
        compare(&plain, &img, 1, &coverage, &colour, &covered);
        c->gl.Disable(GL_CULL_FACE);
        fprintf(stderr, "    %-13s mirrored: covered %d, coverage differs %d, colour differs %d\n", kind_name[k],
                covered, coverage, colour);
        assert(covered > 300 && coverage <= covered * 3 / 1000 && colour <= covered * 3 / 1000);
        d.model[0] = 1.0f;
        d.model[12] = 0.0f;
        d.model[5] = 2.0f; /* stretched along y */
        c->log[0] = 0;
        assert(meso_rt_draw(rt, objs[k], &d) == MESO_ERR_INVALID_ARG);
        assert(strstr(c->log, "model matrix") != NULL);
    }
}

/* What a draw must leave alone or refuse: a bad depth function (refused,
 * nothing in the host's error queue), the host's colour mask after
 * depth-only draws and draw lists, its indexed shader storage binding 0
 * after a draw that counts work. */
static void host_state_kept(ctx* c, meso_rt* rt, meso_rt_object* objs, const camera* cams)
{
    extra_gl* gl = &c->gl;
    meso_rt_draw_desc d = view_desc(&cams[K_FRUSTA], D_STANDARD);
    d.depth_func = 0x1234;
    assert(meso_rt_draw(rt, objs[K_FRUSTA], &d) == MESO_ERR_INVALID_ARG && strstr(c->log, "depth_func"));
    assert(gl->GetError() == GL_NO_ERROR);
    d.depth_func = 0;
    d.pass = MESO_PASS_DEPTH;
    GLboolean mask[4];
    assert(meso_rt_draw(rt, objs[K_FRUSTA], &d) == MESO_OK);
    gl->GetBooleanv(GL_COLOR_WRITEMASK, mask);
    assert(mask[0] && mask[1] && mask[2] && mask[3]);
    const meso_rt_draw_item items[2] = {{.object = objs[K_FRUSTA]}, {.object = objs[K_CELLS]}};
    assert(meso_rt_draw_list(rt, items, 2, &d) == MESO_OK);
    gl->GetBooleanv(GL_COLOR_WRITEMASK, mask);
    assert(mask[0] && mask[1] && mask[2] && mask[3]);
    /* The work counters take shader storage binding 0 for the draw. */
    GLuint host = 0;
    gl->GenBuffers(1, &host);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, host);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    meso_rt_draw_stats stats;
    d.pass = MESO_PASS_FORWARD;
    d.stats = &stats;
    assert(meso_rt_draw(rt, objs[K_FRUSTA], &d) == MESO_OK && stats.supported && stats.hits > 0);
    GLint indexed = 0, generic = -1;
    gl->GetIntegeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, 0, &indexed);
    gl->GetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &generic);
    assert(indexed == (GLint)host && generic == 0);
    assert(meso_rt_draw_list(rt, items, 1, &d) == MESO_OK && stats.supported);
    gl->GetIntegeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, 0, &indexed);
    gl->GetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &generic);
    assert(indexed == (GLint)host && generic == 0);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    gl->DeleteBuffers(1, &host);
    assert(gl->GetError() == GL_NO_ERROR);
    fprintf(stderr, "    bad depth_func refused; colour mask and shader storage binding 0 kept\n");
}

static double srgb_decode(double s)
{
    return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4);
}

static void srgb_framebuffer(ctx* c, meso_rt* rt, meso_rt_object* objs, const camera* cams)
{
    test_fbo* f = &c->fbo;
    GLuint fbo, rb[2];
    f->GenFramebuffers(1, &fbo);
    f->BindFramebuffer(GL_FRAMEBUFFER, fbo);
    f->GenRenderbuffers(2, rb);
    f->BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    f->RenderbufferStorage(GL_RENDERBUFFER, GL_SRGB8_ALPHA8, W, H);
    f->FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    f->BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    f->RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, W, H);
    f->FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    assert(c->gl.CheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);
    c->gl.Enable(GL_FRAMEBUFFER_SRGB);
    for (int k = 0; k < K_COUNT; ++k) {
        /* The background is cleared through the same encoding, so the
         * covered test of compare() sees it as the encoded grey: compare
         * the colour of pixels the linear render covers. */
        assert(render(c, rt, objs[k], k, D_STANDARD, view_desc(&cams[k], D_STANDARD), &img) == MESO_OK);
        double worst = 0.0;
        int checked = 0;
        for (int i = 0; i < W * H; ++i) {
            if (ref[k].depth[i] >= 1.0f || img.depth[i] >= 1.0f)
                continue;
            for (int ch = 0; ch < 3; ++ch)
                worst = fmax(worst, fabs(srgb_decode(img.rgba[4 * i + ch] / 255.0) - ref[k].rgba[4 * i + ch] / 255.0));
            ++checked;
        }
        fprintf(stderr, "    %-13s sRGB target: %d pixels, decoded vs linear render worst %.4f\n", kind_name[k], checked,
                worst);
        /* Half a step of each 8-bit quantisation: linear 0.5/255, and an
         * sRGB step in linear units is at most 2.1/255 (near white). */
        assert(checked > 300 && worst <= 2.7 / 255.0);
    }
    c->gl.Disable(GL_FRAMEBUFFER_SRGB);
    f->BindFramebuffer(GL_FRAMEBUFFER, f->fbo);
    f->DeleteFramebuffers(1, &fbo);
    f->DeleteRenderbuffers(2, rb);
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    ctx c = {.mesobake = argv[1]};
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    if (!egl) {
        fprintf(stderr, "test_rt_conventions: %s\n", why);
        return 1;
    }
#define L(t, n)                                         \
    {                                                   \
        meso_gl_fn f = meso_egl_proc("gl" #n);          \
        assert(f);                                      \
        memcpy(&c.gl.n, &f, sizeof(f));                 \
    }
    EXTRA_GL(L)
#undef L
    assert(test_fbo_create(&c.fbo, W, H));
    test_temp_dir(c.dir, sizeof(c.dir), "conventions");
    bake_all(&c);

    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log, .log_user = c.log},
                          &rt) == MESO_OK);
    meso_rt_object objs[K_COUNT];
    camera cams[K_COUNT];
    for (int k = 0; k < K_COUNT; ++k) {
        objs[k] = load(&c, rt, k);
        cams[k] = frame(rt, objs[k]);
    }
    fprintf(stderr, "  depth_conventions ...\n");
    depth_conventions(&c, rt, objs, cams);
    fprintf(stderr, "  state_policies ...\n");
    state_policies(&c, cams);
    fprintf(stderr, "  prewarm ...\n");
    prewarm(&c, cams);
    fprintf(stderr, "  error_queue_and_unpack ...\n");
    error_queue_and_unpack(&c, cams);
    fprintf(stderr, "  model_matrices ...\n");
    model_matrices(&c, rt, objs, cams);
    fprintf(stderr, "  host_state_kept ...\n");
    host_state_kept(&c, rt, objs, cams);
    fprintf(stderr, "  srgb_framebuffer ...\n");
    srgb_framebuffer(&c, rt, objs, cams);
    meso_rt_destroy(rt);
    test_fbo_destroy(&c.fbo);
    meso_egl_destroy(egl);
    test_temp_dir_remove(c.dir);
    fprintf(stderr, "test_rt_conventions: ok\n");
    return 0;
}
