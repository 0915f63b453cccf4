/*
 * volume_levels.c — native coarser levels of a density-volume shell
 * (volume_levels.h; FORMAT.md §7.10; issue 14). The height-field levels'
 * counterpart (height_field_levels.c), for a TX3D: the same pyramid, a
 * different error, because a volume's surface is a level set, not a graph
 * over (s, t): halving moves it sideways as well as in w, and a thread
 * thinner than a coarse texel fades below 1/2 and is gone.
 *
 * The pyramid (height_field_levels.c builds it for both kinds). Level l
 * halves level l - 1 along s, t and w: texel (i, j, k) is the mean of
 * texels (2i..2i+1, 2j..2j+1, 2k..2k+1), quantised to the nearest stored
 * value (meso_texfn_from_values), the box filter of the runtime's own mip
 * levels (rt_mip_box.c). Each level gets the distance map of its own
 * function (distance_map.h: conservative for exactly what is sampled),
 * with level 0's dims halved.
 *
 * The error in texture space. The runtime samples alpha trilinearly
 * between texel centres, wrapping in s and t and clamped in w, and draws
 * the surface of S = {alpha >= 1/2} within the shell (a ray entering where
 * alpha >= 1/2 hits the shell's own face there). As for height fields
 * (height_field_levels.c), level 0's and level l's texel centres all lie
 * on level 0's half-texel lattice a / (2 W0) (and in w, clamped below the
 * first centre, constant there), so on every cell of that lattice both
 * functions are trilinear and take their extremes at the cell's 8 corners.
 * Call a lattice cell a surface cell of a level when
 *   - its corners hold values both >= 1/2 and < 1/2: alpha crosses 1/2 on
 *     an edge, and the crossing is a point of the surface; or
 *   - it lies in the lowest (highest) layer and a corner on the shell's
 *     face w = 0 (w = 1) is >= 1/2: that corner is solid and on the face,
 *     a surface point.
 * Each surface cell certainly holds a point of the level's surface, and
 * every point of the surface lies in one: a cell whose corners are all
 * < 1/2 is open air, one whose corners are all >= 1/2 is solid throughout,
 * and its points are interior unless they lie on the shell's face (the
 * second case). So for p on level 0's surface, in surface cell c of level
 * 0, and c' the surface cell of level l whose centre is nearest c's, some
 * q of level l's surface in c' has
 *     |p - q| <= |p - centre(c)| + |centre(c) - centre(c')| + |centre(c') - q|
 *             <= d(c) + diag,
 * d(c) the distance from c's centre to the nearest centre of a level-l
 * surface cell (an exact Euclidean distance transform of the surface
 * cells: meso_distmap_edt, periodic in s and t) and diag a cell's diagonal.
 * The same both ways, so
 *     rho = max(max over level-0 surface cells of d_l,
 *               max over level-l surface cells of d_0) + diag
 * bounds the two-sided Hausdorff distance of the two surfaces, in the
 * metric of volume_levels.h (s and t scaled by g0, w by g1).
 *
 * Into object units. In a prism the smooth mapping is
 * Phi(u, v, w) = B(u, v) + w D(u, v) (FORMAT.md §7.2), with B (the bottom)
 * and D (top - bottom) linear in the barycentrics, and the texture
 * coordinates (s, t) affine in them. So dPhi/d(s, t) = (M0 + w M1) A^-1
 * (M0, M1 the bottom's and D's edge vectors, A the texture triangle's) is
 * constant over the triangle and affine in w, and dPhi/dw = D(u, v) is
 * affine in (u, v): the matrix J = [dPhi/d(s, t) / g0, D / g1] is affine
 * on the prism, and its largest singular value, a convex function, is
 * largest at one of the prism's six corners. With g0 the largest singular
 * value of dPhi/d(s, t) and g1 the longest top - bottom, every column of J
 * is at most 1 long; k bounds ||J|| over all corners (Gershgorin's bound
 * on J^T J, and never above sqrt(3)). Along a straight texture-space
 * segment inside a prism, or across prisms that share texture coordinates,
 * object-space length is at most k times the segment's length in the
 * metric, so the levels' surfaces are within k rho of each other.
 *
 * What this does not cover (decided here; the bound is measured against
 * the reference in tests/integration/test_shell_volume_levels.c): where the
 * texture coordinates jump between two prisms (a uv seam), the nearest
 * surface point in texture space may lie across the seam, where the other
 * side draws other texels; the bound assumes it is drawn. Under the curved
 * mapping the w parametrisation changes (as for height fields, not proved).
 * A degenerate texture triangle (A singular) gives no bound: no levels.
 *
 * Decided here: 2 x 2 x 2 means, as the runtime's mips (not a wider filter
 * that would move the surface more), built by height_field_levels.c's
 * pyramid; levels stop at MESOI_HEIGHT_MIN_LEVEL_RES texels a side or an
 * odd side; the lattice is capped (MESOI_VOLUME_MAX_LATTICE: two
 * transforms of 134 MB of doubles) and a bake under --max-memory measures
 * it only when mesoi_volume_level_bytes fits.
 */
