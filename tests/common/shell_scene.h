/* shell_scene.h — what the shell GL test and the shell rendering benchmark
 * share (header-only test code): synthetic tileable textures, planar uvs,
 * a shell .meso image in memory built by normal displacement, cameras, and
 * the comparison of a GL frame with the exact reference image. */
#ifndef MESO_TEST_SHELL_SCENE_H
#define MESO_TEST_SHELL_SCENE_H

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "gl_fbo.h"
#include "mesh_chunk.h"
#include "meso_bake.h"
#include "distance_map.h"
#include "png_io.h"
#include "shell_reference.h"

/* Image size of the comparisons (set by the program). */
static int scene_w = 128, scene_h = 96;


#define CHECK(x) assert(x)
#define CHECK_MSG(x, ...)                                \
    do {                                                 \
        if (!(x)) {                                      \
            fprintf(stderr, "FAILED: %s: ", #x);         \
            fprintf(stderr, __VA_ARGS__);                \
            fprintf(stderr, "\n");                       \
            abort();                                     \
        }                                                \
    } while (0)

typedef struct texture {
    int kind; /* 0 none, 1 height, 2 density */
    uint32_t w, h, d;
    uint8_t* texels;
} texture;

/* Tileable height field: domes on a 2x2 grid with a crisp rim. */
static inline texture make_height(uint32_t n)
{
    texture t = {.kind = 1, .w = n, .h = n, .d = 1};
    t.texels = malloc((size_t)n * n);
    for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            const double s = (i + 0.5) / n, u = (j + 0.5) / n;
            const double fs = fmod(2.0 * s, 1.0) - 0.5, ft = fmod(2.0 * u, 1.0) - 0.5;
            const double r = sqrt(fs * fs + ft * ft);
            const double h = r < 0.4 ? 0.25 + 0.7 * sqrt(1.0 - (r / 0.4) * (r / 0.4)) : 0.1;
            t.texels[(size_t)j * n + i] = (uint8_t)lround(255.0 * h);
        }
    return t;
}

/* Tileable density: a lattice of balls on stalks (overhangs, not a height field). */
static inline texture make_volume(uint32_t n, uint32_t d)
{
    texture t = {.kind = 2, .w = n, .h = n, .d = d};
    t.texels = malloc((size_t)n * n * d);
    for (uint32_t k = 0; k < d; ++k)
        for (uint32_t j = 0; j < n; ++j)
            for (uint32_t i = 0; i < n; ++i) {
                const double s = (i + 0.5) / n, u = (j + 0.5) / n, w = (k + 0.5) / d;
                const double fs = fmod(2.0 * s, 1.0) - 0.5, ft = fmod(2.0 * u, 1.0) - 0.5;
                const double ball = 0.3 - sqrt(fs * fs + ft * ft + (w - 0.6) * (w - 0.6) * 1.0);
                const double stalk = w < 0.6 ? 0.1 - sqrt(fs * fs + ft * ft) : -1.0;
                const double v = fmax(ball, stalk);
                t.texels[((size_t)k * n + j) * n + i] = (uint8_t)lround(255.0 * fmin(fmax(0.5 + 4.0 * v, 0.0), 1.0));
            }
    return t;
}

/* Planar uvs over the two largest extents, `tiles` tiles along the longest. */
static inline void planar_uvs(meso_mesh* m, double tiles)
{
    double lo[3], hi[3];
    meso_mesh_bounds(m, lo, hi);
    int ax[3] = {0, 1, 2};
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b)
            if (hi[ax[b]] - lo[ax[b]] > hi[ax[a]] - lo[ax[a]]) {
                int t = ax[a];
                ax[a] = ax[b];
                ax[b] = t;
            }
    const double len = hi[ax[0]] - lo[ax[0]];
    free(m->uvs);
    m->uvs = malloc(sizeof(float) * 2 * m->vertex_count);
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        m->uvs[2 * v] = (float)(tiles * (m->positions[3 * v + ax[0]] - lo[ax[0]]) / len);
        m->uvs[2 * v + 1] = (float)(tiles * (m->positions[3 * v + ax[1]] - lo[ax[1]]) / len);
    }
}

