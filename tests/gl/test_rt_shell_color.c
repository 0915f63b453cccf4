/* Shell colour end to end (issue 16: "colour error against the source
 * texture <= 2/255 mean at sample points"): `mesobake shell --color`
 * (argv[1]) bakes COLR + CMAP, libmeso draws the G-buffer pass on llvmpipe
 * and the exact CPU reference renders the same view; both albedos are
 * compared with the source colours, computed here from the texels this
 * test wrote (never from the runtime's or the baker's code):
 *
 *  - tiled (--color FILE.png): a flat unit quad (uv = xy) under a constant
 *    height field (the surface is the plane w = 1/2), --tiling 2,3, seen
 *    from straight above. At every covered pixel the hit is unprojected from
 *    GL's depth buffer (the reference's own hit point for the reference),
 *    (s, t') = (2x, 3y), and the expected colour is the PNG (8 x 8, rows top
 *    to bottom, the bottom row at t' = 0) filtered bilinearly with wrap on
 *    sRGB-decoded texels and encoded back. Neighbouring texels differ by at
 *    most 28/255, so a hit a quarter pixel off moves the colour < 1/255;
 *  - volume (--color volume:FILE.raw:4x4x2): the same quad under a density
 *    volume solid below w = 1/2, the colour trilinear in (s, t', w) there
 *    (w = z / thickness), away from the wrap seams of s and t';
 *  - from-mesh: tests/data/gltf/box.gltf (a unit cube, 4 x 4 base-colour PNG
 *    of four 2 x 2 quadrants, factor (1, 0.8, 0.6)), --tiling 2 (the colour
 *    must NOT tile: it is the mesh's), seen from +z. On the top face the
 *    loader's uv is (x + 1/2, y + 1/2) (make_gltf.py), so a hit whose uv lies
 *    at least 0.04 inside one of the four regions where bilinear filtering
 *    meets one quadrant only must show that quadrant's colour times the
 *    factor (linear), re-encoded; 0.04 covers the directors' lateral lean at
 *    w = 1/2 (<= 0.015 here). Smooth mapping only: the curved map bends the
 *    cube's prisms so far (90-degree edges) that a hit's base point leaves
 *    that margin (measured: mean 2.2/255 against the quadrants, GL vs the
 *    curved reference 8.6/255 at the quadrant borders: not covered);
 *  - GL vs reference: the forward images agree as every shell bake does
 *    (tests/common/shell_scene.h check_close_colour: coverage, hits, colour
 *    MAE <= 1 %), smooth (and, for the quad, curved) against their references, and the
 *    G-buffer albedos agree pixel by pixel (mean <= 1/255);
 *  - a shell without --color still draws u_albedo (rgb = the desc's albedo).
 * MESO_TEST_PNG=DIR writes the forward images. */
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "egl_context.h"
#include "gl_gbuffer.h"
#include "gl_log.h"
#include "meso_rt.h"
#include "png_io.h"
#include "shell_reference.h"
#include "shell_scene.h"

enum { W = 160, H = 120 };

typedef struct ctx {
    meso_rt* rt;
    gbuffer_gl gl;
    GLuint fbo, rb[3];
    float *c0, *depth; /* attachment 0 (RGBA), depth */
    log_capture log;
    const char* mesobake;
    char dir[64];
} ctx;

static void target_create(ctx* c)
{
    gbuffer_create(&c->gl, W, H, &c->fbo, c->rb);
    c->c0 = malloc(sizeof(float) * 4 * W * H);
    c->depth = malloc(sizeof(float) * W * H);
}

/* Clears (colour 0, depth 1), draws, reads attachment 0 and depth. */
static void draw(ctx* c, meso_rt_object obj, const meso_rt_draw_desc* d)
{
    gbuffer_gl* gl = &c->gl;
    static const float zero[4] = {0, 0, 0, 0};
    const float one = 1.0f;
    gl->ClearBufferfv(GL_COLOR, 0, zero);
    gl->ClearBufferfv(GL_COLOR, 1, zero);
    gl->ClearBufferfv(GL_DEPTH, 0, &one);
    CHECK_MSG(meso_rt_draw(c->rt, obj, d) == MESO_OK, "%s", c->log.message);
    gl->ReadBuffer(GL_COLOR_ATTACHMENT0);
    gl->ReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, c->c0);
    gl->ReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, c->depth);
}

/* >>colour maths (the test's own) ------------------------------------------ */

