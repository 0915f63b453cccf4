/*
 * egl_context.h — headless OpenGL for tests and tools: an EGL surfaceless
 * context on Mesa (llvmpipe without a GPU) rendering into an FBO, either
 * desktop OpenGL core or OpenGL ES.
 * Recipe: shared/notes/toolchain.md ("Headless OpenGL 4.5 core").
 */
#ifndef MESO_EGL_CONTEXT_H
#define MESO_EGL_CONTEXT_H

#include <stdint.h>

typedef struct meso_egl meso_egl;

typedef enum meso_egl_api {
    MESO_EGL_GL = 0, /* desktop OpenGL, core profile */
    MESO_EGL_GLES,   /* OpenGL ES */
    MESO_EGL_API_COUNT
} meso_egl_api;

/* Create an OpenGL core context (tries 4.5, then 3.3) and make it current
 * with no surface. Returns NULL and writes a reason into `why` on failure. */
meso_egl* meso_egl_create(char* why, int why_size);
/* The same for `api`. `version` (major*10+minor) asks for exactly that
 * version; 0 takes the default: 4.5 then 3.3 core for MESO_EGL_GL, 3.2 for
 * MESO_EGL_GLES (EGL_OPENGL_ES3_BIT config, eglBindAPI(EGL_OPENGL_ES_API)).
 * Note: a driver may hand back a newer compatible version than asked. */
meso_egl* meso_egl_create_api(meso_egl_api api, int version, char* why, int why_size);
void meso_egl_destroy(meso_egl* e);
/* eglGetProcAddress, typed for meso_rt_desc.gl_get_proc_address. */
void (*meso_egl_proc(const char* name))(void);
/* "gl" or "gles" (meso_egl_api_parse reads them back; -1 for neither). */
const char* meso_egl_api_name(meso_egl_api api);
int meso_egl_api_parse(const char* name);

#endif
