/*
 * distance_map.c — see distance_map.h for the method and why it is a lower
 * bound.
 */
#include "distance_map.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"

/* The runtime filters in float: its values may differ from ours (double,
 * from the same quantised texels) by a few ulps. Cells are marked against a
 * threshold lowered by this much. */
#define MARGIN 1e-6

/* >>cell maxima ----------------------------------------------------------------
 * Along one axis, cell c of n covers [c/n, (c+1)/n]; the filtered function is
 * linear between texel centres (a + 1/2)/nt (and constant beyond the first
 * and last centre on a clamped axis), so its extreme values over the cell
 * are at the cell's ends or at centres inside it. */
typedef struct axis_points {
    uint32_t* start; /* n + 1 offsets into x */
    double* x;       /* the points, then their texels and weights (meso_texfn_axis) */
    uint32_t *i0, *i1;
    double* frac;
} axis_points;

static int axis_points_build(uint32_t n, uint32_t nt, axis_points* a)
{
    const size_t per = 3 + (size_t)nt / n + 1;
    a->start = malloc(sizeof(uint32_t) * ((size_t)n + 1));
    a->x = malloc(sizeof(double) * per * n);
    a->i0 = malloc(sizeof(uint32_t) * per * n);
    a->i1 = malloc(sizeof(uint32_t) * per * n);
    a->frac = malloc(sizeof(double) * per * n);
    if (!a->start || !a->x || !a->i0 || !a->i1 || !a->frac)
        return 0;
    uint32_t k = 0;
    for (uint32_t c = 0; c < n; ++c) {
        const double lo = (double)c / n, hi = (double)(c + 1) / n;
        a->start[c] = k;
        a->x[k++] = lo;
        /* Texel centres strictly inside (lo, hi). */
        const double first = ceil(lo * nt - 0.5);
        for (double t = first; t <= (double)nt; t += 1.0) {
            const double x = (t + 0.5) / nt;
            if (x >= hi)
                break;
            if (x > lo)
                a->x[k++] = x;
        }
        a->x[k++] = hi;
    }
    a->start[n] = k;
    return 1;
}

static void axis_points_free(axis_points* a)
{
    free(a->start);
    free(a->x);
    free(a->i0);
    free(a->i1);
    free(a->frac);
}

meso_result meso_distmap_cell_max(const meso_texfn* f, const uint32_t dims[3], int threads, float* out,
                                  meso_error* err)
{
    const int vol = f->kind == MESO_TEXFN_DENSITY;
    const uint32_t W = dims[0], H = dims[1], D = vol ? dims[2] : 1;
    axis_points ax[3];
    memset(ax, 0, sizeof(ax));
    int ok = axis_points_build(W, f->dims[0], &ax[0]) && axis_points_build(H, f->dims[1], &ax[1]) &&
             axis_points_build(D, f->dims[2], &ax[2]);
    if (ok) {
        /* A height field ignores w: one point per column. */
        if (!vol) {
            ax[2].start[0] = 0;
            ax[2].start[1] = 1;
            ax[2].x[0] = 0.0;
        }
        const uint32_t nd[3] = {W, H, D};
        for (int d = 0; d < 3; ++d)
            for (uint32_t p = 0; p < ax[d].start[nd[d]]; ++p)
                meso_texfn_axis(f, d, ax[d].x[p], &ax[d].i0[p], &ax[d].i1[p], &ax[d].frac[p]);
        const int nt = meso_bake_thread_count(threads);
        (void)nt;
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
#endif
        for (long kj = 0; kj < (long)D * H; ++kj) {
            const uint32_t k = (uint32_t)(kj / H), j = (uint32_t)(kj % H);
            for (uint32_t i = 0; i < W; ++i) {
                double m = -INFINITY;
                for (uint32_t c = ax[2].start[k]; c < ax[2].start[k + 1]; ++c)
                    for (uint32_t b = ax[1].start[j]; b < ax[1].start[j + 1]; ++b)
                        for (uint32_t a = ax[0].start[i]; a < ax[0].start[i + 1]; ++a) {
                            const uint32_t i0[3] = {ax[0].i0[a], ax[1].i0[b], ax[2].i0[c]};
                            const uint32_t i1[3] = {ax[0].i1[a], ax[1].i1[b], ax[2].i1[c]};
                            const double fr[3] = {ax[0].frac[a], ax[1].frac[b], ax[2].frac[c]};
                            m = fmax(m, meso_texfn_sample_at(f, i0, i1, fr));
                        }
                float mf = (float)m; /* rounded up: still an upper bound */
                if ((double)mf < m)
                    mf = nextafterf(mf, INFINITY);
                out[((size_t)k * H + j) * W + i] = mf;
            }
        }
    }
    for (int a = 0; a < 3; ++a)
        axis_points_free(&ax[a]);
    return ok ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "distance map: out of memory");
}

