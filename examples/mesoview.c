/*
 * mesoview — the GLFW viewer: opens a window, creates a libmeso context from
 * GLFW's loader, and draws .meso files into the window's framebuffer.
 *
 *   mesoview [FILE.meso] [--size WxH] [--frames N] [--screenshot OUT.png]
 *            [--technique smooth|curved|tetra|segment|slices] [--slices N]
 *            [--slice-interp none|normal|texcoord] [--slice-axis view|levels] [--error-px E] [--animate]
 *            [--keys KEYS] [--print-title]
 *
 * Mouse: drag to orbit, scroll to zoom. Keys: Esc quits, S saves a
 * screenshot (mesoview.png); 1-5 pick the shell technique (5: slices,
 * papers/volume-textures-lp-averaged-shells.md §5), I cycles the slices'
 * interpolation, , . halve/double the slice count, [ ] halve/double
 * the error bound, - = halve/double the step limit, B cycles the bisection
 * steps, D toggles the distance map, A toggles the animation (shells: a
 * twist of the base mesh and its directors, uploaded every frame with
 * meso_rt_shell_update, and a texture function baked with frames
 * (mesobake shell --texture boil --frames N) plays them in a loop with
 * meso_rt_shell_set_time, at the 30 frames per second of animation time the
 * viewer steps; frusta: the skeleton sways, every node turning a
 * little about its parent, rebuilt every frame with meso_rt_frusta_set_pose;
 * no re-bake either way). Frusta use the step limit keys for their relief
 * march (relief_steps). Cells: M cycles first hit / reflection / refraction,
 * N the bounces (0..3), L toggles the thesis's linear search (8 voxels a
 * step) against the exact traversal. Objects stored with levels of detail
 * (FORMAT.md 7.10) are loaded with meso_rt_load_object_levels: O and P halve
 * and double the pixel error each draw may have (0.125..64 px, below
 * 0.125 the finest levels), and the title shows the levels drawn and the
 * bytes resident. The title shows ms/frame and, on
 * OpenGL 4.3+, ray steps per ray-cast fragment counted by the shaders. GLFW lives only in examples/: libmeso itself
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

#include "camera.h"
#include "mesh_chunk.h"
#include "meso_rt.h"
#include "png_io.h"
#include "screenshot.h"

static const char* const usage =
    "Usage: mesoview [FILE.meso] [options]\n"
    "\n"
    "  --size WxH          window size (default 800x600)\n"
    "  --frames N          quit after N frames (0 = run until closed)\n"
    "  --screenshot FILE   save the last frame as PNG when quitting\n"
    "  --technique T       shells: smooth (default), curved, tetra, segment or slices\n"
    "  --slices N          slices: slice polygons per prism (2..1024, default 16)\n"
    "  --slice-interp I    slices: texcoord (default), normal or none\n"
    "  --slice-axis X      slices: view (default: per prism the family the view crosses most\n"
    "                      densely) or levels (always the levels of constant w)\n"
    "  --error-px E        shells: image-space error bound in pixels (default 1)\n"
    "  --animate           start with the animation on (shells twist and play stored texture\n"
    "                      frames, frusta sway)\n"
    "  --cells MODE        cells: first (default), reflect or refract\n"
    "  --keys KEYS         press these keys, one a frame from the second frame on (the\n"
    "                      keys below, as typed: 'PPO' doubles the pixel error twice, then\n"
    "                      halves it), for scripted runs and tests\n"
    "  --print-title       print the window title to stdout each time it changes\n"
    "  -h, --help          this help;  --version  the version\n"
    "\n"
    "Mouse: drag to orbit, scroll to zoom.  Keys: Esc quit, S save mesoview.png,\n"
    "1-5 technique (smooth curved tetra segment slices), I slice interpolation,\n"
    "X slice axis (view / levels), "
    ", . slice count, [ ] error bound, - = step limit,\n"
    "B bisection steps, D distance map on/off, A animation on/off,\n"
    "M cells mode, N cells bounces, L cells linear search on/off,\n"
    "O P levels of detail: halve / double the pixel error\n";

static const char* const cell_mode_names[3] = {"first", "reflect", "refract"};

static const char* const technique_names[MESO_SHELL_TECHNIQUE_COUNT] = {"smooth", "curved", "tetra", "segment",
                                                                        "slices"};
static const char* const interp_names[MESO_SLICE_INTERP_COUNT] = {"texcoord", "normal", "none"};

/* What the keyboard changes. */
typedef struct knobs {
    meso_rt_draw_desc d;
    int animate;
    int changed;
} knobs;