static double srgb_decode(double x)
{
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

static double srgb_encode(double x)
{
    x = x < 0 ? 0 : x > 1 ? 1 : x;
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1 / 2.4) - 0.055;
}

/* The tiled case's 8 x 8 PNG, texel (i, j) with j = 0 the TOP row. */
enum { CW = 8, CH = 8 };
static void texel(int i, int j, uint8_t rgba[4])
{
    rgba[0] = (uint8_t)(16 + 28 * i);
    rgba[1] = (uint8_t)(16 + 28 * j);
    rgba[2] = (uint8_t)(200 - 12 * (i + j));
    rgba[3] = 255;
}

/* Expected sRGB (0..255) of the PNG at (s, t'): bilinear on decoded
 * texels, texel centres at ((i + 1/2)/W, (k + 1/2)/H) with k counted from
 * the bottom row, wrapping. */
static void expected_tiled(double s, double t, double out[3])
{
    const double x = (s - floor(s)) * CW - 0.5, y = (t - floor(t)) * CH - 0.5;
    const int x0 = (int)floor(x), y0 = (int)floor(y);
    const double fx = x - x0, fy = y - y0;
    double lin[3] = {0, 0, 0};
    for (int k = 0; k < 4; ++k) {
        const int xi = ((x0 + (k & 1)) % CW + CW) % CW, yk = ((y0 + (k >> 1)) % CH + CH) % CH;
        const double wgt = ((k & 1) ? fx : 1 - fx) * ((k >> 1) ? fy : 1 - fy);
        uint8_t px[4];
        texel(xi, CH - 1 - yk, px); /* row yk from the bottom */
        for (int i = 0; i < 3; ++i)
            lin[i] += wgt * srgb_decode(px[i] / 255.0);
    }
    for (int i = 0; i < 3; ++i)
        out[i] = 255.0 * srgb_encode(lin[i]);
}

/* The volume case's 4 x 4 x 2 RGBA8 colour, texel (i, j, k), s fastest. */
enum { VW = 4, VH = 4, VD = 2 };
static void vtexel(int i, int j, int k, uint8_t rgba[4])
{
    rgba[0] = (uint8_t)(40 + 40 * i);
    rgba[1] = (uint8_t)(40 + 40 * j);
    rgba[2] = (uint8_t)(60 + 150 * k);
    rgba[3] = 255;
}

/* Expected sRGB of the volume colour at (s, t', w): trilinear on decoded
 * texels, wrapping in s, t', clamped in w; 0 within 0.02 of a wrap seam
 * (texel 3 next to texel 0: a jump a sub-pixel hit error would magnify). */
static int expected_volume(double s, double t, double w, double out[3])
{
    const double x = (s - floor(s)) * VW - 0.5, y = (t - floor(t)) * VH - 0.5;
    double z = w * VD - 0.5;
    if (x < 0.08 || x > VW - 1 - 0.08 || y < 0.08 || y > VH - 1 - 0.08)
        return 0;
    z = z < 0 ? 0 : z > VD - 1 ? VD - 1 : z;
    const int x0 = (int)floor(x), y0 = (int)floor(y), z0 = (int)floor(z) < VD - 1 ? (int)floor(z) : VD - 2;
    const double f[3] = {x - x0, y - y0, z - z0};
    double lin[3] = {0, 0, 0};
    for (int k = 0; k < 8; ++k) {
        const int a = k & 1, b = (k >> 1) & 1, e = k >> 2;
        const double wgt = (a ? f[0] : 1 - f[0]) * (b ? f[1] : 1 - f[1]) * (e ? f[2] : 1 - f[2]);
        uint8_t px[4];
        vtexel(x0 + a, y0 + b, z0 + e, px);
        for (int i = 0; i < 3; ++i)
            lin[i] += wgt * srgb_decode(px[i] / 255.0);
    }
    for (int i = 0; i < 3; ++i)
        out[i] = 255.0 * srgb_encode(lin[i]);
    return 1;
}

/* box.gltf's quadrants (make_gltf.py TEXELS) times the factor (1, 0.8, 0.6)
 * in linear space: the colour of mesh uv (a, b) inside one quadrant's
 * constant region, or 0 when (a, b) is not at least `m` inside one. */
