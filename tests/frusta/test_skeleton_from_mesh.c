/* Skeleton from a closed mesh (bake/skeleton_from_mesh.c, issue #7):
 *  - the exact point-to-truncated-cone distance against a dense sampling of
 *    the cone's surface, and the union distance against the capsule's;
 *  - generated tubes whose skeleton and radius are known: a capsule (one
 *    segment, radius error), a tube bent by 45 degrees (two segments), an
 *    inside-out capsule (flipped, same result);
 *  - the torus (a cycle, cut), the same result twice in one process, and
 *    refusals: open, two components, a non-manifold vertex, duplicated
 *    faces, a bad index, empty;
 *  - the bundled spot_low_resolution.obj (the issue's goal: fit error
 *    within 2 % of the bounding-box diagonal; numbers are printed, a 4 %
 *    guard asserted, and the outside vertices' distance recomputed). */
#include "test_util.h"

#include <string.h>

#include "adapters.h"
#include "skeleton_from_mesh.h"

/* >>distance ------------------------------------------------------------ */

/* Smallest distance from p to points sampled every ~step on the surface of
 * the truncated cone (lateral surface and both flat caps). */
static double brute_frustum(const double a[3], double ra, const double b[3], double rb, const double p[3],
                            double step)
{
    double ax[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double h = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    for (int k = 0; k < 3; ++k)
        ax[k] /= h;
    const double e[3] = {fabs(ax[0]) < 0.6 ? 1 : 0, fabs(ax[0]) < 0.6 ? 0 : 1, 0};
    double u[3] = {ax[1] * e[2] - ax[2] * e[1], ax[2] * e[0] - ax[0] * e[2], ax[0] * e[1] - ax[1] * e[0]};
    const double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; ++k)
        u[k] /= ul;
    const double v[3] = {ax[1] * u[2] - ax[2] * u[1], ax[2] * u[0] - ax[0] * u[2], ax[0] * u[1] - ax[1] * u[0]};
    const double rmax = ra > rb ? ra : rb;
    const int na = (int)ceil(2 * M_PI * rmax / step) + 8;
    double best = 1e300;
    /* (y, rho) on the three surface edges of the half-plane trapezoid. */
    const int ny = (int)ceil(h / step) + 1, nr = (int)ceil(rmax / step) + 1;
    for (int part = 0; part < 3; ++part) {
        const int n = part == 1 ? ny : nr;
        for (int i = 0; i <= n; ++i) {
            const double s = (double)i / n;
            double y, rho;
            if (part == 0)
                y = 0, rho = ra * s;
            else if (part == 1)
                y = h * s, rho = ra + (rb - ra) * s;
            else
                y = h, rho = rb * s;
            for (int j = 0; j < na; ++j) {
                const double ph = 2 * M_PI * j / na;
                double q[3], d2 = 0;
                for (int k = 0; k < 3; ++k) {
                    q[k] = a[k] + y * ax[k] + rho * (cos(ph) * u[k] + sin(ph) * v[k]);
                    d2 += (q[k] - p[k]) * (q[k] - p[k]);
                }
                best = d2 < best ? d2 : best;
            }
        }
    }
    return sqrt(best);
}

