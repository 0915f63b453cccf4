/*
 * preview.c — `mesoinspect preview FILE -o OUT.png`: render a .meso file
 * headlessly with libmeso on an EGL surfaceless context (Mesa llvmpipe when
 * there is no GPU) and write a PNG. --api gles renders through an OpenGL
 * ES 3.2 context instead of desktop OpenGL core (libmeso runs on both).
 *
 * The camera orbits the union of the objects' bounds (from the OBJT records)
 * at --yaw/--pitch, framed so the bounding sphere fills the view. The image
 * is rendered at twice the size and box-filtered down (4 samples a pixel).
 *
 * --reference renders the shell, frusta and cells objects with the exact CPU
 * ray casters (runtime/reference/shell_reference.h, frustum_reference.h,
 * cell_reference.h)
 * instead: no EGL, the same camera, light, clear colour and 2x2 box filter,
 * so the two PNGs compare pixel by pixel. Several objects are composited by
 * depth (the nearest sample wins, as GL_LESS).
 *
 * --pass depth | gbuffer draws libmeso's other passes (meso_rt_pass): the
 * depth buffer as grey, or one PNG per G-buffer attachment plus the depth,
 * all staged and published together.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "cli_common.h"
#include "cli_output.h"
#include "inspect.h"
#include "mesh_chunk.h"
#include "meso_file.h"
#include "meso_rt.h"
#include "png_io.h"
#include "cell_reference.h"
#include "frustum_reference.h"
#include "shell_reference.h"

/* The PNGs go to staged outputs (cli_output.h), published together and
 * whole once all are written. */
/* The PNGs and, when `text_path` is given, one text file (--stats), staged
 * and published together. */
static int write_pngs_and(const char* const* outs, const uint8_t* const* imgs, int n, int width, int height,
                          const char* text_path, const char* text)
{
    if (text_path) {
        meso_output* o = NULL;
        int code = mi_stage_output(text_path, &o);
        meso_error e;
        if (code == MESO_EXIT_OK && meso_output_write(o, text, strlen(text), &e) != MESO_OK) {
            mi_error("cannot write '%s': %s", text_path, e.message);
            code = MESO_EXIT_IO;
        }
        if (code != MESO_EXIT_OK) {
            cli_outputs_discard();
            return code;
        }
    }
    for (int i = 0; i < n; ++i) {
        meso_output* o = NULL;
        int code = mi_stage_output(outs[i], &o);
        if (code != MESO_EXIT_OK) {
            cli_outputs_discard();
            return code;
        }
        char why[256];
        /* Row 0 of the image is the bottom, as glReadPixels'. */
        if (meso_png_write_rgba8(o->temp, imgs[i], width, height, 1, why, sizeof(why)) != 0) {
            cli_outputs_discard();
            mi_error("cannot write '%s': %s", outs[i], why);
            return MESO_EXIT_IO;
        }
    }
    return mi_publish_outputs();
}

static int write_pngs(const char* const* outs, const uint8_t* const* imgs, int n, int width, int height)
{
    return write_pngs_and(outs, imgs, n, width, height, NULL, NULL);
}

static int write_png(const char* out, const uint8_t* img, int width, int height)
{
    return write_pngs(&out, &img, 1, width, height);
}

/* --pass gbuffer's files: OUT.png -> OUT-albedo.png, OUT-normal.png,
 * OUT-depth.png (a name without .png gets the suffix appended). */
static const char* const gbuffer_parts[3] = {"albedo", "normal", "depth"};
static void gbuffer_paths(const char* out, char paths[3][4096])
{
    size_t stem = strlen(out);
    if (stem >= 4 && !strcmp(out + stem - 4, ".png"))
        stem -= 4;
    for (int i = 0; i < 3; ++i)
        snprintf(paths[i], 4096, "%.*s-%s.png", (int)(stem < 4000 ? stem : 4000), out, gbuffer_parts[i]);
}

static const char* const usage_preview =
    "Usage: mesoinspect preview FILE -o OUT.png [options]\n"
    "\n"
    "Render every drawable object of FILE headlessly (EGL + libmeso) into a PNG.\n"
    "FILE is first checked as 'mesoinspect validate --full' does; a file with\n"
    "issues is not drawn: they are listed on stderr and the exit code is 3.\n"
    "\n"
    "  -o, --output FILE   PNG to write (atomically; a symbolic link is written through,\n"
    "                      a device, FIFO or directory refused)\n"
    "      --size WxH      image size (default 512x512)\n"
    "      --object ID     draw only this object (its id, or its name as 'mesoinspect info'\n"
    "                      lists it)\n"
    "      --yaw DEG       camera azimuth around +y (default 30)\n"
    "      --pitch DEG     camera elevation (default 20)\n"
    "      --zoom Z        move the camera Z times closer (default 1: the bounds fill the view)\n"
    "      --api A         gl (default: desktop OpenGL core) or gles (OpenGL ES 3.2)\n"
    "      --technique T   shell technique: smooth (default), curved, tetra or slices\n"
    "                      (slice-based rendering, the Lp-averaged shells paper's section 5)\n"
    "      --slices N      slices: slice polygons per prism (2..1024, default 16)\n"
    "      --slice-interp I  slices: texcoord (default: the paper's two passes), normal or none\n"
    "      --slice-axis X  slices: view (default: per prism the family of slices the view\n"
    "                      crosses most densely) or levels (always the levels of constant w)\n"
    "      --depth D       standard (default: GL_LESS, clip depth -1..1, a far plane) or\n"
    "                      reversed (reversed-Z: GL_GREATER, glClipControl 0..1, no far\n"
    "                      plane), drawn through libmeso's depth conventions; the images\n"
    "                      agree (tests/gl/test_rt_conventions.c)\n"
    "      --time T        shells with stored frames (mesobake --frames): draw the frame\n"
    "                      shown at T seconds (meso_rt_shell_set_time, or the reference's\n"
    "                      meso_ref_shell_set_time; default: frame 0)\n"
    "      --reference     render the shell, frusta and cells objects with the exact CPU\n"
    "                      reference (runtime/reference; no EGL needed, slow).\n"
    "                      --technique curved selects the curved shell mapping,\n"
    "                      smooth, tetra and slices the smooth one; mesh objects are skipped\n"
    "      --samples N     reference: samples per prism along each ray (default 1024)\n"
    "      --level L       reference: draw each shell, frusta and cells object's native level L\n"
    "                      (its own texture, relief or tile map, FORMAT.md 7.10), not level 0;\n"
    "                      an object whose level L is a mesh stand-in, or that has no level\n"
    "                      L, is left out with a note on stderr\n"
    "      --cells MODE    cells objects: first (first hit, default), reflect or refract\n"
    "      --bounces N     cells: reflected rays traced after the first hit, or refraction\n"
    "                      events after it (0..8, default 2)\n"
    "      --cell-step S   cells: the thesis's linear search at S tile-map voxels a step\n"
    "                      (default 0: exact voxel traversal; the reference is always exact)\n"
    "      --pass P        what libmeso draws (meso_rt_draw_desc.pass; not with --reference):\n"
    "                      forward (default): the shaded image;\n"
    "                      depth: the depth-only pass, written as a greyscale PNG of linear\n"
    "                      eye depth (distance along the view axis): 255 at the nearest hit,\n"
    "                      32 at the farthest, linear in between, 0 where nothing was hit\n"
    "                      (then 2x2 box-filtered like the colour);\n"
    "                      gbuffer: the G-buffer pass into OUT-albedo.png (linear albedo as\n"
    "                      stored, no sRGB encoding), OUT-normal.png (world-space normal,\n"
    "                      rgb = n * 0.5 + 0.5) and OUT-depth.png (as depth) beside OUT.png,\n"
    "                      which is not written; background: the forward clear colour.\n"
    "                      Slices: with --slice-interp none only\n";
