/* libmeso cells objects (FORMAT.md §7.2 kind 3) on llvmpipe against the
 * exact CPU reference (runtime/reference/cell_reference.h:
 * meso_ref_cells_render, an exact voxel traversal in double precision):
 * Voronoi cells (a full map: whole-tile skipping both ways) and sphere
 * cells (empty space in the map) in the bundled sphere and torus, first hit
 * from several directions, specular self-reflection with 0..3 bounces,
 * refraction, the host's own environment cube map (and its binding kept),
 * the camera inside the object, mesh stand-in levels far away, the
 * thesis's linear search
 * against the exact traversal on thin plates at grazing angles (its known
 * failure, reproduced and measured), the GL state contract and malformed
 * files.
 *
 * Files are baked by the real `mesobake cells` (argv[1]) into a temporary
 * directory. Metrics: tests/common/shell_scene.h's compare() (coverage
 * mismatch, hits off by more than 1 px, mean hit error in pixel footprints,
 * colour MAE), plus `colour bad`: the fraction of pixels covered by both
 * whose colours differ by more than 0.1 in some channel.
 *
 * `missed`: the share of the reference's covered pixels that GL leaves
 * empty or hits more than a pixel footprint away.
 * What could differ by design: libmeso's rays start on the base mesh
 * (§3.2.1), the reference's at the grid; an INSIDE cell's voxel cubes may
 * reach up to half a voxel diagonal out of the mesh, and GL cannot see such
 * slivers in front of the mesh. In these scenes they cost no pixel (the
 * covered counts agree to a few pixels); the tolerances below bound them.
 * MESO_TEST_PNG=DIR writes each case's GL, reference and difference images. */
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>
#include <unistd.h>

#include "cell_reference.h"
#include "gl_api.h"
#include "gl_fbo.h"
#include "gl_log.h"
#include "gpu_mesh_bytes.h"
#include "meso_layout.h"
#include "meso_rt.h"
#include "rt_cells_skip.h"
#include "prefix_io.h"
#include "shell_scene.h"

enum { W = 160, H = 120 };

#define TEST_GLF(X)                                                                                              \
    X(PFNGLISENABLEDPROC, IsEnabled) X(PFNGLENABLEPROC, Enable) X(PFNGLDISABLEPROC, Disable)                      \
    X(PFNGLGENTEXTURESPROC, GenTextures) X(PFNGLBINDTEXTUREPROC, BindTexture) X(PFNGLTEXIMAGE2DPROC, TexImage2D)  \
    X(PFNGLTEXPARAMETERIPROC, TexParameteri) X(PFNGLDELETETEXTURESPROC, DeleteTextures)                          \
    X(PFNGLGETINTEGERVPROC, GetIntegerv) X(PFNGLACTIVETEXTUREPROC, ActiveTexture)

typedef struct test_gl {
#define TEST_M(t, n) t n;
    TEST_GLF(TEST_M)
#undef TEST_M
} test_gl;

typedef struct ctx {
    meso_rt* rt;
    test_fbo fbo;
    test_gl gl;
    uint8_t* rgba;
    float* depth;
    log_capture log;
    const char* mesobake;
    char dir[64];
} ctx;

/* >>baking ----------------------------------------------------------------- */

/* `mesobake cells -i MESH -o DIR/NAME.meso ARGS`; returns the path. */
static const char* bake(ctx* c, const char* name, const char* mesh, const char* args)
{
    static char path[256];
    snprintf(path, sizeof(path), "%s/%s.meso", c->dir, name);
    char cmd[1024];
    snprintf(cmd, sizeof(cmd), "'%s' cells -i '%s/%s' -o '%s' -j 2 %s >/dev/null 2>&1", c->mesobake, MESO_TEST_DATA,
             mesh, path, args);
    CHECK_MSG(system(cmd) == 0, "bake failed: %s", cmd);
    return path;
}

typedef struct loaded {
    meso_rt_object obj;
    meso_ref_cells ref;
    double lo[3], hi[3];
} loaded;

static loaded load(ctx* c, const char* path)
{
    loaded l;
    memset(&l, 0, sizeof(l));
    meso_error err;
    meso_object_record rec;
    meso_file* f = open_single_object(path, &rec, l.lo, l.hi);
    CHECK(rec.kind == MESO_OBJECT_CELLS);
    CHECK_MSG(meso_rt_load_object(c->rt, f, rec.id, &l.obj) == MESO_OK, "%s", c->log.message);
    CHECK_MSG(meso_ref_cells_load(f, rec.id, &l.ref, &err) == MESO_OK, "%s", err.message);
    meso_file_close(f);
    return l;
}

static void unload(ctx* c, loaded* l)
{
    meso_rt_release_object(c->rt, l->obj);
    meso_ref_cells_free(&l->ref);
}

/* >>rendering and comparing ------------------------------------------------ */

/* Looking at the box's centre from direction `dir`, `dist_scale` times the
 * distance at which its bounding sphere fills the view. */
static camera view_box(const loaded* l, const double dir[3], double dist_scale)
{
    return camera_view_box(l->lo, l->hi, dir, 0.7, dist_scale, 0.01);
}

typedef struct result {
    metrics m;
    double colour_bad;
    double missed; /* missed() */
    meso_rt_draw_stats stats;
} result;

/* The share of the reference's covered pixels that GL leaves empty or hits
 * more than one pixel footprint away from the reference's hit: cells the
 * search stepped over (c holds the GL images). */
static double missed(const ctx* c, const meso_ref_image* ref, const camera* cam)
{
    float view[16], proj[16];
    camera_matrices(cam, view, proj);
    double mvp[16] = {0}, inv[16];
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row)
            for (int k = 0; k < 4; ++k)
                mvp[4 * col + row] += (double)proj[4 * k + row] * (double)view[4 * col + k];
    CHECK(invert4(mvp, inv));
    const double px_angle = 2.0 * tan(cam->fovy / 2) / H;
    long covered = 0, miss = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + x;
            if (!ref->coverage[i])
                continue;
            ++covered;
            if (!(c->depth[i] < 1.0f)) {
                ++miss;
                continue;
            }
            double pg[3], dd = 0, de = 0;
            unproject(inv, x, y, c->depth[i], pg);
            for (int k = 0; k < 3; ++k) {
                dd += (pg[k] - ref->hit[3 * i + (size_t)k]) * (pg[k] - ref->hit[3 * i + (size_t)k]);
                de += (cam->eye[k] - ref->hit[3 * i + (size_t)k]) * (cam->eye[k] - ref->hit[3 * i + (size_t)k]);
            }
            miss += sqrt(dd) > px_angle * sqrt(de);
        }
    return covered ? (double)miss / covered : 0.0;
}

