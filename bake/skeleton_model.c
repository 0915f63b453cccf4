/*
 * skeleton_model.c — the model meso_skeleton_from_mesh measures and its
 * two-sided error: the union of round-ended frusta (each segment the solid
 * truncated cone of radius linear along it, each node a ball of its radius)
 * and its distance to and from the mesh.
 *
 * From skeleton_from_mesh.h, "What is measured": the distance to the union
 * is the minimum over its pieces of their signed distances, exact outside
 * and a lower bound of the depth inside (mesh vertices -> model). The other
 * direction (a model too fat) samples the union's boundary (each piece's
 * surface outside every other piece, spacing max(tolerance/2, enough for
 * 30000 points)) and takes each sample's exact distance to the mesh's
 * triangles (triangle_grid.c). The renderer's model differs at bends and
 * tips (frustum_model.h); the header says by how much.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skeleton_from_mesh_internal.h"
#include "triangle_grid.h"

void mesoi_model_fill(const double* x, const int32_t* parent, const uint8_t* keep, uint32_t n, mesoi_model* md)
{
    md->n = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (keep && !keep[i])
            continue;
        const double* xi = x + 4 * (size_t)i;
        mesoi_piece* b = &md->p[md->n++];
        memcpy(b->a, xi, sizeof(b->a));
        memcpy(b->b, xi, sizeof(b->b));
        memcpy(b->c, xi, sizeof(b->c));
        b->ra = b->rb = b->bound = xi[3];
        b->ball = 1;
        b->node = i;
        if (parent[i] < 0)
            continue;
        const double* xj = x + 4 * (size_t)parent[i];
        mesoi_piece* f = &md->p[md->n++];
        memcpy(f->a, xj, sizeof(f->a));
        memcpy(f->b, xi, sizeof(f->b));
        f->ra = xj[3];
        f->rb = xi[3];
        for (int k = 0; k < 3; ++k)
            f->c[k] = 0.5 * (f->a[k] + f->b[k]);
        f->bound = 0.5 * dist3(f->a, f->b) + (f->ra > f->rb ? f->ra : f->rb);
        f->ball = 0;
        f->node = i;
    }
}

meso_result mesoi_model_alloc(uint32_t n, mesoi_model* md, meso_error* err)
{
    md->n = 0;
    md->p = malloc(sizeof(mesoi_piece) * 2 * (size_t)(n ? n : 1));
    return md->p ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
}

static double piece_distance(const mesoi_piece* q, const double p[3])
{
    return q->ball ? dist3(p, q->c) - q->ra : meso_cone_frustum_distance(q->a, q->ra, q->b, q->rb, p);
}

/* min over pieces of the signed distance, skipping pieces whose bounding
 * sphere proves them no closer; *hint (a piece index) is tried first and
 * updated to the minimiser (neighbouring queries share it). */
double mesoi_model_distance(const mesoi_model* md, const double p[3], uint32_t* hint)
{
    const uint32_t h0 = *hint < md->n ? *hint : 0;
    uint32_t h = h0;
    double best = piece_distance(&md->p[h], p);
    for (uint32_t i = 0; i < md->n; ++i) {
        if (i == h0 || dist3(p, md->p[i].c) - md->p[i].bound >= best)
            continue;
        const double d = piece_distance(&md->p[i], p);
        if (d < best) {
            best = d;
            h = i;
        }
    }
    *hint = h;
    return best;
}

/* Mesh vertices -> model: largest and mean |signed distance|. */
void mesoi_mesh_to_model(const mesoi_clean_mesh* c, const mesoi_model* md, double* emax, double* emean)
{
    uint32_t hint = 0;
    double mx = 0, sum = 0;
    for (uint32_t v = 0; v < c->nv; ++v) {
        const double d = fabs(mesoi_model_distance(md, c->xyz + 3 * (size_t)v, &hint));
        mx = d > mx ? d : mx;
        sum += d;
    }
    *emax = mx;
    *emean = c->nv ? sum / c->nv : 0;
}