static const char* const usage_preview_levels =
    "      --pixel-error T levels of detail (FORMAT.md 7.10): each object draws its coarsest level\n"
    "                      whose error covers at most T pixels of the image (default 1);\n"
    "                      0: the finest levels everywhere\n"
    "      --stream-bytes N draw as if only the first N bytes of FILE had arrived: levels\n"
    "                      whose chunks end later are not read (an object none of whose\n"
    "                      levels has arrived is left out, with a note on stderr)\n"
    "      --stats FILE    write what the draw cost as JSON: per object levels_drawn (its\n"
    "                      lod; drawn in parts, the finest part's), level_count and bytes\n"
    "                      (drawn in parts: also part_levels_drawn, each part's level);\n"
    "                      bytes_resident (file bytes), gpu_bytes_resident (what the\n"
    "                      uploads hold on the GPU, the unit of libmeso's memory budget;\n"
    "                      per object also gpu_bytes_estimated, the budget's estimate\n"
    "                      before upload) and bytes_read over\n"
    "                      all objects; steps_per_pixel and fragments_per_pixel (shader\n"
    "                      work per covered pixel of the rendered image, which is 2x2\n"
    "                      the PNG's; 0 where the context cannot count); gpu_ms (wall time\n"
    "                      of the draws between two glFinish calls: on llvmpipe the GPU is\n"
    "                      the CPU); not with --reference\n"
    "  -h, --help          this help\n";

/* The options that change the drawing. */
typedef struct preview_knobs {
    meso_shell_technique technique;
    int slices;
    meso_slice_interp slice_interp;
    meso_slice_axis slice_axis;
    meso_cells_mode cell_mode;
    int cell_bounces;
    float cell_step;
    double zoom;
    int has_time;
    double time; /* with has_time: seconds, for shells with stored frames */
    int reversed; /* --depth reversed: reversed-Z, 0..1 clip depth, infinite far plane */
    int gles;    /* --api gles: an OpenGL ES 3.2 context */
    meso_rt_pass pass;
    double pixel_error;    /* --pixel-error: pixels of the PNG (0: finest) */
    uint64_t stream_bytes; /* --stream-bytes: 0 = the whole file */
    const char* stats;     /* --stats FILE or NULL */
    int level;             /* --level L with --reference: a native level's own chunks; -1: level 0 */
} preview_knobs;

/* Background: the GL preview's clear colour. */
static const float clear_rgb[3] = {0.18f, 0.20f, 0.24f};