/* The host's environment of test_environment: one colour per cube face. */
static const uint8_t face_rgb[6][3] = {{230, 60, 40}, {40, 200, 60}, {250, 240, 90},
                                       {30, 40, 180}, {200, 80, 220}, {60, 220, 230}};

/* GL's face selection (the major axis; +x, -x, +y, -y, +z, -z), with the
 * face's colour as a linear RGBA8 texel. */
static void face_env(const double u[3], double rgb[3], const void* user)
{
    (void)user;
    const double a[3] = {fabs(u[0]), fabs(u[1]), fabs(u[2])};
    const int axis = a[0] >= a[1] && a[0] >= a[2] ? 0 : a[1] >= a[2] ? 1 : 2;
    const int face = 2 * axis + (u[axis] < 0);
    for (int k = 0; k < 3; ++k)
        rgb[k] = face_rgb[face][k] / 255.0;
}

/* 1: the reference ignores the host's environment (to show it matters). */
static int ref_sky_only = 0;

static meso_ref_cells_opts ref_opts(const meso_rt_draw_desc* d)
{
    return (meso_ref_cells_opts){.mode = (int)d->cells.mode,
                                 .bounces = d->cells.bounces,
                                 .reflectivity = d->cells.reflectivity,
                                 .ior = d->cells.ior,
                                 .transparency = d->cells.transparency,
                                 .env = d->cells.environment && !ref_sky_only ? face_env : NULL};
}

static result render_compare(ctx* c, const char* name, const loaded* l, const camera* cam,
                             const meso_rt_draw_desc* knobs)
{
    meso_rt_draw_desc d = knobs ? *knobs : (meso_rt_draw_desc){0};
    camera_matrices(cam, d.view, d.proj);
    result res;
    memset(&res, 0, sizeof(res));
    d.stats = &res.stats;
    test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
    CHECK_MSG(meso_rt_draw(c->rt, l->obj, &d) == MESO_OK, "%s", c->log.message);
    test_fbo_read(&c->fbo, c->rgba, c->depth);

    meso_ref_view v = {.width = W, .height = H};
    for (int i = 0; i < 16; ++i)
        v.view[i] = d.view[i], v.proj[i] = d.proj[i];
    meso_ref_image img;
    const meso_ref_cells_opts o = ref_opts(&d);
    CHECK(meso_ref_cells_render(&l->ref, &v, &o, &img) == MESO_OK);
    res.m = compare(c->rgba, c->depth, &img, d.view, d.proj, cam->fovy, name);
    long both = 0, bad = 0;
    for (size_t i = 0; i < (size_t)W * H; ++i)
        if (img.coverage[i] && c->depth[i] < 1.0f) {
            ++both;
            int b = 0;
            for (int k = 0; k < 3; ++k)
                b |= fabs(c->rgba[4 * i + (size_t)k] / 255.0 - img.rgb[3 * i + (size_t)k]) > 0.1;
            bad += b;
        }
    res.colour_bad = both ? (double)bad / both : 0.0;
    res.missed = missed(c, &img, cam);
    printf("%-28s covered gl %5ld ref %5ld  coverage mismatch %.4f  off >1px %.4f  hit error %.3f px (>1 px: %.4f)  "
           "colour MAE %.4f bad %.4f  missed %.4f  steps/fragment %.1f\n",
           name, res.m.covered_gl, res.m.covered_ref, res.m.coverage_mismatch, res.m.off_pixel, res.m.hit_err_px,
           res.m.hit_gt1, res.m.colour_mae, res.colour_bad, res.missed,
           res.stats.fragments ? (double)res.stats.steps / (double)res.stats.fragments : 0.0);
    meso_ref_image_free(&img);
    return res;
}

/* Tolerances (margins in the log): silhouette slivers and ties at voxel
 * edges only. `voxels`: the voxel's size against level 0's (2^L at native
 * level L; FORMAT.md 7.10). A tie at a voxel edge (f32 in GL, f64 in the
 * reference) moves the hit along the voxel's faces, by more pixels where
 * voxels cover more: the mean hit error and the share of hits more than a
 * pixel off (missed) are allowed in proportion. */
static void check_close_scaled(const char* what, result r, double colour_bad_tol, double voxels)
{
    CHECK_MSG(r.m.covered_ref > 500, "%s: the reference covers only %ld pixels", what, r.m.covered_ref);
    CHECK_MSG(r.m.coverage_mismatch <= 0.01 && r.m.off_pixel <= 0.01 && r.m.hit_err_px <= 0.1 * voxels &&
                  r.missed <= 0.005 * voxels && r.colour_bad <= colour_bad_tol,
              "%s vs reference: coverage %.4f, off > 1 px %.4f, hit error %.3f px, missed %.4f, colour bad %.4f", what,
              r.m.coverage_mismatch, r.m.off_pixel, r.m.hit_err_px, r.missed, r.colour_bad);
}

static void check_close(const char* what, result r, double colour_bad_tol)
{
    check_close_scaled(what, r, colour_bad_tol, 1.0);
}

/* >>cases ------------------------------------------------------------------ */

static const double dirs[3][3] = {{0.3, 0.4, 1.0}, {-1.0, 0.2, 0.1}, {0.2, -1.0, -0.5}};

static void test_first_hit(ctx* c)
{
    const char* p = bake(c, "voronoi", "sphere.obj", "--tiles 5 --tile-res 16 --tile-map voronoi:8");
    loaded l = load(c, p);
    char name[64];
    for (int i = 0; i < 3; ++i) {
        const camera cam = view_box(&l, dirs[i], 1.0);
        snprintf(name, sizeof(name), "voronoi_first_%d", i);
        check_close(name, render_compare(c, name, &l, &cam, NULL), 0.01);
    }
    /* Close up: cells a few pixels wide become tens. */
    const camera near = view_box(&l, dirs[0], 0.35);
    check_close("voronoi_close", render_compare(c, "voronoi_close", &l, &near, NULL), 0.01);
    unload(c, &l);

    p = bake(c, "spheres", "torus.obj", "--tiles 8 --tile-res 16 --tile-map spheres:6:0.3");
    l = load(c, p);
    for (int i = 0; i < 2; ++i) {
        const camera cam = view_box(&l, dirs[i], 1.0);
        snprintf(name, sizeof(name), "spheres_first_%d", i);
        check_close(name, render_compare(c, name, &l, &cam, NULL), 0.01);
    }
    unload(c, &l);
}

