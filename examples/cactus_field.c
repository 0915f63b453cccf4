/*
 * cactus_field — the conical-frusta paper's showcase (papers/relief-mapped-
 * conical-frusta.md §4: a field of animated cacti) on libmeso's many-object
 * path (issue 18 items 3 and 8): one saguaro object, drawn as COUNT
 * instances in one instanced draw, each swaying with a pose of its own (a
 * pose slot per cactus, re-posed every frame with
 * meso_rt_frusta_set_pose_slot), and rocks, one shell object drawn as
 * instances too; both in one meso_rt_draw_list call per frame. The sand
 * and sky are the host's own clears (the ground below the horizon).
 *
 *   cactus_field CACTUS.meso ROCK.meso [--count N] [--rocks N] [--size WxH]
 *                [--frames N] [--screenshot OUT.png]
 *
 * CACTUS.meso: `mesobake frusta -i tests/data/saguaro.skel --relief ribs:64
 * --relief-repeat 14`; ROCK.meso: `mesobake shell -i tests/data/sphere.obj
 * --texture cobble:32 --tiling 2`. The title shows ms per frame. Esc quits.
 * Headless (CI, the README picture): under xvfb-run with --frames N
 * --screenshot OUT.png (tests/integration/cactus_field_xvfb.sh). GLFW lives
 * only in examples/.
 */
#define GLFW_INCLUDE_NONE
#include <GL/glcorearb.h>
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "meso_rt.h"
#include "png_io.h"
#include "screenshot.h"

static const char* const usage =
    "Usage: cactus_field CACTUS.meso ROCK.meso [options]\n"
    "\n"
    "  --count N           cacti, each an instance with its own pose slot (default 144)\n"
    "  --rocks N           rock instances (default 40)\n"
    "  --size WxH          window size (default 960x540)\n"
    "  --frames N          quit after N frames (0 = run until closed)\n"
    "  --screenshot FILE   save the last frame as PNG when quitting\n";

typedef struct field_gl {
    PFNGLCLEARCOLORPROC ClearColor;
    PFNGLCLEARPROC Clear;
    PFNGLREADPIXELSPROC ReadPixels;
    PFNGLVIEWPORTPROC Viewport;
    PFNGLENABLEPROC Enable;
    PFNGLDISABLEPROC Disable;
    PFNGLSCISSORPROC Scissor;
} field_gl;

static void on_log(void* user, meso_log_level level, meso_log_item item, const char* message)
{
    (void)user;
    if (level == MESO_LOG_ERROR)
        fprintf(stderr, "cactus_field error: %s%s%s\n", meso_log_item_string(item), message ? ": " : "",
                message ? message : "");
}

static int load_gl(void* dst, const char* name)
{
    GLFWglproc p = glfwGetProcAddress(name);
    if (!p)
        fprintf(stderr, "cactus_field error: GL function %s not found\n", name);
    memcpy(dst, &p, sizeof(p));
    return p != NULL;
}

static meso_rt_object load_object(meso_rt* rt, const char* path)
{
    meso_file* f = NULL;
    meso_error err;
    meso_object_record rec;
    uint32_t n = 0;
    meso_rt_object o = {0};
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK) {
        fprintf(stderr, "cactus_field error: %s: %s\n", path, err.message);
        return o;
    }
    if (meso_file_objects(f, &rec, 1, &n, &err) == MESO_OK && n == 1)
        meso_rt_load_object(rt, f, rec.id, &o);
    meso_file_close(f);
    return o;
}

/* Deterministic pseudo-random numbers in [0, 1). */
static double rnd(uint32_t* s)
{
    *s = *s * 1664525u + 1013904223u;
    return (*s >> 8) * (1.0 / 16777216.0);
}

/* Rotation about y by `turn`, uniform scale, base at (x, y, z). */
static void place(float m[16], double x, double y, double z, double turn, double scale)
{
    const double c = cos(turn) * scale, s = sin(turn) * scale;
    memset(m, 0, 16 * sizeof(float));
    m[0] = (float)c, m[2] = (float)-s, m[5] = (float)scale, m[8] = (float)s, m[10] = (float)c;
    m[12] = (float)x, m[13] = (float)y, m[14] = (float)z, m[15] = 1.0f;
}

/* The sway of cactus i at time t: every node moves downwind by its height
 * squared (the trunk bends, the arms follow), the gusts out of phase. */
static void sway(const float* rest, uint32_t nodes, double t, double phase, float* out)
{
    const double a = 0.012 * sin(1.3 * t + phase) + 0.006 * sin(2.9 * t + 1.7 * phase);
    const double b = 0.008 * sin(1.1 * t + 2.3 * phase);
    for (uint32_t k = 0; k < nodes; ++k) {
        const double y = rest[3 * k + 1];
        out[3 * k] = (float)(rest[3 * k] + a * y * y);
        out[3 * k + 1] = rest[3 * k + 1];
        out[3 * k + 2] = (float)(rest[3 * k + 2] + b * y * y);
    }
}

