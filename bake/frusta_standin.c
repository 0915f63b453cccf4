/*
 * frusta_standin.c — a frusta object's mesh stand-in level and its error
 * bound (frusta_standin.h states the construction and the derivation).
 */
#include "frusta_standin.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frusta_tessellation.h"
#include "meso_layout.h"
#include "srgb.h"

#define MAX_CELLS 256u

void meso_frusta_standin_free(meso_frusta_standin* s)
{
    if (!s)
        return;
    free(s->mesh.positions);
    free(s->mesh.normals);
    free(s->mesh.indices);
    free(s->owner);
    free(s->uv);
    memset(s, 0, sizeof(*s));
}

void meso_frusta_height_range(const meso_texfn* t, double* lo, double* hi)
{
    *lo = 1;
    *hi = 0;
    if (!t || !t->encoded)
        return;
    const int wide = t->dtype == MESO_DTYPE_U16;
    const size_t n = (size_t)t->dims[0] * t->dims[1] * t->dims[2];
    const uint8_t* b = t->encoded;
    uint32_t top = 0, bottom = wide ? 65535u : 255u;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t v = wide ? (uint32_t)b[2 * i] | (uint32_t)b[2 * i + 1] << 8 : b[i];
        top = v > top ? v : top;
        bottom = v < bottom ? v : bottom;
    }
    const double full = wide ? 65535.0 : 255.0;
    *lo = bottom / full;
    *hi = top / full;
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* G_f (frusta_standin.h, term 1): the largest |∂p/∂δ| over the frustum's
 * lateral surface; INFINITY when a plane's cut has no bound. */
static double relief_gain(const meso_frustum_rec* r)
{
    meso_frustum_frame fr;
    meso_frustum_rec_frame(r, &fr);
    double g = 1;
    for (int e = 0; e < 2; ++e) {
        const double n[3] = {r->plane[e][0], r->plane[e][1], r->plane[e][2]};
        const double nl = sqrt(dot3(n, n));
        const double alpha = dot3(n, fr.a) / nl;
        const double beta = sqrt(fmax(0, 1 - alpha * alpha));
        const double den_lo = alpha - fr.k * beta, den_hi = alpha + fr.k * beta;
        /* the denominator n·a + k n·w must keep its sign for every w */
        if (!(den_lo * den_hi > 0) || fmin(fabs(den_lo), fabs(den_hi)) < 1e-6)
            return INFINITY;
        for (int x = -1; x <= 1; x += 2) {
            const double c = -beta * x / (alpha + fr.k * beta * x);
            g = fmax(g, sqrt((1 + c * fr.k) * (1 + c * fr.k) + c * c));
        }
    }
    return g;
}

/* Cells around a part of largest radius R for the chord target et. */
static uint32_t cells_around(double R, double et, uint32_t least)
{
    if (!(R > 0) || 0.75 * et >= R)
        return least;
    const double n = ceil(M_PI / acos(1 - 0.75 * et / R));
    return n < least ? least : n > MAX_CELLS ? MAX_CELLS : (uint32_t)n;
}

/* Drop triangles without area; zero normals from their triangles. */
static meso_result to_mesh(const meso_frusta_tess_mesh* t, meso_mesh* m, meso_error* err)
{
    memset(m, 0, sizeof(*m));
    const uint32_t nv = t->vertex_count;
    m->positions = malloc(sizeof(float) * 3 * (size_t)nv);
    m->normals = malloc(sizeof(float) * 3 * (size_t)nv);
    m->indices = malloc(sizeof(uint32_t) * (size_t)(t->index_count ? t->index_count : 1));
    double* acc = calloc(3 * (size_t)nv, sizeof(double));
    if (!m->positions || !m->normals || !m->indices || !acc) {
        free(acc);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frusta stand-in: out of memory (%u vertices)", nv);
    }
    m->vertex_count = nv;
    memcpy(m->positions, t->positions, sizeof(float) * 3 * (size_t)nv);
    memcpy(m->normals, t->normals, sizeof(float) * 3 * (size_t)nv);
    uint32_t kept = 0;
    for (uint32_t i = 0; i + 2 < t->index_count; i += 3) {
        const uint32_t* q = t->indices + i;
        const float* p[3] = {t->positions + 3 * (size_t)q[0], t->positions + 3 * (size_t)q[1],
                             t->positions + 3 * (size_t)q[2]};
        double e1[3], e2[3], n[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)p[1][k] - p[0][k];
            e2[k] = (double)p[2][k] - p[0][k];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        /* two corners at one point (cap centres, ball poles, a pointed tip):
         * no area, nothing drawn, the other triangles cover the surface */
        if (!(sqrt(dot3(n, n)) > 1e-9 * dot3(e1, e1) + 1e-9 * dot3(e2, e2)))
            continue;
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                acc[3 * (size_t)q[c] + k] += n[k];
        memcpy(m->indices + kept, q, 3 * sizeof(uint32_t));
        kept += 3;
    }
    m->triangle_count = kept / 3;
    for (uint32_t v = 0; v < nv; ++v) {
        float* nn = m->normals + 3 * (size_t)v;
        if (nn[0] != 0 || nn[1] != 0 || nn[2] != 0)
            continue;
        const double* a = acc + 3 * (size_t)v;
        const double l = sqrt(dot3(a, a));
        for (int k = 0; k < 3; ++k)
            nn[k] = l > 0 ? (float)(a[k] / l) : (k == 2 ? 1.0f : 0.0f);
    }
    free(acc);
    return MESO_OK;
}