/* >>distance transform --------------------------------------------------------- */

/* d[p] = min_q f[q] + c2 (p − q)² over q in [0, n) (Felzenszwalb and
 * Huttenlocher's lower envelope of parabolas; INFINITY entries are skipped).
 * v (n ints) and z (n + 1 doubles) are scratch. */
static void edt_1d(const double* f, int n, double c2, double* d, int* v, double* z)
{
    int k = -1;
    for (int q = 0; q < n; ++q) {
        if (!isfinite(f[q]))
            continue;
        const double fq = f[q] + c2 * q * q;
        double s = -INFINITY;
        while (k >= 0) {
            const int r = v[k];
            s = (fq - (f[r] + c2 * r * r)) / (2.0 * c2 * (q - r));
            if (s > z[k])
                break;
            --k;
        }
        ++k;
        v[k] = q;
        z[k] = k == 0 ? -INFINITY : s;
        z[k + 1] = INFINITY;
    }
    if (k < 0) {
        for (int p = 0; p < n; ++p)
            d[p] = INFINITY;
        return;
    }
    k = 0;
    for (int p = 0; p < n; ++p) {
        while (z[k + 1] < p)
            ++k;
        const double dp = p - v[k];
        d[p] = c2 * dp * dp + f[v[k]];
    }
}

/* edt_1d for f of 0 and INFINITY only: d[p] = c2 (p - q)^2, q the nearest
 * p with f[q] = 0 (INFINITY without one), by a scan each way. */
static void nearest_1d(const double* f, int n, double c2, double* d)
{
    int last = -1;
    for (int p = 0; p < n; ++p) {
        if (f[p] == 0.0)
            last = p;
        d[p] = last < 0 ? INFINITY : c2 * (double)(p - last) * (double)(p - last);
    }
    last = -1;
    for (int p = n - 1; p >= 0; --p) {
        if (f[p] == 0.0)
            last = p;
        if (last >= 0) {
            const double dp = (double)(last - p), e = c2 * dp * dp;
            d[p] = e < d[p] ? e : d[p];
        }
    }
}

enum { EDT_BLOCK = 8 };

meso_result meso_distmap_edt(const uint8_t* mask, const uint32_t dims[3], const double spacing[3],
                             const int periodic[3], double* sqdist, int threads, meso_error* err)
{
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    for (size_t c = 0; c < n; ++c)
        sqdist[c] = mask[c] ? 0.0 : INFINITY;
    const size_t stride[3] = {1, dims[0], (size_t)dims[0] * dims[1]};
    int failed = 0;
    const int nt = meso_bake_thread_count(threads);
    (void)nt;
    /* Axis w first (usually the shortest lines), then t, then s. The
     * first pass sees only 0 and INFINITY, where the envelope is the
     * nearest mark: found by two scans, with the same arithmetic
     * (c2 dp dp + 0). A periodic line is run over its period with half a
     * period more on each side (the nearest copy of any point is within
     * half a period), and the middle kept. */
    for (int axis = 2; axis >= 0; --axis) {
        const uint32_t len = dims[axis];
        const int half = periodic[axis] ? (int)len / 2 + 1 : 0;
        const int m = (int)len + 2 * half;
        const int first = axis == 2;
        const double c2 = spacing[axis] * spacing[axis];
        const int u = axis == 0 ? 1 : 0, w = axis == 2 ? 1 : 2; /* the two other axes */
        /* Lines along t and w are gathered EDT_BLOCK at a time, neighbours
         * along s, so each cache line read serves several (the lines are
         * independent: the result does not depend on the grouping). */
        const uint32_t blk = stride[u] == 1 ? EDT_BLOCK : 1;
        const long nu = (long)((dims[u] + blk - 1) / blk), blocks = nu * (long)dims[w];
#ifdef _OPENMP
#pragma omp parallel num_threads(nt) reduction(| : failed)
#endif
        {
            double* fin = malloc(sizeof(double) * (size_t)m * blk);
            double* out = malloc(sizeof(double) * (size_t)m * blk);
            double* z = malloc(sizeof(double) * ((size_t)m + 1));
            int* v = malloc(sizeof(int) * (size_t)m);
            const int ok = fin && out && z && v;
            failed |= !ok;
#ifdef _OPENMP
#pragma omp for schedule(static)
#endif
            for (long bl = 0; bl < blocks; ++bl) {
                if (!ok)
                    continue;
                const uint32_t i0 = (uint32_t)(bl % nu) * blk, nb = dims[u] - i0 < blk ? dims[u] - i0 : blk;
                const size_t base = (size_t)i0 * stride[u] + (size_t)(bl / nu) * stride[w];
                for (int p = 0; p < m; ++p) {
                    const double* row = sqdist + base + (size_t)((p - half + 2 * (int)len) % (int)len) * stride[axis];
                    for (uint32_t b = 0; b < nb; ++b)
                        fin[(size_t)b * (size_t)m + (size_t)p] = row[b * stride[u]];
                }
                for (uint32_t b = 0; b < nb; ++b) {
                    if (first)
                        nearest_1d(fin + (size_t)b * (size_t)m, m, c2, out + (size_t)b * (size_t)m);
                    else
                        edt_1d(fin + (size_t)b * (size_t)m, m, c2, out + (size_t)b * (size_t)m, v, z);
                }
                for (uint32_t p = 0; p < len; ++p) {
                    double* row = sqdist + base + p * stride[axis];
                    for (uint32_t b = 0; b < nb; ++b)
                        row[b * stride[u]] = out[(size_t)b * (size_t)m + (size_t)half + p];
                }
            }
            free(fin);
            free(out);
            free(z);
            free(v);
        }
        if (failed)
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "distance map: out of memory");
    }
    return MESO_OK;
}

