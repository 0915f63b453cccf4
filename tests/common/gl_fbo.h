/* gl_fbo.h — an offscreen RGBA8 + depth framebuffer on the headless EGL
 * context, for the GL tests and benchmarks (header-only, test code). Uses
 * only what OpenGL 3.3 core and OpenGL ES 3.2 share, plus reading depth
 * back, which ES has through GL_NV_read_depth (Mesa offers it). */
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
    X(PFNGLREADPIXELSPROC, ReadPixels) X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv) X(PFNGLFINISHPROC, Finish)

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
    static const float far = 1.0f;
    f->ClearColor(r, g, b, 1.0f);
    f->Clear(GL_COLOR_BUFFER_BIT);
    f->ClearBufferfv(GL_DEPTH, 0, &far); /* glClearDepth is desktop only */
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

#endif