#include "volume_levels.h"

#include <math.h>
#include <stdlib.h>

#include "bake_internal.h"
#include "bake_threads.h"

static uint64_t lattice_cells(const meso_texfn* f)
{
    return 8 * (uint64_t)f->dims[0] * f->dims[1] * f->dims[2];
}

uint64_t mesoi_volume_level_bytes(const meso_texfn* f0)
{
    const uint64_t cells = lattice_cells(f0), points = cells / f0->dims[2] * (2 * (uint64_t)f0->dims[2] + 1) / 2;
    return points + 2 * cells + 2 * sizeof(double) * cells;
}

meso_result mesoi_volume_levels_build(const meso_texfn* f0, const meso_distmap* d0, uint32_t want, int threads,
                                      mesoi_height_level* out, uint32_t* count, meso_error* err)
{
    *count = 0;
    if (f0->kind != MESO_TEXFN_DENSITY || lattice_cells(f0) > MESOI_VOLUME_MAX_LATTICE)
        return MESO_OK;
    return mesoi_height_levels_build(f0, d0, want, INFINITY, threads, out, count, err);
}

/* in[p] = alpha >= 1/2 at every point p = (a, b, c) of level 0's half-texel
 * lattice, a < N0, b < N1 (periodic), c <= N2, s fastest. Returns 0 when
 * out of memory. */
static int solid_points(const meso_texfn* f, const uint32_t N[3], int nt, uint8_t* in)
{
    (void)nt;
    uint32_t* ax[3][2] = {{NULL, NULL}, {NULL, NULL}, {NULL, NULL}};
    double* fr[3] = {NULL, NULL, NULL};
    int ok = 1;
    for (int k = 0; k < 3; ++k) {
        const uint32_t n = N[k] + 1;
        ax[k][0] = malloc(sizeof(uint32_t) * n);
        ax[k][1] = malloc(sizeof(uint32_t) * n);
        fr[k] = malloc(sizeof(double) * n);
        ok &= ax[k][0] && ax[k][1] && fr[k];
        for (uint32_t a = 0; ok && a < n; ++a)
            meso_texfn_axis(f, k, (double)a / (double)N[k], &ax[k][0][a], &ax[k][1][a], &fr[k][a]);
    }
    const int64_t planes = ok ? (int64_t)N[2] + 1 : 0;
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t c = 0; c < planes; ++c)
        for (uint32_t b = 0; b < N[1]; ++b)
            for (uint32_t a = 0; a < N[0]; ++a) {
                const uint32_t i0[3] = {ax[0][0][a], ax[1][0][b], ax[2][0][c]};
                const uint32_t i1[3] = {ax[0][1][a], ax[1][1][b], ax[2][1][c]};
                const double w[3] = {fr[0][a], fr[1][b], fr[2][c]};
                in[((size_t)c * N[1] + b) * N[0] + a] = meso_texfn_sample_at(f, i0, i1, w) >= 0.5;
            }
    for (int k = 0; k < 3; ++k) {
        free(ax[k][0]);
        free(ax[k][1]);
        free(fr[k]);
    }
    return ok;
}

/* mask[cell] = the cell is a surface cell (the .c's comment) of the level
 * whose lattice points are `in`; returns how many are. */
