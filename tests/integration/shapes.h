/* shapes.h — analytic inside/outside for the bundled sphere and torus, with
 * margins that cover their tessellation (see the tests for the numbers). */
#ifndef MESO_TEST_SHAPES_H
#define MESO_TEST_SHAPES_H

#include <math.h>

/* Unit sphere: the 1280-face icosphere is inscribed in it and contains the
 * ball of radius 0.9954 (its nearest face plane; test_rt_mesh measures it). */
static inline int sphere_class(const double p[3])
{
    double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return r < 0.97 ? 1 : r > 1.01 ? -1 : 0; /* 0: too close to call */
}

/* Torus R = 1, r = 0.25 around y: tessellated tube radius >= 0.249. */
static inline int torus_class(const double p[3])
{
    double q = sqrt(p[0] * p[0] + p[2] * p[2]) - 1.0;
    double d = sqrt(q * q + p[1] * p[1]);
    return d < 0.22 ? 1 : d > 0.27 ? -1 : 0;
}

#endif
