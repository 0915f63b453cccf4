/* gl_fbo.h — an offscreen RGBA8 + depth framebuffer on the headless EGL
 * context, for the GL tests and benchmarks (header-only, test code). */
#ifndef MESO_TEST_GL_FBO_H
#define MESO_TEST_GL_FBO_H

#include <GL/glcorearb.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "egl_context.h"

#define MESO_TEST_GLF(X)                                                                                         \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                      \
    X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)                  \
    X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage) X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers) X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)        \
    X(PFNGLVIEWPORTPROC, Viewport) X(PFNGLCLEARCOLORPROC, ClearColor) X(PFNGLCLEARPROC, Clear)                     \
    X(PFNGLREADPIXELSPROC, ReadPixels) X(PFNGLCLEARDEPTHPROC, ClearDepth) X(PFNGLFINISHPROC, Finish)

typedef struct test_fbo {
#define MESO_TEST_M(t, n) t n;
    MESO_TEST_GLF(MESO_TEST_M)
#undef MESO_TEST_M
    GLuint fbo, rb[2];
    int w, h;
} test_fbo;

/* Creates and binds a w x h framebuffer; 0 on failure. */
static inline int test_fbo_create(test_fbo* f, int w, int h)
{
    memset(f, 0, sizeof(*f));
#define MESO_TEST_L(t, n)                                    \
    {                                                        \
        void (*fn)(void) = meso_egl_proc("gl" #n);           \
        if (!fn)                                             \
            return 0;                                        \
        memcpy(&f->n, &fn, sizeof(fn));                      \
    }
    MESO_TEST_GLF(MESO_TEST_L)
#undef MESO_TEST_L
    f->w = w;
    f->h = h;
    f->GenFramebuffers(1, &f->fbo);
    f->BindFramebuffer(GL_FRAMEBUFFER, f->fbo);
    f->GenRenderbuffers(2, f->rb);
    f->BindRenderbuffer(GL_RENDERBUFFER, f->rb[0]);
    f->RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    f->FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, f->rb[0]);
    f->BindRenderbuffer(GL_RENDERBUFFER, f->rb[1]);
    f->RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    f->FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, f->rb[1]);
    f->Viewport(0, 0, w, h);
    return 1;
}

static inline void test_fbo_clear(test_fbo* f, float r, float g, float b)
{
    f->ClearColor(r, g, b, 1.0f);
    f->ClearDepth(1.0);
    f->Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

/* Reads colour (RGBA8, row 0 at the bottom) and depth (floats) back. */
static inline void test_fbo_read(test_fbo* f, uint8_t* rgba, float* depth)
{
    if (rgba)
        f->ReadPixels(0, 0, f->w, f->h, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    if (depth)
        f->ReadPixels(0, 0, f->w, f->h, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
}

static inline void test_fbo_destroy(test_fbo* f)
{
    if (f->fbo) {
        f->DeleteFramebuffers(1, &f->fbo);
        f->DeleteRenderbuffers(2, f->rb);
    }
}

/* Column-major camera helpers: perspective and look-at. */
static inline void test_perspective(float m[16], double fovy_rad, double aspect, double zn, double zf)
{
    const double f = 1.0 / __builtin_tan(fovy_rad / 2);
    memset(m, 0, 16 * sizeof(float));
    m[0] = (float)(f / aspect);
    m[5] = (float)f;
    m[10] = (float)((zf + zn) / (zn - zf));
    m[11] = -1.0f;
    m[14] = (float)(2 * zf * zn / (zn - zf));
}

static inline void test_look_at(float m[16], const double eye[3], const double at[3], const double up[3])
{
    double f[3] = {at[0] - eye[0], at[1] - eye[1], at[2] - eye[2]};
    double fl = __builtin_sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int k = 0; k < 3; ++k)
        f[k] /= fl;
    double s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
    double sl = __builtin_sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
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

#endif
