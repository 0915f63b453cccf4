/*
 * frusta_tessellate.c — see frusta_tessellate.h. Moved here from the
 * benchmarks (tests/bench) when `mesoinspect export` needed the same mesh;
 * the relief height is now the reference's own sampler.
 */
#include "frusta_tessellate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double relief_height(const meso_ref_texfn* rel, double s, double t)
{
    return rel && rel->kind == 1 && rel->values ? meso_ref_texfn_value(rel, s, t, 0) : 0;
}

void meso_ref_tess_point(const meso_frustum_rec* f, const meso_ref_texfn* relief, double u, double v, double p[3])
{
    meso_frustum_frame fr;
    meso_frustum_rec_frame(f, &fr);
    const double depth = relief && relief->kind == 1 && relief->values ? f->relief_depth : 0;
    const double hh = depth > 0 ? relief_height(relief, u * f->u_scale, f->v_offset + v * f->v_scale) : 0;
    const double delta = hh * depth;
    double w[3];
    meso_frustum_frame_radial(&fr, 2 * M_PI * (u + f->u_offset) - v * f->twist, w);
    const double y0 = meso_frustum_rec_cut(f, &fr, delta, w, 0, NULL), y1 = meso_frustum_rec_cut(f, &fr, delta, w, 1, NULL);
    const double yy = y0 + v * (y1 - y0);
    const double rr = f->radius[0] + delta + fr.k * yy;
    for (int i = 0; i < 3; ++i)
        p[i] = fr.c0[i] + yy * fr.a[i] + rr * w[i];
}

typedef struct tess_buf {
    meso_ref_tess_mesh m;
    uint32_t cap_v, cap_i;
} tess_buf;

static int tess_grow(tess_buf* b, uint64_t add_v, uint64_t add_i)
{
    meso_ref_tess_mesh* m = &b->m;
    if (m->vertex_count + add_v > UINT32_MAX || m->index_count + add_i > UINT32_MAX)
        return 0;
    if (m->vertex_count + add_v > b->cap_v) {
        uint64_t nc = 2 * ((uint64_t)b->cap_v + add_v);
        if (nc > UINT32_MAX)
            nc = UINT32_MAX;
        float* p = realloc(m->positions, 3 * sizeof(float) * (size_t)nc);
        if (p)
            m->positions = p;
        float* n = realloc(m->normals, 3 * sizeof(float) * (size_t)nc);
        if (n)
            m->normals = n;
        uint32_t* o = realloc(m->owner, sizeof(uint32_t) * (size_t)nc);
        if (o)
            m->owner = o;
        if (!p || !n || !o)
            return 0;
        b->cap_v = (uint32_t)nc;
    }
    if (m->index_count + add_i > b->cap_i) {
        uint64_t nc = 2 * ((uint64_t)b->cap_i + add_i);
        if (nc > UINT32_MAX)
            nc = UINT32_MAX;
        uint32_t* ix = realloc(m->indices, sizeof(uint32_t) * (size_t)nc);
        if (!ix)
            return 0;
        m->indices = ix;
        b->cap_i = (uint32_t)nc;
    }
    return 1;
}

/* Grid of (nu + 1) × (nv + 1) points over (u, v) ∈ [0,1]², fn(u, v) → p;
 * normals by central differences (outward: the callers' grids run so that
 * ∂p/∂v × ∂p/∂u points out, or pass flip). */
typedef void (*tess_fn)(const void* ctx, double u, double v, double p[3]);

