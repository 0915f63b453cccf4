/* point_triangle.h — exact distance from a point to a triangle, brute
 * force for tests that check a stated error against surface points
 * (test_shell_standin.c, test_cells_standin.c). */
#ifndef MESO_TEST_POINT_TRIANGLE_H
#define MESO_TEST_POINT_TRIANGLE_H

#include <math.h>

static inline double seg_clamp(double t) { return t < 0 ? 0 : t > 1 ? 1 : t; }

/* Distance from p to triangle abc (exact: region tests on the plane). */
static inline double point_triangle(const double p[3], const float* a, const float* b, const float* c)
{
    double ab[3], ac[3], ap[3], n[3];
    for (int k = 0; k < 3; ++k) {
        ab[k] = (double)b[k] - a[k];
        ac[k] = (double)c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
    n[0] = ab[1] * ac[2] - ab[2] * ac[1];
    n[1] = ab[2] * ac[0] - ab[0] * ac[2];
    n[2] = ab[0] * ac[1] - ab[1] * ac[0];
    const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    double best = INFINITY;
    if (nn > 0) {
        /* Barycentrics of the projection; inside: the plane distance. */
        const double d00 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
        const double d01 = ab[0] * ac[0] + ab[1] * ac[1] + ab[2] * ac[2];
        const double d11 = ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2];
        const double d20 = ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2];
        const double d21 = ap[0] * ac[0] + ap[1] * ac[1] + ap[2] * ac[2];
        const double den = d00 * d11 - d01 * d01;
        const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
        if (v >= 0 && w >= 0 && v + w <= 1)
            best = fabs(ap[0] * n[0] + ap[1] * n[1] + ap[2] * n[2]) / sqrt(nn);
    }
    const float* e[3][2] = {{a, b}, {b, c}, {c, a}};
    for (int i = 0; i < 3; ++i) { /* the edges */
        double d[3], q[3], dd = 0, t = 0;
        for (int k = 0; k < 3; ++k) {
            d[k] = (double)e[i][1][k] - e[i][0][k];
            dd += d[k] * d[k];
            t += (p[k] - e[i][0][k]) * d[k];
        }
        t = dd > 0 ? seg_clamp(t / dd) : 0;
        double s = 0;
        for (int k = 0; k < 3; ++k) {
            q[k] = e[i][0][k] + t * d[k] - p[k];
            s += q[k] * q[k];
        }
        best = fmin(best, sqrt(s));
    }
    return best;
}

#endif /* MESO_TEST_POINT_TRIANGLE_H */
