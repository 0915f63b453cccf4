/* point_cloud.h — points bucketed on a uniform grid, and the exact distance
 * from a query to the nearest of them: what the stand-in tests
 * (test_cells_standin, test_shell_volume_levels) measure a level's hits
 * against when the other level's surface is known only by samples (a
 * distance to a subset is no smaller than to the whole). Include after
 * test_util.h. */
#ifndef MESO_TEST_POINT_CLOUD_H
#define MESO_TEST_POINT_CLOUD_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct cloud {
    double* p;
    size_t n, cap;
    double lo[3], cell;
    int dim[3];
    size_t *start, *item;
} cloud;

static inline void cloud_add(cloud* c, const double p[3])
{
    if (c->n == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 4096;
        c->p = realloc(c->p, sizeof(double) * 3 * c->cap);
        assert(c->p);
    }
    memcpy(c->p + 3 * c->n++, p, 3 * sizeof(double));
}

static inline int cloud_cell(const cloud* c, const double p[3], int k)
{
    const int i = (int)floor((p[k] - c->lo[k]) / c->cell);
    return i < 0 ? 0 : i >= c->dim[k] ? c->dim[k] - 1 : i;
}

/* Buckets the points in cells of `cell` (again: the last grid is freed). */
static inline void cloud_grid(cloud* c, double cell)
{
    free(c->start);
    free(c->item);
    double hi[3];
    for (int k = 0; k < 3; ++k) {
        c->lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (size_t i = 0; i < c->n; ++i)
        for (int k = 0; k < 3; ++k) {
            c->lo[k] = fmin(c->lo[k], c->p[3 * i + k]);
            hi[k] = fmax(hi[k], c->p[3 * i + k]);
        }
    c->cell = cell;
    for (int k = 0; k < 3; ++k)
        c->dim[k] = (int)((hi[k] - c->lo[k]) / cell) + 1;
    const size_t cells = (size_t)c->dim[0] * c->dim[1] * c->dim[2];
    c->start = calloc(cells + 1, sizeof(size_t));
    c->item = malloc(sizeof(size_t) * (c->n ? c->n : 1));
    assert(c->start && c->item);
    for (size_t i = 0; i < c->n; ++i) {
        const double* p = c->p + 3 * i;
        ++c->start[cloud_cell(c, p, 0) + (size_t)c->dim[0] * (cloud_cell(c, p, 1) + (size_t)c->dim[1] * cloud_cell(c, p, 2)) + 1];
    }
    for (size_t i = 0; i < cells; ++i)
        c->start[i + 1] += c->start[i];
    size_t* fill = malloc(sizeof(size_t) * (cells ? cells : 1));
    assert(fill);
    memcpy(fill, c->start, sizeof(size_t) * cells);
    for (size_t i = 0; i < c->n; ++i) {
        const double* p = c->p + 3 * i;
        c->item[fill[cloud_cell(c, p, 0) + (size_t)c->dim[0] * (cloud_cell(c, p, 1) + (size_t)c->dim[1] * cloud_cell(c, p, 2))]++] = i;
    }
    free(fill);
}

/* Distance from q to the nearest point of the cloud: rings of cells until
 * the ring's inner distance passes the best. */
static inline double cloud_nearest(const cloud* c, const double q[3])
{
    double best = INFINITY;
    int ci[3];
    for (int k = 0; k < 3; ++k)
        ci[k] = cloud_cell(c, q, k);
    const int maxr = c->dim[0] + c->dim[1] + c->dim[2];
    for (int r = 0; r <= maxr; ++r) {
        if ((r - 1) * c->cell > best)
            break;
        for (int z = ci[2] - r; z <= ci[2] + r; ++z)
            for (int y = ci[1] - r; y <= ci[1] + r; ++y)
                for (int x = ci[0] - r; x <= ci[0] + r; ++x) {
                    if (abs(x - ci[0]) != r && abs(y - ci[1]) != r && abs(z - ci[2]) != r)
                        continue;
                    if (x < 0 || y < 0 || z < 0 || x >= c->dim[0] || y >= c->dim[1] || z >= c->dim[2])
                        continue;
                    const size_t cell = (size_t)x + (size_t)c->dim[0] * ((size_t)y + (size_t)c->dim[1] * (size_t)z);
                    for (size_t i = c->start[cell]; i < c->start[cell + 1]; ++i) {
                        const double* p = c->p + 3 * c->item[i];
                        best = fmin(best, sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                               (p[2] - q[2]) * (p[2] - q[2])));
                    }
                }
    }
    return best;
}

static inline void cloud_free(cloud* c)
{
    free(c->p);
    free(c->start);
    free(c->item);
    memset(c, 0, sizeof *c);
}

#endif /* MESO_TEST_POINT_CLOUD_H */