/* The preview camera and light for objects within [lo, hi] (both renderers). */
static void preview_camera(const double lo[3], const double hi[3], int width, int height, double yaw, double pitch,
                           double zoom, meso_rt_draw_desc* d)
{
    const double centre[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double radius = 0.5 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const double fovy = 35.0 * M_PI / 180.0, aspect = (double)width / height;
    const double fit = fmin(fovy, 2 * atan(tan(fovy / 2) * aspect));
    const double dist = (radius > 0 ? radius : 1.0) / sin(fit / 2) * 1.05 / zoom;
    const double y = yaw * M_PI / 180.0, p = pitch * M_PI / 180.0;
    const double eye[3] = {centre[0] + dist * cos(p) * sin(y), centre[1] + dist * sin(p),
                           centre[2] + dist * cos(p) * cos(y)};
    const double up[3] = {0, 1, 0};
    meso_camera_look_at(d->view, eye, centre, up);
    meso_camera_perspective(d->proj, fovy, aspect, fmax(dist - 1.5 * radius, 1e-3 * dist), dist + 1.5 * radius);
    /* Light from the upper left of the viewer. */
    const double ly = y - 0.6, lp = p + 0.7;
    d->light_dir[0] = (float)(cos(lp) * sin(ly));
    d->light_dir[1] = (float)sin(lp);
    d->light_dir[2] = (float)(cos(lp) * cos(ly));
}

/* 2x2 box filter of a (2 width) x (2 height) RGBA8 image, as the GL path. */
static void box_filter(const uint8_t* px, uint8_t* img, int width, int height)
{
    const size_t W = 2 * (size_t)width;
    for (int yy = 0; yy < height; ++yy)
        for (int xx = 0; xx < width; ++xx)
            for (int k = 0; k < 4; ++k) {
                const uint8_t* s = px + 4 * ((size_t)(2 * yy) * W + (size_t)(2 * xx)) + k;
                const unsigned sum = s[0] + s[4] + s[4 * W] + s[4 * W + 4];
                img[4 * ((size_t)yy * (size_t)width + (size_t)xx) + (size_t)k] = (uint8_t)((sum + 2) / 4);
            }
}

static uint8_t unorm8(float c)
{
    return (uint8_t)lrintf(fminf(fmaxf(c, 0.0f), 1.0f) * 255.0f);
}

#define PREVIEW_MAX_REF 64 /* shell, frusta and cells objects the reference renders */

/* One object the reference renders. */
typedef struct ref_object {
    uint32_t kind;
    meso_ref_shell shell;
    meso_ref_frusta frusta;
    meso_ref_cells cells;
} ref_object;

/* --level L: whether the reference can draw object `rec`'s level L (a
 * native level: the shell, frusta and cells references load a level's own
 * chunks); otherwise a note on stderr saying why not. */
static int native_level(meso_file* f, const meso_object_record* rec, uint16_t lod)
{
    uint32_t n = 0;
    meso_level_info li;
    meso_error err;
    if (meso_file_levels(f, rec->id, NULL, 0, &n, &err) != MESO_OK || lod >= n) {
        fprintf(stderr, "mesoinspect: object %u (%s) has %u level%s, no level %u: left out\n", rec->id, rec->name, n,
                n == 1 ? "" : "s", lod);
        return 0;
    }
    meso_level_info* all = malloc(sizeof(*all) * n);
    const int ok = all && meso_file_levels(f, rec->id, all, n, &n, &err) == MESO_OK;
    if (ok)
        li = all[lod];
    free(all);
    if (!ok)
        return 0;
    if (li.rec.form != MESO_LEVEL_NATIVE) {
        fprintf(stderr, "mesoinspect: object %u (%s): level %u is a mesh stand-in, which the reference does not "
                        "draw: left out\n",
                rec->id, rec->name, lod);
        return 0;
    }
    return 1;
}

static int render_reference(const char* path, const char* out, int width, int height, uint32_t only, double yaw,
                            double pitch, int curved, int samples, const preview_knobs* knobs)
{
    int code = MESO_EXIT_OK;
    meso_file* f = NULL;
    ref_object* objs = calloc(PREVIEW_MAX_REF, sizeof(*objs));
    meso_object_record* recs = NULL;
    int nobj = 0;
    uint8_t *px = NULL, *img = NULL;
    float* zbuf = NULL;
    meso_decoder dec = meso_bake_draco_decoder();
    meso_error err;
    if (!objs) {
        fprintf(stderr, "mesoinspect error: out of memory\n");
        return MESO_EXIT_INTERNAL;
    }
    meso_result r = meso_file_open_path(path, &(meso_open_desc){.decoders = &dec, .decoder_count = dec.decode_fn ? 1 : 0},
                                        &f, &err);
    if (r != MESO_OK) {
        fprintf(stderr, "mesoinspect error: %s%s%s\n", strstr(err.message, path) ? "" : path,
                strstr(err.message, path) ? "" : ": ", err.message);
        free(objs);
        return meso_exit_for(r);
    }
    /* The framing covers what the GL preview would draw (meshes, shells,
     * frusta and cells), so the two images share a camera. */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    uint32_t count = 0;
    recs = mi_all_records(f, &count, &r);
    if (!recs) {
        code = meso_exit_for(r);
        goto done;
    }
    for (uint32_t i = 0; i < count; ++i) {
        const meso_object_record* rec = &recs[i];
        if ((only && rec->id != only) ||
            (rec->kind != MESO_OBJECT_MESH && rec->kind != MESO_OBJECT_SHELL && rec->kind != MESO_OBJECT_FRUSTA &&
             rec->kind != MESO_OBJECT_CELLS))
            continue;
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], rec->bbox_min[k]);
            hi[k] = fmax(hi[k], rec->bbox_max[k]);
        }
        if (rec->kind == MESO_OBJECT_MESH) {
            fprintf(stderr,
                    "mesoinspect warning: object %u (%s) is a mesh; --reference renders shells, frusta and cells "
                    "only\n",
                    rec->id, rec->name);
            continue;
        }
        if (nobj == PREVIEW_MAX_REF) {
            fprintf(stderr, "mesoinspect warning: more than %d objects; object %u (%s) is skipped\n", PREVIEW_MAX_REF,
                    rec->id, rec->name);
            continue;
        }
        const uint16_t lod = knobs->level > 0 ? (uint16_t)knobs->level : 0;
        if (lod && !native_level(f, rec, lod))
            continue;
        ref_object* o = &objs[nobj];
        o->kind = rec->kind;
        r = rec->kind == MESO_OBJECT_SHELL    ? meso_ref_shell_load_level(f, rec->id, lod, &o->shell, &err)
            : rec->kind == MESO_OBJECT_FRUSTA ? meso_ref_frusta_load_level(f, rec->id, lod, &o->frusta, &err)
                                              : meso_ref_cells_load_level(f, rec->id, lod, &o->cells, &err);
        if (r == MESO_OK && rec->kind == MESO_OBJECT_SHELL && knobs->has_time)
            r = meso_ref_shell_set_time(f, rec->id, knobs->time, &o->shell, &err);
        if (r != MESO_OK) {
            fprintf(stderr, "mesoinspect error: %s\n", err.message);
            code = meso_exit_for(r);
            goto done;
        }
        ++nobj;
    }
    if (nobj == 0 && knobs->level > 0) {
        fprintf(stderr, "mesoinspect error: %s: no %sshell, frusta or cells object has a native level %d\n", path,
                only ? "such " : "", knobs->level);
        code = MESO_EXIT_UNSUPPORTED;
        goto done;
    }
    if (nobj == 0) {
        fprintf(stderr, "mesoinspect error: %s: no shell, frusta or cells object%s\n", path,
                only ? " with that id" : "");
        code = only ? MESO_EXIT_USAGE : MESO_EXIT_UNSUPPORTED;
        goto done;
    }
    meso_rt_draw_desc d = {0};
    preview_camera(lo, hi, width, height, yaw, pitch, knobs->zoom, &d);
    const int W = 2 * width, H = 2 * height;
    meso_ref_view v = {.width = W, .height = H, .curved = curved, .samples_per_prism = samples};
    for (int k = 0; k < 16; ++k) {
        v.view[k] = d.view[k];
        v.proj[k] = d.proj[k];
    }
    for (int k = 0; k < 3; ++k)
        v.light_dir[k] = d.light_dir[k];
    const size_t n = (size_t)W * (size_t)H;
    px = malloc(n * 4);
    img = malloc((size_t)width * (size_t)height * 4);
    zbuf = malloc(n * sizeof(float));
    if (!px || !img || !zbuf) {
        fprintf(stderr, "mesoinspect error: out of memory\n");
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k)
            px[4 * i + (size_t)k] = unorm8(clear_rgb[k]);
        px[4 * i + 3] = 255;
        zbuf[i] = 1.0f;
    }
    /* Several objects: the nearest hit per sample (GL_LESS). */
    for (int s = 0; s < nobj; ++s) {
        meso_ref_image ri;
        const meso_ref_cells_opts co = {.mode = (int)knobs->cell_mode, .bounces = knobs->cell_bounces};
        r = objs[s].kind == MESO_OBJECT_SHELL    ? meso_ref_render(&objs[s].shell, &v, &ri)
            : objs[s].kind == MESO_OBJECT_FRUSTA ? meso_ref_frusta_render(&objs[s].frusta, &v, &ri)
                                                 : meso_ref_cells_render(&objs[s].cells, &v, &co, &ri);
        if (r != MESO_OK) {
            fprintf(stderr, "mesoinspect error: reference render failed: %s\n", meso_result_string(r));
            code = MESO_EXIT_INTERNAL;
            goto done;
        }
        for (size_t i = 0; i < n; ++i)
            if (ri.coverage[i] && ri.depth[i] < zbuf[i]) {
                zbuf[i] = ri.depth[i];
                for (int k = 0; k < 3; ++k)
                    px[4 * i + (size_t)k] = unorm8(ri.rgb[3 * i + (size_t)k]);
            }
        meso_ref_image_free(&ri);
    }
    box_filter(px, img, width, height);
    /* Row 0 of the reference image is the bottom, as glReadPixels'. */
    code = write_png(out, img, width, height);