/* Levels of detail (FORMAT.md §7.10, meso_rt_load_object_levels): the
 * Voronoi bake of test_first_hit carries native coarser levels (the tile
 * map halved: bake/cells_levels.h) and mesh stand-ins (mesobake cells
 * --levels auto).
 *  - Each native level, drawn by libmeso through the levelled object (a
 *    pixel error found that picks it), matches the exact reference of that
 *    level (meso_ref_cells_load_level) as closely as level 0 matches its
 *    own (check_close).
 *  - With a pixel error of 4, close up the cells themselves are drawn
 *    (a native level); moved away, at the first distance at which a stand-in is
 *    drawn, its image matches the reference's cells within the pixel error
 *    (+1 for rasterising): every pixel either covers has one the other
 *    covers within 5 pixels. (At 1 px the sphere's stand-in, 16 voxels of
 *    carving, is drawn only once it covers a dozen pixels.) */
enum { TAU = 4 };

static void native_levels(ctx* c, meso_file* f, const meso_object_record* rec, meso_rt_object obj, const double lo[3],
                          const double hi[3])
{
    meso_level_info li[16];
    uint32_t n = 0;
    CHECK(meso_file_levels(f, rec->id, li, 16, &n, NULL) == MESO_OK && n >= 3);
    int natives = 0;
    for (uint32_t L = 1; L < n && li[L].rec.form == MESO_LEVEL_NATIVE; ++L) {
        ++natives;
        loaded l = {.obj = obj, .lo = {lo[0], lo[1], lo[2]}, .hi = {hi[0], hi[1], hi[2]}};
        meso_error err;
        CHECK_MSG(meso_ref_cells_load_level(f, rec->id, (uint16_t)L, &l.ref, &err) == MESO_OK, "%s", err.message);
        const camera cam = view_box(&l, dirs[0], 1.0);
        meso_rt_draw_desc d = {0};
        camera_matrices(&cam, d.view, d.proj);
        meso_rt_levels_state st = {0};
        for (float tau = 0.25f; tau < 4096.0f; tau *= 1.1f) { /* the pixel error that picks level L */
            d.pixel_error = tau;
            CHECK_MSG(meso_rt_draw(c->rt, obj, &d) == MESO_OK, "%s", c->log.message);
            CHECK(meso_rt_levels_state_get(c->rt, obj, &st) == MESO_OK);
            if (st.last_drawn >= (int)L)
                break;
        }
        CHECK_MSG(st.last_drawn == (int)L, "no pixel error draws native level %u (drew %d)", L, st.last_drawn);
        char name[64];
        snprintf(name, sizeof name, "native_level_%u (tau %.2f)", L, (double)d.pixel_error);
        /* Level L's voxels are 2^L times level 0's (3 px at level 2 here). */
        check_close_scaled(name, render_compare(c, name, &l, &cam, &d), 0.01, (double)(1 << L));
        meso_ref_cells_free(&l.ref);
    }
    CHECK_MSG(natives >= 1, "no native coarser level");
}

static void test_levels(ctx* c)
{
    char path[256];
    snprintf(path, sizeof path, "%s/voronoi.meso", c->dir);
    meso_object_record rec;
    double lo[3], hi[3];
    meso_file* f = open_single_object(path, &rec, lo, hi);
    meso_ref_cells ref;
    meso_error err;
    CHECK_MSG(meso_ref_cells_load(f, rec.id, &ref, &err) == MESO_OK, "%s", err.message);
    meso_rt_object obj;
    CHECK_MSG(meso_rt_load_object_levels(c->rt, f, rec.id, &obj) == MESO_OK, "%s", c->log.message);
    native_levels(c, f, &rec, obj, lo, hi);
    meso_level_info li[16];
    uint32_t n = 0;
    CHECK(meso_file_levels(f, rec.id, li, 16, &n, NULL) == MESO_OK);
    int standin = 0;
    for (double scale = 1; scale <= 64 && !standin; scale *= 2) {
        const camera cam = view_box(&(loaded){.lo = {lo[0], lo[1], lo[2]}, .hi = {hi[0], hi[1], hi[2]}}, dirs[0],
                                    scale);
        meso_rt_draw_desc d = {.pixel_error = (float)TAU};
        camera_matrices(&cam, d.view, d.proj);
        test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
        CHECK_MSG(meso_rt_draw(c->rt, obj, &d) == MESO_OK, "%s", c->log.message);
        test_fbo_read(&c->fbo, c->rgba, c->depth);
        meso_rt_levels_state st;
        CHECK(meso_rt_levels_state_get(c->rt, obj, &st) == MESO_OK && st.level_count >= 2);
        if (scale == 1)
            CHECK_MSG(st.last_drawn >= 0 && li[st.last_drawn].rec.form == MESO_LEVEL_NATIVE,
                      "close up: level %d drawn, not the cells", st.last_drawn);
        if (st.last_drawn < 0 || li[st.last_drawn].rec.form != MESO_LEVEL_MESH)
            continue;
        standin = 1;
        meso_ref_view v = {.width = W, .height = H};
        for (int i = 0; i < 16; ++i)
            v.view[i] = d.view[i], v.proj[i] = d.proj[i];
        meso_ref_image img;
        CHECK(meso_ref_cells_render(&ref, &v, NULL, &img) == MESO_OK);
        long gl = 0, rf = 0, lonely = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const int g = c->depth[y * W + x] < 1.0f, r = img.coverage[y * W + x];
                gl += g;
                rf += r;
                if (g == r)
                    continue;
                int near = 0; /* the other image covers a pixel within TAU + 1 */
                for (int dy = -TAU - 1; dy <= TAU + 1 && !near; ++dy)
                    for (int dx = -TAU - 1; dx <= TAU + 1 && !near; ++dx) {
                        const int xx = x + dx, yy = y + dy;
                        if (xx >= 0 && yy >= 0 && xx < W && yy < H)
                            near = g ? img.coverage[yy * W + xx] : c->depth[yy * W + xx] < 1.0f;
                    }
                lonely += !near;
            }
        printf("%-28s distance x%.0f: level %d drawn, covered gl %ld ref %ld, %ld pixels with no partner within %d\n",
               "levels_standin", scale, st.last_drawn, gl, rf, lonely, TAU + 1);
        CHECK_MSG(rf > 100 && lonely == 0, "stand-in at x%.0f: %ld of %ld/%ld pixels without a partner", scale, lonely,
                  gl, rf);
        meso_ref_image_free(&img);
    }
    CHECK_MSG(standin, "no stand-in level drawn up to 64 times the fill distance");
    meso_rt_release_object(c->rt, obj);
    meso_ref_cells_free(&ref);
    meso_file_close(f);
}

/* Levels streamed (FORMAT.md §7.10: a prefix of the file holds a level and
 * every coarser one): for the Voronoi bake and the colour-grid bake (its
 * TX3D stored once, at the coarsest native lod), a reader holding only the
 * first prefix_bytes of level k loads the object, and a draw that wants
 * the finest level gets level k; a native level draws as the reference
 * draws that level from the whole file (check_close), a stand-in covers
 * pixels. */