/* A shell file in memory: MESH (+uvs), SDIR (normal displacement by h), the
 * texture and, when with_dist, its conservative distance map at the baker's
 * default resolution (bake/distance_map.c, as mesobake writes it), and
 * optionally one more chunk as given (for malformed-input tests). */
static inline uint8_t* shell_file_extra(const meso_mesh* m, double h, const texture* tex, int with_dist,
                                        const meso_chunk_desc* extra, const void* extra_data, size_t extra_size,
                                        size_t* size)
{
    meso_mesh_chunk chunk;
    meso_error err;
    CHECK(meso_bake_mesh_chunk(m, NULL, &chunk, &err) == MESO_OK);
    float* dirs = malloc(sizeof(float) * 3 * m->vertex_count);
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_SHELL};
    for (int k = 0; k < 3; ++k)
        rec.bbox_min[k] = 1e30f, rec.bbox_max[k] = -1e30f;
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            dirs[3 * v + k] = (float)(h * m->normals[3 * v + k]);
            const float a = m->positions[3 * v + k], b = a + dirs[3 * v + k];
            rec.bbox_min[k] = fminf(rec.bbox_min[k], fminf(a, b));
            rec.bbox_max[k] = fmaxf(rec.bbox_max[k], fmaxf(a, b));
        }
    uint8_t objt[64];
    meso_object_record_encode(&rec, objt);
    meso_writer* w = NULL;
    CHECK(meso_writer_create(NULL, &w) == MESO_OK);
    CHECK(meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_OBJT, .flags = MESO_CHUNK_FLAG_REQUIRED}, objt, 64,
                          &err) == MESO_OK);
    CHECK(meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_MESH, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1},
                          chunk.data, chunk.size, &err) == MESO_OK);
    CHECK(meso_writer_add(w,
                          &(meso_chunk_desc){.type = MESO_CHUNK_SDIR, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1,
                                             .dtype = MESO_DTYPE_F32, .components = 3, .dims = {m->vertex_count, 1, 1}},
                          dirs, sizeof(float) * 3 * m->vertex_count, &err) == MESO_OK);
    if (tex && tex->kind)
        CHECK(meso_writer_add(w,
                              &(meso_chunk_desc){.type = tex->kind == 1 ? MESO_CHUNK_TX2D : MESO_CHUNK_TX3D,
                                                 .object = 1, .dtype = MESO_DTYPE_U8, .components = 1,
                                                 .dims = {tex->w, tex->h, tex->d}},
                              tex->texels, (size_t)tex->w * tex->h * tex->d, &err) == MESO_OK);
    if (extra)
        CHECK(meso_writer_add(w, extra, extra_data, extra_size, &err) == MESO_OK);
    if (tex && tex->kind && with_dist) {
        const size_t n = (size_t)tex->w * tex->h * tex->d;
        float* v = malloc(sizeof(float) * n);
        for (size_t i = 0; i < n; ++i)
            v[i] = tex->texels[i] / 255.0f;
        const uint32_t dims[3] = {tex->w, tex->h, tex->d};
        meso_texfn f;
        CHECK(meso_texfn_from_values(tex->kind == 1 ? MESO_TEXFN_HEIGHT : MESO_TEXFN_DENSITY, dims, v, MESO_DTYPE_U8,
                                     &f, &err) == MESO_OK);
        uint32_t dd[3];
        meso_distmap_default_res(&f, dd);
        meso_distmap dm;
        CHECK(meso_distmap_build(&f, dd, MESO_DTYPE_U8, 0, &dm, &err) == MESO_OK);
        CHECK(meso_writer_add(w,
                              &(meso_chunk_desc){.type = MESO_CHUNK_DIST, .object = 1, .dtype = dm.dtype,
                                                 .components = 1, .dims = {dd[0], dd[1], dd[2]}},
                              dm.encoded, dm.encoded_size, &err) == MESO_OK);
        meso_distmap_free(&dm);
        meso_texfn_free(&f);
        free(v);
    }
    size_t need = 0;
    meso_writer_finish(w, NULL, 0, &need);
    uint8_t* buf = malloc(need);
    CHECK(meso_writer_finish(w, buf, need, size) == MESO_OK);
    meso_writer_destroy(w);
    free(dirs);
    free(chunk.data);
    return buf;
}