static uint64_t surface_cells(const uint8_t* in, const uint32_t N[3], int nt, uint8_t* mask)
{
    (void)nt;
    uint64_t n = 0;
    const size_t plane = (size_t)N[0] * N[1];
#pragma omp parallel for schedule(static) num_threads(nt) reduction(+ : n)
    for (int64_t c = 0; c < (int64_t)N[2]; ++c) {
        const uint8_t* p0 = in + (size_t)c * plane; /* the corners at w index c, then c + 1 */
        const uint8_t* p1 = p0 + plane;
        const int bottom = c == 0, top = c + 1 == (int64_t)N[2];
        for (uint32_t b = 0; b < N[1]; ++b) {
            const uint32_t b1 = b + 1 == N[1] ? 0 : b + 1;
            const uint8_t *r00 = p0 + (size_t)b * N[0], *r01 = p0 + (size_t)b1 * N[0];
            const uint8_t *r10 = p1 + (size_t)b * N[0], *r11 = p1 + (size_t)b1 * N[0];
            uint8_t* out = mask + (size_t)c * plane + (size_t)b * N[0];
            for (uint32_t a = 0; a < N[0]; ++a) {
                const uint32_t a1 = a + 1 == N[0] ? 0 : a + 1;
                const int low = r00[a] | r00[a1] | r01[a] | r01[a1], high = r10[a] | r10[a1] | r11[a] | r11[a1];
                const int all = r00[a] & r00[a1] & r01[a] & r01[a1] & r10[a] & r10[a1] & r11[a] & r11[a1];
                const uint8_t sc = (uint8_t)(((low | high) && !all) || (bottom && low) || (top && high));
                out[a] = sc;
                n += sc;
            }
        }
    }
    return n;
}

/* The largest of sqdist over the cells `mask` marks. */
static double masked_max(const double* sqdist, const uint8_t* mask, size_t cells)
{
    double m = 0.0;
    for (size_t i = 0; i < cells; ++i)
        if (mask[i] && sqdist[i] > m)
            m = sqdist[i];
    return m;
}

meso_result mesoi_volume_level_distances(const meso_texfn* f0, const mesoi_height_level* levels, uint32_t count,
                                         const double g[2], double stop, int threads, double* out, meso_error* err)
{
    for (uint32_t l = 0; l < count; ++l)
        out[l] = INFINITY;
    const uint32_t N[3] = {2 * f0->dims[0], 2 * f0->dims[1], 2 * f0->dims[2]};
    if (!count || lattice_cells(f0) > MESOI_VOLUME_MAX_LATTICE)
        return MESO_OK;
    const size_t cells = (size_t)N[0] * N[1] * N[2], points = (size_t)N[0] * N[1] * (N[2] + 1);
    const int nt = meso_bake_thread_count(threads);
    uint8_t* in = malloc(points);
    uint8_t* m0 = malloc(cells);
    uint8_t* ml = malloc(cells);
    double* sq0 = malloc(sizeof(double) * cells);
    double* sq = malloc(sizeof(double) * cells);
    meso_result r = in && m0 && ml && sq0 && sq
                        ? MESO_OK
                        : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture levels: out of memory");
    const double spacing[3] = {g[0] / N[0], g[0] / N[1], g[1] / N[2]};
    const double diag = mesoi_volume_level_floor(f0, g);
    const int periodic[3] = {1, 1, 0};
    uint64_t n0 = 0;
    if (r == MESO_OK && !solid_points(f0, N, nt, in))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture levels: out of memory");
    if (r == MESO_OK) {
        n0 = surface_cells(in, N, nt, m0);
        if (n0)
            r = meso_distmap_edt(m0, N, spacing, periodic, sq0, threads, err); /* every level's d_0 */
    }
    for (uint32_t l = 0; r == MESO_OK && l < count; ++l) {
        if (!solid_points(&levels[l].fn, N, nt, in)) {
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture levels: out of memory");
            break;
        }
        const uint64_t nl = surface_cells(in, N, nt, ml);
        if (!n0 || !nl) {
            out[l] = !n0 && !nl ? 0.0 : INFINITY;
            continue;
        }
        if ((r = meso_distmap_edt(ml, N, spacing, periodic, sq, threads, err)) == MESO_OK)
            out[l] = sqrt(fmax(masked_max(sq, m0, cells), masked_max(sq0, ml, cells))) + diag;
        if (!(out[l] < stop))
            break; /* coarser levels are no nearer (their errors are made non-decreasing) */
    }
    free(in);
    free(m0);
    free(ml);
    free(sq0);
    free(sq);
    return r;
}

double mesoi_volume_level_floor(const meso_texfn* f0, const double g[2])
{
    const double a = g[0] / (2.0 * f0->dims[0]), b = g[0] / (2.0 * f0->dims[1]), c = g[1] / (2.0 * f0->dims[2]);
    return sqrt(a * a + b * b + c * c);
}

/* Largest singular value of the 3 x 2 matrix with columns x, y, exactly:
 * the larger eigenvalue of its 2 x 2 Gram matrix. */