static void test_prefixes(ctx* c)
{
    static const char* names[2] = {"voronoi", "from_mesh"};
    for (int fi = 0; fi < 2; ++fi) {
        char path[256];
        snprintf(path, sizeof path, "%s/%s.meso", c->dir, names[fi]);
        FILE* fp = fopen(path, "rb");
        CHECK(fp);
        CHECK(fseek(fp, 0, SEEK_END) == 0);
        const long size = ftell(fp);
        CHECK(size > 0 && fseek(fp, 0, SEEK_SET) == 0);
        uint8_t* data = malloc((size_t)size);
        CHECK(data && fread(data, 1, (size_t)size, fp) == (size_t)size);
        fclose(fp);
        meso_object_record rec;
        loaded whole = {0};
        meso_file* wf = open_single_object(path, &rec, whole.lo, whole.hi);
        meso_level_info li[16];
        uint32_t n = 0;
        CHECK(meso_file_levels(wf, rec.id, li, 16, &n, NULL) == MESO_OK && n >= 3 && li[1].rec.form == MESO_LEVEL_NATIVE);
        for (int k = (int)n - 1; k >= 0; --k) {
            prefix_io p = {data, li[k].prefix_bytes};
            const meso_io io = {.read_fn = prefix_read, .size = (uint64_t)size, .user = &p};
            meso_file* f = NULL;
            CHECK(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
            loaded l = whole;
            CHECK_MSG(meso_rt_load_object_levels(c->rt, f, rec.id, &l.obj) == MESO_OK, "%s", c->log.message);
            const camera cam = view_box(&l, dirs[0], 1.0);
            char name[64];
            snprintf(name, sizeof name, "%s_prefix_level_%d", names[fi], k);
            const meso_rt_draw_desc want_finest = {.pixel_error = -1.0f};
            if (li[k].rec.form == MESO_LEVEL_NATIVE) {
                meso_error err;
                CHECK_MSG(meso_ref_cells_load_level(wf, rec.id, (uint16_t)k, &l.ref, &err) == MESO_OK, "%s",
                          err.message);
                check_close_scaled(name, render_compare(c, name, &l, &cam, &want_finest), 0.03, (double)(1 << k));
                meso_ref_cells_free(&l.ref);
            } else {
                meso_rt_draw_desc d = want_finest;
                camera_matrices(&cam, d.view, d.proj);
                test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
                CHECK_MSG(meso_rt_draw(c->rt, l.obj, &d) == MESO_OK, "%s", c->log.message);
                test_fbo_read(&c->fbo, c->rgba, c->depth);
                long covered = 0;
                for (size_t i = 0; i < (size_t)W * H; ++i)
                    covered += c->depth[i] < 1.0f;
                printf("%-28s stand-in covers %ld pixels\n", name, covered);
                CHECK_MSG(covered > 500, "%s: %ld pixels", name, covered);
            }
            meso_rt_levels_state st;
            CHECK(meso_rt_levels_state_get(c->rt, l.obj, &st) == MESO_OK);
            CHECK_MSG(st.last_drawn == k, "%s: %llu of %ld bytes: level %d drawn", name,
                      (unsigned long long)p.limit, size, st.last_drawn);
            meso_rt_release_object(c->rt, l.obj);
            meso_file_close(f);
        }
        meso_file_close(wf);
        free(data);
    }
}

/* The mesh's colour grid (--colour from-mesh, FORMAT.md 7.2 kind 3 TX3D):
 * the albedo trilinear at the hit, in GL as in the reference; first hit and
 * reflections (the bounces' hits take it too). */
static void test_colour_grid(ctx* c)
{
    const char* p = bake(c, "from_mesh", "gltf/box.gltf", "--tiles 4 --tile-res 16 --colour from-mesh:24");
    loaded l = load(c, p);
    CHECK(l.ref.grid[0] == 24 && l.ref.grid_rgb != NULL);
    char name[64];
    for (int i = 0; i < 2; ++i) {
        const camera cam = view_box(&l, dirs[i], 1.0);
        snprintf(name, sizeof(name), "from_mesh_first_%d", i);
        check_close(name, render_compare(c, name, &l, &cam, NULL), 0.01);
    }
    const camera cam = view_box(&l, dirs[0], 0.8);
    meso_rt_draw_desc d = {.cells = {.mode = MESO_CELLS_REFLECT, .bounces = 2}};
    check_close("from_mesh_reflect_2", render_compare(c, "from_mesh_reflect_2", &l, &cam, &d), 0.03);
    unload(c, &l);
}

static void test_reflection_refraction(ctx* c)
{
    const char* p = bake(c, "voronoi_rr", "sphere.obj", "--tiles 5 --tile-res 16 --tile-map voronoi:8");
    loaded l = load(c, p);
    const camera cam = view_box(&l, dirs[0], 0.6);
    char name[64];
    for (int b = 0; b <= 3; ++b) {
        meso_rt_draw_desc d = {.cells = {.mode = MESO_CELLS_REFLECT, .bounces = b}};
        snprintf(name, sizeof(name), "reflect_%d", b);
        check_close(name, render_compare(c, name, &l, &cam, &d), 0.03);
    }
    for (int b = 0; b <= 4; b += 2) {
        meso_rt_draw_desc d = {.cells = {.mode = MESO_CELLS_REFRACT, .bounces = b, .ior = 1.33f}};
        snprintf(name, sizeof(name), "refract_%d", b);
        check_close(name, render_compare(c, name, &l, &cam, &d), 0.03);
    }
    unload(c, &l);
    p = bake(c, "spheres_rr", "torus.obj", "--tiles 8 --tile-res 16 --tile-map spheres:6:0.3");
    l = load(c, p);
    const camera cam2 = view_box(&l, dirs[1], 0.7);
    meso_rt_draw_desc d = {.cells = {.mode = MESO_CELLS_REFRACT, .bounces = 3}};
    check_close("spheres_refract_3", render_compare(c, "spheres_refract_3", &l, &cam2, &d), 0.03);
    d = (meso_rt_draw_desc){.cells = {.mode = MESO_CELLS_REFLECT, .bounces = 2, .reflectivity = 0.8f}};
    check_close("spheres_reflect_2", render_compare(c, "spheres_reflect_2", &l, &cam2, &d), 0.03);
    unload(c, &l);
}

/* The walk leaves each cube of one split cell in a step (rt_cells_skip.c):
 * the same images as the voxel-by-voxel walk, in fewer steps, for first
 * hits, reflections and refractions. The hit distances come from the cube's
 * faces instead of the walk's running sums, so depth may differ in its
 * last bits. */
static void test_cube_skip(ctx* c)
{
    static const char* files[2] = {"voronoi_rr", "spheres_rr"};
    const meso_rt_draw_desc knobs[3] = {
        {.cells = {.mode = MESO_CELLS_FIRST_HIT}},
        {.cells = {.mode = MESO_CELLS_REFLECT, .bounces = 2}},
        {.cells = {.mode = MESO_CELLS_REFRACT, .bounces = 2, .ior = 1.33f}},
    };
    const size_t n = (size_t)W * H;
    uint8_t* rgba = malloc(3 * n * 4); /* the walk's images, one per mode */
    float* depth = malloc(3 * n * sizeof(float));
    CHECK(rgba && depth);
    for (int fi = 0; fi < 2; ++fi) {
        char path[256];
        snprintf(path, sizeof path, "%s/%s.meso", c->dir, files[fi]);
        meso_rt_draw_stats st[2][3];
        for (int on = 0; on <= 1; ++on) {
            mesoi_cells_skipping = on;
            loaded l = load(c, path);
            mesoi_cells_skipping = 1;
            const camera cam = view_box(&l, dirs[fi], 0.6);
            for (int k = 0; k < 3; ++k) {
                meso_rt_draw_desc d = knobs[k];
                camera_matrices(&cam, d.view, d.proj);
                memset(&st[on][k], 0, sizeof st[on][k]);
                d.stats = &st[on][k];
                test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
                CHECK_MSG(meso_rt_draw(c->rt, l.obj, &d) == MESO_OK, "%s", c->log.message);
                test_fbo_read(&c->fbo, c->rgba, c->depth);
                if (!on) {
                    memcpy(rgba + (size_t)k * n * 4, c->rgba, n * 4);
                    memcpy(depth + (size_t)k * n, c->depth, n * sizeof(float));
                    continue;
                }
                size_t colour = 0;
                double dz = 0.0;
                for (size_t i = 0; i < n; ++i) {
                    colour += memcmp(rgba + ((size_t)k * n + i) * 4, c->rgba + 4 * i, 4) != 0;
                    dz = fmax(dz, fabs((double)depth[(size_t)k * n + i] - c->depth[i]));
                }
                const meso_rt_draw_stats* a = &st[0][k];
                const meso_rt_draw_stats* b = &st[1][k];
                printf("cube_skip %s mode %d: %zu pixels of another colour, depth within %.2g; steps/fragment %.1f -> "
                       "%.1f\n",
                       files[fi], k, colour, dz, a->fragments ? (double)a->steps / (double)a->fragments : 0.0,
                       b->fragments ? (double)b->steps / (double)b->fragments : 0.0);
                CHECK_MSG(colour <= n / 10000, "%s mode %d: %zu pixels differ with the cubes skipped", files[fi], k,
                          colour);
                CHECK_MSG(dz <= 1e-5, "%s mode %d: depth differs by %g with the cubes skipped", files[fi], k, dz);
                CHECK(a->fragments == b->fragments && a->hits == b->hits);
                CHECK_MSG(!a->supported || b->steps < a->steps * 9 / 10,
                          "%s mode %d: skipping the cubes should save a tenth of the steps: %llu -> %llu", files[fi],
                          k, (unsigned long long)a->steps, (unsigned long long)b->steps);
            }
            unload(c, &l);
        }
    }
    free(rgba);
    free(depth);
}

/* The host's own environment: a cube map with one colour per face, seen
 * by reflected and refracted rays; the reference looks the same faces up.
 * The host's own cube map binding on unit 4 comes back after the draw. */
static void test_environment(ctx* c)
{
    GLuint cube = 0, host_cube = 0;
    c->gl.GenTextures(1, &cube);
    c->gl.GenTextures(1, &host_cube);
    c->gl.ActiveTexture(GL_TEXTURE4);
    c->gl.BindTexture(GL_TEXTURE_CUBE_MAP, host_cube);
    c->gl.ActiveTexture(GL_TEXTURE0);
    c->gl.BindTexture(GL_TEXTURE_CUBE_MAP, cube);
    for (int f = 0; f < 6; ++f) {
        uint8_t texels[4 * 4 * 4];
        for (int i = 0; i < 16; ++i) {
            memcpy(texels + 4 * i, face_rgb[f], 3);
            texels[4 * i + 3] = 255;
        }
        c->gl.TexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)f, 0, GL_RGBA8, 4, 4, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                         texels);
    }
    c->gl.TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    c->gl.TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    c->gl.TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAX_LEVEL, 0);
    c->gl.BindTexture(GL_TEXTURE_CUBE_MAP, 0);
    const char* p = bake(c, "env", "sphere.obj", "--tiles 5 --tile-res 16 --tile-map voronoi:8");
    loaded l = load(c, p);
    const camera cam = view_box(&l, dirs[0], 0.6);
    meso_rt_draw_desc d = {.cells = {.mode = MESO_CELLS_REFLECT, .bounces = 1, .environment = cube}};
    const result r = render_compare(c, "environment_reflect_1", &l, &cam, &d);
    check_close("environment_reflect_1", r, 0.01);
    d = (meso_rt_draw_desc){.cells = {.mode = MESO_CELLS_REFRACT, .bounces = 2, .environment = cube}};
    check_close("environment_refract_2", render_compare(c, "environment_refract_2", &l, &cam, &d), 0.02);
    /* The cube map is what the rays see: against the built-in sky the same
     * image is far off. */
    ref_sky_only = 1;
    const result sky = render_compare(c, "environment_vs_sky", &l, &cam, &d);
    ref_sky_only = 0;
    CHECK_MSG(sky.colour_bad > 0.3, "the cube map changes only %.4f of the pixels", sky.colour_bad);
    GLint bound = -1, active = -1;
    c->gl.GetIntegerv(GL_ACTIVE_TEXTURE, &active);
    c->gl.ActiveTexture(GL_TEXTURE4);
    c->gl.GetIntegerv(GL_TEXTURE_BINDING_CUBE_MAP, &bound);
    c->gl.ActiveTexture(GL_TEXTURE0);
    CHECK_MSG(active == GL_TEXTURE0 && bound == (GLint)host_cube, "after the draw: active unit 0x%x, unit 4 cube map %d",
              active, bound);
    c->gl.DeleteTextures(1, &cube);
    c->gl.DeleteTextures(1, &host_cube);
    unload(c, &l);
}