static void on_key(GLFWwindow* w, int key, int scancode, int action, int mods)
{
    (void)scancode;
    (void)mods;
    if (action != GLFW_PRESS)
        return;
    knobs* k = ((knobs**)glfwGetWindowUserPointer(w))[1];
    meso_rt_draw_desc* d = &k->d;
    meso_rt_shell_draw* sh = &d->shell;
    if (key >= GLFW_KEY_1 && key <= GLFW_KEY_5)
        sh->technique = (meso_shell_technique)(key - GLFW_KEY_1);
    else if (key == GLFW_KEY_I)
        sh->slice_interp = (meso_slice_interp)((sh->slice_interp + 1) % MESO_SLICE_INTERP_COUNT);
    else if (key == GLFW_KEY_X)
        sh->slice_axis = (meso_slice_axis)((sh->slice_axis + 1) % MESO_SLICE_AXIS_COUNT);
    else if (key == GLFW_KEY_COMMA)
        sh->slices = sh->slices > 4 ? sh->slices / 2 : 2;
    else if (key == GLFW_KEY_PERIOD)
        sh->slices = sh->slices < 512 ? sh->slices * 2 : 1024;
    else if (key == GLFW_KEY_LEFT_BRACKET)
        sh->error_px = fmaxf(sh->error_px * 0.5f, 0.0625f);
    else if (key == GLFW_KEY_RIGHT_BRACKET)
        sh->error_px = fminf(sh->error_px * 2.0f, 64.0f);
    else if (key == GLFW_KEY_MINUS) {
        sh->max_steps = sh->max_steps > 4 ? sh->max_steps / 2 : 4;
        d->frusta.relief_steps = d->frusta.relief_steps > 2 ? d->frusta.relief_steps / 2 : 2;
    } else if (key == GLFW_KEY_EQUAL) {
        sh->max_steps = sh->max_steps < 4096 ? sh->max_steps * 2 : 4096;
        d->frusta.relief_steps = d->frusta.relief_steps < 1024 ? d->frusta.relief_steps * 2 : 1024;
    }
    else if (key == GLFW_KEY_B) { /* one count for every kind's bisection */
        sh->bisection_steps = sh->bisection_steps >= 8 ? 1 : sh->bisection_steps + 1;
        d->frusta.bisection_steps = d->cells.bisection_steps = sh->bisection_steps;
    } else if (key == GLFW_KEY_D)
        sh->no_distance_map = !sh->no_distance_map;
    else if (key == GLFW_KEY_A)
        k->animate = !k->animate;
    else if (key == GLFW_KEY_M)
        d->cells.mode = (meso_cells_mode)((d->cells.mode + 1) % 3);
    else if (key == GLFW_KEY_N)
        d->cells.bounces = (d->cells.bounces + 1) % 4;
    else if (key == GLFW_KEY_L)
        d->cells.step = d->cells.step > 0.0f ? 0.0f : 8.0f;
    else if (key == GLFW_KEY_O) { /* below 1/8 px: the finest levels (< 0); 0 is libmeso's default, 1 px */
        const float t = d->pixel_error == 0.0f ? 1.0f : d->pixel_error;
        d->pixel_error = t < 0.0f ? -1.0f : t > 0.125f ? t * 0.5f : -1.0f;
    } else if (key == GLFW_KEY_P) {
        const float t = d->pixel_error == 0.0f ? 1.0f : d->pixel_error;
        d->pixel_error = t < 0.0f ? 0.125f : fminf(t * 2.0f, 64.0f);
    }
    else
        return;
    k->changed = 1;
}

