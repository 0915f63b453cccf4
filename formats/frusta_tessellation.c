/*
 * frusta_tessellation.c — see frusta_tessellation.h. Moved here from the
 * benchmarks (tests/bench) when `mesoinspect export` needed the same mesh,
 * then from the references (runtime/reference) when the baker's mesh
 * stand-in did; the relief height is the caller's (the reference passes its
 * own sampler, the baker a constant).
 */
#include "frusta_tessellation.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double meso_frusta_height_constant(const void* ctx, double s, double t)
{
    (void)s;
    (void)t;
    return *(const double*)ctx;
}

void meso_frusta_tess_point(const meso_frustum_rec* f, meso_frusta_height_fn height, const void* ctx, double u,
    double v, double p[3])
{
    meso_frustum_frame fr;
    meso_frustum_rec_frame(f, &fr);
    const double depth = height ? f->relief_depth : 0;
    const double hh = depth > 0 ? height(ctx, u * f->u_scale, f->v_offset + v * f->v_scale) : 0;
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
    meso_frusta_tess_mesh m;
    uint32_t cap_v, cap_i;
    double* edge_sag; /* NULL: not measured */
} tess_buf;

static int tess_grow(tess_buf* b, uint64_t add_v, uint64_t add_i)
{
    meso_frusta_tess_mesh* m = &b->m;
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
        float* uv = realloc(m->uv, 2 * sizeof(float) * (size_t)nc);
        if (uv)
            m->uv = uv;
        if (!p || !n || !o || !uv)
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

/* |fn(midpoint) − (fn(a) + fn(b)) / 2| for the grid edge (u0, v0)–(u1, v1). */
static double edge_sag(tess_fn fn, const void* ctx, double u0, double v0, double u1, double v1)
{
    double a[3], b[3], m[3], s = 0;
    fn(ctx, u0, v0, a);
    fn(ctx, u1, v1, b);
    fn(ctx, 0.5 * (u0 + u1), 0.5 * (v0 + v1), m);
    for (int k = 0; k < 3; ++k)
        s += (m[k] - 0.5 * (a[k] + b[k])) * (m[k] - 0.5 * (a[k] + b[k]));
    return sqrt(s);
}

/* The sag of every edge of the grid (frusta_tessellation.h, edge_sag): each
 * cell's bottom and left sides and its diagonal (b–c below), the last
 * column's right sides and the last row's tops. */
static double grid_sag(tess_fn fn, const void* ctx, uint32_t nu, uint32_t nv)
{
    const double du = 1.0 / nu, dv = 1.0 / nv;
    double worst = 0;
    for (uint32_t j = 0; j <= nv; ++j)
        for (uint32_t i = 0; i <= nu; ++i) {
            const double u = i * du, v = j * dv;
            if (i < nu)
                worst = fmax(worst, edge_sag(fn, ctx, u, v, u + du, v));
            if (j < nv)
                worst = fmax(worst, edge_sag(fn, ctx, u, v, u, v + dv));
            if (i < nu && j < nv)
                worst = fmax(worst, edge_sag(fn, ctx, u + du, v, u, v + dv));
        }
    return worst;
}

/* cap_end: -1 for a lateral grid or a ball (uv = the grid's (u, v)), else
 * the end whose cap this is (uv = (u, -1) at end 0, (u, 2) at end 1). */
static int tess_grid(tess_buf* b, tess_fn fn, const void* ctx, uint32_t owner, uint32_t nu, uint32_t nv, int flip,
    int measure, int cap_end)
{
    if (!tess_grow(b, ((uint64_t)nu + 1) * ((uint64_t)nv + 1), 6 * (uint64_t)nu * nv))
        return 0;
    if (b->edge_sag && measure)
        *b->edge_sag = fmax(*b->edge_sag, grid_sag(fn, ctx, nu, nv));
    meso_frusta_tess_mesh* m = &b->m;
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
            m->uv[2 * (size_t)m->vertex_count] = (float)u;
            m->uv[2 * (size_t)m->vertex_count + 1] = (float)(cap_end < 0 ? v : cap_end ? 2 : -1);
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
    meso_frusta_height_fn height;
    const void* height_ctx;
} seg_ctx;

static void seg_fn(const void* ctx, double u, double v, double p[3])
{
    const seg_ctx* c = ctx;
    meso_frusta_tess_point(c->f, c->height, c->height_ctx, u, v, p);
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
    seg_ctx seg;
    int end;
} cap_ctx;

static void cap_fn(const void* ctx, double u, double v, double p[3])
{
    const cap_ctx* c = ctx;
    double rim[3];
    seg_fn(&c->seg, u, (double)c->end, rim);
    for (int i = 0; i < 3; ++i)
        p[i] = c->seg.f->center[c->end][i] + v * (rim[i] - c->seg.f->center[c->end][i]);
}

int meso_frusta_tessellate(const meso_frustum_rec* recs, uint32_t count, const meso_frustum_ball_rec* balls,
    uint32_t ball_count, const meso_frusta_tess_grid* grid, meso_frusta_tess_mesh* out)
{
    tess_buf b;
    memset(&b, 0, sizeof(b));
    memset(out, 0, sizeof(*out));
    b.edge_sag = grid->edge_sag;
    if (b.edge_sag)
        *b.edge_sag = 0;
    for (uint32_t f = 0; f < count; ++f) {
        const uint32_t nu = grid->nu[f], nv = grid->nv[f];
        if (!nu || !nv)
            goto fail;
        const seg_ctx c = {&recs[f], grid->height, grid->height_ctx};
        if (!tess_grid(&b, seg_fn, &c, f, nu, nv, 0, 1, -1))
            goto fail;
        for (int e = 0; e < 2; ++e) {
            if (!(recs[f].flags & (e ? MESO_FSEG_CAP1 : MESO_FSEG_CAP0)))
                continue;
            const cap_ctx cc = {c, e};
            /* a cap is not measured: a plane region, convex (a convex
             * cone's cut), fanned from its centre to the lateral grid's own
             * rim points, so it is within the rim's sag (measured there)
             * of the fan; its (u, v) midpoints would only measure the
             * fan's parametrisation */
            if (!tess_grid(&b, cap_fn, &cc, f, nu, 1, e == 0, 0, e))
                goto fail;
        }
    }
    for (uint32_t i = 0; i < ball_count; ++i) {
        const uint32_t nu = grid->ball_nu[i];
        if (!nu || !tess_grid(&b, ball_fn, &balls[i], count + i, nu, nu / 2 ? nu / 2 : 1, 1, 1, -1))
            goto fail;
    }
    *out = b.m;
    return 1;
fail:
    meso_frusta_tess_free(&b.m);
    return 0;
}

void meso_frusta_tess_free(meso_frusta_tess_mesh* m)
{
    free(m->positions);
    free(m->normals);
    free(m->owner);
    free(m->uv);
    free(m->indices);
    memset(m, 0, sizeof(*m));
}