static inline uint8_t* shell_file(const meso_mesh* m, double h, const texture* tex, int with_dist, size_t* size)
{
    return shell_file_extra(m, h, tex, with_dist, NULL, NULL, 0, size);
}

typedef struct camera {
    double eye[3], at[3];
    double fovy, zn, zf;
} camera;

typedef struct metrics {
    double coverage_mismatch, off_pixel, colour_mae;
    double hit_err_px; /* mean distance GL hit to reference hit at the same pixel, in pixel footprints */
    double hit_gt1;    /* fraction of pixels covered in both whose hit error exceeds 1 pixel footprint */
    long covered_gl, covered_ref;
} metrics;

/* The tolerances every accurate shell technique meets against its reference
 * (the "within 1 pixel"): coverage mismatch and > 1 px hits at most
 * 0.5% of the pixels, mean hit (depth) error at most a quarter pixel, mean
 * colour error at most `colour_tol` (1%; 2% for strongly bent curved
 * shells). Shared by tests/gl/test_rt_shell.c (shells built in the test) and
 * tests/gl/test_rt_shell_baked.c (shells baked by mesobake). */
static inline void check_close_colour(const char* what, metrics m, double colour_tol)
{
    CHECK_MSG(m.coverage_mismatch <= 0.005 && m.off_pixel <= 0.005 && m.hit_err_px <= 0.25 &&
                  m.colour_mae <= colour_tol,
              "%s vs reference: coverage %.4f, off > 1 px %.4f, hit error %.3f px, colour %.4f", what,
              m.coverage_mismatch, m.off_pixel, m.hit_err_px, m.colour_mae);
}

/* Opens the file at `path`, which must hold exactly one object (aborts
 * otherwise): its record into *rec, its bounds into lo and hi. */
static inline meso_file* open_single_object(const char* path, meso_object_record* rec, double lo[3], double hi[3])
{
    meso_file* f = NULL;
    meso_error err;
    CHECK_MSG(meso_file_open_path(path, NULL, &f, &err) == MESO_OK, "%s", err.message);
    uint32_t n = 0;
    CHECK(meso_file_objects(f, rec, 1, &n, &err) == MESO_OK && n == 1);
    for (int k = 0; k < 3; ++k) {
        lo[k] = rec->bbox_min[k];
        hi[k] = rec->bbox_max[k];
    }
    return f;
}

/* Looking at the box [lo, hi]'s centre from direction `dir`, dist_scale
 * times the distance at which its bounding sphere fills a view of fovy;
 * near plane at least zn_frac of that distance. */