done:
    for (int s = 0; s < nobj; ++s) {
        meso_ref_shell_free(&objs[s].shell);
        meso_ref_frusta_free(&objs[s].frusta);
        meso_ref_cells_free(&objs[s].cells);
    }
    free(objs);
    free(recs);
    free(px);
    free(img);
    free(zbuf);
    meso_file_close(f);
    return code;
}

#if MESO_HAVE_EGL
#include <GL/glcorearb.h>

#include "egl_context.h"
#include "meso_clock.h"

/* --stats: the draw's cost as JSON (a malloc'd string). */
static char* preview_stats_json(meso_rt* rt, const meso_rt_object* objs, const uint32_t* ids, int n, uint64_t steps,
                                uint64_t fragments, int counted, uint64_t covered, double gpu_ms, uint64_t stream)
{
    size_t cap = 512 + (size_t)n * 288, len = 0;
    for (int i = 0; i < n; ++i) { /* room for each part's level (FORMAT.md 7.11) */
        uint32_t parts = 0;
        meso_rt_parts_state_get(rt, objs[i], NULL, 0, &parts);
        cap += 4 * (size_t)parts;
    }
    char* s = malloc(cap);
    if (!s)
        return NULL;
    uint64_t resident = 0, read = 0, gpu = 0;
    len += (size_t)snprintf(s + len, cap - len, "{\n  \"objects\": [");
    for (int i = 0; i < n; ++i) {
        meso_rt_levels_state ls;
        meso_rt_levels_state_get(rt, objs[i], &ls);
        resident += ls.bytes_resident;
        read += ls.bytes_read;
        gpu += ls.gpu_bytes_resident;
        len += (size_t)snprintf(s + len, cap - len,
                                "%s\n    {\"id\": %u, \"levels_drawn\": %d, \"level_count\": %u, "
                                "\"bytes_resident\": %llu, \"gpu_bytes_resident\": %llu, "
                                "\"gpu_bytes_estimated\": %llu",
                                i ? "," : "", ids[i], (int)ls.last_drawn, ls.level_count,
                                (unsigned long long)ls.bytes_resident, (unsigned long long)ls.gpu_bytes_resident,
                                (unsigned long long)ls.gpu_bytes_estimated);
        /* Drawn in parts: the level each part drew (rt_parts.c); not
         * where the draw drew a whole level. */
        uint32_t parts = 0;
        meso_rt_parts_state_get(rt, objs[i], NULL, 0, &parts);
        uint8_t* pl = parts ? malloc(parts) : NULL;
        if (pl && meso_rt_parts_state_get(rt, objs[i], pl, parts, &parts) == MESO_OK &&
            pl[0] != MESO_RT_PART_NOT_DRAWN) {
            len += (size_t)snprintf(s + len, cap - len, ", \"part_levels_drawn\": [");
            for (uint32_t q = 0; q < parts; ++q)
                len += (size_t)snprintf(s + len, cap - len, "%s%u", q ? "," : "", pl[q]);
            len += (size_t)snprintf(s + len, cap - len, "]");
        }
        free(pl);
        len += (size_t)snprintf(s + len, cap - len, "}");
    }
    const double per = covered ? 1.0 / (double)covered : 0.0;
    len += (size_t)snprintf(s + len, cap - len,
                            "\n  ],\n  \"bytes_resident\": %llu,\n  \"gpu_bytes_resident\": %llu,\n"
                            "  \"bytes_read\": %llu,\n"
                            "  \"stream_bytes\": %llu,\n  \"covered_pixels\": %llu,\n"
                            "  \"steps_per_pixel\": %.4f,\n  \"fragments_per_pixel\": %.4f,\n"
                            "  \"counted\": %s,\n  \"gpu_ms\": %.3f\n}\n",
                            (unsigned long long)resident, (unsigned long long)gpu, (unsigned long long)read,
                            (unsigned long long)stream,
                            (unsigned long long)covered, counted ? (double)steps * per : 0.0,
                            counted ? (double)fragments * per : 0.0, counted ? "true" : "false", gpu_ms);
    (void)len;
    return s;
}

/* --stream-bytes: a reader over FILE that has received only its first
 * `limit` bytes; a read reaching past them answers "not yet"
 * (MESO_IO_PENDING), as a network reader would. */
typedef struct partial_file {
    FILE* fp;
    uint64_t limit;
} partial_file;

static int partial_read(void* user, uint64_t offset, void* dst, size_t size)
{
    partial_file* p = user;
    if (offset > p->limit || size > p->limit - offset)
        return MESO_IO_PENDING;
    if (offset > (uint64_t)LONG_MAX || fseek(p->fp, (long)offset, SEEK_SET) != 0 || fread(dst, 1, size, p->fp) != size)
        return -1;
    return 0;
}

#define PREVIEW_GL(X)                                                                                              \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                        \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers) X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)                \
    X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)              \
    X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage) X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus) X(PFNGLVIEWPORTPROC, Viewport)                        \
    X(PFNGLCLEARCOLORPROC, ClearColor) X(PFNGLCLEARPROC, Clear) X(PFNGLREADPIXELSPROC, ReadPixels)                  \
    X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv) X(PFNGLDEPTHFUNCPROC, DepthFunc)                                       \
    X(PFNGLDRAWBUFFERSPROC, DrawBuffers) X(PFNGLREADBUFFERPROC, ReadBuffer) X(PFNGLFINISHPROC, Finish)

typedef struct preview_gl {
#define M(t, n) t n;
    PREVIEW_GL(M)
#undef M
} preview_gl;

static void on_log(void* user, meso_log_level level, meso_log_item item, const char* message)
{
    (void)user;
    if (level == MESO_LOG_INFO)
        return;
    fprintf(stderr, "mesoinspect %s: libmeso: %s%s%s\n", level == MESO_LOG_ERROR ? "error" : "warning",
            meso_log_item_string(item), message ? ": " : "", message ? message : "");
}

/* Eye depth (along the view axis) of window depth z under proj: standard
 * (-1..1 clip depth, GL_LESS) or, with `reversed`, preview's reversed-Z
 * projection (0..1 clip depth, NDC z = near / depth, proj[14] = near).
 * Negative where nothing was hit (the cleared far value). */