/* Host-side copy of a shell's base mesh and directors, for animation. */
typedef struct shell_anim {
    meso_rt_object obj;
    uint32_t n, layers;
    float *pos0, *dir0, *pos, *dir;
} shell_anim;

/* Reads the object's MESH positions and SDIR chunk (as a host would keep its
 * own skinned mesh). 0 when the object is not a shell. */
static int anim_load(meso_file* f, const meso_rt* rt, meso_rt_object obj, uint32_t id, shell_anim* a)
{
    memset(a, 0, sizeof(*a));
    a->obj = obj;
    if (meso_rt_shell_info(rt, obj, &a->n, &a->layers) != MESO_OK || a->n == 0)
        return 0;
    /* Level 0's chunks (FORMAT.md 7.10: a levelled shell's SDIR sits at its
     * coarsest native lod, which level 0 resolves to as well). */
    const int mi = meso_file_find_level(f, MESO_CHUNK_MESH, id, 0), di = meso_file_find_level(f, MESO_CHUNK_SDIR, id, 0);
    if (mi < 0 || di < 0)
        return 0;
    const meso_chunk_info* mc = meso_file_chunk(f, (uint32_t)mi);
    void* mesh = malloc((size_t)mc->decoded_size);
    a->pos0 = malloc(sizeof(float) * 3 * a->n);
    a->pos = malloc(sizeof(float) * 3 * a->n);
    a->dir0 = malloc(sizeof(float) * 3 * a->n * a->layers);
    a->dir = malloc(sizeof(float) * 3 * a->n * a->layers);
    meso_error err;
    meso_mesh_view mv;
    int ok = mesh && a->pos0 && a->pos && a->dir0 && a->dir &&
             meso_file_read_chunk(f, (uint32_t)mi, mesh, (size_t)mc->decoded_size, &err) == MESO_OK &&
             meso_mesh_parse(mesh, (size_t)mc->decoded_size, &mv, &err) == MESO_OK && mv.layout.vertex_count == a->n &&
             meso_file_read_chunk(f, (uint32_t)di, a->dir0, sizeof(float) * 3 * a->n * a->layers, &err) == MESO_OK;
    if (ok)
        memcpy(a->pos0, mv.positions, sizeof(float) * 3 * a->n);
    free(mesh);
    if (!ok) {
        free(a->pos0);
        free(a->pos);
        free(a->dir0);
        free(a->dir);
        memset(a, 0, sizeof(*a));
    }
    return ok;
}

/* Twist about the vertical axis through `c`: angle grows with height. */
static void anim_step(meso_rt* rt, shell_anim* a, double time, const double c[3], double radius)
{
    const double amp = 0.6 * sin(time);
    for (uint32_t v = 0; v < a->n; ++v) {
        const float* p = a->pos0 + 3 * (size_t)v;
        const double ang = amp * (p[1] - c[1]) / radius, cs = cos(ang), sn = sin(ang);
        a->pos[3 * v + 0] = (float)(c[0] + cs * (p[0] - c[0]) + sn * (p[2] - c[2]));
        a->pos[3 * v + 1] = p[1];
        a->pos[3 * v + 2] = (float)(c[2] - sn * (p[0] - c[0]) + cs * (p[2] - c[2]));
        for (uint32_t l = 0; l < a->layers; ++l) {
            const float* d = a->dir0 + 3 * ((size_t)l * a->n + v);
            float* o = a->dir + 3 * ((size_t)l * a->n + v);
            o[0] = (float)(cs * d[0] + sn * d[2]);
            o[1] = d[1];
            o[2] = (float)(-sn * d[0] + cs * d[2]);
        }
    }
    meso_rt_shell_update(rt, a->obj, a->pos, a->dir, a->n);
}

