/* mesh_bump.h — a local edit of a mesh for the incremental shell re-bake's
 * test and benchmark (tests/integration/test_shell_update.c,
 * tests/bench/bench_shell_update.c): the `count` vertices nearest to vertex
 * c pushed away from the centroid by a smooth cosine bump of height amp at
 * c, zero at the count-th nearest (so fewer than count + 1 move). */
#ifndef MESO_TEST_MESH_BUMP_H
#define MESO_TEST_MESH_BUMP_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

static int mesh_bump_cmp(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static inline void mesh_bump(float* p, uint32_t nv, uint32_t c, uint32_t count, double amp)
{
    double* dist = malloc(sizeof(double) * nv);
    double* sorted = malloc(sizeof(double) * nv);
    double centroid[3] = {0, 0, 0};
    for (uint32_t v = 0; v < nv; ++v) {
        double s = 0;
        for (int k = 0; k < 3; ++k) {
            s += ((double)p[3 * v + k] - p[3 * c + k]) * ((double)p[3 * v + k] - p[3 * c + k]);
            centroid[k] += p[3 * v + k] / nv;
        }
        dist[v] = sorted[v] = sqrt(s);
    }
    qsort(sorted, nv, sizeof(double), mesh_bump_cmp);
    const double R = sorted[count < nv ? count : nv - 1];
    for (uint32_t v = 0; v < nv; ++v) {
        if (dist[v] >= R)
            continue;
        const double w = 0.5 + 0.5 * cos(M_PI * dist[v] / R);
        double u[3], l = 0;
        for (int k = 0; k < 3; ++k) {
            u[k] = p[3 * v + k] - centroid[k];
            l += u[k] * u[k];
        }
        l = sqrt(l);
        for (int k = 0; k < 3; ++k)
            p[3 * v + k] = (float)(p[3 * v + k] + amp * w * u[k] / l);
    }
    free(dist);
    free(sorted);
}

#endif /* MESO_TEST_MESH_BUMP_H */