meso_result meso_frusta_standin_build(const meso_frusta_object* obj, const meso_texfn* relief,
    meso_frusta_standin* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    double hlo, hhi;
    meso_frusta_height_range(relief, &hlo, &hhi);
    const int has_relief = hhi >= hlo;
    double hm = has_relief ? 0.5 * (hlo + hhi) : 0;
    /* Term 1: the relief. */
    double relief_err = 0;
    if (has_relief)
        for (uint32_t f = 0; f < obj->count; ++f) {
            const double d = obj->recs[f].relief_depth;
            if (d > 0) {
                const double g = d * relief_gain(&obj->recs[f]);
                relief_err = fmax(relief_err, 0.5 * (hhi - hlo) * g);
                out->relief_gain = fmax(out->relief_gain, g);
            }
        }
    if (!isfinite(relief_err))
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                              "frusta stand-in: a cutting plane runs along a generator, the relief term has no bound");
    double diag = 0;
    for (int k = 0; k < 3; ++k)
        diag += ((double)obj->bbox_max[k] - obj->bbox_min[k]) * ((double)obj->bbox_max[k] - obj->bbox_min[k]);
    const double et = fmax(relief_err, 0.005 * sqrt(diag));
    /* Grids. */
    const uint32_t nf = obj->count, nb = obj->ball_count;
    uint32_t* cells = malloc(sizeof(uint32_t) * (2 * (size_t)nf + nb + 1));
    if (!cells)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frusta stand-in: out of memory");
    out->nu_min = UINT32_MAX;
    for (uint32_t f = 0; f < nf; ++f) {
        const meso_frustum_rec* r = &obj->recs[f];
        const double R = fmax(r->radius[0], r->radius[1]) + (has_relief ? r->relief_depth * hm : 0);
        const uint32_t nu = cells_around(R, et, 3);
        /* along: a twist turns a cell no more along v than across u; a taper
         * Δr shifts a diagonal's midpoint sideways by about
         * Δr / nv · sin(π / nu) / 2 from the surface point of its (u, v) */
        const double taper = fabs((double)r->radius[0] - r->radius[1]) * sin(M_PI / nu) / (1.5 * et);
        const double nv = ceil(fmax(fabs(r->twist) * nu / (2 * M_PI), taper));
        cells[f] = nu;
        cells[nf + f] = nv < 1 ? 1u : nv > 64.0 * nu ? 64u * nu : (uint32_t)nv;
        out->nu_min = nu < out->nu_min ? nu : out->nu_min;
        out->nu_max = nu > out->nu_max ? nu : out->nu_max;
    }
    for (uint32_t b = 0; b < nb; ++b) {
        const uint32_t nu = cells_around(obj->balls[b].radius, et, 4);
        cells[2 * (size_t)nf + b] = nu + (nu & 1u);
    }
    double sag = 0;
    const meso_frusta_tess_grid g = {.nu = cells, .nv = cells + nf, .ball_nu = cells + 2 * (size_t)nf,
                                     .height = has_relief ? meso_frusta_height_constant : NULL, .height_ctx = &hm,
                                     .edge_sag = &sag};
    meso_frusta_tess_mesh t;
    const int ok = meso_frusta_tessellate(obj->recs, nf, obj->balls, nb, &g, &t);
    free(cells);
    if (!ok)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frusta stand-in: out of memory tessellating");
    meso_result r = to_mesh(&t, &out->mesh, err);
    /* Term 3 and the bounds. */
    double big = 0;
    for (int k = 0; k < 3; ++k) {
        out->bbox_min[k] = FLT_MAX;
        out->bbox_max[k] = -FLT_MAX;
    }
    for (uint32_t v = 0; r == MESO_OK && v < t.vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            const float x = t.positions[3 * (size_t)v + k];
            big = fmax(big, fabs(x));
            out->bbox_min[k] = fminf(out->bbox_min[k], x);
            out->bbox_max[k] = fmaxf(out->bbox_max[k], x);
        }
    if (r == MESO_OK) { /* kept for the stand-in's colours */
        out->owner = t.owner;
        out->uv = t.uv;
        t.owner = NULL;
        t.uv = NULL;
    }
    meso_frusta_tess_free(&t);
    if (r != MESO_OK) {
        meso_frusta_standin_free(out);
        return r;
    }
    out->relief_error = relief_err;
    out->chord_error = 4.0 / 3.0 * sag;
    const double e = relief_err + out->chord_error + ldexp(big, -23);
    float fe = (float)e;
    if ((double)fe < e)
        fe = nextafterf(fe, INFINITY);
    out->error = fe;
    return MESO_OK;
}