static void frustum_distance_vs_brute_force(void)
{
    uint64_t rng = 0x5EED5EEDULL;
    const double step = 0.004;
    int inside = 0;
    for (int it = 0; it < 60; ++it) {
        double a[3], b[3], p[3];
        for (int k = 0; k < 3; ++k) {
            a[k] = test_rng_uniform(&rng, -0.5, 0.5);
            b[k] = test_rng_uniform(&rng, -0.5, 0.5);
        }
        double ra = test_rng_uniform(&rng, 0.05, 0.3), rb = test_rng_uniform(&rng, 0.05, 0.3);
        if (it % 5 == 1)
            rb = 0; /* pointed tip */
        if (it % 5 == 2)
            rb = ra; /* cylinder */
        for (int k = 0; k < 3; ++k)
            p[k] = 0.5 * (a[k] + b[k]) + test_rng_uniform(&rng, -0.6, 0.6) * (it % 3 == 0 ? 0.4 : 1.0);
        const double d = meso_cone_frustum_distance(a, ra, b, rb, p);
        const double bf = brute_frustum(a, ra, b, rb, p, step);
        /* The samples are a subset of the surface: bf >= |d|, and within
         * the sampling's covering radius (~step) of it. */
        if (!(bf >= fabs(d) - 1e-12 && bf - fabs(d) < 1.5 * step))
            fprintf(stderr, "    it %d: exact %.6f brute %.6f\n", it, d, bf);
        assert(bf >= fabs(d) - 1e-12 && bf - fabs(d) < 1.5 * step);
        /* Sign: inside by an independent test in 3-D. */
        double ab[3], ap[3], c[3];
        for (int k = 0; k < 3; ++k) {
            ab[k] = b[k] - a[k];
            ap[k] = p[k] - a[k];
        }
        const double l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
        const double t = (ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2]) / l2;
        for (int k = 0; k < 3; ++k)
            c[k] = p[k] - (a[k] + t * ab[k]);
        const int in = t >= 0 && t <= 1 && sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) <= ra + (rb - ra) * t;
        assert(in == (d < 0));
        inside += in;
    }
    assert(inside >= 5);
    fprintf(stderr, "    60 frusta (%d points inside) agree with sampling at %.3f\n", inside, step);
    /* a == b: the ball of the larger radius. */
    const double o[3] = {0, 0, 0}, q[3] = {0, 0.5, 0};
    assert(fabs(meso_cone_frustum_distance(o, 0.2, o, 0.3, q) - 0.2) < 1e-15);
}

static void union_distance_is_the_capsule_outside(void)
{
    meso_skeleton_node nodes[2];
    memset(nodes, 0, sizeof(nodes));
    nodes[0].radius = nodes[1].radius = 0.25;
    nodes[0].parent = -1;
    nodes[1].pos[0] = 2;
    nodes[1].parent = 0;
    nodes[0].child_count = 1;
    uint32_t children[1] = {1};
    const meso_skeleton s = {2, 1, nodes, children};
    uint64_t rng = 7;
    for (int it = 0; it < 2000; ++it) {
        const double p[3] = {test_rng_uniform(&rng, -0.6, 2.6), test_rng_uniform(&rng, -0.6, 0.6),
                             test_rng_uniform(&rng, -0.6, 0.6)};
        const double t = p[0] < 0 ? 0 : p[0] > 2 ? 2 : p[0];
        const double exact = sqrt((p[0] - t) * (p[0] - t) + p[1] * p[1] + p[2] * p[2]) - 0.25;
        const double d = meso_skeleton_surface_distance(&s, p);
        if (exact >= 0)
            assert(fabs(d - exact) < 1e-12); /* exact outside */
        else
            assert(d < 0 && d >= exact - 1e-12); /* inside: a lower bound of the depth */
    }
}

/* >>meshes -------------------------------------------------------------- */

typedef struct builder {
    double* xyz;
    uint32_t* idx;
    uint32_t nv, nt, cv, ct;
} builder;

static uint32_t add_vertex(builder* b, const double p[3])
{
    if (b->nv == b->cv) {
        b->cv = b->cv ? 2 * b->cv : 256;
        b->xyz = realloc(b->xyz, sizeof(double) * 3 * b->cv);
        assert(b->xyz);
    }
    memcpy(b->xyz + 3 * (size_t)b->nv, p, sizeof(double) * 3);
    return b->nv++;
}

static void add_tri(builder* b, uint32_t i, uint32_t j, uint32_t k)
{
    if (b->nt == b->ct) {
        b->ct = b->ct ? 2 * b->ct : 256;
        b->idx = realloc(b->idx, sizeof(uint32_t) * 3 * b->ct);
        assert(b->idx);
    }
    b->idx[3 * (size_t)b->nt] = i;
    b->idx[3 * (size_t)b->nt + 1] = j;
    b->idx[3 * (size_t)b->nt + 2] = k;
    b->nt++;
}

static meso_mesh to_mesh(builder* b)
{
    meso_mesh m = {0};
    m.vertex_count = b->nv;
    m.triangle_count = b->nt;
    m.positions = malloc(sizeof(float) * 3 * b->nv);
    m.indices = b->idx;
    assert(m.positions);
    for (size_t i = 0; i < 3 * (size_t)b->nv; ++i)
        m.positions[i] = (float)b->xyz[i];
    free(b->xyz);
    memset(b, 0, sizeof(*b));
    return m;
}

static void unit(double v[3])
{
    const double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k)
        v[k] /= l;
}

