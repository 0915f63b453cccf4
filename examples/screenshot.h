/* screenshot.h — what the GLFW examples share: the window's framebuffer
 * saved as a PNG (rows flipped to top-first). Header-only, examples only. */
#ifndef MESO_EXAMPLES_SCREENSHOT_H
#define MESO_EXAMPLES_SCREENSHOT_H

#include <stdio.h>
#include <stdlib.h>

#include "png_io.h"

/* 0 on success; else the reason on stderr after `who` and non-zero. */
static inline int example_save_screenshot(PFNGLREADPIXELSPROC read_pixels, GLFWwindow* win, const char* path,
                                          const char* who)
{
    int w, h;
    glfwGetFramebufferSize(win, &w, &h);
    unsigned char* px = malloc((size_t)w * (size_t)h * 4);
    if (!px)
        return -1;
    read_pixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px);
    char why[256];
    const int rc = meso_png_write_rgba8(path, px, w, h, 1, why, sizeof(why));
    if (rc != 0)
        fprintf(stderr, "%s error: %s\n", who, why);
    free(px);
    return rc;
}

#endif /* MESO_EXAMPLES_SCREENSHOT_H */