/* The near plane inside the grid: back faces start the rays there. The eye
 * is put in empty space between the sphere cells (checked on the reference's
 * voxels), so rays travel before they hit. */
static void test_camera_inside(ctx* c)
{
    const char* p = bake(c, "inside", "sphere.obj", "--tiles 5 --tile-res 16 --tile-map spheres:4:0.25");
    loaded l = load(c, p);
    camera cam = {.fovy = 1.0, .zn = 0.01, .zf = 10.0, .at = {0.6, -0.2, -0.9}};
    int found = 0;
    for (int t = 0; t < 200 && !found; ++t) {
        const double e[3] = {0.3 * sin(0.7 * t), 0.3 * cos(1.3 * t), 0.2 * sin(2.1 * t)};
        int64_t v[3];
        for (int k = 0; k < 3; ++k)
            v[k] = (int64_t)floor((e[k] - l.ref.origin[k]) / l.ref.voxel);
        found = 1;
        for (int dz = -2; dz <= 2; ++dz)
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx)
                    found &= !meso_ref_cells_solid(&l.ref, v[0] + dx, v[1] + dy, v[2] + dz);
        if (found)
            memcpy(cam.eye, e, sizeof(e));
    }
    CHECK_MSG(found, "no empty space for the eye");
    result r = render_compare(c, "camera_inside", &l, &cam, NULL);
    check_close("camera_inside", r, 0.01);
    CHECK_MSG(r.stats.supported == 0 || r.stats.steps > 2 * r.stats.fragments,
              "camera inside: %llu steps for %llu fragments; the rays should travel", (unsigned long long)r.stats.steps,
              (unsigned long long)r.stats.fragments);
    unload(c, &l);
}

