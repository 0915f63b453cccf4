/*
 * egl_context.h — headless OpenGL for tests and tools: an EGL surfaceless
 * context on Mesa (llvmpipe without a GPU) rendering into an FBO.
 * Recipe: shared/notes/toolchain.md ("Headless OpenGL 4.5 core").
 */
#ifndef MESO_EGL_CONTEXT_H
#define MESO_EGL_CONTEXT_H

#include <stdint.h>

typedef struct meso_egl meso_egl;

/* Create an OpenGL core context (tries 4.5, then 3.3) and make it current
 * with no surface. Returns NULL and writes a reason into `why` on failure. */
meso_egl* meso_egl_create(char* why, int why_size);
void meso_egl_destroy(meso_egl* e);
/* eglGetProcAddress, typed for meso_rt_desc.gl_get_proc_address. */
void (*meso_egl_proc(const char* name))(void);

#endif