static double eye_depth(float z, const float proj[16], int reversed)
{
    if (reversed)
        return z > 0.0f ? proj[14] / z : -1.0;
    return z < 1.0f ? proj[14] / (2.0 * z - 1.0 + proj[10]) : -1.0;
}

/* The depth buffer (2 width x 2 height window depths) as grey RGBA8: eye
 * depth from proj, 255 at the nearest hit, 32 at the farthest, 0 where
 * nothing was hit (--help). */
static void depth_grey(const float* depth, const float proj[16], int reversed, size_t n, uint8_t* px)
{
    double dmin = INFINITY, dmax = -INFINITY;
    for (size_t i = 0; i < n; ++i) {
        const double dist = eye_depth(depth[i], proj, reversed);
        if (dist >= 0.0) {
            dmin = fmin(dmin, dist);
            dmax = fmax(dmax, dist);
        }
    }
    for (size_t i = 0; i < n; ++i) {
        uint8_t g = 0;
        const double dist = eye_depth(depth[i], proj, reversed);
        if (dist >= 0.0)
            g = (uint8_t)lrint(dmax > dmin ? 32.0 + 223.0 * (dmax - dist) / (dmax - dmin) : 255.0);
        px[4 * i] = px[4 * i + 1] = px[4 * i + 2] = g;
        px[4 * i + 3] = 255;
    }
}