/* A far view whose near plane lies just in front of the object, tilted:
 * the near plane's rectangle is then as large as the object and its
 * bounding box overlaps the grid's, while the whole grid lies beyond the
 * plane, so no ray starts inside it. The draw must then rasterise front
 * faces only, as it does with a near plane close to the eye: x and y of a
 * perspective projection do not depend on the near plane, so both views
 * cover the same pixels with the same fragments (before, the first drew
 * back faces as well, twice the fragments, whose hits tied in depth with
 * the front faces'). Both match the reference. */
static void test_near_plane_in_front(ctx* c)
{
    const char* p = bake(c, "voronoi_far", "sphere.obj", "--tiles 5 --tile-res 16 --tile-map voronoi:8");
    loaded l = load(c, p);
    const double dir[3] = {0.3, 0.8, 1.0};
    camera cam[2];
    cam[0] = cam[1] = view_box(&l, dir, 2.0);
    double r = 0.0, fwd[3], dist = 0.0;
    for (int k = 0; k < 3; ++k) {
        r += 0.25 * (l.hi[k] - l.lo[k]) * (l.hi[k] - l.lo[k]);
        fwd[k] = cam[0].at[k] - cam[0].eye[k];
        dist += fwd[k] * fwd[k];
    }
    r = sqrt(r);
    dist = sqrt(dist);
    for (int k = 0; k < 3; ++k)
        fwd[k] /= dist;
    cam[0].zn = dist - 1.05 * r; /* just in front of the grid's corners */
    cam[1].zn = 0.01 * dist;
    /* The case is the one meant: every grid corner beyond the near plane,
     * and the near rectangle's bounding box overlapping the grid's box.
     * The eye's axes are the view matrix's rows (camera_matrices' up). */
    double view[16];
    const double world_up[3] = {0, 1, 0};
    meso_camera_look_at_d(view, cam[0].eye, cam[0].at, world_up);
    const double right[3] = {view[0], view[4], view[8]}, u[3] = {view[1], view[5], view[9]};
    for (int i = 0; i < 8; ++i) {
        double depth = 0.0;
        for (int k = 0; k < 3; ++k)
            depth += ((i >> k & 1 ? l.hi[k] : l.lo[k]) - cam[0].eye[k]) * fwd[k];
        CHECK_MSG(depth > cam[0].zn, "grid corner %d at depth %g is not beyond the near plane %g", i, depth, cam[0].zn);
    }
    const double ty = tan(cam[0].fovy / 2), tx = ty * W / H;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) {
            const double q = cam[0].eye[k] +
                             cam[0].zn * (fwd[k] + (i & 1 ? tx : -tx) * right[k] + (i & 2 ? ty : -ty) * u[k]);
            lo[k] = fmin(lo[k], q);
            hi[k] = fmax(hi[k], q);
        }
    int overlap = 1;
    for (int k = 0; k < 3; ++k)
        overlap &= hi[k] >= l.lo[k] && lo[k] <= l.hi[k];
    CHECK_MSG(overlap, "the near rectangle's box does not overlap the grid: not the case meant");
    result res[2];
    res[0] = render_compare(c, "near_plane_in_front", &l, &cam[0], NULL);
    check_close("near_plane_in_front", res[0], 0.01);
    res[1] = render_compare(c, "near_plane_at_eye", &l, &cam[1], NULL);
    check_close("near_plane_at_eye", res[1], 0.01);
    CHECK_MSG(res[0].stats.supported == 0 || res[0].stats.fragments == res[1].stats.fragments,
              "near plane in front of the grid: %llu fragments, near the eye: %llu (back faces drawn?)",
              (unsigned long long)res[0].stats.fragments, (unsigned long long)res[1].stats.fragments);
    printf("near plane in front of the grid: %llu fragments, near the eye: %llu\n",
           (unsigned long long)res[0].stats.fragments, (unsigned long long)res[1].stats.fragments);
    unload(c, &l);
}

/* Small sphere cells under the flat top of a cube, seen steeply and at a
 * grazing angle. The thesis's linear search (Algorithm 3.1) at a fixed step
 * longer than a cell steps over cells (§3.2.2: "at grazing angles ... the
 * step size is too high and therefore missing an inside cell"); its remedy,
 * the step shrunk with the angle to the base mesh's normal, helps at grazing
 * angles (measured: 44 % of the covered pixels wrong -> 27 %) and costs
 * steps; meso's default, the exact traversal, never misses, at about the
 * steps of a 1-voxel linear search (which still misses 9 %). */
static void test_grazing(ctx* c)
{
    const char* p = bake(c, "grazing", "cube_no_bottom.obj", "--tiles 4 --tile-res 16 --tile-map spheres:4:0.2");
    loaded l = load(c, p);
    /* Steep: 66 degrees above the top. Grazing: the eye 0.2 above the top
     * (the cube is [-1, 1]^3), looking along it: the top is seen at 3 to 20
     * degrees, and nothing else. */
    const double dir[3] = {0.3, 1.0, 0.4};
    const camera views[2] = {view_box(&l, dir, 0.5),
                             {.fovy = 0.7, .zn = 0.01, .zf = 10.0, .eye = {-0.95, 1.2, 0.05}, .at = {1.0, 0.85, 0.0}}};
    const char* names[2] = {"steep", "grazing"};
    for (int k = 0; k < 2; ++k) {
        const camera cam = views[k];
        char name[64];
        snprintf(name, sizeof(name), "%s_exact", names[k]);
        const double exact = render_compare(c, name, &l, &cam, NULL).missed;
        meso_rt_draw_desc d = {.cells = {.step = 8.0f, .fixed_step = 1}};
        snprintf(name, sizeof(name), "%s_linear_8", names[k]);
        const double fixed = render_compare(c, name, &l, &cam, &d).missed;
        d.cells.fixed_step = 0;
        snprintf(name, sizeof(name), "%s_linear_8_angle", names[k]);
        const double angle = render_compare(c, name, &l, &cam, &d).missed;
        d = (meso_rt_draw_desc){.cells = {.step = 1.0f, .fixed_step = 1}};
        snprintf(name, sizeof(name), "%s_linear_1", names[k]);
        const double fine = render_compare(c, name, &l, &cam, &d).missed;
        CHECK_MSG(exact <= 0.002, "%s: the exact traversal missed %.4f", names[k], exact);
        CHECK_MSG(fixed >= 0.05, "%s: 8-voxel steps over cells 6 voxels wide should miss some: %.4f", names[k], fixed);
        CHECK_MSG(fine < fixed, "%s: 1-voxel steps must miss less than 8: %.4f vs %.4f", names[k], fine, fixed);
        if (k == 1)
            CHECK_MSG(angle < 0.75 * fixed, "grazing: the angle rule should cut the misses by a quarter: %.4f vs %.4f",
                      angle, fixed);
    }
    unload(c, &l);
}

