/* gl_api.h — which OpenGL API a GL test runs on (header-only, test code):
 * desktop OpenGL core by default, OpenGL ES 3.2 when the environment says
 * MESO_TEST_GL_API=gles (tests/meson.build registers an `_es` variant of
 * the GL tests with it). An ES run fails, never skips, without an ES
 * context. */
#ifndef MESO_TEST_GL_API_H
#define MESO_TEST_GL_API_H

#include <stdio.h>
#include <stdlib.h>

#include "egl_context.h"

/* MESO_EGL_GL or MESO_EGL_GLES from MESO_TEST_GL_API ("gl" or "gles";
 * unset: "gl"); -1 for anything else. */
static inline int test_gl_api(void)
{
    const char* s = getenv("MESO_TEST_GL_API");
    return s && s[0] ? meso_egl_api_parse(s) : MESO_EGL_GL;
}

/* The test's context (meso_egl_create_api with the default version), or
 * NULL with the reason in `why`. */
static inline meso_egl* test_egl_create(char* why, int why_size)
{
    const int api = test_gl_api();
    if (api < 0) {
        snprintf(why, (size_t)why_size, "MESO_TEST_GL_API=%s: neither gl nor gles", getenv("MESO_TEST_GL_API"));
        return NULL;
    }
    return meso_egl_create_api((meso_egl_api)api, 0, why, why_size);
}

#endif /* MESO_TEST_GL_API_H */