/* Joins ring `prev` to ring `next` (N vertices each, same angular order). */
static void join_rings(builder* b, uint32_t prev, uint32_t next, int n)
{
    for (int i = 0; i < n; ++i) {
        const uint32_t a = prev + (uint32_t)i, bb = prev + (uint32_t)((i + 1) % n);
        const uint32_t c = next + (uint32_t)((i + 1) % n), d = next + (uint32_t)i;
        add_tri(b, a, bb, c);
        add_tri(b, a, c, d);
    }
}

/* A closed tube of radius r along the polyline path[0..np): hemispherical
 * caps, straight cylinders, mitred joints (rings on the bisector plane; the
 * next segment's frame is the previous one reflected in that plane). Rings
 * of n vertices about every `spacing` along the axis. CCW from outside. */
static meso_mesh tube(const double (*path)[3], int np, double r, int n, double spacing)
{
    builder b = {0};
    double d[3] = {path[1][0] - path[0][0], path[1][1] - path[0][1], path[1][2] - path[0][2]};
    unit(d);
    double u[3] = {0, 0, 1}, v[3];
    if (fabs(d[2]) > 0.9)
        u[0] = 1, u[2] = 0;
    const double ud = u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
    for (int k = 0; k < 3; ++k)
        u[k] -= ud * d[k];
    unit(u);
    v[0] = d[1] * u[2] - d[2] * u[1]; /* (u, v, d) right-handed: v = d x u */
    v[1] = d[2] * u[0] - d[0] * u[2];
    v[2] = d[0] * u[1] - d[1] * u[0];
    const int ncap = (int)ceil(0.5 * M_PI * r / spacing);
    /* Start cap: pole, then rings up to the equator at path[0]. */
    double p[3];
    for (int k = 0; k < 3; ++k)
        p[k] = path[0][k] - r * d[k];
    const uint32_t pole = add_vertex(&b, p);
    uint32_t ring = UINT32_MAX;
    for (int j = 1; j <= ncap; ++j) {
        const double al = 0.5 * M_PI * j / ncap;
        const uint32_t first = b.nv;
        for (int i = 0; i < n; ++i) {
            const double ph = 2 * M_PI * i / n;
            for (int k = 0; k < 3; ++k)
                p[k] = path[0][k] - r * cos(al) * d[k] + r * sin(al) * (cos(ph) * u[k] + sin(ph) * v[k]);
            add_vertex(&b, p);
        }
        if (j == 1)
            for (int i = 0; i < n; ++i)
                add_tri(&b, pole, first + (uint32_t)((i + 1) % n), first + (uint32_t)i);
        else
            join_rings(&b, ring, first, n);
        ring = first;
    }
    for (int s = 0; s + 1 < np; ++s) {
        const double* a = path[s];
        const double* e = path[s + 1];
        const double len = sqrt((e[0] - a[0]) * (e[0] - a[0]) + (e[1] - a[1]) * (e[1] - a[1]) + (e[2] - a[2]) * (e[2] - a[2]));
        const int steps = (int)ceil(len / spacing);
        const int last = s + 2 == np;
        double nrm[3] = {0, 0, 0}, d2[3] = {0, 0, 0};
        if (!last) {
            for (int k = 0; k < 3; ++k)
                d2[k] = path[s + 2][k] - e[k];
            unit(d2);
            for (int k = 0; k < 3; ++k)
                nrm[k] = d[k] + d2[k];
            unit(nrm);
        }
        for (int j = 1; j <= steps; ++j) {
            const uint32_t first = b.nv;
            for (int i = 0; i < n; ++i) {
                const double ph = 2 * M_PI * i / n;
                double w[3], sh = 0;
                for (int k = 0; k < 3; ++k)
                    w[k] = r * (cos(ph) * u[k] + sin(ph) * v[k]);
                if (j == steps && !last) /* onto the mitre plane along d */
                    sh = -(w[0] * nrm[0] + w[1] * nrm[1] + w[2] * nrm[2]) / (d[0] * nrm[0] + d[1] * nrm[1] + d[2] * nrm[2]);
                for (int k = 0; k < 3; ++k)
                    p[k] = a[k] + (len * j / steps + sh) * d[k] + w[k];
                add_vertex(&b, p);
            }
            join_rings(&b, ring, first, n);
            ring = first;
        }
        if (!last) { /* reflect the frame in the mitre plane */
            double* f[2] = {u, v};
            for (int q = 0; q < 2; ++q) {
                const double dn = f[q][0] * nrm[0] + f[q][1] * nrm[1] + f[q][2] * nrm[2];
                for (int k = 0; k < 3; ++k)
                    f[q][k] -= 2 * dn * nrm[k];
            }
            memcpy(d, d2, sizeof(d));
        }
    }
    /* End cap: rings from the equator (already there) to the pole. */
    const double* z = path[np - 1];
    for (int j = ncap - 1; j >= 1; --j) {
        const double al = 0.5 * M_PI * j / ncap;
        const uint32_t first = b.nv;
        for (int i = 0; i < n; ++i) {
            const double ph = 2 * M_PI * i / n;
            for (int k = 0; k < 3; ++k)
                p[k] = z[k] + r * cos(al) * d[k] + r * sin(al) * (cos(ph) * u[k] + sin(ph) * v[k]);
            add_vertex(&b, p);
        }
        join_rings(&b, ring, first, n);
        ring = first;
    }
    for (int k = 0; k < 3; ++k)
        p[k] = z[k] + r * d[k];
    const uint32_t end = add_vertex(&b, p);
    for (int i = 0; i < n; ++i)
        add_tri(&b, ring + (uint32_t)i, ring + (uint32_t)((i + 1) % n), end);
    return to_mesh(&b);
}