/* Host-side skeleton of a frusta object, for the sway animation. */
typedef struct frusta_anim {
    meso_rt_object obj;
    uint32_t n;
    float *rest, *pos;
    int32_t* parent;
    double* rot; /* 9 per node: the node's accumulated rotation (row-major) */
} frusta_anim;

/* The rest pose and hierarchy through the runtime. 0 when not frusta. */
static int frusta_anim_load(const meso_rt* rt, meso_rt_object obj, frusta_anim* a)
{
    memset(a, 0, sizeof(*a));
    a->obj = obj;
    uint32_t segments = 0;
    if (meso_rt_frusta_info(rt, obj, &segments, &a->n) != MESO_OK || segments == 0 || a->n == 0)
        return 0;
    a->rest = malloc(sizeof(float) * 3 * a->n);
    a->pos = malloc(sizeof(float) * 3 * a->n);
    a->parent = malloc(sizeof(int32_t) * a->n);
    a->rot = malloc(sizeof(double) * 9 * a->n);
    if (!a->rest || !a->pos || !a->parent || !a->rot ||
        meso_rt_frusta_rest_pose(rt, obj, a->rest, a->parent, a->n) != MESO_OK) {
        free(a->rest);
        free(a->pos);
        free(a->parent);
        free(a->rot);
        memset(a, 0, sizeof(*a));
        return 0;
    }
    return 1;
}

static void frusta_anim_free(frusta_anim* a)
{
    free(a->rest);
    free(a->pos);
    free(a->parent);
    free(a->rot);
}

/* Sway: node i turns about its parent by a small angle that oscillates in
 * time (a different phase per node, about an axis ⟂ to its bone and the
 * vertical), on top of its parent's own turn: a plant in the wind. Parents
 * come before children in SKEL, so one pass suffices. */
static void frusta_anim_step(meso_rt* rt, frusta_anim* a, double time)
{
    for (uint32_t i = 0; i < a->n; ++i) {
        double* R = a->rot + 9 * (size_t)i;
        const int32_t p = a->parent[i];
        if (p < 0 || (uint32_t)p >= i) {
            static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            memcpy(R, id, sizeof(id));
            memcpy(a->pos + 3 * (size_t)i, a->rest + 3 * (size_t)i, sizeof(float) * 3);
            continue;
        }
        double b[3], ax[3];
        for (int k = 0; k < 3; ++k)
            b[k] = a->rest[3 * (size_t)i + k] - a->rest[3 * (size_t)p + k];
        ax[0] = b[2], ax[1] = 0.0, ax[2] = -b[0]; /* b × up */
        double l = sqrt(ax[0] * ax[0] + ax[2] * ax[2]);
        if (l < 1e-12)
            ax[0] = 1.0, ax[2] = 0.0, l = 1.0;
        ax[0] /= l, ax[2] /= l;
        const double ang = 0.12 * sin(1.3 * time + 0.9 * (double)(i % 17)), c = cos(ang), sn = sin(ang);
        /* Rodrigues: L = I cos + sin [ax]x + (1 − cos) ax axᵀ, then R = R_parent · L. */
        const double L[9] = {c + (1 - c) * ax[0] * ax[0], -sn * ax[2], sn * ax[1] + (1 - c) * ax[0] * ax[2],
                             sn * ax[2], c, -sn * ax[0],
                             -sn * ax[1] + (1 - c) * ax[2] * ax[0], sn * ax[0], c + (1 - c) * ax[2] * ax[2]};
        const double* P = a->rot + 9 * (size_t)p;
        for (int r = 0; r < 3; ++r)
            for (int cc = 0; cc < 3; ++cc)
                R[3 * r + cc] = P[3 * r] * L[cc] + P[3 * r + 1] * L[3 + cc] + P[3 * r + 2] * L[6 + cc];
        for (int k = 0; k < 3; ++k)
            a->pos[3 * (size_t)i + k] =
                (float)(a->pos[3 * (size_t)p + k] + R[3 * k] * b[0] + R[3 * k + 1] * b[1] + R[3 * k + 2] * b[2]);
    }
    meso_rt_frusta_set_pose(rt, a->obj, a->pos, a->n);
}