/* >>model-to-mesh ------------------------------------------------------ */
/* Model -> mesh: points on the union's boundary (each piece's surface at
 * spacing ~h, kept when no other piece contains them) and their exact
 * distance to the mesh. Returns the largest; *count the points used. */
meso_result mesoi_model_to_mesh(const mesoi_clean_mesh* c, const mesoi_model* md, double h, double* out_max,
                                uint32_t* count, meso_error* err)
{
    /* Bounds of the mesh and of every piece, for the grid. */
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (uint32_t v = 0; v < c->nv; ++v)
        for (int k = 0; k < 3; ++k) {
            const double x = c->xyz[3 * (size_t)v + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    for (uint32_t i = 0; i < md->n; ++i)
        for (int k = 0; k < 3; ++k) {
            const double l = md->p[i].c[k] - md->p[i].bound, u = md->p[i].c[k] + md->p[i].bound;
            lo[k] = l < lo[k] ? l : lo[k];
            hi[k] = u > hi[k] ? u : hi[k];
        }
    mesoi_tri_grid g;
    meso_result r = mesoi_tri_grid_build(c->xyz, c->tri, c->nt, lo, hi, &g, err);
    if (r != MESO_OK)
        return r;
    const double eps = 1e-9 * c->diag;
    double mx = 0;
    uint32_t used = 0;
    for (uint32_t i = 0; i < md->n; ++i) {
        const mesoi_piece* q = &md->p[i];
        /* Axis frame (u, v, ax); a ball uses the z axis. */
        double ax[3] = {0, 0, 1}, u[3], v[3];
        double len = 0;
        if (!q->ball) {
            sub3(q->b, q->a, ax);
            if ((len = normalize3(ax)) <= 0)
                continue;
        }
        any_perp3(ax, u);
        cross3(ax, u, v);
        /* Rings: along the axis for a cone, over the polar angle for a ball. */
        const uint32_t rings = q->ball ? 1 + (uint32_t)ceil(M_PI * q->ra / h) : 1 + (uint32_t)ceil(len / h);
        for (uint32_t ri = 0; ri <= rings; ++ri) {
            const double s = (double)ri / rings;
            double centre[3], rr;
            if (q->ball) {
                const double th = M_PI * s;
                rr = q->ra * sin(th);
                for (int k = 0; k < 3; ++k)
                    centre[k] = q->c[k] + q->ra * cos(th) * ax[k];
            } else {
                rr = q->ra + (q->rb - q->ra) * s;
                for (int k = 0; k < 3; ++k)
                    centre[k] = q->a[k] + s * len * ax[k];
            }
            const uint32_t around = rr > 0 ? 1 + (uint32_t)ceil(2 * M_PI * rr / h) : 1;
            for (uint32_t ai = 0; ai < around; ++ai) {
                const double ph = 2 * M_PI * (ai + 0.5 * (ri & 1)) / around;
                double p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = centre[k] + rr * (cos(ph) * u[k] + sin(ph) * v[k]);
                int hidden = 0;
                for (uint32_t j = 0; j < md->n && !hidden; ++j)
                    hidden = j != i && dist3(p, md->p[j].c) - md->p[j].bound < -eps &&
                             piece_distance(&md->p[j], p) < -eps;
                if (hidden)
                    continue;
                const double d = mesoi_tri_grid_distance(&g, p);
                mx = d > mx ? d : mx;
                ++used;
            }
        }
    }
    mesoi_tri_grid_free(&g);
    *out_max = mx;
    *count = used;
    return MESO_OK;
}

/* Sample spacing for mesoi_model_to_mesh: half the tolerance, coarsened so that
 * the pieces' total area holds at most ~30000 points. */
double mesoi_sample_spacing(const mesoi_model* md, double tol)
{
    double area = 0;
    for (uint32_t i = 0; i < md->n; ++i) {
        const mesoi_piece* q = &md->p[i];
        if (q->ball)
            area += 4 * M_PI * q->ra * q->ra;
        else
            area += M_PI * (q->ra + q->rb) * hypot(dist3(q->a, q->b), q->ra - q->rb);
    }
    const double h = 0.5 * tol, hmin = sqrt(area / 30000.0);
    return h > hmin ? h : hmin;
}