/* >>build ---------------------------------------------------------------------- */

void meso_distmap_free(meso_distmap* m)
{
    if (!m)
        return;
    free(m->dist);
    free(m->encoded);
    memset(m, 0, sizeof(*m));
}

double meso_distmap_stored(const meso_distmap* m, size_t i)
{
    const uint8_t* e = m->encoded;
    switch (m->dtype) {
    case MESO_DTYPE_U8: return e[i] / 255.0;
    case MESO_DTYPE_U16: return (e[2 * i] | e[2 * i + 1] << 8) / 65535.0;
    default: {
        float x;
        memcpy(&x, e + 4 * i, 4);
        return x;
    }
    }
}

/* One-cell dilation along `axis` (wrapping when periodic): dst = OR of src
 * at offsets -1, 0, +1. */
static void dilate_axis(const uint8_t* src, uint8_t* dst, const uint32_t dims[3], int axis, int periodic)
{
    const size_t stride[3] = {1, dims[0], (size_t)dims[0] * dims[1]};
    const size_t n = (size_t)dims[0] * dims[1] * dims[2], st = stride[axis];
    const uint32_t len = dims[axis];
    for (size_t c = 0; c < n; ++c) {
        const uint32_t p = (uint32_t)((c / st) % len);
        const size_t base = c - p * st;
        uint8_t v = src[c];
        if (p > 0)
            v |= src[c - st];
        else if (periodic)
            v |= src[base + (len - 1) * st];
        if (p + 1 < len)
            v |= src[c + st];
        else if (periodic)
            v |= src[base];
        dst[c] = v;
    }
}