typedef struct orbit {
    double yaw, pitch, zoom; /* degrees, degrees, distance factor */
    double last_x, last_y;
    int dragging;
} orbit;

static void on_scroll(GLFWwindow* w, double dx, double dy)
{
    (void)dx;
    orbit* o = ((orbit**)glfwGetWindowUserPointer(w))[0];
    o->zoom *= pow(0.9, dy);
    o->zoom = fmin(fmax(o->zoom, 0.05), 20.0);
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
    return example_save_screenshot(gl->ReadPixels, win, path, "mesoview");
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
    knobs kn = {.d = {.shell = {.error_px = 1.0f, .max_steps = 256, .bisection_steps = 4, .slices = 16},
                      .frusta = {.relief_steps = 64, .bisection_steps = 4},
                      .cells = {.bounces = 1, .bisection_steps = 4}}};
    const char *file = NULL, *shot = NULL, *keys = "";
    int print_title = 0;
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
        } else if (!strcmp(a, "--cells") && i + 1 < argc) {
            const char* m = argv[++i];
            int found = -1;
            for (int k = 0; k < 3; ++k)
                if (!strcmp(m, cell_mode_names[k]))
                    found = k;
            if (found < 0) {
                fprintf(stderr, "mesoview error: --cells expects first, reflect or refract, got '%s'\n", m);
                return 1;
            }
            kn.d.cells.mode = (meso_cells_mode)found;
        } else if (!strcmp(a, "--frames") && i + 1 < argc) {
            frames = atoi(argv[++i]);
        } else if (!strcmp(a, "--screenshot") && i + 1 < argc) {
            shot = argv[++i];
        } else if (!strcmp(a, "--technique") && i + 1 < argc) {
            const char* t = argv[++i];
            int found = -1;
            for (int k = 0; k < MESO_SHELL_TECHNIQUE_COUNT; ++k)
                if (!strcmp(t, technique_names[k]))
                    found = k;
            if (found < 0) {
                fprintf(stderr, "mesoview error: --technique expects smooth, curved, tetra, segment or slices, got '%s'\n",
                        t);
                return 1;
            }
            kn.d.shell.technique = (meso_shell_technique)found;
        } else if (!strcmp(a, "--slices") && i + 1 < argc) {
            kn.d.shell.slices = atoi(argv[++i]);
            if (kn.d.shell.slices < 2 || kn.d.shell.slices > 1024) {
                fprintf(stderr, "mesoview error: --slices expects 2..1024\n");
                return 1;
            }
        } else if (!strcmp(a, "--slice-interp") && i + 1 < argc) {
            const char* m = argv[++i];
            int found = -1;
            for (int k = 0; k < MESO_SLICE_INTERP_COUNT; ++k)
                if (!strcmp(m, interp_names[k]))
                    found = k;
            if (found < 0) {
                fprintf(stderr, "mesoview error: --slice-interp expects texcoord, normal or none, got '%s'\n", m);
                return 1;
            }
            kn.d.shell.slice_interp = (meso_slice_interp)found;
        } else if (!strcmp(a, "--slice-axis") && i + 1 < argc) {
            const char* m = argv[++i];
            if (strcmp(m, "view") && strcmp(m, "levels")) {
                fprintf(stderr, "mesoview error: --slice-axis expects view or levels, got '%s'\n", m);
                return 1;
            }
            kn.d.shell.slice_axis = strcmp(m, "view") ? MESO_SLICE_AXIS_LEVELS : MESO_SLICE_AXIS_VIEW;
        } else if (!strcmp(a, "--error-px") && i + 1 < argc) {
            kn.d.shell.error_px = (float)atof(argv[++i]);
            if (!(kn.d.shell.error_px > 0.0f)) {
                fprintf(stderr, "mesoview error: --error-px expects a positive number\n");
                return 1;
            }
        } else if (!strcmp(a, "--animate")) {
            kn.animate = 1;
        } else if (!strcmp(a, "--keys") && i + 1 < argc) {
            keys = argv[++i];
            for (const char* c = keys; *c; ++c) /* GLFW's printable key codes are their ASCII capitals */
                if (!strchr("12345IX,.[]-=BDAMNLOP", *c)) {
                    fprintf(stderr, "mesoview error: --keys: '%c' is not one of 1-5 I X , . [ ] - = B D A M N L O P\n",
                            *c);
                    return 1;
                }
        } else if (!strcmp(a, "--print-title")) {
            print_title = 1;
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
    shell_anim anims[64];
    frusta_anim fanims[64];
    int nobj = 0, nanim = 0, nfanim = 0;
    meso_file* view_file = NULL; /* open until the end: levelled objects read their levels from it */
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
            /* Objects with levels keep them (the file stays open until the
             * end); the others are uploaded whole, as before. */
            uint32_t levels = 1;
            meso_file_levels(f, recs[i].id, NULL, 0, &levels, NULL);
            if ((levels > 1 ? meso_rt_load_object_levels(rt, f, recs[i].id, &objs[nobj])
                            : meso_rt_load_object(rt, f, recs[i].id, &objs[nobj])) != MESO_OK)
                continue;
            if (anim_load(f, rt, objs[nobj], recs[i].id, &anims[nanim]))
                ++nanim;
            else if (frusta_anim_load(rt, objs[nobj], &fanims[nfanim]))
                ++nfanim;
            float l[3], h[3];
            meso_rt_object_bounds(rt, objs[nobj], l, h);
            for (int k = 0; k < 3; ++k) {
                lo[k] = nobj ? fmin(lo[k], l[k]) : l[k];
                hi[k] = nobj ? fmax(hi[k], h[k]) : h[k];
            }
            ++nobj;
        }
        view_file = f;
        if (nobj == 0)
            fprintf(stderr, "mesoview warning: %s has no object this build can draw\n", file);
    }
    const double centre[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double radius = 0.5 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
    orbit cam = {.yaw = 30, .pitch = 20, .zoom = 1};
    void* user[2] = {&cam, &kn};
    glfwSetWindowUserPointer(win, user);
    glfwSetScrollCallback(win, on_scroll);
    glfwSetKeyCallback(win, on_key);
    double t_last = glfwGetTime(), ms_avg = 0.0, anim_time = 0.0;
    meso_rt_draw_stats stats = {0};

    int rc = 0;
    for (int frame = 0; !glfwWindowShouldClose(win); ++frame) {
        int fw, fh;
        glfwGetFramebufferSize(win, &fw, &fh);
        gl.Viewport(0, 0, fw, fh);
        gl.ClearColor(0.18f, 0.20f, 0.24f, 1.0f);
        gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        if (frame > 0 && *keys) /* --keys: one a frame, through the keyboard's own handler */
            on_key(win, *keys++, 0, GLFW_PRESS, 0);
        if (nobj > 0 && fw > 0 && fh > 0) {
            const double fovy = 35.0 * M_PI / 180.0, dist = cam.zoom * radius / sin(fovy / 2) * 1.05;
            meso_rt_draw_desc d = kn.d;
            d.light_dir[0] = 0.3f, d.light_dir[1] = 0.8f, d.light_dir[2] = 0.5f;
            orbit_view(d.view, centre, cam.yaw * M_PI / 180.0, cam.pitch * M_PI / 180.0, dist);
            meso_camera_perspective(d.proj, fovy, (double)fw / fh, fmax(dist - 1.5 * radius, 1e-3 * dist),
                                    dist + 1.5 * radius);
            if (kn.animate) {
                anim_time += 1.0 / 30.0;
                for (int i = 0; i < nanim; ++i) {
                    anim_step(rt, &anims[i], anim_time, centre, radius);
                    /* a texture function with stored frames (mesobake --frames) plays them */
                    meso_rt_shell_set_time(rt, anims[i].obj, anim_time);
                }
                for (int i = 0; i < nfanim; ++i)
                    frusta_anim_step(rt, &fanims[i], anim_time);
            }
            meso_rt_draw_stats total = {0};
            for (int i = 0; i < nobj; ++i) {
                d.stats = &stats;
                meso_rt_draw(rt, objs[i], &d);
                total.supported |= stats.supported;
                total.fragments += stats.fragments;
                total.steps += stats.steps;
            }
            stats = total;
            meso_rt_frame_end(rt);
        }
        const double t_now = glfwGetTime();
        ms_avg = frame == 0 ? 1e3 * (t_now - t_last) : 0.9 * ms_avg + 100.0 * (t_now - t_last);
        t_last = t_now;
        if (frame % 10 == 0 || kn.changed) {
            char title[384];
            snprintf(title, sizeof(title),
                     "mesoview  %s%s%s%.0d%s  err %.3g px  steps %d  bisect %d%s%s  cells %s/%d%s  %.1f ms/frame",
                     technique_names[kn.d.shell.technique],
                     kn.d.shell.technique == MESO_SHELL_SLICES ? " " : "",
                     kn.d.shell.technique == MESO_SHELL_SLICES ? interp_names[kn.d.shell.slice_interp] : "",
                     kn.d.shell.technique == MESO_SHELL_SLICES ? kn.d.shell.slices : 0,
                     kn.d.shell.technique == MESO_SHELL_SLICES && kn.d.shell.slice_axis == MESO_SLICE_AXIS_LEVELS
                         ? " levels"
                         : "",
                     kn.d.shell.error_px,
                     kn.d.shell.max_steps,
                     kn.d.shell.bisection_steps, kn.d.shell.no_distance_map ? "  no-dist" : "",
                     kn.animate ? "  animated" : "", cell_mode_names[kn.d.cells.mode], kn.d.cells.bounces,
                     kn.d.cells.step > 0 ? " linear" : "", ms_avg);
            meso_rt_budget_state bs;
            meso_rt_budget_state_get(rt, &bs);
            char lods[96] = "";
            for (int i = 0, len = 0; i < nobj && len < 80; ++i) {
                meso_rt_levels_state ls;
                if (meso_rt_levels_state_get(rt, objs[i], &ls) == MESO_OK && ls.level_count > 1)
                    len += snprintf(lods + len, sizeof(lods) - (size_t)len, "%s%d/%u", len ? "," : "",
                                    (int)ls.last_drawn, ls.level_count);
            }
            if (lods[0])
                snprintf(title + strlen(title), sizeof(title) - strlen(title), "  lod %s at %s%.3g px, %.0f KiB",
                         lods, kn.d.pixel_error < 0 ? "finest " : "",
                         kn.d.pixel_error < 0 ? 0.0 : kn.d.pixel_error == 0 ? 1.0 : (double)kn.d.pixel_error,
                         (double)bs.bytes_resident / 1024.0);
            if (stats.supported && stats.fragments)
                snprintf(title + strlen(title), sizeof(title) - strlen(title), "  %.1f steps/fragment",
                         (double)stats.steps / (double)stats.fragments);
            glfwSetWindowTitle(win, title);
            if (print_title && (frame == 0 || kn.changed))
                printf("%s\n", title);
            kn.changed = 0;
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
    for (int i = 0; i < nfanim; ++i)
        frusta_anim_free(&fanims[i]);
    for (int i = 0; i < nanim; ++i) {
        free(anims[i].pos0);
        free(anims[i].pos);
        free(anims[i].dir0);
        free(anims[i].dir);
    }
    meso_rt_destroy(rt);
    meso_file_close(view_file);
    glfwDestroyWindow(win);
    glfwTerminate();
    return rc;
}