static int render(const char* path, const char* out, int width, int height, uint32_t only, double yaw, double pitch,
                  const preview_knobs* knobs)
{
    char why[256];
    meso_egl* egl = meso_egl_create_api(knobs->gles ? MESO_EGL_GLES : MESO_EGL_GL, 0, why, sizeof(why));
    if (!egl) {
        fprintf(stderr, "mesoinspect error: no headless OpenGL%s: %s\n", knobs->gles ? " ES 3.2" : "", why);
        return MESO_EXIT_UNSUPPORTED;
    }
    preview_gl gl;
    int missing = 0;
#define L(t, n)                                       \
    {                                                 \
        void (*p)(void) = meso_egl_proc("gl" #n);     \
        missing += p == NULL;                         \
        memcpy(&gl.n, &p, sizeof(p));                 \
    }
    PREVIEW_GL(L)
#undef L
    int code = MESO_EXIT_OK;
    meso_rt* rt = NULL;
    meso_file* f = NULL;
    uint8_t *px = NULL, *img = NULL;
    float* depth = NULL;
    meso_rt_object* objs = NULL;
    meso_object_record* recs = NULL;
    uint32_t* obj_ids = NULL;
    char* stats_text = NULL;
    partial_file partial = {NULL, 0};
    int nobj = 0;
    if (missing) {
        fprintf(stderr, "mesoinspect error: the GL context lacks framebuffer objects\n");
        code = MESO_EXIT_UNSUPPORTED;
        goto done;
    }
    if (meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log}, &rt) != MESO_OK) {
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    meso_decoder dec = meso_bake_draco_decoder();
    meso_error err;
    const meso_open_desc od = {.decoders = &dec, .decoder_count = dec.decode_fn ? 1 : 0};
    meso_result r;
    if (knobs->stream_bytes) {
        partial.fp = fopen(path, "rb");
        long end = -1;
        if (partial.fp && fseek(partial.fp, 0, SEEK_END) == 0)
            end = ftell(partial.fp);
        if (end < 0) {
            fprintf(stderr, "mesoinspect error: %s: cannot open: %s\n", path, strerror(errno));
            code = MESO_EXIT_IO;
            goto done;
        }
        partial.limit = knobs->stream_bytes < (uint64_t)end ? knobs->stream_bytes : (uint64_t)end;
        const meso_io io = {.read_fn = partial_read, .size = (uint64_t)end, .user = &partial};
        r = meso_file_open_io(&io, &od, &f, &err);
    } else {
        r = meso_file_open_path(path, &od, &f, &err);
    }
    if (r != MESO_OK) {
        fprintf(stderr, "mesoinspect error: %s%s%s\n", strstr(err.message, path) ? "" : path,
                strstr(err.message, path) ? "" : ": ", err.message);
        code = meso_exit_for(r);
        goto done;
    }
    /* Every object of the OBJT table (or just --object). */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    uint32_t count = 0;
    recs = mi_all_records(f, &count, &r);
    objs = recs ? calloc(count ? count : 1, sizeof(*objs)) : NULL;
    obj_ids = recs ? calloc(count ? count : 1, sizeof(*obj_ids)) : NULL;
    if (!objs || !obj_ids) {
        code = meso_exit_for(recs ? MESO_ERR_OUT_OF_MEMORY : r);
        goto done;
    }
    for (uint32_t i = 0; i < count; ++i) {
        const meso_object_record* rec = &recs[i];
        if (only && rec->id != only)
            continue;
        /* Levelled: each draw picks its level (--pixel-error); the file
         * stays open until the objects are released. */
        r = meso_rt_load_object_levels(rt, f, rec->id, &objs[nobj]);
        meso_rt_levels_state ls = {.resident_mask = 1};
        if (r == MESO_OK && knobs->stream_bytes)
            meso_rt_levels_state_get(rt, objs[nobj], &ls);
        if (r == MESO_OK && ls.resident_mask == 0) { /* loaded, nothing arrived: it would draw nothing */
            meso_rt_release_object(rt, objs[nobj]);
            r = MESO_ERR_PENDING;
        }
        if (r != MESO_OK && r != MESO_ERR_UNSUPPORTED && knobs->stream_bytes) {
            fprintf(stderr, "mesoinspect note: object %u (%s): none of its levels is within the first %llu bytes\n",
                    rec->id, rec->name, (unsigned long long)partial.limit);
            continue;
        }
        if (r == MESO_ERR_UNSUPPORTED && !only) {
            fprintf(stderr, "mesoinspect warning: object %u (%s) cannot be previewed by this build\n", rec->id,
                    rec->name);
            continue;
        }
        if (r == MESO_OK && knobs->has_time && rec->kind == MESO_OBJECT_SHELL) {
            /* Frames are a shell's own: --time draws the object as
             * meso_rt_load_object loads it (its finest level). */
            meso_rt_release_object(rt, objs[nobj]);
            r = meso_rt_load_object(rt, f, rec->id, &objs[nobj]);
            if (r == MESO_OK)
                r = meso_rt_shell_set_time(rt, objs[nobj], knobs->time);
        }
        obj_ids[nobj] = rec->id;
        if (r != MESO_OK) {
            code = meso_exit_for(r);
            goto done;
        }
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], rec->bbox_min[k]);
            hi[k] = fmax(hi[k], rec->bbox_max[k]);
        }
        ++nobj;
    }
    if (nobj == 0) {
        fprintf(stderr, "mesoinspect error: %s: no drawable object%s\n", path, only ? " with that id" : "");
        code = only ? MESO_EXIT_USAGE : MESO_EXIT_UNSUPPORTED;
        goto done;
    }

    const int W = 2 * width, H = 2 * height;
    GLuint fbo, rb[3];
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl.GenRenderbuffers(3, rb);
    /* The G-buffer pass draws into two UNORM attachments (albedo, normal). */
    const GLenum attach[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_DEPTH_ATTACHMENT};
    for (int i = 0; i < 3; ++i) {
        if (i == 1 && knobs->pass != MESO_PASS_GBUFFER)
            continue;
        gl.BindRenderbuffer(GL_RENDERBUFFER, rb[i]);
        gl.RenderbufferStorage(GL_RENDERBUFFER, i == 2 ? GL_DEPTH_COMPONENT32F : GL_RGBA8, W, H);
        gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, attach[i], GL_RENDERBUFFER, rb[i]);
    }
    gl.DrawBuffers(knobs->pass == MESO_PASS_GBUFFER ? 2 : 1, attach);
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        fprintf(stderr, "mesoinspect error: cannot create a %dx%d framebuffer\n", W, H);
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    gl.Viewport(0, 0, W, H);
    meso_rt_draw_desc d = {0};
    preview_camera(lo, hi, width, height, yaw, pitch, knobs->zoom, &d);
    if (knobs->reversed) {
        /* The same frustum, reversed-Z with the far plane at infinity:
         * NDC z = near / distance. */
        PFNGLCLIPCONTROLPROC clip_control = NULL;
        /* OpenGL ES has it as glClipControlEXT (GL_EXT_clip_control, which llvmpipe offers). */
        void (*p)(void) = meso_egl_proc(knobs->gles ? "glClipControlEXT" : "glClipControl");
        memcpy(&clip_control, &p, sizeof(p));
        if (!clip_control || (!knobs->gles && meso_rt_gl_version(rt) < 45)) {
            fprintf(stderr, "mesoinspect error: --depth reversed needs glClipControl (OpenGL 4.5, or ES with "
                            "GL_EXT_clip_control)\n");
            code = MESO_EXIT_UNSUPPORTED;
            goto done;
        }
        clip_control(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
        const float znear = d.proj[14] / (d.proj[10] - 1.0f);
        d.proj[10] = 0.0f;
        d.proj[14] = znear;
        d.depth = MESO_DEPTH_REVERSED;
        d.clip_depth = MESO_CLIP_DEPTH_ZERO_TO_ONE;
        gl.DepthFunc(GL_GREATER);
    }
    const float clear_depth = knobs->reversed ? 0.0f : 1.0f;
    gl.ClearColor(clear_rgb[0], clear_rgb[1], clear_rgb[2], 1.0f);
    gl.Clear(GL_COLOR_BUFFER_BIT);
    gl.ClearBufferfv(GL_DEPTH, 0, &clear_depth); /* glClearDepth is desktop only */

    d.shell.technique = knobs->technique;
    d.shell.slices = knobs->slices;
    d.shell.slice_interp = knobs->slice_interp;
    d.shell.slice_axis = knobs->slice_axis;
    d.cells.mode = knobs->cell_mode;
    d.cells.bounces = knobs->cell_bounces;
    d.cells.step = knobs->cell_step;
    d.pass = knobs->pass;
    /* The image is rendered at 2x2 the PNG's pixels: the error budget in
     * PNG pixels is twice that in the viewport's. */
    d.pixel_error = knobs->pixel_error > 0 ? (float)(2.0 * knobs->pixel_error) : -1.0f;
    meso_rt_draw_stats st_one;
    uint64_t steps = 0, fragments = 0;
    int counted = 1;
    gl.Finish();
    const double t0 = meso_seconds();
    for (int i = 0; i < nobj; ++i) {
        memset(&st_one, 0, sizeof st_one);
        d.stats = knobs->stats ? &st_one : NULL;
        if (meso_rt_draw(rt, objs[i], &d) != MESO_OK) {
            code = MESO_EXIT_INTERNAL;
            goto done;
        }
        steps += st_one.steps;
        fragments += st_one.fragments;
        counted = counted && st_one.supported;
    }
    gl.Finish();
    const double gpu_ms = 1e3 * (meso_seconds() - t0);
    const size_t full = (size_t)W * (size_t)H, small = (size_t)width * (size_t)height * 4;
    px = malloc(full * 4);
    img = malloc(3 * small);
    depth = malloc(full * sizeof(float));
    if (!px || !img || !depth) {
        fprintf(stderr, "mesoinspect error: out of memory\n");
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    /* forward: the colour; depth: the depth as grey; gbuffer: albedo,
     * normal and depth as grey, three files. */
    const int files = knobs->pass == MESO_PASS_GBUFFER ? 3 : 1;
    gl.ReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    for (int i = 0; i < files; ++i) {
        if (knobs->pass == MESO_PASS_DEPTH || i == 2) {
            depth_grey(depth, d.proj, knobs->reversed, full, px);
        } else {
            gl.ReadBuffer(attach[i]);
            gl.ReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, px);
        }
        box_filter(px, img + (size_t)i * small, width, height);
    }
    char paths[3][4096];
    gbuffer_paths(out, paths);
    const char* const outs[3] = {paths[0], paths[1], paths[2]};
    const uint8_t* const imgs[3] = {img, img + small, img + 2 * small};
    if (knobs->stats) {
        /* Covered pixels: where the depth buffer holds a hit. */
        const float clear = knobs->reversed ? 0.0f : 1.0f;
        uint64_t covered = 0;
        for (size_t i = 0; i < full; ++i)
            covered += depth[i] != clear;
        stats_text = preview_stats_json(rt, objs, obj_ids, nobj, steps, fragments, counted, covered, gpu_ms,
                                        partial.limit);
        if (!stats_text) {
            fprintf(stderr, "mesoinspect error: out of memory\n");
            code = MESO_EXIT_INTERNAL;
            goto done;
        }
    }
    if ((code = write_pngs_and(files == 3 ? outs : &out, imgs, files, width, height, knobs->stats, stats_text)) !=
        MESO_EXIT_OK)
        goto done;
    gl.DeleteRenderbuffers(3, rb);
    gl.DeleteFramebuffers(1, &fbo);
done:
    free(px);
    free(img);
    free(depth);
    free(recs);
    free(objs);
    free(obj_ids);
    free(stats_text);
    meso_rt_destroy(rt); /* before the file: levelled objects read from it until released */
    meso_file_close(f);
    if (partial.fp)
        fclose(partial.fp);
    meso_egl_destroy(egl);
    return code;
}
#endif