static meso_mesh load(const char* path)
{
    meso_mesh m;
    meso_error err = {0};
    const meso_result r = meso_openmesh_read(path, &m, NULL, &err);
    if (r != MESO_OK)
        fprintf(stderr, "%s: %s\n", path, err.message);
    assert(r == MESO_OK);
    return m;
}

/* >>fits ---------------------------------------------------------------- */

static void print_stats(const char* what, const meso_skeleton_fit_stats* st)
{
    fprintf(stderr,
            "    %s: %u vertices, CGAL %u nodes %u edges (%.2f s), cycles cut %u, unmapped %u -> %u nodes %u "
            "segments; tol %.4g (diag %.4g)\n"
            "      mesh->model max %.4g mean %.4g (CGAL tree: max %.4g mean %.4g); model->mesh max %.4g "
            "(%u samples); Hausdorff %.4g = %.2f %% of diag; %.2f s\n",
            what, st->mesh_vertices, st->cgal_nodes, st->cgal_edges, st->seconds_cgal, st->cycles_broken,
            st->unmapped_vertices, st->nodes, st->segments, st->tolerance, st->bbox_diagonal, st->fit_error_max,
            st->fit_error_mean, st->cgal_fit_error_max, st->cgal_fit_error_mean, st->model_to_mesh_max,
            st->surface_samples, st->hausdorff, 100 * st->hausdorff / st->bbox_diagonal, st->seconds_total);
}

/* Fields of the output are consistent: ids, parents before children,
 * children lists, counts. */
static void check_skeleton(const meso_skeleton* s, const meso_skeleton_fit_stats* st)
{
    assert(s->node_count == st->nodes && s->root_count == st->roots);
    assert(st->segments == s->node_count - s->root_count);
    uint32_t roots = 0, listed = 0;
    for (uint32_t i = 0; i < s->node_count; ++i) {
        const meso_skeleton_node* n = &s->nodes[i];
        assert(n->id == (int64_t)i + 1 && n->type == 0 && n->line == 0);
        assert(n->radius >= 0 && isfinite(n->radius));
        assert(n->parent < (int32_t)i);
        roots += n->parent < 0;
        for (uint32_t k = 0; k < n->child_count; ++k) {
            const uint32_t c = s->children[n->first_child + k];
            assert(c < s->node_count && s->nodes[c].parent == (int32_t)i);
            ++listed;
        }
    }
    assert(roots == s->root_count && listed == s->node_count - s->root_count);
}

static meso_skeleton fit(const meso_mesh* m, const meso_skeleton_fit_options* o, meso_skeleton_fit_stats* st)
{
    meso_skeleton s;
    meso_error err = {0};
    const meso_result r = meso_skeleton_from_mesh(m, o, &s, st, &err);
    if (r != MESO_OK)
        fprintf(stderr, "    fit failed: E%u %s\n", err.code, err.message);
    assert(r == MESO_OK);
    check_skeleton(&s, st);
    return s;
}