static int expected_box(double a, double b, double m, double out[3])
{
    static const uint8_t quad[4][3] = {{200, 40, 40}, {40, 200, 40}, {40, 40, 200}, {220, 220, 40}};
    static const double factor[3] = {1.0, 0.8, 0.6};
    const double lo[2] = {0.125 + m, 0.625 + m}, hi[2] = {0.375 - m, 0.875 - m};
    int qa = -1, qb = -1;
    for (int k = 0; k < 2; ++k) {
        if (a >= lo[k] && a <= hi[k])
            qa = k;
        if (b >= lo[k] && b <= hi[k])
            qb = k;
    }
    if (qa < 0 || qb < 0)
        return 0;
    /* glTF rows run down from v = 0: the loader's b = 1 - v, so b > 1/2 is
     * the image's top half (red, green), a > 1/2 its right half. */
    const int q = (qb == 1 ? 0 : 2) + qa;
    for (int i = 0; i < 3; ++i)
        out[i] = 255.0 * srgb_encode(srgb_decode(quad[q][i] / 255.0) * factor[i]);
    return 1;
}

/* >>cases ------------------------------------------------------------------ */

typedef struct loaded {
    meso_rt_object obj;
    meso_ref_shell shell;
    double lo[3], hi[3];
} loaded;

static const char* bake(ctx* c, const char* name, const char* args)
{
    static char path[256];
    snprintf(path, sizeof(path), "%s/%s.meso", c->dir, name);
    char cmd[5200];
    snprintf(cmd, sizeof(cmd), "'%s' shell %s -o '%s' >/dev/null 2>&1", c->mesobake, args, path);
    CHECK_MSG(system(cmd) == 0, "bake failed: %s", cmd);
    return path;
}

static loaded load(ctx* c, const char* path)
{
    loaded l;
    memset(&l, 0, sizeof(l));
    meso_error err;
    meso_object_record rec;
    meso_file* f = open_single_object(path, &rec, l.lo, l.hi);
    CHECK_MSG(meso_rt_load_object(c->rt, f, rec.id, &l.obj) == MESO_OK, "%s", c->log.message);
    CHECK(meso_ref_shell_load(f, rec.id, &l.shell, &err) == MESO_OK);
    meso_file_close(f);
    return l;
}

static void unload(ctx* c, loaded* l)
{
    meso_rt_release_object(c->rt, l->obj);
    meso_ref_shell_free(&l->shell);
}

/* Expected sRGB colour at object-space hit p; 0 where the case has none. */
typedef int (*expect_fn)(const double p[3], double out[3]);

static int expect_quad(const double p[3], double out[3])
{
    if (p[0] < 0.02 || p[0] > 0.98 || p[1] < 0.02 || p[1] > 0.98)
        return 0;
    expected_tiled(2 * p[0], 3 * p[1], out);
    return 1;
}

/* The volume case: the quad at thickness 0.1, --tiling 2,3, w = z / 0.1. */
static int expect_volume(const double p[3], double out[3])
{
    if (p[0] < 0.02 || p[0] > 0.98 || p[1] < 0.02 || p[1] > 0.98)
        return 0;
    return expected_volume(2 * p[0], 3 * p[1], p[2] / 0.1, out);
}

static int expect_top(const double p[3], double out[3])
{
    if (p[2] < 0.5)
        return 0; /* not the top face */
    return expected_box(p[0] + 0.5, p[1] + 0.5, 0.04, out);
}

typedef struct colour_err {
    double mean, max; /* in 1/255, per channel */
    long n;
} colour_err;

static void add_err(colour_err* e, const double want[3], const float lin[3])
{
    for (int i = 0; i < 3; ++i) {
        const double d = fabs(255.0 * srgb_encode(lin[i]) - want[i]);
        e->mean += d;
        e->max = fmax(e->max, d);
    }
    ++e->n;
}