/* "WxH", each 1..8192; digits only, so nothing can overflow or wrap
 * (sscanf's %d would, and 4294967297 became 1). */
static int parse_size(const char* s, int* w, int* h)
{
    long v[2];
    for (int k = 0; k < 2; ++k) {
        char* end = NULL;
        if (*s < '0' || *s > '9')
            return 0;
        errno = 0;
        v[k] = strtol(s, &end, 10);
        if (errno || v[k] < 1 || v[k] > 8192 || *end != (k == 0 ? 'x' : '\0'))
            return 0;
        s = end + 1;
    }
    *w = (int)v[0];
    *h = (int)v[1];
    return 1;
}

int mesoinspect_preview(int argc, char** argv)
{
    const char *file = NULL, *out = NULL;
    int width = 512, height = 512;
    unsigned long only = 0;
    const char* only_name = NULL;
    double yaw = 30, pitch = 20;
    meso_shell_technique technique = MESO_SHELL_SMOOTH;
    preview_knobs knobs = {.cell_bounces = 2, .zoom = 1.0, .pixel_error = 1.0, .level = -1};
    int reference = 0;
    long samples = 0;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        const int val = i + 1 < argc;
        char* end = NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage_preview, stdout);
            fputs(usage_preview_levels, stdout);
            return MESO_EXIT_OK;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && val) {
            out = argv[++i];
        } else if (!strcmp(a, "--size") && val) {
            if (!parse_size(argv[++i], &width, &height)) {
                fprintf(stderr, "mesoinspect error: --size expects WxH (1..8192), got '%s'\n"
                                "See 'mesoinspect --help'.\n", argv[i]);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--object") && val) {
            const int code = mi_object_option(argv[++i], &only, &only_name);
            if (code != MESO_EXIT_OK)
                return code;
        } else if ((!strcmp(a, "--yaw") || !strcmp(a, "--pitch")) && val) {
            double v = strtod(argv[++i], &end);
            if (!end || *end || !(v >= -360 && v <= 360)) {
                fprintf(stderr, "mesoinspect error: %s expects degrees, got '%s'\nSee 'mesoinspect --help'.\n", a,
                        argv[i]);
                return MESO_EXIT_USAGE;
            }
            *(a[2] == 'y' ? &yaw : &pitch) = v;
        } else if (!strcmp(a, "--technique") && val) {
            const char* t = argv[++i];
            if (!strcmp(t, "smooth"))
                technique = MESO_SHELL_SMOOTH;
            else if (!strcmp(t, "curved"))
                technique = MESO_SHELL_CURVED;
            else if (!strcmp(t, "tetra"))
                technique = MESO_SHELL_TETRA;
            else if (!strcmp(t, "slices"))
                technique = MESO_SHELL_SLICES;
            else {
                fprintf(stderr, "mesoinspect error: --technique expects smooth, curved, tetra or slices, got '%s'\n"
                                "See 'mesoinspect --help'.\n", t);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--slices") && val) {
            const long n = strtol(argv[++i], &end, 10);
            if (!end || *end || n < 2 || n > 1024) {
                fprintf(stderr, "mesoinspect error: --slices expects 2..1024, got '%s'\nSee 'mesoinspect --help'.\n",
                        argv[i]);
                return MESO_EXIT_USAGE;
            }
            knobs.slices = (int)n;
        } else if (!strcmp(a, "--slice-interp") && val) {
            const char* m = argv[++i];
            if (!strcmp(m, "texcoord"))
                knobs.slice_interp = MESO_SLICE_TEXCOORD;
            else if (!strcmp(m, "normal"))
                knobs.slice_interp = MESO_SLICE_NORMAL;
            else if (!strcmp(m, "none"))
                knobs.slice_interp = MESO_SLICE_NONE;
            else {
                fprintf(stderr, "mesoinspect error: --slice-interp expects texcoord, normal or none, got '%s'\n"
                                "See 'mesoinspect --help'.\n", m);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--slice-axis") && val) {
            const char* m = argv[++i];
            if (!strcmp(m, "view"))
                knobs.slice_axis = MESO_SLICE_AXIS_VIEW;
            else if (!strcmp(m, "levels"))
                knobs.slice_axis = MESO_SLICE_AXIS_LEVELS;
            else {
                fprintf(stderr, "mesoinspect error: --slice-axis expects view or levels, got '%s'\n"
                                "See 'mesoinspect --help'.\n", m);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--reference")) {
            reference = 1;
        } else if (!strcmp(a, "--samples") && val) {
            samples = strtol(argv[++i], &end, 10);
            if (!end || *end || samples < 2 || samples > 1000000) {
                fprintf(stderr, "mesoinspect error: --samples expects 2..1000000, got '%s'\n"
                                "See 'mesoinspect --help'.\n", argv[i]);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--level") && val) {
            const long l = strtol(argv[++i], &end, 10);
            if (!end || *end || end == argv[i] || l < 0 || l > 65535) {
                fprintf(stderr, "mesoinspect error: --level expects 0..65535, got '%s'\nSee 'mesoinspect --help'.\n",
                        argv[i]);
                return MESO_EXIT_USAGE;
            }
            knobs.level = (int)l;
        } else if (!strcmp(a, "--time") && val) {
            knobs.time = strtod(argv[++i], &end);
            knobs.has_time = 1;
            if (!end || end == argv[i] || *end || !(knobs.time >= -1e9 && knobs.time <= 1e9)) {
                fprintf(stderr, "mesoinspect error: --time expects seconds, got '%s'\nSee 'mesoinspect --help'.\n",
                        argv[i]);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--depth") && val) {
            const char* m = argv[++i];
            if (!strcmp(m, "standard") || !strcmp(m, "reversed")) {
                knobs.reversed = !strcmp(m, "reversed");
            } else {
                fprintf(stderr, "mesoinspect error: --depth expects standard or reversed, got '%s'\n"
                                "See 'mesoinspect --help'.\n", m);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--zoom") && val) {
            knobs.zoom = strtod(argv[++i], &end);
            if (!end || *end || !(knobs.zoom >= 0.01 && knobs.zoom <= 1000)) {
                fprintf(stderr, "mesoinspect error: --zoom expects 0.01..1000, got '%s'\nSee 'mesoinspect --help'.\n",
                        argv[i]);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--api") && val) {
            const char* m = argv[++i];
            if (strcmp(m, "gl") && strcmp(m, "gles")) {
                fprintf(stderr, "mesoinspect error: --api expects gl or gles, got '%s'\nSee 'mesoinspect --help'.\n",
                        m);
                return MESO_EXIT_USAGE;
            }
            knobs.gles = !strcmp(m, "gles");
        } else if (!strcmp(a, "--cells") && val) {
            const char* m = argv[++i];
            if (!strcmp(m, "first"))
                knobs.cell_mode = MESO_CELLS_FIRST_HIT;
            else if (!strcmp(m, "reflect"))
                knobs.cell_mode = MESO_CELLS_REFLECT;
            else if (!strcmp(m, "refract"))
                knobs.cell_mode = MESO_CELLS_REFRACT;
            else {
                fprintf(stderr, "mesoinspect error: --cells expects first, reflect or refract, got '%s'\n"
                                "See 'mesoinspect --help'.\n", m);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--bounces") && val) {
            const long b = strtol(argv[++i], &end, 10);
            if (!end || *end || b < 0 || b > 8) {
                fprintf(stderr, "mesoinspect error: --bounces expects 0..8, got '%s'\nSee 'mesoinspect --help'.\n",
                        argv[i]);
                return MESO_EXIT_USAGE;
            }
            knobs.cell_bounces = (int)b;
        } else if (!strcmp(a, "--cell-step") && val) {
            const double st = strtod(argv[++i], &end);
            if (!end || *end || !(st >= 0 && st <= 1e6)) {
                fprintf(stderr, "mesoinspect error: --cell-step expects voxels >= 0, got '%s'\n"
                                "See 'mesoinspect --help'.\n", argv[i]);
                return MESO_EXIT_USAGE;
            }
            knobs.cell_step = (float)st;
        } else if (!strcmp(a, "--pixel-error") && val) {
            knobs.pixel_error = strtod(argv[++i], &end);
            if (!end || *end || !(knobs.pixel_error >= 0 && knobs.pixel_error <= 1e6)) {
                fprintf(stderr, "mesoinspect error: --pixel-error expects pixels >= 0, got '%s'\n"
                                "See 'mesoinspect --help'.\n", argv[i]);
                return MESO_EXIT_USAGE;
            }
        } else if (!strcmp(a, "--stream-bytes") && val) {
            const char* v = argv[++i];
            errno = 0;
            const unsigned long long n = strtoull(v, &end, 10);
            if (!end || *end || errno || *v < '0' || *v > '9' || n == 0) {
                fprintf(stderr, "mesoinspect error: --stream-bytes expects a byte count >= 1, got '%s'\n"
                                "See 'mesoinspect --help'.\n", v);
                return MESO_EXIT_USAGE;
            }
            knobs.stream_bytes = n;
        } else if (!strcmp(a, "--stats") && val) {
            knobs.stats = argv[++i];
        } else if (!strcmp(a, "--pass") && val) {
            const char* m = argv[++i];
            if (!strcmp(m, "forward"))
                knobs.pass = MESO_PASS_FORWARD;
            else if (!strcmp(m, "depth"))
                knobs.pass = MESO_PASS_DEPTH;
            else if (!strcmp(m, "gbuffer"))
                knobs.pass = MESO_PASS_GBUFFER;
            else {
                fprintf(stderr, "mesoinspect error: --pass expects forward, depth or gbuffer, got '%s'\n"
                                "See 'mesoinspect --help'.\n", m);
                return MESO_EXIT_USAGE;
            }
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "mesoinspect error: %s '%s'\nSee 'mesoinspect --help'.\n",
                    (!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--size") || !strcmp(a, "--object") ||
                     !strcmp(a, "--yaw") || !strcmp(a, "--pitch") || !strcmp(a, "--technique") ||
                     !strcmp(a, "--samples") || !strcmp(a, "--cells") || !strcmp(a, "--bounces") ||
                     !strcmp(a, "--cell-step") || !strcmp(a, "--zoom") || !strcmp(a, "--time") ||
                     !strcmp(a, "--depth") || !strcmp(a, "--slices") || !strcmp(a, "--slice-interp") ||
                     !strcmp(a, "--slice-axis") || !strcmp(a, "--api") || !strcmp(a, "--pass") ||
                     !strcmp(a, "--pixel-error") || !strcmp(a, "--stream-bytes") || !strcmp(a, "--stats") ||
                     !strcmp(a, "--level"))
                        ? "missing value for option"
                        : "unrecognized option",
                    a);
            return MESO_EXIT_USAGE;
        } else if (!file) {
            file = a;
        } else {
            fprintf(stderr, "mesoinspect error: unexpected argument '%s'\nSee 'mesoinspect --help'.\n", a);
            return MESO_EXIT_USAGE;
        }
    }
    if (!file || !out) {
        fputs(usage_preview, stderr);
        fputs(usage_preview_levels, stderr);
        return MESO_EXIT_USAGE;
    }
    if (reference && (knobs.stats || knobs.stream_bytes)) {
        fprintf(stderr, "mesoinspect error: --stats and --stream-bytes describe libmeso's draw, not the reference's\n"
                        "See 'mesoinspect --help'.\n");
        return MESO_EXIT_USAGE;
    }
    if (!reference && knobs.level >= 0) {
        fprintf(stderr, "mesoinspect error: --level is the reference's; libmeso picks levels by --pixel-error\n"
                        "See 'mesoinspect --help'.\n");
        return MESO_EXIT_USAGE;
    }
    if (reference && knobs.pass != MESO_PASS_FORWARD) {
        fprintf(stderr, "mesoinspect error: --pass depth and gbuffer are libmeso's passes, not the reference's\n"
                        "See 'mesoinspect --help'.\n");
        return MESO_EXIT_USAGE;
    }
    char paths[3][4096];
    gbuffer_paths(out, paths);
    for (int i = 0; i < (knobs.pass == MESO_PASS_GBUFFER ? 3 : 1); ++i) {
        const int checked = mi_check_output(knobs.pass == MESO_PASS_GBUFFER ? paths[i] : out);
        if (checked != MESO_EXIT_OK)
            return checked;
    }
    knobs.technique = technique;
    const int valid = mi_validate_full(file, "drawn");
    if (valid != MESO_EXIT_OK)
        return valid;
    if (only_name) {
        const int found = mi_object_by_name(file, only_name, &only);
        if (found != MESO_EXIT_OK)
            return found;
    }
    if (reference)
        return render_reference(file, out, width, height, (uint32_t)only, yaw, pitch,
                                technique == MESO_SHELL_CURVED, (int)samples, &knobs);
#if MESO_HAVE_EGL
    return render(file, out, width, height, (uint32_t)only, yaw, pitch, &knobs);
#else
    (void)knobs;
    fprintf(stderr, "mesoinspect error: preview needs EGL, which this build does not have (try --reference)\n");
    return MESO_EXIT_UNSUPPORTED;
#endif
}