static void capsule_is_one_segment(void)
{
    const double path[2][3] = {{0, 0, 0}, {2, 0, 0}};
    const double r = 0.25;
    meso_mesh m = tube(path, 2, r, 32, 0.05);
    meso_skeleton_fit_stats st;
    meso_skeleton_fit_options o = {0};
    o.no_simplify = 1;
    meso_skeleton s = fit(&m, &o, &st);
    print_stats("capsule, CGAL tree", &st);
    assert(st.flipped == 0 && st.cycles_broken == 0);
    /* CGAL's nodes lie on the axis, and more than r away from the caps'
     * centres their radius is r. Nearer the caps (and in them: CGAL's tips
     * stop short of the poles) a node's vertices include cap vertices and
     * its radius is not the medial ball's, so only the fit error says
     * there. */
    double rmax = 0, amax = 0;
    uint32_t on = 0;
    for (uint32_t i = 0; i < s.node_count; ++i) {
        const double* p = s.nodes[i].pos;
        amax = fmax(amax, hypot(p[1], p[2]));
        if (p[0] < r || p[0] > 2 - r)
            continue;
        rmax = fmax(rmax, fabs(s.nodes[i].radius - r));
        ++on;
    }
    fprintf(stderr,
            "      nodes off the axis by <= %.4g (%.2f %% of r); radius error of the %u nodes in [r, 2 - r] <= "
            "%.4g (%.2f %% of r)\n",
            amax, 100 * amax / r, on, rmax, 100 * rmax / r);
    assert(amax < 0.05 * r && on > s.node_count / 2 && rmax < 0.01 * r);
    meso_skeleton_free(&s);

    o.no_simplify = 0;
    s = fit(&m, &o, &st);
    print_stats("capsule, simplified", &st);
    assert(st.segments == 1 && s.node_count == 2);
    for (uint32_t i = 0; i < 2; ++i)
        fprintf(stderr, "      node %u at (%.4f %.4f %.4f) r %.4f\n", i, s.nodes[i].pos[0], s.nodes[i].pos[1],
                s.nodes[i].pos[2], s.nodes[i].radius);
    assert(st.fit_error_max <= st.tolerance && st.hausdorff <= 1.5 * st.tolerance);
    meso_skeleton_free(&s);

    /* Inside out: flipped for CGAL, the same skeleton. */
    for (uint32_t f = 0; f < m.triangle_count; ++f) {
        const uint32_t t = m.indices[3 * f + 1];
        m.indices[3 * f + 1] = m.indices[3 * f + 2];
        m.indices[3 * f + 2] = t;
    }
    meso_skeleton_fit_stats st2;
    s = fit(&m, &o, &st2);
    assert(st2.flipped == 1 && st2.segments == 1 && st2.fit_error_max <= st2.tolerance);
    meso_skeleton_free(&s);
    meso_mesh_free(&m);
}

static void bent_tube_is_two_segments(void)
{
    const double c45 = cos(M_PI / 4), s45 = sin(M_PI / 4);
    const double path[3][3] = {{0, 0, 0}, {1, 0, 0}, {1 + c45, s45, 0}};
    meso_mesh m = tube(path, 3, 0.1, 24, 0.03);
    meso_skeleton_fit_stats st;
    meso_skeleton s = fit(&m, NULL, &st);
    print_stats("45-degree bent tube", &st);
    /* The least-squares fit finds the corner, which CGAL's flow rounds off
     * (its tree is beyond the tolerance there: the mitre's outer corner). */
    assert(st.segments == 2 && s.node_count == 3);
    for (uint32_t i = 0; i < s.node_count; ++i) {
        const double* p = s.nodes[i].pos;
        double best = 1e9;
        for (int k = 0; k < 3; ++k)
            best = fmin(best, sqrt((p[0] - path[k][0]) * (p[0] - path[k][0]) + (p[1] - path[k][1]) * (p[1] - path[k][1]) +
                                   (p[2] - path[k][2]) * (p[2] - path[k][2])));
        fprintf(stderr, "      node %u at (%.4f %.4f %.4f) r %.4f: %.4f from the path's point\n", i, p[0], p[1], p[2],
                s.nodes[i].radius, best);
        assert(best < 0.01 && fabs(s.nodes[i].radius - 0.1) < 0.002);
    }
    assert(st.fit_error_max <= st.tolerance && st.cgal_fit_error_max > st.fit_error_max);
    meso_skeleton_free(&s);
    meso_mesh_free(&m);
}

