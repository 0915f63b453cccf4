/*
 * frusta_tessellate.h — the polygon baseline of relief-mapped-conical-
 * frusta.md §4 (its Figure 6: "at least 256k polygons are necessary to
 * achieve similar quality to ray casting"): each frustum's relief surface
 * (FORMAT.md §7.2 kind 4, w = h(s, t)) sampled on a regular (u, v) grid and
 * triangulated, balls as latitude–longitude spheres, flagged caps as fans.
 *
 * The grid point (u, v) of a frustum lies on the parallel cone r(y) + h D
 * through it: angle φ = 2π (u + u_offset − v·twist/2π) around the axis, and
 * the axial coordinate y = y0 + v (y1 − y0) between where that cone's
 * generator meets the two planes — the exact inverse of the ray caster's
 * (u, v), so a finer grid converges to the surface the reference renders.
 * Normals are central differences of the grid. Neighbouring frusta meet at
 * the joint plane along the same curve, but their grids do not share
 * vertices (u frames agree at one point only), so a coarse tessellation can
 * show hairline cracks there; the error metric counts them, as it would in
 * an engine. Bench-only code: not part of meso.
 */
#ifndef MESO_FRUSTA_TESSELLATE_H
#define MESO_FRUSTA_TESSELLATE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "frusta_pose.h"

typedef struct tess_relief {
    uint32_t w, h;
    const float* values; /* w*h in [0, 1], s fastest */
} tess_relief;

typedef struct tess_mesh {
    uint32_t vertex_count, index_count;
    float* positions;
    float* normals;
    uint32_t* indices;
} tess_mesh;

static double tess_height(const tess_relief* r, double s, double t)
{
    if (!r || !r->values)
        return 0;
    double x = s * r->w - 0.5, y = t * r->h - 0.5;
    double fx = floor(x), fy = floor(y);
    double ax = x - fx, ay = y - fy;
    long ix = (long)fx, iy = (long)fy;
    long W = (long)r->w, H = (long)r->h;
    long x0 = ((ix % W) + W) % W, x1 = (x0 + 1) % W, y0 = ((iy % H) + H) % H, y1 = (y0 + 1) % H;
    double v00 = r->values[y0 * W + x0], v10 = r->values[y0 * W + x1];
    double v01 = r->values[y1 * W + x0], v11 = r->values[y1 * W + x1];
    return (1 - ay) * ((1 - ax) * v00 + ax * v10) + ay * ((1 - ax) * v01 + ax * v11);
}

/* Surface point of frustum f at (u, v). */
static void tess_point(const meso_frustum_rec* f, const tess_relief* rel, double u, double v, double p[3])
{
    meso_frustum_frame fr;
    meso_frustum_rec_frame(f, &fr);
    double depth = rel && rel->values ? f->relief_depth : 0;
    double hh = depth > 0 ? tess_height(rel, u * f->u_scale, f->v_offset + v * f->v_scale) : 0;
    double delta = hh * depth, w[3];
    meso_frustum_frame_radial(&fr, 2 * M_PI * (u + f->u_offset) - v * f->twist, w);
    double y0 = meso_frustum_rec_cut(f, &fr, delta, w, 0, NULL), y1 = meso_frustum_rec_cut(f, &fr, delta, w, 1, NULL);
    double yy = y0 + v * (y1 - y0);
    double rr = f->radius[0] + delta + fr.k * yy;
    for (int i = 0; i < 3; ++i)
        p[i] = fr.c0[i] + yy * fr.a[i] + rr * w[i];
}

static int tess_grow(tess_mesh* m, uint32_t add_v, uint32_t add_i, uint32_t* cap_v, uint32_t* cap_i)
{
    if (m->vertex_count + add_v > *cap_v) {
        uint32_t nc = (*cap_v + add_v) * 2;
        float* p = realloc(m->positions, 3 * sizeof(float) * nc);
        if (p)
            m->positions = p;
        float* n = realloc(m->normals, 3 * sizeof(float) * nc);
        if (n)
            m->normals = n;
        if (!p || !n)
            return 0;
        *cap_v = nc;
    }
    if (m->index_count + add_i > *cap_i) {
        uint32_t nc = (*cap_i + add_i) * 2;
        uint32_t* ix = realloc(m->indices, sizeof(uint32_t) * nc);
        if (!ix)
            return 0;
        m->indices = ix;
        *cap_i = nc;
    }
    return 1;
}

/* Grid of (nu + 1) × (nv + 1) points over (u, v) ∈ [0,1]², fn(u, v) → p;
 * normals by central differences (outward: the callers' grids run so that
 * ∂p/∂v × ∂p/∂u points out). */
typedef void (*tess_fn)(const void* ctx, double u, double v, double p[3]);