static double norm32(const double x[3], const double y[3])
{
    const double a = x[0] * x[0] + x[1] * x[1] + x[2] * x[2], c = y[0] * y[0] + y[1] * y[1] + y[2] * y[2];
    const double b = x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    return sqrt(0.5 * (a + c) + sqrt(0.25 * (a - c) * (a - c) + b * b));
}

/* dPhi/d(s, t) of triangle f at w = 0 and 1 into J[w][column][3]; 0 when
 * the texture triangle is degenerate. */
static int jacobian_st(const meso_mesh* m, const float* sdir, int layers, uint32_t f, double J[2][2][3])
{
    const uint32_t* t = m->indices + 3 * (size_t)f;
    const size_t nv = m->vertex_count;
    double B[3][3], D[3][3], st[3][2];
    for (int v = 0; v < 3; ++v) {
        for (int k = 0; k < 3; ++k) {
            const double p = m->positions[3 * (size_t)t[v] + (size_t)k], top = sdir[3 * (size_t)t[v] + (size_t)k];
            const double bottom = layers == 2 ? sdir[3 * (nv + t[v]) + (size_t)k] : 0.0;
            B[v][k] = p + bottom;
            D[v][k] = top - bottom;
        }
        st[v][0] = m->uvs[2 * (size_t)t[v]];
        st[v][1] = m->uvs[2 * (size_t)t[v] + 1];
    }
    const double a = st[1][0] - st[0][0], b = st[2][0] - st[0][0], c = st[1][1] - st[0][1], d = st[2][1] - st[0][1];
    const double det = a * d - b * c;
    if (!(fabs(det) > 1e-14 * (fabs(a * d) + fabs(b * c))) || !isfinite(det))
        return 0;
    /* A^-1 = [d -b; -c a] / det: d(u, v)/ds = (d, -c) / det, d(u, v)/dt = (-b, a) / det. */
    const double inv[2][2] = {{d / det, -c / det}, {-b / det, a / det}};
    for (int w = 0; w < 2; ++w)
        for (int k = 0; k < 3; ++k) {
            const double e1 = B[1][k] - B[0][k] + w * (D[1][k] - D[0][k]);
            const double e2 = B[2][k] - B[0][k] + w * (D[2][k] - D[0][k]);
            for (int col = 0; col < 2; ++col)
                J[w][col][k] = e1 * inv[col][0] + e2 * inv[col][1];
        }
    return 1;
}

int mesoi_volume_level_scales(const meso_mesh* base, const float* sdir, int layers, double span, double g[2],
                              double* k)
{
    g[0] = 0.0;
    g[1] = span;
    *k = INFINITY;
    const size_t nv = base->vertex_count;
    for (uint32_t f = 0; f < base->triangle_count; ++f) {
        double J[2][2][3];
        if (!base->uvs || !jacobian_st(base, sdir, layers, f, J))
            return 0;
        g[0] = fmax(g[0], fmax(norm32(J[0][0], J[0][1]), norm32(J[1][0], J[1][1])));
    }
    if (!(g[0] > 0.0) || !(g[1] > 0.0))
        return 0;
    double kk = 0.0;
    for (uint32_t f = 0; f < base->triangle_count; ++f) {
        double J[2][2][3];
        jacobian_st(base, sdir, layers, f, J);
        const uint32_t* t = base->indices + 3 * (size_t)f;
        for (int w = 0; w < 2; ++w)
            for (int v = 0; v < 3; ++v) {
                double c[3][3]; /* the columns of J at this corner, scaled */
                for (int q = 0; q < 3; ++q) {
                    c[0][q] = J[w][0][q] / g[0];
                    c[1][q] = J[w][1][q] / g[0];
                    c[2][q] = ((double)sdir[3 * (size_t)t[v] + (size_t)q] -
                               (layers == 2 ? sdir[3 * (nv + t[v]) + (size_t)q] : 0.0)) /
                              g[1];
                }
                double row_max = 0.0; /* Gershgorin: lambda_max(J^T J) <= max row sum of |Gram| */
                for (int i = 0; i < 3; ++i) {
                    double sum = 0.0;
                    for (int j = 0; j < 3; ++j)
                        sum += fabs(c[i][0] * c[j][0] + c[i][1] * c[j][1] + c[i][2] * c[j][2]);
                    row_max = fmax(row_max, sum);
                }
                kk = fmax(kk, sqrt(fmin(row_max, 3.0)));
            }
    }
    *k = kk * (1.0 + 1e-9);
    return 1;
}
