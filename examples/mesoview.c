/*
 * mesoview — the GLFW viewer: opens a window, creates a libmeso context from
 * GLFW's loader, and draws .meso files into the window's framebuffer.
 *
 *   mesoview [FILE.meso] [--size WxH] [--frames N] [--screenshot OUT.png]
 *
 * Mouse: drag to orbit, scroll to zoom. Keys: Esc quits, S saves a
 * screenshot (mesoview.png). GLFW lives only in examples/: libmeso itself
 * never sees a window. Draco-encoded chunks are decoded with the baker's
 * decoder, passed in through meso_open_desc as any host would pass its own.
 */
#define GLFW_INCLUDE_NONE
#include <GL/glcorearb.h>
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_chunk.h"
#include "meso_rt.h"
#include "png_io.h"

static const char* const usage =
    "Usage: mesoview [FILE.meso] [options]\n"
    "\n"
    "  --size WxH          window size (default 800x600)\n"
    "  --frames N          quit after N frames (0 = run until closed)\n"
    "  --screenshot FILE   save the last frame as PNG when quitting\n"
    "  -h, --help          this help;  --version  the version\n"
    "\n"
    "Mouse: drag to orbit, scroll to zoom.  Keys: Esc quit, S save mesoview.png\n";

typedef struct orbit {
    double yaw, pitch, zoom; /* degrees, degrees, distance factor */
    double last_x, last_y;
    int dragging;
} orbit;

static void on_scroll(GLFWwindow* w, double dx, double dy)
{
    (void)dx;
    orbit* o = glfwGetWindowUserPointer(w);
    o->zoom *= pow(0.9, dy);
    o->zoom = fmin(fmax(o->zoom, 0.05), 20.0);
}

static void perspective(float m[16], double fovy, double aspect, double zn, double zf)
{
    const double f = 1.0 / tan(fovy / 2);
    memset(m, 0, 16 * sizeof(float));
    m[0] = (float)(f / aspect);
    m[5] = (float)f;
    m[10] = (float)((zf + zn) / (zn - zf));
    m[11] = -1.0f;
    m[14] = (float)(2 * zf * zn / (zn - zf));
}

/* View matrix of an orbit camera: rotate by -yaw about y, -pitch about x,
 * then push back by `dist`, around `centre`. Column-major. */
static void orbit_view(float m[16], const double c[3], double yaw, double pitch, double dist)
{
    const double cy = cos(yaw), sy = sin(yaw), cp = cos(pitch), sp = sin(pitch);
    /* Rows of R = Rx(pitch) * Ry(-yaw), the inverse of the camera's rotation;
     * the eye sits at centre + dist * (cp sy, sp, cp cy). */
    const double r[3][3] = {{cy, 0, -sy}, {-sp * sy, cp, -sp * cy}, {cp * sy, sp, cp * cy}};
    memset(m, 0, 16 * sizeof(float));
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j)
            m[4 * j + i] = (float)r[i][j];
        m[12 + i] = (float)(-(r[i][0] * c[0] + r[i][1] * c[1] + r[i][2] * c[2]));
    }
    m[14] -= (float)dist;
    m[15] = 1.0f;
}

typedef struct view_gl {
    PFNGLCLEARCOLORPROC ClearColor;
    PFNGLCLEARPROC Clear;
    PFNGLREADPIXELSPROC ReadPixels;
    PFNGLVIEWPORTPROC Viewport;
    PFNGLENABLEPROC Enable;
} view_gl;

static void on_log(void* user, meso_log_level level, meso_log_item item, const char* message)
{
    (void)user;
    fprintf(stderr, "mesoview %s: [%d] %s%s%s\n", level == MESO_LOG_ERROR ? "error" : level == MESO_LOG_WARNING ? "warning" : "info",
            (int)item, meso_log_item_string(item), message ? ": " : "", message ? message : "");
}

static int save_screenshot(const view_gl* gl, GLFWwindow* win, const char* path)
{
    int w, h;
    glfwGetFramebufferSize(win, &w, &h);
    unsigned char* px = malloc((size_t)w * (size_t)h * 4);
    if (!px)
        return -1;
    gl->ReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px);
    char why[256];
    int rc = meso_png_write_rgba8(path, px, w, h, 1, why, sizeof(why));
    if (rc != 0)
        fprintf(stderr, "mesoview error: %s\n", why);
    free(px);
    return rc;
}

static void load(void* dst, const char* name, int* missing)
{
    GLFWglproc p = glfwGetProcAddress(name);
    if (!p) {
        fprintf(stderr, "mesoview error: GL function %s not found\n", name);
        ++*missing;
    }
    memcpy(dst, &p, sizeof(p));
}