meso_result meso_distmap_build(const meso_texfn* f, const uint32_t dims[3], uint16_t dtype, int threads,
                               meso_distmap* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    for (int a = 0; a < 3; ++a)
        if (dims[a] < 1 || dims[a] > MESO_DISTMAP_MAX_RES)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "distance map: each side must be 1..%u",
                                  MESO_DISTMAP_MAX_RES);
    if (dtype != MESO_DTYPE_U8 && dtype != MESO_DTYPE_U16 && dtype != MESO_DTYPE_F32)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "distance map: store type must be U8, U16 or F32");
    const uint32_t W = dims[0], H = dims[1], D = dims[2];
    const size_t n = (size_t)W * H * D, cols = (size_t)W * H;
    const int vol = f->kind == MESO_TEXFN_DENSITY;
    float* cmax = malloc(sizeof(float) * (vol ? n : cols));
    uint8_t* mask = malloc(n);
    uint8_t* tmp = malloc(n);
    double* sq = malloc(sizeof(double) * n);
    const size_t bytes = dtype == MESO_DTYPE_U8 ? 1 : dtype == MESO_DTYPE_U16 ? 2 : 4;
    out->dist = malloc(sizeof(float) * n);
    out->encoded = malloc(bytes * n);
    meso_result r = cmax && mask && tmp && sq && out->dist && out->encoded
                        ? MESO_OK
                        : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "distance map: out of memory");
    if (r == MESO_OK)
        r = meso_distmap_cell_max(f, dims, threads, cmax, err);
    if (r == MESO_OK) {
        /* 1. Cells that may touch the solid. */
        uint64_t solid = 0;
        for (size_t c = 0; c < n; ++c) {
            const uint32_t k = (uint32_t)(c / cols);
            mask[c] = vol ? cmax[c] >= 0.5 - MARGIN : (double)k / D <= cmax[c % cols] + MARGIN;
            solid += mask[c];
        }
        out->solid_cells = solid;
        /* 2. Dilate by one cell: w is not periodic (nothing below 0 or above 1). */
        dilate_axis(mask, tmp, dims, 0, 1);
        dilate_axis(tmp, mask, dims, 1, 1);
        dilate_axis(mask, tmp, dims, 2, 0);
        /* 3. Exact distance from each cell centre to the dilated marks =
         *    box-to-box distance to the nearest marked cell. */
        const double spacing[3] = {1.0 / W, 1.0 / H, 1.0 / D};
        const int periodic[3] = {1, 1, 0};
        r = meso_distmap_edt(tmp, dims, spacing, periodic, sq, threads, err);
    }
    if (r == MESO_OK) {
        const double max = dtype == MESO_DTYPE_U8 ? 255.0 : 65535.0;
        uint8_t* e = out->encoded;
        for (size_t c = 0; c < n; ++c) {
            const double d = sqrt(sq[c]);
            float fd = (float)d;
            if ((double)fd > d)
                fd = nextafterf(fd, 0.0f);
            out->dist[c] = fd;
            if (dtype == MESO_DTYPE_F32) {
                const float x = isfinite(d) ? fd : 1e30f;
                memcpy(e + 4 * c, &x, 4);
            } else {
                /* Round down, with a hair of slack for the runtime's float
                 * division value / max. */
                const uint32_t q = d >= 1.0 ? (uint32_t)max : (uint32_t)floor(d * max * (1.0 - 1e-7));
                e[bytes * c] = (uint8_t)(q & 0xFF);
                if (bytes == 2)
                    e[bytes * c + 1] = (uint8_t)(q >> 8);
            }
        }
        memcpy(out->dims, dims, sizeof(out->dims));
        out->dtype = dtype;
        out->encoded_size = bytes * n;
    }
    free(cmax);
    free(mask);
    free(tmp);
    free(sq);
    if (r != MESO_OK)
        meso_distmap_free(out);
    return r;
}

static int cmp_double(const void* a, const void* b)
{
    const double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static uint32_t clampu(uint32_t x, uint32_t lo, uint32_t hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

void meso_distmap_default_res(const meso_texfn* f, uint32_t dims[3])
{
    dims[0] = clampu(f->dims[0] / 2, 8, 128);
    dims[1] = clampu(f->dims[1] / 2, 8, 128);
    if (f->kind == MESO_TEXFN_DENSITY) {
        dims[2] = clampu(f->dims[2] / 2, 8, 128);
        return;
    }
    dims[2] = 8;
    const uint32_t W = dims[0], H = dims[1];
    float* hm = malloc(sizeof(float) * W * H);
    double* steps = malloc(sizeof(double) * 2 * W * H);
    meso_error err;
    if (hm && steps && meso_distmap_cell_max(f, dims, 0, hm, &err) == MESO_OK) {
        size_t k = 0;
        for (uint32_t j = 0; j < H; ++j)
            for (uint32_t i = 0; i < W; ++i) {
                const double h = hm[j * W + i];
                const double dx = fabs(hm[j * W + (i + 1) % W] - h), dy = fabs(hm[((j + 1) % H) * W + i] - h);
                if (dx >= 1.0 / 256)
                    steps[k++] = dx;
                if (dy >= 1.0 / 256)
                    steps[k++] = dy;
            }
        if (k) {
            qsort(steps, k, sizeof(double), cmp_double);
            const double step = steps[k / 4];
            const double d = ceil(1.0 / step / 8.0) * 8.0;
            dims[2] = clampu(d > 128 ? 128u : (uint32_t)d, 8, 128);
        }
    }
    free(hm);
    free(steps);
}
