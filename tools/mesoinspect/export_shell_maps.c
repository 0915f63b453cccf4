/*
 * export_shell_maps.c — a shell's mesostructure baked onto its base mesh
 * for `mesoinspect export` (export.h): one texture tile's tangent-space
 * normal map and base-colour map, and the per-vertex tangents that give
 * the normal map its frame.
 *
 * What is baked. The shell (FORMAT.md §7.2 kind 2) is solid where w ≤ h(s,
 * t') for a height field; for a density volume the baked height of a
 * column is its top-most solid w (the largest w with α ≥ ½, found between
 * the texel centres where α crosses ½, linear in w as the trilinear
 * filter is there; 1 when the top texel is solid, 0 for an empty column).
 * The normal of the height surface is the reference's
 * (runtime/reference/shell_reference.h): n = normalize(J⁻ᵀ g), g = (−∂h/∂s,
 * −∂h/∂t', 1) by central differences one texel apart
 * (meso_ref_texfn_gradient), J = ∂Φ/∂(s, t', w). A normal map cannot hold
 * J per point, so J is taken as a uniform scale: the uv directions carry
 * L object units per unit of texture space and w carries the prism height
 * d, which gives the tangent-space normal normalize(k g_s, k g_t', 1) with
 * k = d / L. Decided here (the papers draw the shell, not a fallback):
 * one k per object, the median over triangles of the triangle's mean prism
 * height over its sqrt(object area / uv area) — robust to the few
 * stretched triangles at seams and poles, exact on a uniformly
 * parametrised mesh (tests/integration/test_export_glb.c checks it on a
 * plane against the analytic normals of a sine height field).
 *
 * glTF conventions (glTF 2.0 §3.9.3 normalTexture, §3.7.2.1 TANGENT): the
 * exported uv is (s, 1 − t') and the images are written with meso's row
 * t' = 1 at the top, so the image shows what libmeso draws and glTF's
 * v = 0 is the image's top row. The normal texture's +X is the tangent
 * (increasing u = s), +Y "up in the image" (increasing t'), +Z the vertex
 * normal; each texel is (n · ½ + ½) in 8 bits, linear. The TANGENT
 * attribute spells that frame out (bitangent = cross(normal, tangent) ·
 * w, pointing along increasing t'), so a reader need not guess it; the
 * tangents are area-weighted sums of each triangle's ∂P/∂u, made
 * perpendicular to the normal (Lengyel's construction; MikkTSpace gives
 * the same directions up to its angle weights).
 *
 * Base colour: the shell's COLR chunk when it has one (RGBA8, sRGB), as
 * its CMAP record maps it (FORMAT.md §7.2 "Shell colour"). TILED: the
 * image is one texture tile on TEXCOORD_0, c = (s, t'); a W × H × 1 COLR is
 * that tile texel for texel, a W × H × D one is sampled at each texel
 * column's baked height w = h as the runtime's fetch would (decoded to
 * linear, linear between the slices whose centres (k + ½)/D bracket w,
 * clamped, re-encoded). BASE (`--color from-mesh`): the image is the COLR
 * itself, spanning the base mesh's uv square once; export.c writes
 * TEXCOORD_1 = (s · scale0, 1 − t' · scale1) for it (the same v flip as
 * TEXCOORD_0) and points baseColorTexture.texCoord at it (a D > 1 BASE
 * COLR, which mesobake never writes, shows its top slice). Either way the
 * image rows run t' = 1 at the top, as the normal map's. Without a COLR:
 * libmeso's shading without light, the default albedo times the built-in
 * occlusion 0.25 + 0.75 w at the baked height, sRGB-encoded as glTF
 * requires of baseColorTexture.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "export.h"
#include "png_io.h"

/* >>colour ------------------------------------------------------------------ */

uint8_t mi_srgb8(double c)
{
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    const double s = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1 / 2.4) - 0.055;
    return (uint8_t)lrint(s * 255.0);
}

double mi_srgb_to_linear(uint8_t c)
{
    const double s = c / 255.0;
    return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4);
}