static inline camera camera_view_box(const double lo[3], const double hi[3], const double dir[3], double fovy,
                                     double dist_scale, double zn_frac)
{
    double ctr[3], r = 0, dl = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int k = 0; k < 3; ++k) {
        ctr[k] = 0.5 * (lo[k] + hi[k]);
        r += 0.25 * (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    r = sqrt(r);
    const double dist = dist_scale * r / sin(fovy / 2);
    camera cam = {.fovy = fovy, .zn = fmax(dist - 2 * r, zn_frac * dist), .zf = dist + 2 * r};
    for (int k = 0; k < 3; ++k) {
        cam.eye[k] = ctr[k] + dist * dir[k] / dl;
        cam.at[k] = ctr[k];
    }
    return cam;
}

static inline void camera_matrices(const camera* c, float view[16], float proj[16])
{
    const int W = scene_w, H = scene_h;
    const double up[3] = {0, 1, 0};
    meso_camera_look_at(view, c->eye, c->at, up);
    meso_camera_perspective(proj, c->fovy, (double)W / H, c->zn, c->zf);
}

/* Object-space point of pixel (x, y) at window depth z (model = identity). */
static inline void unproject(const double inv[16], int x, int y, double z, double p[3])
{
    const int W = scene_w, H = scene_h;
    const double ndc[4] = {2.0 * (x + 0.5) / W - 1.0, 2.0 * (y + 0.5) / H - 1.0, 2.0 * z - 1.0, 1.0};
    double r[4] = {0, 0, 0, 0};
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 4; ++k)
            r[i] += inv[4 * k + i] * ndc[k];
    for (int i = 0; i < 3; ++i)
        p[i] = r[i] / r[3];
}

static inline int invert4(const double m[16], double out[16])
{
    double a[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 8; ++j)
            a[i][j] = j < 4 ? m[4 * j + i] : (j - 4 == i);
    for (int c = 0; c < 4; ++c) {
        int p = c;
        for (int r = c + 1; r < 4; ++r)
            if (fabs(a[r][c]) > fabs(a[p][c]))
                p = r;
        if (fabs(a[p][c]) < 1e-300)
            return 0;
        for (int j = 0; j < 8; ++j) {
            double t = a[c][j];
            a[c][j] = a[p][j];
            a[p][j] = t;
        }
        for (int r = 0; r < 4; ++r)
            if (r != c) {
                const double f = a[r][c] / a[c][c];
                for (int j = 0; j < 8; ++j)
                    a[r][j] -= f * a[c][j];
            }
    }
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            out[4 * j + i] = a[i][j + 4] / a[i][i];
    return 1;
}

