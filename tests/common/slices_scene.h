/* slices_scene.h — what tests/gl/test_rt_slices.c and
 * tests/bench/bench_slices.c share (header-only test code): Figure 12 of
 * papers/volume-textures-lp-averaged-shells.md (§5) as a shell — the
 * `icospheres` built-in density (bake/texture_function.c) in one unit cube,
 * a quad of two triangles with directors of length 1 — its camera, and the
 * normal error of a GL frame against the exact reference.
 *
 * Normal error without a normal output: libmeso shades
 * albedo · a(w) · (0.15 + 0.85 max(0, n·l)) with n turned to face the ray
 * (shell_reference.h), so for a light l and its opposite −l the difference
 * of the two colours is albedo · a(w) · 0.85 (n·l): the same positive factor
 * for every l. Six frames lit along ±x, ±y, ±z give a vector parallel to n
 * (summed over the colour channels; 8-bit colours resolve it to about
 * 0.3°), compared by angle with the reference's normal at pixels both
 * cover. Both the mean and the median angle are reported: slices err
 * differently — no interpolation by a little everywhere (the slices'
 * terraces), interpolation by a lot in thin bands where α is far from
 * linear between two slices (where small spheres meet the large one, and
 * at their silhouettes) — and the mean weighs the bands, the median the
 * typical pixel. */
#ifndef MESO_TEST_SLICES_SCENE_H
#define MESO_TEST_SLICES_SCENE_H

#include "shell_scene.h"
#include "texture_function.h"

/* The Figure 12 shell: the unit cube [0,1]³ (w along +y), texture
 * icospheres:RES. */
static inline uint8_t* icospheres_file(int res, size_t* size)
{
    meso_mesh m = {0};
    m.vertex_count = 4;
    m.triangle_count = 2;
    m.positions = calloc(12, sizeof(float));
    m.normals = calloc(12, sizeof(float));
    m.indices = malloc(sizeof(uint32_t) * 6);
    for (uint32_t v = 0; v < 4; ++v) {
        m.positions[3 * v] = (float)(v & 1);
        m.positions[3 * v + 2] = (float)(v >> 1);
        m.normals[3 * v + 1] = 1.0f;
    }
    const uint32_t ix[6] = {0, 2, 1, 1, 2, 3}; /* +y faces */
    memcpy(m.indices, ix, sizeof(ix));
    planar_uvs(&m, 1.0); /* s = x, t = z */
    char spec[32];
    snprintf(spec, sizeof(spec), "icospheres:%d", res);
    meso_texfn f;
    meso_error err;
    CHECK(meso_texfn_from_spec(spec, &f, &err) == MESO_OK);
    texture tex = {.kind = 2, .w = f.dims[0], .h = f.dims[1], .d = f.dims[2]};
    const size_t n = (size_t)tex.w * tex.h * tex.d;
    tex.texels = malloc(n);
    for (size_t i = 0; i < n; ++i)
        tex.texels[i] = (uint8_t)lround(255.0 * f.values[i]);
    uint8_t* file = shell_file(&m, 1.0, &tex, 1, size);
    free(tex.texels);
    meso_texfn_free(&f);
    meso_mesh_free(&m);
    return file;
}

/* Looking at the cube's centre from 40° off the slices' normal. */
static inline camera icospheres_camera(void)
{
    const double d[3] = {0.5, 1.0, 0.7}, len = sqrt(0.25 + 1.0 + 0.49), dist = 2.3;
    camera c = {.at = {0.5, 0.5, 0.5}, .fovy = 0.7, .zn = 0.5, .zf = 10};
    for (int k = 0; k < 3; ++k)
        c.eye[k] = 0.5 + dist * d[k] / len;
    return c;
}

/* The same distance and azimuth at `elevation_deg` above the slices' plane
 * (90 = looking down the directors; a hair off the pole, where look_at's up
 * is degenerate). */
static inline camera icospheres_camera_at(double elevation_deg)
{
    camera c = icospheres_camera();
    const double el = elevation_deg * M_PI / 180.0, dist = 2.3;
    const double ce = fmax(cos(el), 1e-3), az = atan2(0.7, 0.5);
    c.eye[0] = 0.5 + dist * ce * cos(az);
    c.eye[2] = 0.5 + dist * ce * sin(az);
    c.eye[1] = 0.5 + dist * sin(el);
    return c;
}

typedef struct normal_error {
    double mean_deg, median_deg;
} normal_error;

static inline int cmp_angle(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

/* Mean and median angle (degrees) between the GL frame's normals (six
 * draws of `d` with its view and projection, see the header) and the
 * reference's, over the pixels both cover; `rgba` and `depth` are scratch of
 * scene_w × scene_h. */
static inline normal_error normal_error_deg(meso_rt* rt, test_fbo* fbo, meso_rt_object obj, meso_rt_draw_desc d,
                                      const meso_ref_image* ref, uint8_t* rgba, float* depth)
{
    const size_t n = (size_t)scene_w * scene_h;
    float* vec = calloc(3 * n, sizeof(float));
    uint8_t* cov = calloc(n, 1);
    for (int axis = 0; axis < 3; ++axis)
        for (int sign = 0; sign < 2; ++sign) {
            memset(d.light_dir, 0, sizeof(d.light_dir));
            d.light_dir[axis] = sign ? -1.0f : 1.0f;
            test_fbo_clear(fbo, 0, 0, 0);
            CHECK(meso_rt_draw(rt, obj, &d) == MESO_OK);
            test_fbo_read(fbo, rgba, depth);
            for (size_t i = 0; i < n; ++i) {
                const float c = (float)rgba[4 * i] + rgba[4 * i + 1] + rgba[4 * i + 2];
                vec[3 * i + (size_t)axis] += sign ? -c : c;
                cov[i] |= depth[i] < 1.0f;
            }
        }
    double sum = 0.0;
    long count = 0;
    double* angles = malloc(sizeof(double) * n);
    for (size_t i = 0; i < n; ++i) {
        if (!cov[i] || !ref->coverage[i])
            continue;
        const float* g = vec + 3 * i;
        const float* r = ref->normal + 3 * i;
        const double gl = sqrt((double)g[0] * g[0] + (double)g[1] * g[1] + (double)g[2] * g[2]);
        const double rl = sqrt((double)r[0] * r[0] + (double)r[1] * r[1] + (double)r[2] * r[2]);
        if (gl <= 0.0 || rl <= 0.0)
            continue;
        const double c = (g[0] * r[0] + g[1] * r[1] + g[2] * r[2]) / (gl * rl);
        angles[count] = acos(fmax(-1.0, fmin(1.0, c))) * 180.0 / M_PI;
        sum += angles[count++];
    }
    qsort(angles, (size_t)count, sizeof(double), cmp_angle);
    const normal_error e = {count ? sum / (double)count : 0.0, count ? angles[count / 2] : 0.0};
    free(angles);
    free(vec);
    free(cov);
    return e;
}

#endif