/* >>scale ------------------------------------------------------------------- */

static void sub3(const float* a, const float* b, double out[3])
{
    for (int k = 0; k < 3; ++k)
        out[k] = (double)a[k] - (double)b[k];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Edge vectors p1 − p0, p2 − p0 of a triangle; returns twice its area. */
static double tri_edges(const mi_shell_src* s, const uint32_t tri[3], double e1[3], double e2[3])
{
    double c[3];
    sub3(s->positions + 3 * (size_t)tri[1], s->positions + 3 * (size_t)tri[0], e1);
    sub3(s->positions + 3 * (size_t)tri[2], s->positions + 3 * (size_t)tri[0], e2);
    cross3(e1, e2, c);
    return sqrt(dot3(c, c));
}

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

double mi_shell_slope_scale(const mi_shell_src* s)
{
    double* ratio = malloc(sizeof(double) * (s->triangle_count ? s->triangle_count : 1));
    if (!ratio)
        return 0;
    size_t n = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const uint32_t* tri = s->indices + 3 * (size_t)t;
        double e1[3], e2[3];
        const double area2 = tri_edges(s, tri, e1, e2);
        const float* a = s->uvs + 2 * (size_t)tri[0];
        const float* b = s->uvs + 2 * (size_t)tri[1];
        const float* d = s->uvs + 2 * (size_t)tri[2];
        const double uv2 = fabs(((double)b[0] - a[0]) * ((double)d[1] - a[1]) - ((double)d[0] - a[0]) * ((double)b[1] - a[1]));
        if (uv2 < 1e-12 || !(area2 > 0))
            continue;
        const double h = ((double)s->heights[tri[0]] + s->heights[tri[1]] + s->heights[tri[2]]) / 3;
        ratio[n++] = h / sqrt(area2 / uv2);
    }
    double k = 0;
    if (n) {
        qsort(ratio, n, sizeof(double), cmp_double);
        k = n % 2 ? ratio[n / 2] : 0.5 * (ratio[n / 2 - 1] + ratio[n / 2]);
    }
    free(ratio);
    return k;
}

/* >>tangents ---------------------------------------------------------------- */