static void torus_cycle_is_cut(void)
{
    meso_mesh m = load(test_data("torus.obj"));
    meso_skeleton_fit_stats st;
    meso_skeleton s = fit(&m, NULL, &st);
    print_stats("torus (R 1, r 0.25)", &st);
    assert(st.cycles_broken == 1);
    /* Nodes near the core circle (radius 1 in the xz plane: the polygon's
     * corners sit a little outside it), radii ~0.25; one segment ends at
     * the copy of the node where the ring was cut. */
    double dr = 0, dy = 0, drad = 0;
    for (uint32_t i = 0; i < s.node_count; ++i) {
        const double* p = s.nodes[i].pos;
        dr = fmax(dr, fabs(hypot(p[0], p[2]) - 1));
        dy = fmax(dy, fabs(p[1]));
        drad = fmax(drad, fabs(s.nodes[i].radius - 0.25));
    }
    fprintf(stderr, "      nodes off the core circle by <= %.4f (in the plane) and %.4f (out of it); radius error <= %.4f\n",
            dr, dy, drad);
    assert(dr < 0.05 && dy < 0.01 && drad < 0.03);
    assert(st.fit_error_max <= st.tolerance);
    meso_skeleton_free(&s);
    meso_mesh_free(&m);
}

/* >>refusals ------------------------------------------------------------ */

static void refuse(const meso_mesh* m, meso_result want, uint32_t code, const char* what)
{
    meso_skeleton s;
    meso_skeleton_fit_stats st;
    meso_error err = {0};
    const meso_result r = meso_skeleton_from_mesh(m, NULL, &s, &st, &err);
    fprintf(stderr, "    %s: E%u %s\n", what, err.code, err.message);
    assert(r == want && err.code == code);
    assert(s.node_count == 0 && s.nodes == NULL && s.children == NULL);
}

static void refusals(void)
{
    meso_mesh open = load(test_data("cube_no_bottom.obj"));
    refuse(&open, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_OPEN, "open");
    meso_mesh_free(&open);

    /* Two spheres: the bundled one and a shifted copy. */
    meso_mesh one = load(test_data("sphere.obj"));
    builder b = {0};
    for (int copy = 0; copy < 2; ++copy) {
        const uint32_t base = b.nv;
        for (uint32_t v = 0; v < one.vertex_count; ++v) {
            const double p[3] = {one.positions[3 * v] + 3.0 * copy, one.positions[3 * v + 1], one.positions[3 * v + 2]};
            add_vertex(&b, p);
        }
        for (uint32_t f = 0; f < one.triangle_count; ++f)
            add_tri(&b, base + one.indices[3 * f], base + one.indices[3 * f + 1], base + one.indices[3 * f + 2]);
    }
    meso_mesh two = to_mesh(&b);
    refuse(&two, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_COMPONENTS, "two components");
    meso_mesh_free(&two);
    meso_mesh_free(&one);

    /* Two tetrahedra sharing vertex 0: every edge has two faces, but the
     * faces at vertex 0 form two fans. */
    const double tp[7][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
    for (int i = 0; i < 7; ++i)
        add_vertex(&b, tp[i]);
    const uint32_t tf[8][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 5, 4}, {0, 4, 6}, {0, 6, 5}, {4, 5, 6}};
    for (int f = 0; f < 8; ++f)
        add_tri(&b, tf[f][0], tf[f][1], tf[f][2]);
    meso_mesh bow = to_mesh(&b);
    refuse(&bow, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_NONMANIFOLD, "bow tie");
    /* The same triangle both ways: closed, but no volume and duplicated. */
    bow.triangle_count = 2;
    bow.indices[3] = 0, bow.indices[4] = 1, bow.indices[5] = 2;
    refuse(&bow, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_DEGENERATE, "flat pair");
    bow.indices[5] = 9;
    refuse(&bow, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_INDEX, "bad index");
    bow.triangle_count = 0;
    refuse(&bow, MESO_ERR_INVALID_ARG, MESO_SKELFIT_ISSUE_EMPTY, "empty");
    meso_mesh_free(&bow);
}

/* >>real meshes --------------------------------------------------------- */