static int save_screenshot(const field_gl* gl, GLFWwindow* win, const char* path)
{
    return example_save_screenshot(gl->ReadPixels, win, path, "cactus_field");
}

int main(int argc, char** argv)
{
    const char* files[2] = {NULL, NULL};
    const char* shot = NULL;
    int width = 960, height = 540, frames = 0, count = 144, rocks = 40, nfiles = 0;
    for (int i = 1; i < argc; ++i) {
        const char* a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage, stdout);
            return 0;
        } else if (!strcmp(a, "--size") && i + 1 < argc && sscanf(argv[i + 1], "%dx%d", &width, &height) == 2) {
            ++i;
        } else if (!strcmp(a, "--frames") && i + 1 < argc) {
            frames = atoi(argv[++i]);
        } else if (!strcmp(a, "--count") && i + 1 < argc) {
            count = atoi(argv[++i]);
        } else if (!strcmp(a, "--rocks") && i + 1 < argc) {
            rocks = atoi(argv[++i]);
        } else if (!strcmp(a, "--screenshot") && i + 1 < argc) {
            shot = argv[++i];
        } else if (a[0] != '-' && nfiles < 2) {
            files[nfiles++] = a;
        } else {
            fprintf(stderr, "cactus_field error: unexpected argument '%s'\n%s", a, usage);
            return 1;
        }
    }
    if (nfiles != 2 || count < 1 || count > 4096 || rocks < 0 || rocks > 4096 || width < 16 || height < 16) {
        fputs(usage, stderr);
        return 1;
    }
    if (!glfwInit()) {
        fprintf(stderr, "cactus_field error: cannot initialise GLFW\n");
        return 4;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    GLFWwindow* win = glfwCreateWindow(width, height, "cactus field", NULL, NULL);
    if (!win) {
        fprintf(stderr, "cactus_field error: cannot open a window\n");
        glfwTerminate();
        return 4;
    }
    glfwMakeContextCurrent(win);
    glfwSwapInterval(0);
    field_gl gl;
    int ok = load_gl(&gl.ClearColor, "glClearColor") & load_gl(&gl.Clear, "glClear") &
             load_gl(&gl.ReadPixels, "glReadPixels") & load_gl(&gl.Viewport, "glViewport") &
             load_gl(&gl.Enable, "glEnable") & load_gl(&gl.Disable, "glDisable") & load_gl(&gl.Scissor, "glScissor");
    meso_rt* rt = NULL;
    if (!ok || meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = glfwGetProcAddress, .log_fn = on_log,
                                              .prepare = 1},
                              &rt) != MESO_OK) {
        glfwDestroyWindow(win);
        glfwTerminate();
        return 4;
    }
    const meso_rt_object cactus = load_object(rt, files[0]), rock = load_object(rt, files[1]);
    uint32_t nodes = 0;
    if (!cactus.id || !rock.id || meso_rt_frusta_info(rt, cactus, NULL, &nodes) != MESO_OK || nodes == 0 ||
        meso_rt_frusta_pose_slots(rt, cactus, (uint32_t)count) != MESO_OK) {
        fprintf(stderr, "cactus_field error: CACTUS.meso must hold a frusta object, ROCK.meso a shell\n");
        meso_rt_destroy(rt);
        glfwDestroyWindow(win);
        glfwTerminate();
        return 3;
    }

    /* The field: cacti on a jittered grid, rocks scattered between. Object
     * units: the saguaro is baked in metres, the rock sphere is 2 across. */
    float lo[3], hi[3];
    meso_rt_object_bounds(rt, rock, lo, hi);
    const double rock_size = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    const int side = (int)ceil(sqrt((double)count));
    const double spacing = 7.0, extent = side * spacing;
    meso_rt_instance* ci = calloc((size_t)count, sizeof(*ci));
    meso_rt_instance* ri = calloc((size_t)(rocks ? rocks : 1), sizeof(*ri));
    double* phase = malloc(sizeof(double) * (size_t)count);
    float* rest = malloc(sizeof(float) * 3 * nodes);
    float* pose = malloc(sizeof(float) * 3 * nodes);
    uint32_t seed = 12345u;
    for (int i = 0; i < count; ++i) {
        const double x = (i % side + 0.5 + 0.6 * (rnd(&seed) - 0.5)) * spacing - 0.5 * extent;
        const double z = -(i / side + 0.5 + 0.6 * (rnd(&seed) - 0.5)) * spacing;
        place(ci[i].model, x, 0.0, z, 6.2832 * rnd(&seed), 0.7 + 0.5 * rnd(&seed));
        ci[i].pose_slot = (uint32_t)i;
        phase[i] = 6.2832 * rnd(&seed);
    }
    for (int i = 0; i < rocks; ++i) {
        const double s = (1.0 + 2.0 * rnd(&seed)) / rock_size; /* 1..3 m across */
        const double x = (rnd(&seed) - 0.5) * extent, z = -rnd(&seed) * extent;
        place(ri[i].model, x - s * 0.5 * (lo[0] + hi[0]), -0.25 * s * rock_size - s * 0.5 * (lo[1] + hi[1]),
              z - s * 0.5 * (lo[2] + hi[2]), 6.2832 * rnd(&seed), s);
    }
    meso_rt_frusta_rest_pose(rt, cactus, rest, NULL, nodes);

    meso_rt_draw_desc common = {0}, cactus_knobs = {0}, rock_knobs = {0};
    const double eye[3] = {0.0, 9.0, 14.0}, at[3] = {0.0, 1.5, -0.45 * extent}, up[3] = {0, 1, 0};
    meso_camera_look_at(common.view, eye, at, up);
    meso_camera_perspective(common.proj, 0.8, (double)width / height, 0.5, 4.0 * extent + 50.0);
    const float light[3] = {0.5f, 0.8f, 0.35f};
    memcpy(common.light_dir, light, sizeof(light));
    cactus_knobs = common;
    cactus_knobs.albedo[0] = 0.30f, cactus_knobs.albedo[1] = 0.52f, cactus_knobs.albedo[2] = 0.22f;
    rock_knobs = common;
    rock_knobs.albedo[0] = 0.78f, rock_knobs.albedo[1] = 0.68f, rock_knobs.albedo[2] = 0.58f;
    const meso_rt_draw_item items[2] = {
        {.object = cactus, .knobs = &cactus_knobs, .instances = ci, .instance_count = (uint32_t)count},
        {.object = rock, .knobs = &rock_knobs, .instances = ri, .instance_count = (uint32_t)rocks}};

    /* The horizon's row: where horizontal directions project. */
    double horizon = 0.5;
    {
        const float* v = common.view;
        const float* p = common.proj;
        const double dir[4] = {0.0, 0.0, -1.0, 0.0};
        double e[4] = {0, 0, 0, 0}, c[4] = {0, 0, 0, 0};
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k)
                e[r] += v[4 * k + r] * dir[k];
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k)
                c[r] += p[4 * k + r] * e[k];
        horizon = c[3] != 0.0 ? 0.5 * (c[1] / c[3]) + 0.5 : 0.5;
    }

    int rc = 0;
    double t_prev = glfwGetTime(), ms = 0.0;
    for (int frame = 0; !glfwWindowShouldClose(win) && (frames == 0 || frame < frames); ++frame) {
        const double t = frame / 30.0;
        int w, h;
        glfwGetFramebufferSize(win, &w, &h);
        gl.Viewport(0, 0, w, h);
        gl.ClearColor(0.55f, 0.70f, 0.88f, 1.0f); /* sky */
        gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        gl.Enable(GL_SCISSOR_TEST); /* sand below the horizon */
        gl.Scissor(0, 0, w, (GLsizei)(horizon * h));
        gl.ClearColor(0.80f, 0.68f, 0.50f, 1.0f);
        gl.Clear(GL_COLOR_BUFFER_BIT);
        gl.Disable(GL_SCISSOR_TEST);
        for (int i = 0; i < count; ++i) {
            sway(rest, nodes, t, phase[i], pose);
            meso_rt_frusta_set_pose_slot(rt, cactus, (uint32_t)i, pose, nodes);
        }
        common.viewport[2] = w, common.viewport[3] = h;
        if (meso_rt_draw_list(rt, items, rocks ? 2u : 1u, &common) != MESO_OK) {
            rc = 3;
            break;
        }
        if (shot && frames && frame == frames - 1)
            rc = save_screenshot(&gl, win, shot) ? 2 : 0;
        glfwSwapBuffers(win);
        glfwPollEvents();
        if (glfwGetKey(win, GLFW_KEY_ESCAPE) == GLFW_PRESS)
            glfwSetWindowShouldClose(win, 1);
        const double now = glfwGetTime();
        ms = 0.9 * ms + 0.1 * 1e3 * (now - t_prev);
        t_prev = now;
        char title[96];
        snprintf(title, sizeof(title), "cactus field: %d cacti, %d rocks, %.1f ms/frame", count, rocks, ms);
        glfwSetWindowTitle(win, title);
    }
    free(ci);
    free(ri);
    free(phase);
    free(rest);
    free(pose);
    meso_rt_destroy(rt);
    glfwDestroyWindow(win);
    glfwTerminate();
    return rc;
}