/* >>appearance */

/* The colour map at (s, t) as frusta_frag.glsl's color_bilinear at level 0. */
static void map_bilinear(const meso_color_map* m, double s, double t, float out[3])
{
    const double W = m->width, H = m->height, x = s * W - 0.5, y = t * H - 0.5;
    const double x0 = floor(x), y0 = floor(y), fx = x - x0, fy = y - y0;
    const uint32_t a[2] = {(uint32_t)fmin(fmod(fmod(x0, W) + W, W), W - 1), (uint32_t)fmin(fmod(fmod(x0 + 1, W) + W, W), W - 1)};
    const uint32_t b[2] = {(uint32_t)fmin(fmod(fmod(y0, H) + H, H), H - 1), (uint32_t)fmin(fmod(fmod(y0 + 1, H) + H, H), H - 1)};
    for (int k = 0; k < 3; ++k) {
        double c[2][2];
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i)
                c[j][i] = meso_srgb8_to_linear(m->rgba[4 * ((size_t)b[j] * m->width + a[i]) + (size_t)k]);
        out[k] = (float)((1 - fy) * ((1 - fx) * c[0][0] + fx * c[0][1]) + fy * ((1 - fx) * c[1][0] + fx * c[1][1]));
    }
}

static void frusta_at(const mesoi_appearance* a, mesoi_tri_grid* grid, uint32_t t, const double b[3],
                      const double p[3], float out[4])
{
    (void)grid;
    (void)p;
    const meso_frusta_colours* c = a->ctx;
    const uint32_t* ix = c->st->mesh.indices + 3 * (size_t)t;
    const uint32_t o = c->st->owner[ix[0]];
    out[3] = 1.0f;
    if (o >= c->obj->count) { /* a ball */
        memcpy(out, c->mean, sizeof c->mean);
        return;
    }
    const meso_frustum_rec* r = &c->obj->recs[o];
    double uv[2] = {0, 0};
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 2; ++j)
            uv[j] += b[k] * c->st->uv[2 * (size_t)ix[k] + (size_t)j];
    /* A cap's point (v outside [0, 1]: frusta_tessellation.h) shows the
     * colour at its end's relief coordinates, and on a relief frustum
     * occlusion 0.25: it lies inside the cone, below the relief layer, so
     * the shader's w there is negative, clamped to 0. */
    const int cap = uv[1] < 0 || uv[1] > 1;
    const double v = cap ? (uv[1] < 0 ? 0 : 1) : uv[1];
    const double s = uv[0] * r->u_scale, tt = r->v_offset + v * r->v_scale;
    if (c->color)
        map_bilinear(c->color, s, tt, out);
    else
        out[0] = out[1] = out[2] = 1.0f; /* the draw's albedo */
    if (c->relief && r->relief_depth > 0)
        out[3] = cap ? 0.25f : (float)(0.25 + 0.75 * fmin(fmax(meso_texfn_sample(c->relief, s, tt, 0), 0), 1));
}

void meso_frusta_standin_appearance(const meso_frusta_object* obj, const meso_frusta_standin* st,
    const meso_texfn* relief, const meso_color_map* color, meso_frusta_colours* ctx, mesoi_appearance* out)
{
    double sum[3] = {0, 0, 0};
    const size_t n = color ? (size_t)color->width * color->height : 0;
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k)
            sum[k] += meso_srgb8_to_linear(color->rgba[4 * i + (size_t)k]);
    *ctx = (meso_frusta_colours){.obj = obj, .st = st, .relief = relief, .color = color};
    for (int k = 0; k < 3; ++k)
        ctx->mean[k] = (float)(n ? sum[k] / (double)n : 0.5);
    /* Asking is cheap (two bilinear lookups): 16 x 16 sub-triangles at
     * most, as a triangle may span many texels of the map. */
    *out = (mesoi_appearance){.at = frusta_at, .ctx = ctx, .subdivisions = 16, .occlusion_only = color == NULL};
}