static int tess_grid(tess_buf* b, tess_fn fn, const void* ctx, uint32_t owner, uint32_t nu, uint32_t nv, int flip)
{
    if (!tess_grow(b, ((uint64_t)nu + 1) * ((uint64_t)nv + 1), 6 * (uint64_t)nu * nv))
        return 0;
    meso_ref_tess_mesh* m = &b->m;
    const uint32_t base = m->vertex_count;
    const double du = 1.0 / nu, dv = 1.0 / nv, e = 1e-4;
    for (uint32_t j = 0; j <= nv; ++j)
        for (uint32_t i = 0; i <= nu; ++i) {
            const double u = i * du, v = j * dv;
            double p[3], pu0[3], pu1[3], pv0[3], pv1[3];
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
            const double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            float* P = m->positions + 3 * (size_t)m->vertex_count;
            float* N = m->normals + 3 * (size_t)m->vertex_count;
            for (int k = 0; k < 3; ++k) {
                P[k] = (float)p[k];
                N[k] = (float)(l > 0 ? (flip ? -n[k] : n[k]) / l : 0);
            }
            m->owner[m->vertex_count++] = owner;
        }
    for (uint32_t j = 0; j < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i) {
            const uint32_t a = base + j * (nu + 1) + i, bb = a + 1, c = a + nu + 1, d = c + 1;
            uint32_t q[6] = {a, c, bb, bb, c, d};
            if (flip) {
                q[1] = bb;
                q[2] = c;
                q[4] = d;
                q[5] = c;
            }
            for (int k = 0; k < 6; ++k)
                m->indices[m->index_count++] = q[k];
        }
    return 1;
}

typedef struct seg_ctx {
    const meso_frustum_rec* f;
    const meso_ref_texfn* rel;
} seg_ctx;

static void seg_fn(const void* ctx, double u, double v, double p[3])
{
    const seg_ctx* c = ctx;
    meso_ref_tess_point(c->f, c->rel, u, v, p);
}

static void ball_fn(const void* ctx, double u, double v, double p[3])
{
    const meso_frustum_ball_rec* b = ctx;
    const double th = M_PI * v, ph = 2 * M_PI * u;
    p[0] = b->center[0] + b->radius * sin(th) * cos(ph);
    p[1] = b->center[1] + b->radius * sin(th) * sin(ph);
    p[2] = b->center[2] + b->radius * cos(th);
}

/* Cap of end e: a disc in the plane, as a degenerate grid from the centre
 * (v = 0) out to the cut curve (v = 1). */
typedef struct cap_ctx {
    const meso_frustum_rec* f;
    const meso_ref_texfn* rel;
    int end;
} cap_ctx;

static void cap_fn(const void* ctx, double u, double v, double p[3])
{
    const cap_ctx* c = ctx;
    double rim[3];
    meso_ref_tess_point(c->f, c->rel, u, (double)c->end, rim);
    for (int i = 0; i < 3; ++i)
        p[i] = c->f->center[c->end][i] + v * (rim[i] - c->f->center[c->end][i]);
}

int meso_ref_frusta_tessellate(const meso_frustum_rec* recs, uint32_t count, const meso_frustum_ball_rec* balls,
    uint32_t ball_count, const meso_ref_texfn* relief, uint32_t nu, meso_ref_tess_mesh* out)
{
    tess_buf b;
    memset(&b, 0, sizeof(b));
    memset(out, 0, sizeof(*out));
    if (nu == 0 || nu > MESO_REF_TESS_MAX_GRID)
        return 0;
    for (uint32_t f = 0; f < count; ++f) {
        const double ratio = recs[f].u_scale > 0 ? recs[f].v_scale / recs[f].u_scale : 1;
        /* a long thin frustum gets at most 64 nu rings (a valid file must
         * not fail for its proportions; its cells are then longer than wide) */
        const double nvd = fmin(fmax(2.0, ceil(nu * ratio)), 64.0 * nu);
        const uint32_t nv = (uint32_t)nvd;
        const seg_ctx c = {&recs[f], relief};
        if (!tess_grid(&b, seg_fn, &c, f, nu, nv, 0))
            goto fail;
        for (int e = 0; e < 2; ++e) {
            if (!(recs[f].flags & (e ? MESO_FSEG_CAP1 : MESO_FSEG_CAP0)))
                continue;
            const cap_ctx cc = {&recs[f], relief, e};
            if (!tess_grid(&b, cap_fn, &cc, f, nu, 1, e == 0))
                goto fail;
        }
    }
    for (uint32_t i = 0; i < ball_count; ++i)
        if (!tess_grid(&b, ball_fn, &balls[i], count + i, nu, nu / 2 ? nu / 2 : 1, 1))
            goto fail;
    *out = b.m;
    return 1;
fail:
    meso_ref_tess_free(&b.m);
    return 0;
}

void meso_ref_tess_free(meso_ref_tess_mesh* m)
{
    free(m->positions);
    free(m->normals);
    free(m->owner);
    free(m->indices);
    memset(m, 0, sizeof(*m));
}
