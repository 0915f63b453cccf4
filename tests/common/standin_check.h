/* standin_check.h — what the stand-in level tests (test_shell_standin,
 * test_frusta_standin) share: the exact distance from a point to a
 * triangle (float corners, double arithmetic) for checking a mesh level's
 * stated error by brute force over its triangles, reading that mesh, and
 * the one-level file of `--levels 1`. Include after test_util.h. */
#ifndef MESO_TEST_STANDIN_CHECK_H
#define MESO_TEST_STANDIN_CHECK_H

#include <math.h>
#include <stdlib.h>

#include "meso_file.h"
#include "meso_layout.h"

static inline double test_seg_clamp(double t) { return t < 0 ? 0 : t > 1 ? 1 : t; }

/* Distance from p to triangle abc (exact: region tests on the plane). */
static inline double test_point_triangle(const double p[3], const float* a, const float* b, const float* c)
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
        t = dd > 0 ? test_seg_clamp(t / dd) : 0;
        double s = 0;
        for (int k = 0; k < 3; ++k) {
            q[k] = e[i][0][k] + t * d[k] - p[k];
            s += q[k] * q[k];
        }
        best = fmin(best, sqrt(s));
    }
    return best;
}

/* Object 1's MESH at `lod`, parsed into *mv; returns the buffer mv points
 * into (free it). */
static inline uint8_t* test_read_level_mesh(meso_file* f, uint16_t lod, meso_mesh_view* mv)
{
    const int32_t mi = meso_file_find(f, MESO_CHUNK_MESH, 1, lod);
    assert(mi >= 0);
    const meso_chunk_info* mc = meso_file_chunk(f, (uint32_t)mi);
    uint8_t* mb = malloc((size_t)mc->decoded_size);
    assert(mb && meso_file_read_chunk(f, (uint32_t)mi, mb, (size_t)mc->decoded_size, NULL) == MESO_OK);
    assert(meso_mesh_parse(mb, (size_t)mc->decoded_size, mv, NULL) == MESO_OK);
    return mb;
}

/* The file at `path` (a bake with --levels 1) has one level and no LODS. */
static inline void test_assert_one_level(const char* path)
{
    meso_file* f = NULL;
    assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, NULL, 0, &n, NULL) == MESO_OK && n == 1);
    assert(meso_file_find(f, MESO_CHUNK_LODS, UINT32_MAX, UINT16_MAX) < 0);
    meso_file_close(f);
}

#endif /* MESO_TEST_STANDIN_CHECK_H */
