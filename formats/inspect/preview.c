/*
 * preview.c — `mesoinspect preview FILE -o OUT.png`: render a .meso file
 * headlessly with libmeso on an EGL surfaceless context (Mesa llvmpipe when
 * there is no GPU) and write a PNG.
 *
 * The camera orbits the union of the objects' bounds (from the OBJT records)
 * at --yaw/--pitch, framed so the bounding sphere fills the view. The image
 * is rendered at twice the size and box-filtered down (4 samples a pixel).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_common.h"
#include "mesh_chunk.h"
#include "meso_file.h"
#include "meso_rt.h"
#include "png_io.h"

int mesoinspect_preview(int argc, char** argv);

static const char* const usage_preview =
    "Usage: mesoinspect preview FILE -o OUT.png [options]\n"
    "\n"
    "Render every drawable object of FILE headlessly (EGL + libmeso) into a PNG.\n"
    "\n"
    "  -o, --output FILE   PNG to write\n"
    "      --size WxH      image size (default 512x512)\n"
    "      --object ID     draw only this object\n"
    "      --yaw DEG       camera azimuth around +y (default 30)\n"
    "      --pitch DEG     camera elevation (default 20)\n"
    "  -h, --help          this help\n";

#if MESO_HAVE_EGL
#include <GL/glcorearb.h>

#include "egl_context.h"

static void perspective(float m[16], double fovy, double aspect, double zn, double zf)
{
    const double f = 1.0 / tan(fovy / 2);
    memset(m, 0, 16 * sizeof(float));
    m[0] = (float)(f / aspect);
    m[5] = (float)f;
    m[10] = (float)((zf + zn) / (zn - zf));
    m[11] = -1.0f;
    m[14] = (float)(2 * zf * zn / (zn - zf));
}

static void look_at(float m[16], const double eye[3], const double at[3])
{
    double f[3] = {at[0] - eye[0], at[1] - eye[1], at[2] - eye[2]};
    double fl = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int k = 0; k < 3; ++k)
        f[k] /= fl;
    const double up[3] = {0, 1, 0};
    double s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
    double sl = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int k = 0; k < 3; ++k)
        s[k] /= sl;
    const double u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
    memset(m, 0, 16 * sizeof(float));
    for (int k = 0; k < 3; ++k) {
        m[4 * k + 0] = (float)s[k];
        m[4 * k + 1] = (float)u[k];
        m[4 * k + 2] = (float)-f[k];
    }
    m[12] = (float)-(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    m[13] = (float)-(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    m[14] = (float)(f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2]);
    m[15] = 1.0f;
}

#define PREVIEW_GL(X)                                                                                              \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                        \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers) X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)                \
    X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)              \
    X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage) X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus) X(PFNGLVIEWPORTPROC, Viewport)                        \
    X(PFNGLCLEARCOLORPROC, ClearColor) X(PFNGLCLEARPROC, Clear) X(PFNGLREADPIXELSPROC, ReadPixels)

typedef struct preview_gl {
#define M(t, n) t n;
    PREVIEW_GL(M)
#undef M
} preview_gl;

static void on_log(void* user, meso_log_level level, meso_log_item item, const char* message)
{
    (void)user;
    if (level == MESO_LOG_INFO)
        return;
    fprintf(stderr, "mesoinspect %s: libmeso: %s%s%s\n", level == MESO_LOG_ERROR ? "error" : "warning",
            meso_log_item_string(item), message ? ": " : "", message ? message : "");
}

static int render(const char* path, const char* out, int width, int height, uint32_t only, double yaw, double pitch)
{
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    if (!egl) {
        fprintf(stderr, "mesoinspect error: no headless OpenGL: %s\n", why);
        return MESO_EXIT_UNSUPPORTED;
    }
    preview_gl gl;
    int missing = 0;
#define L(t, n)                                       \
    {                                                 \
        void (*p)(void) = meso_egl_proc("gl" #n);     \
        missing += p == NULL;                         \
        memcpy(&gl.n, &p, sizeof(p));                 \
    }
    PREVIEW_GL(L)
#undef L
    int code = MESO_EXIT_OK;
    meso_rt* rt = NULL;
    meso_file* f = NULL;
    uint8_t *px = NULL, *img = NULL;
    meso_rt_object objs[256];
    int nobj = 0;
    if (missing) {
        fprintf(stderr, "mesoinspect error: the GL context lacks framebuffer objects\n");
        code = MESO_EXIT_UNSUPPORTED;
        goto done;
    }
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log}, &rt) != MESO_OK) {
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    meso_decoder dec = meso_bake_draco_decoder();
    meso_error err;
    meso_result r = meso_file_open_path(path, &(meso_open_desc){.decoders = &dec, .decoder_count = dec.decode_fn ? 1 : 0},
                                        &f, &err);
    if (r != MESO_OK) {
        fprintf(stderr, "mesoinspect error: %s\n", err.message);
        code = meso_exit_for(r);
        goto done;
    }
    /* Every object of the OBJT table (or just --object). */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    meso_object_record recs[256];
    uint32_t count = 0;
    if ((r = meso_file_objects(f, recs, 256, &count, &err)) != MESO_OK) {
        fprintf(stderr, "mesoinspect error: %s\n", err.message);
        code = meso_exit_for(r);
        goto done;
    }
    for (uint32_t i = 0; i < count && i < 256; ++i) {
        const meso_object_record* rec = &recs[i];
        if (only && rec->id != only)
            continue;
        r = meso_rt_load_object(rt, f, rec->id, &objs[nobj]);
        if (r == MESO_ERR_UNSUPPORTED && !only) {
            fprintf(stderr, "mesoinspect warning: object %u (%s) cannot be previewed by this build\n", rec->id,
                    rec->name);
            continue;
        }
        if (r != MESO_OK) {
            code = meso_exit_for(r);
            goto done;
        }
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], rec->bbox_min[k]);
            hi[k] = fmax(hi[k], rec->bbox_max[k]);
        }
        ++nobj;
    }
    if (nobj == 0) {
        fprintf(stderr, "mesoinspect error: %s: no drawable object%s\n", path, only ? " with that id" : "");
        code = only ? MESO_EXIT_USAGE : MESO_EXIT_UNSUPPORTED;
        goto done;
    }

    const int W = 2 * width, H = 2 * height;
    GLuint fbo, rb[2];
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl.GenRenderbuffers(2, rb);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, W, H);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, W, H);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        fprintf(stderr, "mesoinspect error: cannot create a %dx%d framebuffer\n", W, H);
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    gl.Viewport(0, 0, W, H);
    gl.ClearColor(0.18f, 0.20f, 0.24f, 1.0f);
    gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

    const double centre[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double radius = 0.5 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const double fovy = 35.0 * M_PI / 180.0, aspect = (double)width / height;
    const double fit = fmin(fovy, 2 * atan(tan(fovy / 2) * aspect));
    const double dist = (radius > 0 ? radius : 1.0) / sin(fit / 2) * 1.05;
    const double y = yaw * M_PI / 180.0, p = pitch * M_PI / 180.0;
    const double eye[3] = {centre[0] + dist * cos(p) * sin(y), centre[1] + dist * sin(p),
                           centre[2] + dist * cos(p) * cos(y)};
    meso_rt_draw_desc d = {0};
    look_at(d.view, eye, centre);
    perspective(d.proj, fovy, aspect, fmax(dist - 1.5 * radius, 1e-3 * dist), dist + 1.5 * radius);
    /* Light from the upper left of the viewer. */
    const double ly = y - 0.6, lp = p + 0.7;
    d.light_dir[0] = (float)(cos(lp) * sin(ly));
    d.light_dir[1] = (float)sin(lp);
    d.light_dir[2] = (float)(cos(lp) * cos(ly));
    for (int i = 0; i < nobj; ++i)
        if (meso_rt_draw(rt, objs[i], &d) != MESO_OK) {
            code = MESO_EXIT_INTERNAL;
            goto done;
        }
    px = malloc((size_t)W * (size_t)H * 4);
    img = malloc((size_t)width * (size_t)height * 4);
    if (!px || !img) {
        fprintf(stderr, "mesoinspect error: out of memory\n");
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    gl.ReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, px);
    for (int yy = 0; yy < height; ++yy)
        for (int xx = 0; xx < width; ++xx)
            for (int k = 0; k < 4; ++k) {
                const uint8_t* s = px + 4 * ((size_t)(2 * yy) * (size_t)W + (size_t)(2 * xx)) + k;
                const unsigned sum = s[0] + s[4] + s[4 * (size_t)W] + s[4 * (size_t)W + 4];
                img[4 * ((size_t)yy * (size_t)width + (size_t)xx) + (size_t)k] = (uint8_t)((sum + 2) / 4);
            }
    if (meso_png_write_rgba8(out, img, width, height, 1, why, sizeof(why)) != 0) {
        fprintf(stderr, "mesoinspect error: %s\n", why);
        code = MESO_EXIT_IO;
        goto done;
    }
    gl.DeleteRenderbuffers(2, rb);
    gl.DeleteFramebuffers(1, &fbo);
done:
    free(px);
    free(img);
    meso_file_close(f);
    meso_rt_destroy(rt);
    meso_egl_destroy(egl);
    return code;
}
#endif