meso_result mi_shell_tangents(const mi_shell_src* s, float** out)
{
    *out = NULL;
    const size_t nv = s->vertex_count;
    double* acc = calloc(6 * (nv ? nv : 1), sizeof(double)); /* ∂P/∂u, ∂P/∂v sums */
    float* tan = malloc(4 * sizeof(float) * (nv ? nv : 1));
    if (!acc || !tan) {
        free(acc);
        free(tan);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const uint32_t* tri = s->indices + 3 * (size_t)t;
        double e1[3], e2[3];
        const double area2 = tri_edges(s, tri, e1, e2);
        const float* a = s->uvs + 2 * (size_t)tri[0];
        const double du1 = (double)s->uvs[2 * (size_t)tri[1]] - a[0], dv1 = (double)s->uvs[2 * (size_t)tri[1] + 1] - a[1];
        const double du2 = (double)s->uvs[2 * (size_t)tri[2]] - a[0], dv2 = (double)s->uvs[2 * (size_t)tri[2] + 1] - a[1];
        const double det = du1 * dv2 - du2 * dv1;
        if (fabs(det) < 1e-12 || !(area2 > 0))
            continue;
        /* ∂P/∂u and ∂P/∂v of the triangle's affine parametrisation. */
        double pu[3], pv[3];
        for (int k = 0; k < 3; ++k) {
            pu[k] = (dv2 * e1[k] - dv1 * e2[k]) / det;
            pv[k] = (du1 * e2[k] - du2 * e1[k]) / det;
        }
        const double lu = sqrt(dot3(pu, pu)), lv = sqrt(dot3(pv, pv));
        for (int c3 = 0; c3 < 3; ++c3) {
            double* dst = acc + 6 * (size_t)tri[c3];
            for (int k = 0; k < 3; ++k) {
                dst[k] += lu > 0 ? area2 * pu[k] / lu : 0;
                dst[3 + k] += lv > 0 ? area2 * pv[k] / lv : 0;
            }
        }
    }
    for (size_t v = 0; v < nv; ++v) {
        const double n[3] = {s->normals[3 * v], s->normals[3 * v + 1], s->normals[3 * v + 2]};
        double* pu = acc + 6 * v;
        double t[3];
        const double along = dot3(n, pu);
        for (int k = 0; k < 3; ++k)
            t[k] = pu[k] - along * n[k];
        double l = sqrt(dot3(t, t));
        if (!(l > 1e-12 && l > 1e-6 * sqrt(dot3(pu, pu)))) {
            /* No uv direction here (an unused or degenerate vertex, or
             * one whose triangles' ∂P/∂u sum along the normal, as at a
             * welded cube corner, where what is left is rounding): any
             * perpendicular, from the axis least along the normal. */
            const int ax = fabs(n[0]) <= fabs(n[1]) && fabs(n[0]) <= fabs(n[2]) ? 0 : fabs(n[1]) <= fabs(n[2]) ? 1 : 2;
            double e[3] = {0, 0, 0};
            e[ax] = 1;
            for (int k = 0; k < 3; ++k)
                t[k] = e[k] - n[ax] * n[k];
            l = sqrt(dot3(t, t));
        }
        double b[3];
        for (int k = 0; k < 3; ++k)
            t[k] /= l;
        cross3(n, t, b);
        /* +Y of the normal texture is up in the image: decreasing v. */
        const double w = dot3(b, pu + 3) <= 0 ? 1.0 : -1.0;
        for (int k = 0; k < 3; ++k)
            tan[4 * v + (size_t)k] = (float)t[k];
        tan[4 * v + 3] = (float)w;
    }
    free(acc);
    *out = tan;
    return MESO_OK;
}

/* >>maps -------------------------------------------------------------------- */

/* Top-most solid w of column (i, j) of a W × H × D density volume (see the
 * header comment). */
static double column_height(const float* a, uint32_t W, uint32_t H, uint32_t D, uint32_t i, uint32_t j)
{
    const size_t plane = (size_t)W * H, col = (size_t)j * W + i;
    if (a[(size_t)(D - 1) * plane + col] >= 0.5f)
        return 1.0;
    for (uint32_t k = D - 1; k-- > 0;) {
        const double lo = a[(size_t)k * plane + col], hi = a[(size_t)(k + 1) * plane + col];
        if (lo >= 0.5) {
            /* α falls from lo ≥ ½ at w_k to hi < ½ at w_k+1. */
            const double f = (lo - 0.5) / (lo - hi);
            return (k + 0.5 + f) / D;
        }
    }
    return 0.0;
}

/* The tile's height per texel, meso's row order (row j at t' = (j + ½)/H);
 * NULL on out of memory. */
static float* baked_heights(const meso_ref_texfn* tf)
{
    const size_t n = (size_t)tf->w * tf->h;
    float* h = malloc(sizeof(float) * (n ? n : 1));
    if (!h)
        return NULL;
    if (tf->kind == 1) {
        memcpy(h, tf->values, sizeof(float) * n);
        return h;
    }
    for (uint32_t j = 0; j < tf->h; ++j)
        for (uint32_t i = 0; i < tf->w; ++i)
            h[(size_t)j * tf->w + i] = (float)column_height(tf->values, tf->w, tf->h, tf->d, i, j);
    return h;
}