int main(int argc, char** argv)
{
    int width = 800, height = 600, frames = 0;
    const char *file = NULL, *shot = NULL;
    for (int i = 1; i < argc; ++i) {
        const char* a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage, stdout);
            return 0;
        } else if (!strcmp(a, "--version")) {
            printf("mesoview %s (format %d.%d)\n", MESO_VERSION_STRING, MESO_FORMAT_MAJOR, MESO_FORMAT_MINOR);
            return 0;
        } else if (!strcmp(a, "--size") && i + 1 < argc) {
            if (sscanf(argv[++i], "%dx%d", &width, &height) != 2 || width < 1 || height < 1 || width > 16384 ||
                height > 16384) {
                fprintf(stderr, "mesoview error: --size expects WxH, got '%s'\nSee 'mesoview --help'.\n", argv[i]);
                return 1;
            }
        } else if (!strcmp(a, "--frames") && i + 1 < argc) {
            frames = atoi(argv[++i]);
        } else if (!strcmp(a, "--screenshot") && i + 1 < argc) {
            shot = argv[++i];
        } else if (a[0] == '-') {
            fprintf(stderr, "mesoview error: unrecognized option '%s'\nSee 'mesoview --help'.\n", a);
            return 1;
        } else if (!file) {
            file = a;
        } else {
            fprintf(stderr, "mesoview error: unexpected argument '%s'\nSee 'mesoview --help'.\n", a);
            return 1;
        }
    }
    if (!glfwInit()) {
        const char* why = NULL;
        glfwGetError(&why);
        fprintf(stderr, "mesoview error: cannot initialise GLFW: %s\n", why ? why : "unknown reason");
        return 4;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    GLFWwindow* win = glfwCreateWindow(width, height, "mesoview", NULL, NULL);
    if (!win) {
        const char* why = NULL;
        glfwGetError(&why);
        fprintf(stderr, "mesoview error: cannot open a window: %s\n", why ? why : "unknown reason");
        glfwTerminate();
        return 4;
    }
    glfwMakeContextCurrent(win);
    glfwSwapInterval(1);

    view_gl gl;
    int missing = 0;
    load(&gl.ClearColor, "glClearColor", &missing);
    load(&gl.Clear, "glClear", &missing);
    load(&gl.ReadPixels, "glReadPixels", &missing);
    load(&gl.Viewport, "glViewport", &missing);
    load(&gl.Enable, "glEnable", &missing);
    meso_rt* rt = NULL;
    meso_result r = missing ? MESO_ERR_GL
                            : meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = glfwGetProcAddress, .log_fn = on_log}, &rt);
    if (r != MESO_OK) {
        fprintf(stderr, "mesoview error: cannot create the libmeso context: %s\n", meso_result_string(r));
        glfwDestroyWindow(win);
        glfwTerminate();
        return 4;
    }
    meso_rt_object objs[64];
    int nobj = 0;
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    if (file) {
        meso_decoder dec = meso_bake_draco_decoder();
        meso_file* f = NULL;
        meso_error err;
        r = meso_file_open_path(file, &(meso_open_desc){.decoders = &dec, .decoder_count = dec.decode_fn ? 1 : 0}, &f,
                                &err);
        if (r != MESO_OK) {
            fprintf(stderr, "mesoview error: %s\n", err.message);
            meso_rt_destroy(rt);
            glfwDestroyWindow(win);
            glfwTerminate();
            return r == MESO_ERR_IO ? 2 : 3;
        }
        meso_object_record recs[64];
        uint32_t count = 0;
        if (meso_file_objects(f, recs, 64, &count, &err) != MESO_OK)
            fprintf(stderr, "mesoview error: %s\n", err.message);
        for (uint32_t i = 0; i < count && i < 64; ++i) {
            if (meso_rt_load_object(rt, f, recs[i].id, &objs[nobj]) != MESO_OK)
                continue;
            float l[3], h[3];
            meso_rt_object_bounds(rt, objs[nobj], l, h);
            for (int k = 0; k < 3; ++k) {
                lo[k] = nobj ? fmin(lo[k], l[k]) : l[k];
                hi[k] = nobj ? fmax(hi[k], h[k]) : h[k];
            }
            ++nobj;
        }
        meso_file_close(f);
        if (nobj == 0)
            fprintf(stderr, "mesoview warning: %s has no object this build can draw\n", file);
    }
    const double centre[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double radius = 0.5 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
    orbit cam = {.yaw = 30, .pitch = 20, .zoom = 1};
    glfwSetWindowUserPointer(win, &cam);
    glfwSetScrollCallback(win, on_scroll);

    int rc = 0;
    for (int frame = 0; !glfwWindowShouldClose(win); ++frame) {
        int fw, fh;
        glfwGetFramebufferSize(win, &fw, &fh);
        gl.Viewport(0, 0, fw, fh);
        gl.ClearColor(0.18f, 0.20f, 0.24f, 1.0f);
        gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        if (nobj > 0 && fw > 0 && fh > 0) {
            const double fovy = 35.0 * M_PI / 180.0, dist = cam.zoom * radius / sin(fovy / 2) * 1.05;
            meso_rt_draw_desc d = {.light_dir = {0.3f, 0.8f, 0.5f}};
            orbit_view(d.view, centre, cam.yaw * M_PI / 180.0, cam.pitch * M_PI / 180.0, dist);
            perspective(d.proj, fovy, (double)fw / fh, fmax(dist - 1.5 * radius, 1e-3 * dist), dist + 1.5 * radius);
            for (int i = 0; i < nobj; ++i)
                meso_rt_draw(rt, objs[i], &d);
        }
        const int last = frames > 0 && frame + 1 >= frames;
        if (last && shot)
            rc = save_screenshot(&gl, win, shot) ? 2 : 0;
        glfwSwapBuffers(win);
        glfwPollEvents();
        if (glfwGetKey(win, GLFW_KEY_ESCAPE) == GLFW_PRESS)
            glfwSetWindowShouldClose(win, GLFW_TRUE);
        if (glfwGetKey(win, GLFW_KEY_S) == GLFW_PRESS)
            save_screenshot(&gl, win, "mesoview.png");
        double mx, my;
        glfwGetCursorPos(win, &mx, &my);
        if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
            if (cam.dragging) {
                cam.yaw -= 0.4 * (mx - cam.last_x);
                cam.pitch = fmin(fmax(cam.pitch + 0.4 * (my - cam.last_y), -89.0), 89.0);
            }
            cam.dragging = 1;
        } else {
            cam.dragging = 0;
        }
        cam.last_x = mx;
        cam.last_y = my;
        if (last)
            break;
    }
    meso_rt_destroy(rt);
    glfwDestroyWindow(win);
    glfwTerminate();
    return rc;
}