static inline metrics compare(const uint8_t* rgba, const float* depth, const meso_ref_image* ref, const float view[16],
                       const float proj[16], double fovy, const char* png_prefix)
{
    const int W = scene_w, H = scene_h;
    double mvp[16] = {0}, inv[16];
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k)
                mvp[4 * c + r] += (double)proj[4 * k + r] * (double)view[4 * c + k];
    CHECK(invert4(mvp, inv));
    double eye[3];
    {
        double iv[16], v[16];
        for (int i = 0; i < 16; ++i)
            v[i] = view[i];
        CHECK(invert4(v, iv));
        eye[0] = iv[12], eye[1] = iv[13], eye[2] = iv[14];
    }
    const double px_angle = 2.0 * tan(fovy / 2) / H;
    metrics m = {0};
    uint8_t* diff_img = getenv("MESO_TEST_PNG") && png_prefix ? calloc((size_t)W * H, 1) : NULL;
    long either = 0, mismatch = 0, both = 0, off = 0;
    double colour = 0.0, hit_err = 0.0;
    long hit_gt1 = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + x;
            const int cg = depth[i] < 1.0f, cr = ref->coverage[i] != 0;
            m.covered_gl += cg;
            m.covered_ref += cr;
            if (!cg && !cr)
                continue;
            ++either;
            int near_g = 0, near_r = 0;
            double best = 1e300;
            double pg[3] = {0, 0, 0};
            if (cg)
                unproject(inv, x, y, depth[i], pg);
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H)
                        continue;
                    const size_t j = (size_t)yy * W + xx;
                    near_g |= depth[j] < 1.0f;
                    near_r |= ref->coverage[j] != 0;
                    if (cg && ref->coverage[j]) {
                        const float* pr = ref->hit + 3 * j;
                        const double d = sqrt((pg[0] - pr[0]) * (pg[0] - pr[0]) + (pg[1] - pr[1]) * (pg[1] - pr[1]) +
                                              (pg[2] - pr[2]) * (pg[2] - pr[2]));
                        best = fmin(best, d);
                    }
                }
            const int bad_cov = (cg && !near_r) || (cr && !near_g);
            mismatch += bad_cov;
            if (diff_img)
                diff_img[i] = bad_cov ? (cg ? 1 : 2) : 0;
            if (cg) {
                const double dist = sqrt((pg[0] - eye[0]) * (pg[0] - eye[0]) + (pg[1] - eye[1]) * (pg[1] - eye[1]) +
                                         (pg[2] - eye[2]) * (pg[2] - eye[2]));
                if (near_r && best > 2.0 * px_angle * dist) {
                    ++off;
                    if (diff_img)
                        diff_img[i] = 3;
                }
            }
            if (cg && cr) {
                ++both;
                const float* pr = ref->hit + 3 * i;
                const double dd = sqrt((pg[0] - pr[0]) * (pg[0] - pr[0]) + (pg[1] - pr[1]) * (pg[1] - pr[1]) +
                                       (pg[2] - pr[2]) * (pg[2] - pr[2]));
                const double de = sqrt((pr[0] - eye[0]) * (pr[0] - eye[0]) + (pr[1] - eye[1]) * (pr[1] - eye[1]) +
                                       (pr[2] - eye[2]) * (pr[2] - eye[2]));
                hit_err += dd / (px_angle * de);
                hit_gt1 += dd > px_angle * de;
                for (int k = 0; k < 3; ++k)
                    colour += fabs(rgba[4 * i + (size_t)k] / 255.0 - ref->rgb[3 * i + (size_t)k]);
            }
        }
    m.coverage_mismatch = either ? (double)mismatch / either : 0.0;
    m.off_pixel = either ? (double)off / either : 0.0;
    m.colour_mae = both ? colour / (3.0 * both) : 0.0;
    m.hit_err_px = both ? hit_err / both : 0.0;
    m.hit_gt1 = both ? (double)hit_gt1 / both : 0.0;
    if (getenv("MESO_TEST_PNG") && png_prefix) {
        char path[512], why[128];
        snprintf(path, sizeof(path), "%s/%s_gl.png", getenv("MESO_TEST_PNG"), png_prefix);
        meso_png_write_rgba8(path, rgba, W, H, 1, why, sizeof(why));
        uint8_t* r8 = malloc((size_t)W * H * 4);
        for (size_t i = 0; i < (size_t)W * H; ++i) {
            for (int k = 0; k < 3; ++k)
                r8[4 * i + (size_t)k] = ref->coverage[i] ? (uint8_t)lround(255.0 * fmin(ref->rgb[3 * i + (size_t)k], 1.0))
                                                         : rgba[4 * ((size_t)0)] ; /* background sample */
            r8[4 * i + 3] = 255;
        }
        snprintf(path, sizeof(path), "%s/%s_ref.png", getenv("MESO_TEST_PNG"), png_prefix);
        meso_png_write_rgba8(path, r8, W, H, 1, why, sizeof(why));
        /* Differences: red GL-only coverage, blue reference-only, yellow > 1 px off. */
        static const uint8_t pal[4][3] = {{0, 0, 0}, {255, 40, 40}, {60, 90, 255}, {255, 230, 0}};
        for (size_t i = 0; i < (size_t)W * H; ++i) {
            const int g = depth[i] < 1.0f || ref->coverage[i];
            for (int k = 0; k < 3; ++k)
                r8[4 * i + (size_t)k] = diff_img[i] ? pal[diff_img[i]][k] : (uint8_t)(g ? 70 : 0);
        }
        snprintf(path, sizeof(path), "%s/%s_diff.png", getenv("MESO_TEST_PNG"), png_prefix);
        meso_png_write_rgba8(path, r8, W, H, 1, why, sizeof(why));
        free(r8);
    }
    free(diff_img);
    return m;
}

#endif
