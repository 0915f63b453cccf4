/*
 * vec3d.h — the one set of double-precision 3-vector helpers, used by the
 * baker (bake/), the CPU references (runtime/reference/) and the frusta pose
 * rebuild (frusta_pose.c). Internal, header-only, in the bottom layer so
 * every layer above shares it. One argument order: inputs first, the output
 * last; an output may alias an input.
 */
#ifndef MESO_VEC3D_H
#define MESO_VEC3D_H

#include <math.h>

/* o = a - b. */
static inline void sub3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[0] - b[0];
    o[1] = a[1] - b[1];
    o[2] = a[2] - b[2];
}

static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* |a| */
static inline double len3(const double a[3])
{
    return sqrt(dot3(a, a));
}

/* |a - b| */
static inline double dist3(const double a[3], const double b[3])
{
    double d[3];
    sub3(a, b, d);
    return len3(d);
}

/* o = a × b (o may alias a or b). */
static inline void cross3(const double a[3], const double b[3], double o[3])
{
    const double t0 = a[1] * b[2] - a[2] * b[1], t1 = a[2] * b[0] - a[0] * b[2], t2 = a[0] * b[1] - a[1] * b[0];
    o[0] = t0;
    o[1] = t1;
    o[2] = t2;
}

/* Scales v to unit length (a zero vector stays zero); returns its length. */
static inline double normalize3(double v[3])
{
    const double l = sqrt(dot3(v, v));
    if (l > 0) {
        v[0] /= l;
        v[1] /= l;
        v[2] /= l;
    }
    return l;
}

/* A unit vector perpendicular to a: a × the axis a is least aligned with. */
static inline void any_perp3(const double a[3], double o[3])
{
    double e[3] = {0, 0, 0};
    const int m = fabs(a[0]) < fabs(a[1]) ? (fabs(a[0]) < fabs(a[2]) ? 0 : 2) : (fabs(a[1]) < fabs(a[2]) ? 1 : 2);
    e[m] = 1;
    cross3(a, e, o);
    normalize3(o);
}

#endif /* MESO_VEC3D_H */