/* meso_rt_draw's promise: the state it changes comes back. */
static void test_state_contract(ctx* c)
{
    const char* p = bake(c, "state", "sphere.obj", "--tiles 3 --tile-res 8");
    loaded l = load(c, p);
    c->gl.Enable(GL_CULL_FACE);
    const camera cam = view_box(&l, dirs[0], 1.0);
    meso_rt_draw_desc d = {0};
    camera_matrices(&cam, d.view, d.proj);
    CHECK(meso_rt_draw(c->rt, l.obj, &d) == MESO_OK);
    CHECK(c->gl.IsEnabled(GL_CULL_FACE));
    c->gl.Disable(GL_CULL_FACE);
    const camera in = {.fovy = 1.0, .zn = 0.01, .zf = 10.0, .eye = {0, 0, 0}, .at = {0, 0, -1}};
    camera_matrices(&in, d.view, d.proj);
    CHECK(meso_rt_draw(c->rt, l.obj, &d) == MESO_OK);
    CHECK(!c->gl.IsEnabled(GL_CULL_FACE));
    /* Knobs out of range are refused, nothing drawn. */
    d.cells.bounces = 9;
    c->log.errors = 0;
    CHECK(meso_rt_draw(c->rt, l.obj, &d) == MESO_ERR_INVALID_ARG && c->log.errors == 1);
    unload(c, &l);
}

/* A cells level streamed through requests (meso_rt_desc.stream_requests:
 * read, checked and decoded on a worker thread, uploaded from the decoded
 * copies, rt_stream.c) draws pixel for pixel what a synchronous load draws. */
static int run_all(void* arg)
{
    for (meso_rt_request** q = arg; *q; ++q)
        CHECK(meso_rt_stream_run(*q) == MESO_OK);
    return 0;
}

/* Streamed through requests at `budget` bytes per upload call (0: all):
 * the image drawn once level 0 has come is a synchronous load's, bit for
 * bit. With a budget smaller than a level, the level goes up over several
 * calls (rt_transfer.c): no call moves more than the budget (plus one
 * texel row or 64 KB of a buffer, the smallest piece), and the level is
 * not drawn before all of it is up. */
static void test_streamed_one(ctx* c, const char* name, const char* args, meso_cells_mode mode, uint64_t budget)
{
    const char* p = bake(c, name, "sphere.obj", args);
    loaded l = load(c, p);
    const camera cam = view_box(&l, dirs[0], 1.0);
    meso_rt_draw_desc d = {.cells = {.mode = mode, .bounces = 2}};
    camera_matrices(&cam, d.view, d.proj);
    d.pixel_error = -1.0f; /* the finest level */
    test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
    CHECK(meso_rt_draw(c->rt, l.obj, &d) == MESO_OK);
    uint8_t* want = malloc((size_t)W * H * 4);
    CHECK(want);
    test_fbo_read(&c->fbo, want, NULL);
    meso_rt* rt = NULL;
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .stream_requests = 1}, &rt) ==
          MESO_OK);
    meso_file* f = NULL;
    CHECK(meso_file_open_path(p, NULL, &f, NULL) == MESO_OK);
    meso_rt_object obj;
    CHECK(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    meso_rt_levels_state st = {.last_drawn = -1}; /* nothing drawn yet */
    meso_level_info li[16];
    uint32_t levels = 0;
    CHECK(meso_file_levels(f, 1, li, 16, &levels, NULL) == MESO_OK && levels > 1);
    uint64_t most = 0, calls = 0, moved = 0;
    for (int round = 0; round < 4000 && st.last_drawn != 0; ++round) {
        test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
        CHECK(meso_rt_draw(rt, obj, &d) == MESO_OK); /* requests the level it wants, draws what is there */
        meso_rt_request* reqs[5] = {0};
        const uint32_t n = meso_rt_stream_take(rt, reqs, 4);
        thrd_t t;
        CHECK(thrd_create(&t, run_all, reqs) == thrd_success && thrd_join(t, NULL) == thrd_success);
        meso_rt_stream_give(rt, reqs, n);
        meso_rt_stream_state ss;
        meso_rt_stream_state_get(rt, &ss);
        const uint64_t up = meso_rt_stream_upload(rt, budget);
        most = up > most ? up : most;
        calls += ss.decoded > 0;
        moved += up;
        meso_rt_frame_end(rt);
        test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
        CHECK(meso_rt_draw(rt, obj, &d) == MESO_OK);
        CHECK(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        /* Drawn only once whole: a level drawn has had all its bytes moved
         * (its MESH as the GPU holds it, meso_rt.h). */
        if (st.last_drawn >= 0 && (uint32_t)st.last_drawn + 1 < levels && budget) {
            const int32_t mi = meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)st.last_drawn);
            CHECK(mi >= 0);
            const uint64_t whole = li[st.last_drawn].bytes - meso_file_chunk(f, (uint32_t)mi)->stored_size +
                                   gpu_mesh_bytes(f, (uint32_t)mi);
            CHECK_MSG(moved >= whole, "level %d drawn after %llu of its %llu bytes", st.last_drawn,
                      (unsigned long long)moved, (unsigned long long)whole);
        }
    }
    CHECK_MSG(st.last_drawn == 0, "streamed cells: level %d drawn", st.last_drawn);
    if (budget) {
        printf("cells streamed at %llu bytes per call: %llu calls with decoded levels, at most %llu bytes a call, "
               "%llu moved (level 0's chunks: %llu bytes)\n",
               (unsigned long long)budget, (unsigned long long)calls, (unsigned long long)most,
               (unsigned long long)moved, (unsigned long long)li[0].bytes);
        CHECK(most <= budget + (64u << 10));
        CHECK(calls * (budget + (64u << 10)) >= li[0].bytes); /* level 0 took as many calls as its size asks */
        CHECK(calls >= 3);
    }
    test_fbo_read(&c->fbo, c->rgba, NULL);
    size_t differ = 0;
    for (size_t i = 0; i < (size_t)W * H * 4; ++i)
        differ += c->rgba[i] != want[i];
    printf("cells streamed through requests (%s, mode %d): %zu bytes of the image differ from a synchronous load\n",
           args, (int)mode, differ);
    CHECK(differ == 0);
    meso_rt_release_object(rt, obj);
    meso_rt_destroy(rt);
    meso_file_close(f);
    free(want);
    unload(c, &l);
}