static void run_case(ctx* c, const char* name, const char* path, const double dir[3], expect_fn expect, int with_curved)
{
    loaded l = load(c, path);
    const camera cam = camera_view_box(l.lo, l.hi, dir, 0.6, 1.0, 0.01);
    for (int curved = 0; curved < 1 + with_curved; ++curved) {
        meso_rt_draw_desc d = {.pass = MESO_PASS_GBUFFER,
                               .shell = {.technique = curved ? MESO_SHELL_CURVED : MESO_SHELL_SMOOTH}};
        camera_matrices(&cam, d.view, d.proj);
        meso_ref_view v = {.width = W, .height = H, .curved = curved, .samples_per_prism = 256};
        for (int i = 0; i < 16; ++i)
            v.view[i] = d.view[i], v.proj[i] = d.proj[i];
        meso_ref_image ref;
        CHECK(meso_ref_render(&l.shell, &v, &ref) == MESO_OK);

        /* G-buffer albedo against the source and against the reference. */
        draw(c, l.obj, &d);
        double mvp[16] = {0}, inv[16];
        for (int a = 0; a < 4; ++a)
            for (int r = 0; r < 4; ++r)
                for (int k = 0; k < 4; ++k)
                    mvp[4 * a + r] += (double)d.proj[4 * k + r] * (double)d.view[4 * a + k];
        CHECK(invert4(mvp, inv));
        colour_err eg = {0}, er = {0}, ggr = {0};
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const size_t i = (size_t)y * W + x;
                double want[3];
                if (c->depth[i] < 1.0f) {
                    double p[3];
                    unproject(inv, x, y, c->depth[i], p);
                    if (expect(p, want))
                        add_err(&eg, want, c->c0 + 4 * i);
                }
                if (ref.coverage[i]) {
                    const double p[3] = {ref.hit[3 * i], ref.hit[3 * i + 1], ref.hit[3 * i + 2]};
                    if (expect(p, want))
                        add_err(&er, want, ref.albedo + 3 * i);
                }
                if (c->depth[i] < 1.0f && ref.coverage[i]) {
                    double r8[3];
                    for (int k = 0; k < 3; ++k)
                        r8[k] = 255.0 * srgb_encode(ref.albedo[3 * i + (size_t)k]);
                    add_err(&ggr, r8, c->c0 + 4 * i);
                }
            }
        const char* tn = curved ? "curved" : "smooth";
        printf("%-6s %-6s albedo vs source: GL mean %.3f max %.2f (%ld px), reference mean %.3f max %.2f (%ld px); "
               "GL vs reference mean %.3f (/255)\n",
               name, tn, eg.mean / (3.0 * (double)eg.n), eg.max, eg.n, er.mean / (3.0 * (double)er.n), er.max, er.n,
               ggr.mean / (3.0 * (double)ggr.n));
        CHECK_MSG(eg.n >= 400 && er.n >= 400, "%s: too few sample points (%ld, %ld)", name, eg.n, er.n);
        CHECK_MSG(eg.mean / (3.0 * (double)eg.n) <= 2.0, "%s %s: GL albedo mean error above 2/255", name, tn);
        CHECK_MSG(er.mean / (3.0 * (double)er.n) <= 2.0, "%s %s: reference albedo mean error above 2/255", name, tn);
        CHECK_MSG(ggr.n > 0 && ggr.mean / (3.0 * (double)ggr.n) <= 1.0, "%s %s: GL vs reference albedo", name, tn);

        /* Forward images: the usual shell agreement, colour included. */
        meso_rt_draw_desc fd = d;
        fd.pass = MESO_PASS_FORWARD;
        draw(c, l.obj, &fd);
        uint8_t* rgba = malloc((size_t)4 * W * H);
        for (size_t i = 0; i < (size_t)4 * W * H; ++i) {
            const float f = c->c0[i] < 0 ? 0 : c->c0[i] > 1 ? 1 : c->c0[i];
            rgba[i] = (uint8_t)lrintf(f * 255.0f);
        }
        char prefix[64];
        snprintf(prefix, sizeof(prefix), "color_%s_%s", name, tn);
        const metrics m = compare(rgba, c->depth, &ref, d.view, d.proj, cam.fovy, prefix);
        printf("%-6s %-6s forward vs reference: coverage %.4f, off > 1 px %.4f, hit %.3f px, colour MAE %.4f\n", name,
               tn, m.coverage_mismatch, m.off_pixel, m.hit_err_px, m.colour_mae);
        check_close_colour(prefix, m, 0.01);
        free(rgba);
        meso_ref_image_free(&ref);
    }
    unload(c, &l);
}

/* Without --color the G-buffer albedo is the desc's, exactly. */
static void run_plain(ctx* c, const char* path)
{
    loaded l = load(c, path);
    static const double dir[3] = {0, 0, 1};
    const camera cam = camera_view_box(l.lo, l.hi, dir, 0.6, 1.0, 0.01);
    meso_rt_draw_desc d = {.pass = MESO_PASS_GBUFFER, .albedo = {0.3f, 0.5f, 0.7f}};
    camera_matrices(&cam, d.view, d.proj);
    draw(c, l.obj, &d);
    long n = 0;
    for (size_t i = 0; i < (size_t)W * H; ++i)
        if (c->depth[i] < 1.0f) {
            ++n;
            CHECK(c->c0[4 * i] == 0.3f && c->c0[4 * i + 1] == 0.5f && c->c0[4 * i + 2] == 0.7f);
        }
    CHECK(n > W * H / 10);
    unload(c, &l);
}