static int tess_grid(tess_mesh* m, uint32_t* cap_v, uint32_t* cap_i, tess_fn fn, const void* ctx, uint32_t nu,
    uint32_t nv, int flip)
{
    if (!tess_grow(m, (nu + 1) * (nv + 1), 6 * nu * nv, cap_v, cap_i))
        return 0;
    uint32_t base = m->vertex_count;
    double du = 1.0 / nu, dv = 1.0 / nv, e = 1e-4;
    for (uint32_t j = 0; j <= nv; ++j)
        for (uint32_t i = 0; i <= nu; ++i) {
            double u = i * du, v = j * dv, p[3], pu0[3], pu1[3], pv0[3], pv1[3];
            fn(ctx, u, v, p);
            fn(ctx, u - e, v, pu0);
            fn(ctx, u + e, v, pu1);
            fn(ctx, u, fmax(0, v - e), pv0);
            fn(ctx, u, fmin(1, v + e), pv1);
            double tu[3], tv[3], n[3];
            for (int k = 0; k < 3; ++k) {
                tu[k] = pu1[k] - pu0[k];
                tv[k] = pv1[k] - pv0[k];
            }
            n[0] = tv[1] * tu[2] - tv[2] * tu[1];
            n[1] = tv[2] * tu[0] - tv[0] * tu[2];
            n[2] = tv[0] * tu[1] - tv[1] * tu[0];
            double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            float* P = m->positions + 3 * (size_t)m->vertex_count;
            float* N = m->normals + 3 * (size_t)m->vertex_count;
            for (int k = 0; k < 3; ++k) {
                P[k] = (float)p[k];
                N[k] = (float)(l > 0 ? (flip ? -n[k] : n[k]) / l : 0);
            }
            m->vertex_count++;
        }
    for (uint32_t j = 0; j < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i) {
            uint32_t a = base + j * (nu + 1) + i, b = a + 1, c = a + nu + 1, d = c + 1;
            uint32_t q[6] = {a, c, b, b, c, d};
            if (flip) {
                q[1] = b;
                q[2] = c;
                q[4] = d;
                q[5] = c;
            }
            for (int k = 0; k < 6; ++k)
                m->indices[m->index_count++] = q[k];
        }
    return 1;
}

typedef struct tess_seg_ctx {
    const meso_frustum_rec* f;
    const tess_relief* rel;
} tess_seg_ctx;

static void tess_seg_fn(const void* ctx, double u, double v, double p[3])
{
    const tess_seg_ctx* c = ctx;
    tess_point(c->f, c->rel, u, v, p);
}

typedef struct tess_ball_ctx {
    const meso_frustum_ball_rec* b;
} tess_ball_ctx;

static void tess_ball_fn(const void* ctx, double u, double v, double p[3])
{
    const meso_frustum_ball_rec* b = ((const tess_ball_ctx*)ctx)->b;
    double th = M_PI * v, ph = 2 * M_PI * u;
    p[0] = b->center[0] + b->radius * sin(th) * cos(ph);
    p[1] = b->center[1] + b->radius * sin(th) * sin(ph);
    p[2] = b->center[2] + b->radius * cos(th);
}

/* Cap of end e: a disc in the plane, as a degenerate grid from the centre
 * (v = 0) out to the cut curve (v = 1). */
typedef struct tess_cap_ctx {
    const meso_frustum_rec* f;
    const tess_relief* rel;
    int end;
} tess_cap_ctx;

static void tess_cap_fn(const void* ctx, double u, double v, double p[3])
{
    const tess_cap_ctx* c = ctx;
    double rim[3];
    tess_point(c->f, c->rel, u, (double)c->end, rim);
    for (int i = 0; i < 3; ++i)
        p[i] = c->f->center[c->end][i] + v * (rim[i] - c->f->center[c->end][i]);
}

/* The whole object: per frustum an nu × nv grid (plus caps) with nv chosen
 * so grid cells cover as much relief texture along v as across u
 * (nv = nu · v_scale / u_scale, at least 2), per ball an nu × nu/2 sphere.
 * Returns 0 on out of memory. Free with tess_free. */
static int tess_frusta(const meso_frustum_rec* recs, uint32_t count, const meso_frustum_ball_rec* balls,
    uint32_t ball_count, const tess_relief* rel, uint32_t nu, tess_mesh* out)
{
    tess_mesh m = {0};
    uint32_t cap_v = 0, cap_i = 0;
    for (uint32_t f = 0; f < count; ++f) {
        double ratio = recs[f].u_scale > 0 ? recs[f].v_scale / recs[f].u_scale : 1;
        uint32_t nv = (uint32_t)fmax(2.0, ceil(nu * ratio));
        tess_seg_ctx c = {&recs[f], rel};
        if (!tess_grid(&m, &cap_v, &cap_i, tess_seg_fn, &c, nu, nv, 0))
            goto oom;
        for (int e = 0; e < 2; ++e) {
            if (!(recs[f].flags & (e ? MESO_FSEG_CAP1 : MESO_FSEG_CAP0)))
                continue;
            tess_cap_ctx cc = {&recs[f], rel, e};
            if (!tess_grid(&m, &cap_v, &cap_i, tess_cap_fn, &cc, nu, 1, e == 0))
                goto oom;
        }
    }
    for (uint32_t b = 0; b < ball_count; ++b) {
        tess_ball_ctx c = {&balls[b]};
        if (!tess_grid(&m, &cap_v, &cap_i, tess_ball_fn, &c, nu, nu / 2 ? nu / 2 : 1, 1))
            goto oom;
    }
    *out = m;
    return 1;
oom:
    free(m.positions);
    free(m.normals);
    free(m.indices);
    return 0;
}

static void tess_free(tess_mesh* m)
{
    free(m->positions);
    free(m->normals);
    free(m->indices);
    m->positions = m->normals = NULL;
    m->indices = NULL;
}

#endif /* MESO_FRUSTA_TESSELLATE_H */