/* Streamed levels get their skip radii off the GL thread, packed before
 * the loader sees the map: the refraction case's map has empty voxels, so
 * its INSIDE tiles may not be crossed whole when a ray looks for empty. */
static void test_streamed(ctx* c)
{
    test_streamed_one(c, "streamed", "--tiles 3 --tile-res 8", MESO_CELLS_FIRST_HIT, 0);
    test_streamed_one(c, "streamed_spheres", "--tiles 4 --tile-res 16 --tile-map spheres:4:0.45",
                      MESO_CELLS_REFRACT, 0);
    /* 2 KB a call: every level of it goes up over several calls. */
    test_streamed_one(c, "streamed_budget", "--tiles 4 --tile-res 16 --tile-map spheres:4:0.45",
                      MESO_CELLS_REFRACT, 2048);
}

/* Loads `bytes` and expects a refusal, logged, with no object. */
static void expect_refused(ctx* c, const char* what, const uint8_t* bytes, size_t size)
{
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(bytes, size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    c->log.errors = 0;
    const meso_result r = meso_rt_load_object(c->rt, f, 1, &obj);
    CHECK_MSG(r == MESO_ERR_CORRUPT && obj.id == 0 && c->log.errors >= 1, "%s loaded: %s", what,
              meso_result_string(r));
    printf("%s refused: %s\n", what, c->log.message);
    meso_file_close(f);
}

static void put32(uint8_t* p, uint32_t v)
{
    for (int k = 0; k < 4; ++k)
        p[k] = (uint8_t)(v >> (8 * k));
}

/* A corrupted MEMB is refused at load with the validator's message: once
 * as a bad checksum, once with the checksums made right again, so what
 * refuses it is the structure check that guards the shaders' indexing. */
static void test_malformed(ctx* c)
{
    const char* p = bake(c, "bad", "sphere.obj", "--tiles 3 --tile-res 8");
    FILE* fp = fopen(p, "rb");
    CHECK(fp != NULL);
    fseek(fp, 0, SEEK_END);
    const size_t size = (size_t)ftell(fp);
    fseek(fp, 0, SEEK_SET);
    uint8_t* bytes = malloc(size);
    CHECK(bytes && fread(bytes, 1, size, fp) == size);
    fclose(fp);
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(bytes, size, NULL, &f, &err) == MESO_OK);
    int32_t mi = -1;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i)
        if (meso_file_chunk(f, i)->type == MESO_CHUNK_MEMB)
            mi = (int32_t)i;
    CHECK(mi >= 0);
    const meso_chunk_info mc = *meso_file_chunk(f, (uint32_t)mi);
    meso_file_close(f);
    CHECK(mc.stored_size >= 4);
    put32(bytes + mc.offset, 0xFFFFFFFFu); /* every tile of the first word class 3: invalid */
    expect_refused(c, "MEMB with a bad checksum", bytes, size);
    const uint32_t n = (uint32_t)bytes[MESO_HDR_OFF_CHUNK_COUNT] | (uint32_t)bytes[MESO_HDR_OFF_CHUNK_COUNT + 1] << 8;
    uint8_t* entry = bytes + MESO_HDR_SIZE + (size_t)mi * MESO_TOC_ENTRY_SIZE;
    put32(entry + MESO_TOC_OFF_CRC, meso_crc32c(0, bytes + mc.offset, (size_t)mc.stored_size));
    put32(bytes + MESO_HDR_OFF_TOC_CRC, meso_crc32c(0, bytes + MESO_HDR_SIZE, (size_t)n * MESO_TOC_ENTRY_SIZE));
    put32(bytes + MESO_HDR_OFF_HEADER_CRC, 0);
    put32(bytes + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, bytes, MESO_HDR_SIZE));
    expect_refused(c, "MEMB with tile class 3", bytes, size);
    free(bytes);
}

int main(int argc, char** argv)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    CHECK_MSG(argc == 2, "usage: test_rt_cells MESOBAKE");
    scene_w = W;
    scene_h = H;
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof(why));
    CHECK_MSG(egl != NULL, "%s", why);
    ctx c;
    memset(&c, 0, sizeof(c));
    c.mesobake = argv[1];
    test_temp_dir(c.dir, sizeof(c.dir), "rt_cells");
    CHECK(test_fbo_create(&c.fbo, W, H));
#define TEST_L(t, n)                                  \
    {                                                 \
        void (*fn)(void) = meso_egl_proc("gl" #n);    \
        CHECK(fn != NULL);                            \
        memcpy(&c.gl.n, &fn, sizeof(fn));             \
    }
    TEST_GLF(TEST_L)
#undef TEST_L
    /* MESO_FILTER_LEVEL0: the exact reference shades one ray per pixel;
     * these views see more than a voxel per pixel in places, where the
     * default forward shading averages several rays across the pixel by
     * design (measured: colour "bad" 0.065 on voronoi_first_0, over the
     * tolerance, which bounds the traversal and shading this test is
     * about). tests/gl/test_rt_mips.c measures that averaging against a
     * supersampled render. */
    const meso_rt_desc desc = {.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error, .log_user = &c.log,
                               .texture_filter = MESO_FILTER_LEVEL0};
    CHECK(meso_rt_create(&desc, &c.rt) == MESO_OK);
    CHECK(meso_rt_gl_is_es(c.rt) == (test_gl_api() == MESO_EGL_GLES)); /* the API asked for */
    c.rgba = malloc((size_t)W * H * 4);
    c.depth = malloc(sizeof(float) * W * H);

    test_first_hit(&c);
    test_levels(&c);
    test_colour_grid(&c);
    test_prefixes(&c);
    test_reflection_refraction(&c);
    test_cube_skip(&c);
    test_environment(&c);
    test_camera_inside(&c);
    test_near_plane_in_front(&c);
    test_grazing(&c);
    test_state_contract(&c);
    test_streamed(&c);
    test_malformed(&c);

    test_temp_dir_remove(c.dir);
    free(c.rgba);
    free(c.depth);
    meso_rt_destroy(c.rt);
    test_fbo_destroy(&c.fbo);
    meso_egl_destroy(egl);
    printf("ok\n");
    return 0;
}