static void real_mesh(void)
{
    /* spot_low_resolution.obj (bundled, public domain). The armadillo of
     * the wider data set outside the repository (Stanford's terms: not
     * bundleable) was used instead when
     * present, with a bound of 3 %; spot was already the fallback, with the
     * bound below (measured 3.22 %), and it still is. */
    const char* path = test_data("spot_low_resolution.obj");
    const char* what = "spot_low_resolution.obj";
    const double bound = 0.04;
    meso_mesh m = load(path);
    meso_skeleton_fit_stats st, sn;
    meso_skeleton s = fit(&m, NULL, &st);
    print_stats(what, &st);
    /* Independently of the fit's own bookkeeping: the vertices outside the
     * model, by the union distance checked above against the capsule (exact
     * outside), are no farther than the reported maximum. */
    double outside_max = 0;
    for (uint32_t v = 0; v < m.vertex_count; ++v) {
        const double p[3] = {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
        const double d = meso_skeleton_surface_distance(&s, p);
        outside_max = d > outside_max ? d : outside_max;
    }
    fprintf(stderr, "    vertices outside the model: farthest %.4g (reported max %.4g)\n", outside_max, st.fit_error_max);
    assert(outside_max <= st.fit_error_max + 1e-9 * st.bbox_diagonal);
    assert(outside_max <= bound * st.bbox_diagonal);
    meso_skeleton_free(&s);
    meso_skeleton_fit_options o = {0};
    o.fit = MESO_SKELFIT_CGAL_NODES;
    s = fit(&m, &o, &sn);
    print_stats("  same, CGAL nodes and radii", &sn);
    meso_skeleton_free(&s);
    /* The issue's goal is 2 % of the bounding-box diagonal. Not met on the
     * armadillo: the vertices beyond it are on the flat chest, where no
     * round cross-section fits (see skeleton_from_mesh.h). */
    fprintf(stderr, "    issue goal, fit error max <= 2 %% of the diagonal: %s (%.2f %%)\n",
            st.fit_error_max <= 0.02 * st.bbox_diagonal ? "met" : "NOT met", 100 * st.fit_error_max / st.bbox_diagonal);
    assert(st.fit_error_max <= bound * st.bbox_diagonal);
    /* The least-squares fit is no worse than CGAL's own tree at its worst,
     * better on average, and needs fewer segments than CGAL's nodes do. */
    assert(st.fit_error_max <= st.cgal_fit_error_max + st.tolerance);
    assert(st.fit_error_mean < sn.fit_error_mean && st.segments <= sn.segments);
    assert(st.segments * 4 < st.cgal_nodes);
    meso_mesh_free(&m);
}

/* The same mesh twice in one process gives the same skeleton, bit for bit
 * (CGAL's flow runs on an arena: its collapse order follows addresses), and
 * so does the mesh with an unused vertex in front. */
static void deterministic(void)
{
    const double path[3][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}};
    meso_mesh m = tube(path, 3, 0.15, 20, 0.04);
    meso_skeleton_fit_stats st;
    meso_skeleton a = fit(&m, NULL, &st), b = fit(&m, NULL, &st);
    assert(a.node_count == b.node_count && a.root_count == b.root_count);
    assert(!memcmp(a.nodes, b.nodes, sizeof(meso_skeleton_node) * a.node_count));
    assert(!memcmp(a.children, b.children, sizeof(uint32_t) * (a.node_count - a.root_count)));
    meso_skeleton_free(&b);
    /* A vertex no face uses (here a non-finite one, at the front) is
     * dropped: same skeleton. */
    float* pos = malloc(sizeof(float) * 3 * (m.vertex_count + 1));
    assert(pos);
    pos[0] = pos[1] = pos[2] = NAN;
    memcpy(pos + 3, m.positions, sizeof(float) * 3 * m.vertex_count);
    free(m.positions);
    m.positions = pos;
    m.vertex_count++;
    for (uint32_t i = 0; i < 3 * m.triangle_count; ++i)
        m.indices[i]++;
    meso_skeleton_fit_stats st2;
    b = fit(&m, NULL, &st2);
    assert(st2.mesh_vertices == st.mesh_vertices && b.node_count == a.node_count);
    assert(!memcmp(a.nodes, b.nodes, sizeof(meso_skeleton_node) * a.node_count));
    meso_skeleton_free(&a);
    meso_skeleton_free(&b);
    meso_mesh_free(&m);
}

int main(void)
{
    TEST_RUN(frustum_distance_vs_brute_force);
    TEST_RUN(union_distance_is_the_capsule_outside);
    TEST_RUN(refusals);
    TEST_RUN(capsule_is_one_segment);
    TEST_RUN(bent_tube_is_two_segments);
    TEST_RUN(torus_cycle_is_cut);
    TEST_RUN(deterministic);
    TEST_RUN(real_mesh);
    return 0;
}