int mesoinspect_preview(int argc, char** argv)
{
    const char *file = NULL, *out = NULL;
    int width = 512, height = 512;
    unsigned long only = 0;
    double yaw = 30, pitch = 20;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        const int val = i + 1 < argc;
        char* end = NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage_preview, stdout);
            return MESO_EXIT_OK;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && val) {
            out = argv[++i];
        } else if (!strcmp(a, "--size") && val) {
            if (sscanf(argv[++i], "%dx%d", &width, &height) != 2 || width < 1 || height < 1 || width > 8192 ||
                height > 8192) {
                fprintf(stderr, "mesoinspect error: --size expects WxH (1..8192), got '%s'\n"
                                "See 'mesoinspect --help'.\n", argv[i]);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--object") && val) {
            only = strtoul(argv[++i], &end, 10);
            if (!end || *end || only == 0 || only > UINT32_MAX) {
                fprintf(stderr, "mesoinspect error: --object expects an object id >= 1, got '%s'\n"
                                "See 'mesoinspect --help'.\n", argv[i]);
                return MESO_EXIT_USAGE;
            }
        } else if ((!strcmp(a, "--yaw") || !strcmp(a, "--pitch")) && val) {
            double v = strtod(argv[++i], &end);
            if (!end || *end || !(v >= -360 && v <= 360)) {
                fprintf(stderr, "mesoinspect error: %s expects degrees, got '%s'\nSee 'mesoinspect --help'.\n", a,
                        argv[i]);
                return MESO_EXIT_USAGE;
            }
            *(a[2] == 'y' ? &yaw : &pitch) = v;
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "mesoinspect error: %s '%s'\nSee 'mesoinspect --help'.\n",
                    (!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--size") || !strcmp(a, "--object") ||
                     !strcmp(a, "--yaw") || !strcmp(a, "--pitch"))
                        ? "missing value for option"
                        : "unrecognized option",
                    a);
            return MESO_EXIT_USAGE;
        } else if (!file) {
            file = a;
        } else {
            fprintf(stderr, "mesoinspect error: unexpected argument '%s'\nSee 'mesoinspect --help'.\n", a);
            return MESO_EXIT_USAGE;
        }
    }
    if (!file || !out) {
        fputs(usage_preview, stderr);
        return MESO_EXIT_USAGE;
    }
#if MESO_HAVE_EGL
    return render(file, out, width, height, (uint32_t)only, yaw, pitch);
#else
    fprintf(stderr, "mesoinspect error: preview needs EGL, which this build does not have\n");
    return MESO_EXIT_UNSUPPORTED;
#endif
}
