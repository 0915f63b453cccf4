/* embed_minimal.c — the shortest complete program that embeds libmeso
 * (issue 18 item 8): a GLFW window, a libmeso context on its GL context,
 * the first drawable object of a .meso file, drawn every frame by a camera
 * circling it, and the clean-up. Everything else (knobs, animation, several
 * objects, Draco-encoded files, screenshots) is in mesoview.c.
 *
 *   embed_minimal FILE.meso [--frames N]     N: quit after N frames (tests)
 *
 * Exit codes: 0 fine, 1 usage, 2 the file could not be opened or read, 3 it
 * holds no object this build draws, 4 no window, no OpenGL 3.3 core, or a
 * draw failed.
 */
#define GLFW_INCLUDE_NONE
#include <GL/glcorearb.h>
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meso_rt.h"

/* World -> eye for an eye circling `c` at distance `dist`: `yaw` radians
 * around +y, 0.45 radians above the horizon, looking at c. Column-major. */
static void orbit(float v[16], const float c[3], float yaw, float dist)
{
    const float cy = cosf(yaw), sy = sinf(yaw), cp = cosf(0.45f), sp = sinf(0.45f);
    /* The camera's axes in world space; +z points from c towards the eye. */
    const float ax[3][3] = {{cy, 0.0f, -sy}, {-sp * sy, cp, -sp * cy}, {cp * sy, sp, cp * cy}};
    memset(v, 0, 16 * sizeof(float));
    for (int row = 0; row < 3; ++row) {
        for (int k = 0; k < 3; ++k)
            v[4 * k + row] = ax[row][k];
        v[12 + row] = -(ax[row][0] * c[0] + ax[row][1] * c[1] + ax[row][2] * c[2]);
    }
    v[14] -= dist;
    v[15] = 1.0f;
}

int main(int argc, char** argv)
{
    if (argc != 2 && !(argc == 4 && !strcmp(argv[2], "--frames"))) {
        fprintf(stderr, "usage: embed_minimal FILE.meso [--frames N]\n");
        return 1;
    }
    const int frames = argc == 4 ? atoi(argv[3]) : 0;
    if (!glfwInit())
        return 4;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    GLFWwindow* win = glfwCreateWindow(640, 480, "embed_minimal", NULL, NULL);
    if (!win) {
        glfwTerminate();
        return 4;
    }
    glfwMakeContextCurrent(win);
    glfwSwapInterval(1);
    /* The host's own GL calls; libmeso loads its own through the same loader. */
    PFNGLVIEWPORTPROC Viewport = (PFNGLVIEWPORTPROC)glfwGetProcAddress("glViewport");
    PFNGLCLEARCOLORPROC ClearColor = (PFNGLCLEARCOLORPROC)glfwGetProcAddress("glClearColor");
    PFNGLCLEARPROC Clear = (PFNGLCLEARPROC)glfwGetProcAddress("glClear");

    int rc = 4;
    meso_rt* rt = NULL;
    meso_file* f = NULL;
    meso_error err;
    meso_rt_object obj = {0};
    meso_object_record recs[64];
    uint32_t count = 0;
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = glfwGetProcAddress}, &rt) != MESO_OK) {
        fprintf(stderr, "embed_minimal: libmeso needs OpenGL 3.3 core\n");
        goto done;
    }
    rc = 2;
    if (meso_file_open_path(argv[1], NULL, &f, &err) != MESO_OK ||
        meso_file_objects(f, recs, 64, &count, &err) != MESO_OK) {
        fprintf(stderr, "embed_minimal: %s\n", err.message);
        meso_file_close(f);
        goto done;
    }
    /* The first object this build can draw; the upload copies what it needs. */
    for (uint32_t i = 0; i < count && i < 64 && !obj.id; ++i)
        meso_rt_load_object(rt, f, recs[i].id, &obj);
    meso_file_close(f);
    rc = 3;
    if (!obj.id) {
        fprintf(stderr, "embed_minimal: %s has no object this build can draw\n", argv[1]);
        goto done;
    }
    float lo[3], hi[3];
    meso_rt_object_bounds(rt, obj, lo, hi);
    const float c[3] = {0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2])};
    const float radius = 0.5f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                      (hi[2] - lo[2]) * (hi[2] - lo[2]));
    rc = 0;
    for (int frame = 0; !glfwWindowShouldClose(win) && (frames <= 0 || frame < frames); ++frame) {
        int w, h;
        glfwGetFramebufferSize(win, &w, &h);
        Viewport(0, 0, w, h);
        ClearColor(0.18f, 0.20f, 0.24f, 1.0f);
        Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        if (w > 0 && h > 0) {
            meso_rt_draw_desc d = {0}; /* zero: identity model, default light, colour and knobs */
            const float dist = 3.0f * radius;
            orbit(d.view, c, 0.5f * (float)glfwGetTime(), dist);
            /* Eye -> clip: gluPerspective, 40 degrees vertically, near and far planes around the object. */
            const float cot = 1.0f / tanf(0.35f), zn = 0.5f * radius, zf = dist + 1.5f * radius;
            const float proj[16] = {cot * h / w, 0, 0, 0, 0, cot, 0, 0, 0, 0, (zf + zn) / (zn - zf), -1,
                                    0, 0, 2 * zf * zn / (zn - zf), 0};
            memcpy(d.proj, proj, sizeof(proj));
            if (meso_rt_draw(rt, obj, &d) != MESO_OK) {
                fprintf(stderr, "embed_minimal: meso_rt_draw failed\n");
                rc = 4;
                break;
            }
        }
        glfwSwapBuffers(win);
        glfwPollEvents();
    }
done:
    meso_rt_release_object(rt, obj); /* before the GL context goes */
    meso_rt_destroy(rt);
    glfwDestroyWindow(win);
    glfwTerminate();
    return rc;
}
