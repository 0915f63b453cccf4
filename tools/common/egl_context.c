/* egl_context.c — see egl_context.h. */
#include "egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct meso_egl {
    EGLDisplay dpy;
    EGLContext ctx;
};

void (*meso_egl_proc(const char* name))(void)
{
    return eglGetProcAddress(name);
}

const char* meso_egl_api_name(meso_egl_api api)
{
    return api == MESO_EGL_GLES ? "gles" : "gl";
}

int meso_egl_api_parse(const char* name)
{
    if (name && strcmp(name, "gl") == 0)
        return MESO_EGL_GL;
    if (name && strcmp(name, "gles") == 0)
        return MESO_EGL_GLES;
    return -1;
}

meso_egl* meso_egl_create(char* why, int why_size)
{
    return meso_egl_create_api(MESO_EGL_GL, 0, why, why_size);
}

meso_egl* meso_egl_create_api(meso_egl_api api, int version, char* why, int why_size)
{
    const int es = api == MESO_EGL_GLES;
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
    const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                               es ? EGL_OPENGL_ES3_BIT : EGL_OPENGL_BIT,
                               EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_NONE};
    EGLConfig cfg;
    EGLint n = 0;
    if (!eglChooseConfig(dpy, cfg_attr, &cfg, 1, &n) || n < 1) {
        snprintf(why, (size_t)why_size, "eglChooseConfig found no %s config", es ? "OpenGL ES 3" : "OpenGL");
        eglTerminate(dpy);
        return NULL;
    }
    if (!eglBindAPI(es ? EGL_OPENGL_ES_API : EGL_OPENGL_API)) {
        snprintf(why, (size_t)why_size, "eglBindAPI(%s) failed", es ? "EGL_OPENGL_ES_API" : "EGL_OPENGL_API");
        eglTerminate(dpy);
        return NULL;
    }
    EGLint versions[2][2] = {{4, 5}, {3, 3}};
    int tries = 2;
    if (version > 0 || es) {
        versions[0][0] = version > 0 ? version / 10 : 3;
        versions[0][1] = version > 0 ? version % 10 : 2;
        tries = 1;
    }
    EGLContext ctx = EGL_NO_CONTEXT;
    for (int i = 0; i < tries && ctx == EGL_NO_CONTEXT; ++i) {
        /* The profile mask is desktop-only: an ES context ends the list there. */
        const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, versions[i][0], EGL_CONTEXT_MINOR_VERSION,
                                   versions[i][1], es ? EGL_NONE : EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                   EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
    }
    if (ctx == EGL_NO_CONTEXT) {
        if (tries == 2)
            snprintf(why, (size_t)why_size, "eglCreateContext (core 4.5 and 3.3) failed: 0x%x", eglGetError());
        else
            snprintf(why, (size_t)why_size, "eglCreateContext (%s %d.%d) failed: 0x%x", es ? "OpenGL ES" : "core",
                     versions[0][0], versions[0][1], eglGetError());
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
