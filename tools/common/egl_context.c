/* egl_context.c — see egl_context.h. */
#include "egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdio.h>
#include <stdlib.h>

struct meso_egl {
    EGLDisplay dpy;
    EGLContext ctx;
};

void (*meso_egl_proc(const char* name))(void)
{
    return eglGetProcAddress(name);
}

meso_egl* meso_egl_create(char* why, int why_size)
{
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)(void (*)(void))eglGetProcAddress("eglGetPlatformDisplayEXT");
    EGLDisplay dpy = EGL_NO_DISPLAY;
    if (get_display)
        dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    if (dpy == EGL_NO_DISPLAY) {
        snprintf(why, (size_t)why_size, "no EGL surfaceless display (EGL_MESA_platform_surfaceless missing?)");
        return NULL;
    }
    EGLint maj = 0, min = 0;
    if (!eglInitialize(dpy, &maj, &min)) {
        snprintf(why, (size_t)why_size, "eglInitialize failed: 0x%x", eglGetError());
        return NULL;
    }
    const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                               EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_NONE};
    EGLConfig cfg;
    EGLint n = 0;
    if (!eglChooseConfig(dpy, cfg_attr, &cfg, 1, &n) || n < 1) {
        snprintf(why, (size_t)why_size, "eglChooseConfig found no OpenGL config");
        eglTerminate(dpy);
        return NULL;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        snprintf(why, (size_t)why_size, "eglBindAPI(EGL_OPENGL_API) failed");
        eglTerminate(dpy);
        return NULL;
    }
    static const EGLint versions[][2] = {{4, 5}, {3, 3}};
    EGLContext ctx = EGL_NO_CONTEXT;
    for (int i = 0; i < 2 && ctx == EGL_NO_CONTEXT; ++i) {
        const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, versions[i][0], EGL_CONTEXT_MINOR_VERSION,
                                   versions[i][1], EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                   EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
    }
    if (ctx == EGL_NO_CONTEXT) {
        snprintf(why, (size_t)why_size, "eglCreateContext (core 4.5 and 3.3) failed: 0x%x", eglGetError());
        eglTerminate(dpy);
        return NULL;
    }
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        snprintf(why, (size_t)why_size, "eglMakeCurrent (surfaceless) failed: 0x%x", eglGetError());
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        return NULL;
    }
    meso_egl* e = malloc(sizeof(*e));
    if (!e) {
        snprintf(why, (size_t)why_size, "out of memory");
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        return NULL;
    }
    e->dpy = dpy;
    e->ctx = ctx;
    return e;
}

void meso_egl_destroy(meso_egl* e)
{
    if (!e)
        return;
    eglMakeCurrent(e->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(e->dpy, e->ctx);
    eglTerminate(e->dpy);
    free(e);
}
