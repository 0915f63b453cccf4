/* gl_gbuffer.h — the host G-buffer the pass tests draw into (header-only
 * test code): the GL entry points they call themselves, and a framebuffer
 * of two RGBA32F colour attachments (draw buffers 0 and 1) and a 32-bit
 * float depth buffer. Shared by tests/gl/test_rt_passes.c and
 * tests/gl/test_rt_shell_color.c. */
#ifndef MESO_TEST_GL_GBUFFER_H
#define MESO_TEST_GL_GBUFFER_H

#include <string.h>

#include "egl_context.h"
#include "shell_scene.h" /* CHECK, the GL types (gl_fbo.h) */

#define GBUFFER_GL(X)                                                                                             \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                       \
    X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)                   \
    X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)                                                          \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) X(PFNGLDRAWBUFFERSPROC, DrawBuffers)              \
    X(PFNGLREADBUFFERPROC, ReadBuffer) X(PFNGLREADPIXELSPROC, ReadPixels) X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv) \
    X(PFNGLVIEWPORTPROC, Viewport) X(PFNGLGETBOOLEANVPROC, GetBooleanv) X(PFNGLGENBUFFERSPROC, GenBuffers)         \
    X(PFNGLBINDBUFFERPROC, BindBuffer) X(PFNGLBUFFERDATAPROC, BufferData)                                         \
    X(PFNGLBINDBUFFERBASEPROC, BindBufferBase) X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)

typedef struct gbuffer_gl {
#define GBUFFER_GL_M(t, n) t n;
    GBUFFER_GL(GBUFFER_GL_M)
#undef GBUFFER_GL_M
} gbuffer_gl;

/* Loads the entry points, then creates and binds the w x h G-buffer
 * (*fbo, rb: colour 0, colour 1, depth) with both draw buffers and the
 * viewport set. */
static inline void gbuffer_create(gbuffer_gl* gl, int w, int h, GLuint* fbo, GLuint rb[3])
{
#define GBUFFER_GL_L(t, n)                         \
    {                                              \
        void (*fn)(void) = meso_egl_proc("gl" #n); \
        CHECK(fn);                                 \
        memcpy(&gl->n, &fn, sizeof(fn));           \
    }
    GBUFFER_GL(GBUFFER_GL_L)
#undef GBUFFER_GL_L
    gl->GenFramebuffers(1, fbo);
    gl->BindFramebuffer(GL_FRAMEBUFFER, *fbo);
    gl->GenRenderbuffers(3, rb);
    const GLenum fmt[3] = {GL_RGBA32F, GL_RGBA32F, GL_DEPTH_COMPONENT32F};
    const GLenum att[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_DEPTH_ATTACHMENT};
    for (int i = 0; i < 3; ++i) {
        gl->BindRenderbuffer(GL_RENDERBUFFER, rb[i]);
        gl->RenderbufferStorage(GL_RENDERBUFFER, fmt[i], w, h);
        gl->FramebufferRenderbuffer(GL_FRAMEBUFFER, att[i], GL_RENDERBUFFER, rb[i]);
    }
    gl->DrawBuffers(2, att);
    CHECK(gl->CheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);
    gl->Viewport(0, 0, w, h);
}

#endif