int mi_shell_maps(const mi_shell_src* s, double k, uint8_t** normal_png, size_t* normal_size, uint8_t** color_png,
                  size_t* color_size, char* why, int why_size)
{
    *normal_png = *color_png = NULL;
    *normal_size = *color_size = 0;
    const meso_ref_texfn* tf = s->tex;
    const int has_fn = tf && tf->kind != 0 && tf->values && tf->w && tf->h;
    float* heights = has_fn ? baked_heights(tf) : NULL;
    const meso_ref_texfn hf = {.kind = 1, .w = has_fn ? tf->w : 0, .h = has_fn ? tf->h : 0, .d = 1, .values = heights};
    uint8_t* px = NULL;
    int rc = -1;
    if (has_fn && !heights)
        goto oom;
    if (has_fn) {
        const uint32_t W = tf->w, H = tf->h;
        px = malloc((size_t)W * H * 3);
        if (!px)
            goto oom;
        for (uint32_t j = 0; j < H; ++j)
            for (uint32_t i = 0; i < W; ++i) {
                double g[3];
                meso_ref_texfn_gradient(&hf, (i + 0.5) / W, (j + 0.5) / H, 0, g);
                double n[3] = {k * g[0], k * g[1], 1.0};
                const double l = sqrt(dot3(n, n));
                uint8_t* p = px + 3 * ((size_t)j * W + i);
                for (int c = 0; c < 3; ++c)
                    p[c] = (uint8_t)lrint((n[c] / l * 0.5 + 0.5) * 255.0);
            }
        /* Rows in meso's order are bottom to top in the image. */
        if (meso_png_encode_memory(px, (int)W, (int)H, 3, 1, normal_png, normal_size, why, why_size) != 0)
            goto done;
        free(px);
        px = NULL;
    }
    if (s->colr) {
        const uint32_t W = s->colr_dims[0], H = s->colr_dims[1], D = s->colr_dims[2];
        px = malloc((size_t)W * H * 3);
        if (!px)
            goto oom;
        const int tiled = s->colr_mapping == MESO_CMAP_TILED;
        for (uint32_t j = 0; j < H; ++j)
            for (uint32_t i = 0; i < W; ++i) {
                /* The colour at the texel centre's column top, w = h: the
                 * GL fetch there is the texel's own colour in s and t'
                 * and linear (in linear light) between slices in w. */
                const double h = tiled && has_fn ? meso_ref_texfn_value(&hf, (i + 0.5) / W, (j + 0.5) / H, 0) : 1.0;
                const double z = fmin(D - 1.0, fmax(0.0, h * D - 0.5));
                const uint32_t z0 = (uint32_t)floor(z), z1 = z0 + 1 < D ? z0 + 1 : z0;
                const double fz = z - z0;
                const uint8_t* c0 = s->colr + 4 * (((size_t)z0 * H + j) * W + i);
                const uint8_t* c1 = s->colr + 4 * (((size_t)z1 * H + j) * W + i);
                for (int c = 0; c < 3; ++c)
                    px[3 * ((size_t)j * W + i) + (size_t)c] =
                        z1 == z0 || fz == 0 ? c0[c]
                                            : mi_srgb8((1 - fz) * mi_srgb_to_linear(c0[c]) + fz * mi_srgb_to_linear(c1[c]));
            }
        if (meso_png_encode_memory(px, (int)W, (int)H, 3, 1, color_png, color_size, why, why_size) != 0)
            goto done;
    } else if (has_fn) {
        const uint32_t W = tf->w, H = tf->h;
        const double albedo[3] = {MI_DEFAULT_ALBEDO_R, MI_DEFAULT_ALBEDO_G, MI_DEFAULT_ALBEDO_B};
        px = malloc((size_t)W * H * 3);
        if (!px)
            goto oom;
        for (size_t t = 0; t < (size_t)W * H; ++t)
            for (int c = 0; c < 3; ++c)
                px[3 * t + (size_t)c] = mi_srgb8(albedo[c] * (0.25 + 0.75 * heights[t]));
        if (meso_png_encode_memory(px, (int)W, (int)H, 3, 1, color_png, color_size, why, why_size) != 0)
            goto done;
    }
    rc = 0;
    goto done;
oom:
    snprintf(why, (size_t)why_size, "out of memory baking the shell's maps");
done:
    if (rc != 0) {
        free(*normal_png);
        free(*color_png);
        *normal_png = *color_png = NULL;
        *normal_size = *color_size = 0;
    }
    free(px);
    free(heights);
    return rc;
}