int main(int argc, char** argv)
{
    CHECK_MSG(argc == 2, "usage: test_rt_shell_color MESOBAKE");
    setvbuf(stdout, NULL, _IONBF, 0);
    scene_w = W;
    scene_h = H;
    char why[256];
    meso_egl* egl = meso_egl_create(why, sizeof(why));
    CHECK_MSG(egl != NULL, "%s", why);
    ctx c;
    memset(&c, 0, sizeof(c));
    c.mesobake = argv[1];
    test_temp_dir(c.dir, sizeof(c.dir), "rt_shell_color");
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error,
                                         .log_user = &c.log},
                         &c.rt) == MESO_OK);
    target_create(&c);

    /* Inputs: the colour PNG (rows top to bottom), a constant height map,
     * a unit quad with uv = xy. */
    char png[128], flat[128], quad[128], args[4600];
    snprintf(png, sizeof(png), "%s/colour.png", c.dir);
    snprintf(flat, sizeof(flat), "%s/flat.png", c.dir);
    snprintf(quad, sizeof(quad), "%s/quad.obj", c.dir);
    uint8_t px[CW * CH * 4];
    for (int j = 0; j < CH; ++j)
        for (int i = 0; i < CW; ++i)
            texel(i, j, px + 4 * (j * CW + i));
    CHECK(meso_png_write_rgba8(png, px, CW, CH, 0, why, sizeof(why)) == 0);
    uint16_t half[16];
    for (int i = 0; i < 16; ++i)
        half[i] = 32768; /* 16-bit: 32768 / 65535, the plane w = 0.500008 */
    CHECK(meso_png_write_gray(flat, half, 4, 4, 16, why, sizeof(why)) == 0);
    FILE* f = fopen(quad, "w");
    CHECK(f);
    fputs("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n", f);
    CHECK(fclose(f) == 0);

    static const double down[3] = {0, 0, 1};
    snprintf(args, sizeof(args), "-i '%s' --thickness 0.1 --texture 'height:%s' --tiling 2,3 --color '%s'", quad, flat,
             png);
    run_case(&c, "tiled", bake(&c, "tiled", args), down, expect_quad, 1);
    /* A density solid below w = 1/2 (layers 0, 1 of 4 full, 2, 3 empty:
     * alpha = 1/2 at w = 1/2) and the 3D colour, trilinear across w there. */
    char dens[128], vcol[128];
    snprintf(dens, sizeof(dens), "%s/dens.raw", c.dir);
    snprintf(vcol, sizeof(vcol), "%s/colour.raw", c.dir);
    f = fopen(dens, "wb");
    CHECK(f);
    for (int i = 0; i < 8 * 8 * 4; ++i)
        fputc(i < 8 * 8 * 2 ? 255 : 0, f);
    CHECK(fclose(f) == 0);
    f = fopen(vcol, "wb");
    CHECK(f);
    for (int k = 0; k < VD; ++k)
        for (int j = 0; j < VH; ++j)
            for (int i = 0; i < VW; ++i) {
                uint8_t v[4];
                vtexel(i, j, k, v);
                CHECK(fwrite(v, 1, 4, f) == 4);
            }
    CHECK(fclose(f) == 0);
    snprintf(args, sizeof(args),
             "-i '%s' --thickness 0.1 --texture 'volume:%s:8x8x4' --tiling 2,3 --color 'volume:%s:%dx%dx%d'", quad,
             dens, vcol, VW, VH, VD);
    run_case(&c, "volume", bake(&c, "volume", args), down, expect_volume, 1);
    snprintf(args, sizeof(args), "-i '%s' --thickness-rel 0.03 --texture 'height:%s' --tiling 2 --color from-mesh",
             test_data("gltf/box.gltf"), flat);
    run_case(&c, "mesh", bake(&c, "mesh", args), down, expect_top, 0);
    snprintf(args, sizeof(args), "-i '%s' --thickness 0.1 --texture 'height:%s'", quad, flat);
    run_plain(&c, bake(&c, "plain", args));

    meso_rt_destroy(c.rt);
    test_temp_dir_remove(c.dir);
    free(c.c0);
    free(c.depth);
    meso_egl_destroy(egl);
    printf("OK\n");
    return 0;
}
