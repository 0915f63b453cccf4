/*
 * voxel_rows.c — the voxelizer's work on one tile row (voxelize.h, "Tiles"):
 * exact ray crossings along +x from the voxel centres (the perturbed
 * predicates of voxel_predicates.c), the candidate tiles a triangle meets,
 * the other tiles from one representative row (PARITY: its parity; WINDING:
 * X - w_C with the Biot-Savart bound on |grad w|), and the candidates centre
 * by centre along their R^2 voxel rows.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec3d.h"
#include "voxelize_internal.h"

#define FOUR_PI 12.566370614359172953850573533118

/* >>rows ------------------------------------------------------------------------ */

int mesoi_grow_buf(void** p, size_t* cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    void* q = realloc(*p, c * elem);
    if (!q)
        return 0;
    *p = q;
    *cap = c;
    return 1;
}

static int cmp_xing(const void* pa, const void* pb)
{
    const mesoi_xing *a = pa, *b = pb;
    return a->k < b->k ? -1 : a->k > b->k;
}

/* Crossings of the ray from centre row (j, k) with the row's triangles
 * sc->lt[items[0..n)] (items NULL: the first n), sorted by k. Returns the
 * count, or -1 when out of memory. */
static long trace(const mesoi_job* jb, mesoi_scratch* sc, uint32_t j, uint32_t k, const uint32_t* items, uint32_t n)
{
    const mesoi_grid* g = jb->g;
    const int64_t N0 = g->N[0];
    double q[3] = {mesoi_centre_coord(g, 0, 0), mesoi_centre_coord(g, 1, j), mesoi_centre_coord(g, 2, k)};
    size_t m = 0;
    uint64_t* ex = &sc->n.exact;
    for (uint32_t i = 0; i < n; ++i) {
        const mesoi_ltri* t = &sc->lt[items ? items[i] : i];
        const double(*v)[3] = t->v;
        const double *lo = t->lo, *hi = t->hi;
        if (q[1] < lo[1] || q[1] > hi[1] || q[2] < lo[2] || q[2] > hi[2])
            continue;
        const int e0 = mesoi_edge_side(v[0], v[1], q, ex);
        if (!e0 || mesoi_edge_side(v[1], v[2], q, ex) != e0 || mesoi_edge_side(v[2], v[0], q, ex) != e0)
            continue;
        /* Centres strictly before the crossing see it: cross(i) <=> e0 side3(q_i*) > 0, which is
         * true for i < K and false from K on. Search K in the centres the triangle's x-extent
         * leaves open, starting from the rounded crossing point. */
        int64_t a, b;
        if (!mesoi_centre_span(g, 0, lo[0], hi[0], 0, N0 - 1, &a, &b)) {
            a = b = hi[0] < g->o[0] + 0.5 * g->h ? 0 : N0; /* wholly before or after the row's centres */
        } else {
            b += 1; /* K in [a, b] */
        }
        double e1[3], e2[3], nrm[3];
        sub3(v[1], v[0], e1);
        sub3(v[2], v[0], e2);
        cross3(e1, e2, nrm);
        const double xi = v[0][0] - (nrm[1] * (q[1] - v[0][1]) + nrm[2] * (q[2] - v[0][2])) / nrm[0];
        int64_t guess = (int64_t)a;
        if (isfinite(xi)) {
            const double f = -mesoi_ffloor(0.5 - (xi - g->o[0]) / g->h); /* ceil(. - 1/2) */
            guess = f < (double)a ? a : f > (double)b ? b : (int64_t)f;
        }
        /* invariant: cross(i) for i < lo_k, !cross(i) for i >= hi_k. The first two probes are
         * the guess and its neighbour (usually settling K), then bisection. */
        int64_t lo_k = a, hi_k = b, probe = guess;
        for (int step = 0; lo_k < hi_k; ++step) {
            if (step >= 2 || probe < lo_k || probe >= hi_k)
                probe = lo_k + (hi_k - lo_k) / 2;
            q[0] = mesoi_centre_coord(g, 0, probe);
            if (e0 * mesoi_side3(v[0], v[1], v[2], q, ex) > 0) {
                lo_k = probe + 1;
                probe = probe + 1;
            } else {
                hi_k = probe;
                probe = probe - 1;
            }
        }
        if (!mesoi_grow_buf((void**)&sc->xs, &sc->xs_cap, m + 1, sizeof(mesoi_xing)))
            return -1;
        sc->xs[m++] = (mesoi_xing){(uint32_t)lo_k, e0};
    }
    if (m > 16) {
        qsort(sc->xs, m, sizeof(mesoi_xing), cmp_xing);
    } else {
        for (size_t a = 1; a < m; ++a) /* usually a handful */
            for (size_t b = a; b > 0 && sc->xs[b - 1].k > sc->xs[b].k; --b) {
                const mesoi_xing t = sc->xs[b];
                sc->xs[b] = sc->xs[b - 1];
                sc->xs[b - 1] = t;
            }
    }
    sc->n.rows++;
    sc->n.crossings += m;
    return (long)m;
}

/* X at centre i of a traced row: sum of s over crossings with k > i. */
static long crossings_ahead(const mesoi_xing* xs, long n, int64_t i)
{
    long x = 0;
    for (long t = 0; t < n; ++t)
        x += xs[t].k > (uint64_t)i ? xs[t].s : 0;
    return x;
}

/* WINDING: |grad w| bound over a box (Biot-Savart of the chain boundary). */
static double gradient_bound(const mesoi_job* jb, const double lo[3], const double hi[3])
{
    double G = 0.0;
    for (uint32_t e = 0; e < jb->bedge_count; ++e) {
        const float* p = jb->bedge[e];
        double d2 = 0.0, len2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double a = mesoi_dmin(p[k], p[3 + k]), b = mesoi_dmax(p[k], p[3 + k]);
            const double gap = mesoi_dmax(0.0, mesoi_dmax(a - hi[k], lo[k] - b));
            d2 += gap * gap;
            len2 += (b - a) * (b - a);
        }
        if (!(d2 > 0.0))
            return INFINITY;
        G += sqrt(len2) / (FOUR_PI * d2);
    }
    return G;
}

/* WINDING: w at centre (i, j, k) = X - w_C, and the bound G rho + margin on
 * |w(q) - w(centre)| over the centres of tiles [t0, t1) of the job's row (a
 * box where w is harmonic: no mesh triangle meets it). */
static double winding_at(const mesoi_job* jb, mesoi_scratch* sc, long X, int64_t i, uint32_t j, uint32_t k, uint32_t t0,
                         uint32_t t1, double* spread)
{
    const mesoi_grid* g = jb->g;
    const uint32_t R = g->R;
    const double q[3] = {mesoi_centre_coord(g, 0, i), mesoi_centre_coord(g, 1, j), mesoi_centre_coord(g, 2, k)};
    const double lo[3] = {mesoi_centre_coord(g, 0, (int64_t)t0 * R), mesoi_centre_coord(g, 1, (int64_t)jb->ty * R),
                          mesoi_centre_coord(g, 2, (int64_t)jb->tz * R)};
    const double hi[3] = {mesoi_centre_coord(g, 0, (int64_t)t1 * R - 1),
                          mesoi_centre_coord(g, 1, (int64_t)jb->ty * R + R - 1),
                          mesoi_centre_coord(g, 2, (int64_t)jb->tz * R + R - 1)};
    double rho2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double d = mesoi_dmax(q[a] - lo[a], hi[a] - q[a]);
        rho2 += d * d;
    }
    *spread = gradient_bound(jb, lo, hi) * sqrt(rho2) + (jb->s->cone_tree ? 0.05 : 1e-9);
    return (double)X - mesoi_cone_winding(jb->s, q, &sc->n.exact);
}

/* WINDING: decide tiles [t0, t1) of the row (no mesh triangle meets them)
 * from the representative row (j, k), or mark the undecidable ones
 * candidates (cand bit 2). */
static void certify(const mesoi_job* jb, mesoi_scratch* sc, const mesoi_xing* xs, long nx, uint32_t j, uint32_t k,
                    uint32_t t0, uint32_t t1, uint8_t* classes)
{
    const int64_t i = ((int64_t)t0 + t1) * jb->g->R / 2;
    double spread;
    const double w = winding_at(jb, sc, crossings_ahead(xs, nx, i), i, j, k, t0, t1, &spread);
    if (fabs(w - MESO_WINDING_INSIDE) > spread) {
        for (uint32_t t = t0; t < t1; ++t)
            classes[t] = meso_winding_inside(w) ? MESO_TILE_INSIDE : MESO_TILE_OUTSIDE;
    } else if (t1 - t0 == 1) {
        sc->cand[t0] |= 2;
    } else {
        const uint32_t mid = t0 + (t1 - t0) / 2;
        certify(jb, sc, xs, nx, j, k, t0, mid, classes);
        certify(jb, sc, xs, nx, j, k, mid, t1, classes);
    }
}

/* Lists in CSR form are built in two passes: count into start[k + 1], then
 * (after csr_counted) fill at start[k]++, then csr_filled. */
int mesoi_csr_counted(uint32_t* start, uint64_t n, uint32_t** items, size_t* cap)
{
    for (uint64_t k = 0; k < n; ++k) {
        if (start[k + 1] > UINT32_MAX - start[k])
            return 0;
        start[k + 1] += start[k];
    }
    return mesoi_grow_buf((void**)items, cap, (size_t)start[n] + 1, sizeof(uint32_t));
}

void mesoi_csr_filled(uint32_t* start, uint64_t n) /* the fill advanced each start to the next one's */
{
    memmove(start + 1, start, sizeof(uint32_t) * (size_t)n);
    start[0] = 0;
}

/* Bin the row's triangles into its R^2 voxel rows by their (y, z) bounds. */
static int bin_rows(const mesoi_job* jb, mesoi_scratch* sc)
{
    const mesoi_grid* g = jb->g;
    const uint32_t R = g->R;
    const int64_t j0 = (int64_t)jb->ty * R, k0 = (int64_t)jb->tz * R;
    memset(sc->bstart, 0, sizeof(uint32_t) * ((size_t)R * R + 1));
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t i = 0; i < jb->list_count; ++i) {
            const double *lo = sc->lt[i].lo, *hi = sc->lt[i].hi;
            int64_t a0, a1, b0, b1;
            if (!mesoi_centre_span(g, 1, lo[1], hi[1], j0, j0 + R - 1, &a0, &a1) ||
                !mesoi_centre_span(g, 2, lo[2], hi[2], k0, k0 + R - 1, &b0, &b1))
                continue;
            for (int64_t b = b0; b <= b1; ++b)
                for (int64_t a = a0; a <= a1; ++a) {
                    const size_t cell = (size_t)(a - j0) + (size_t)R * (size_t)(b - k0);
                    if (pass == 0)
                        sc->bstart[cell + 1]++;
                    else
                        sc->bucket[sc->bstart[cell]++] = i;
                }
        }
        if (pass == 0 && !mesoi_csr_counted(sc->bstart, (uint64_t)R * R, &sc->bucket, &sc->bucket_cap))
            return 0;
    }
    mesoi_csr_filled(sc->bstart, (uint64_t)R * R);
    return 1;
}

/* Set bits [from, to) of a bit array. */
static void set_bits(uint64_t* w, uint64_t from, uint64_t to)
{
    while (from < to) {
        const uint64_t word = from >> 6, lo = from & 63, hi = to - (word << 6) < 64 ? to - (word << 6) : 64;
        const uint64_t mask = (hi == 64 ? ~(uint64_t)0 : (((uint64_t)1 << hi) - 1)) & ~(((uint64_t)1 << lo) - 1);
        w[word] |= mask;
        from = (word << 6) + hi;
    }
}

/* Step 1 of a tile row: its triangles unpacked into sc->lt, and the
 * candidates: tiles whose grown box a mesh triangle meets (cand bit 1);
 * tiles a cone triangle meets (bit 4), where w_C jumps. 0: out of memory. */
static int mark_candidates(const mesoi_job* jb, mesoi_scratch* sc)
{
    const mesoi_grid* g = jb->g;
    const mesoi_soup* s = jb->s;
    if (!mesoi_grow_buf((void**)&sc->lt, &sc->lt_cap, (size_t)jb->list_count + 1, sizeof(mesoi_ltri)))
        return 0;
    for (uint32_t i = 0; i < jb->list_count; ++i)
        mesoi_tri_corners(s, jb->list[i], sc->lt[i].v, sc->lt[i].lo, sc->lt[i].hi);
    const double half[3] = {0.5 * g->tile + g->margin, 0.5 * g->tile + g->margin, 0.5 * g->tile + g->margin};
    for (uint32_t i = 0; i < jb->list_count; ++i) {
        const uint8_t bit = jb->list[i] < s->surface ? 1 : 4;
        uint32_t a, b;
        if (!mesoi_tile_span(g, 0, sc->lt[i].lo[0], sc->lt[i].hi[0], &a, &b))
            continue;
        for (uint32_t t = a; t <= b; ++t) {
            if (sc->cand[t] & bit)
                continue;
            const double ct[3] = {g->o[0] + (t + 0.5) * g->tile, g->o[1] + (jb->ty + 0.5) * g->tile,
                                  g->o[2] + (jb->tz + 0.5) * g->tile};
            if (mesoi_tri_box(ct, half, &sc->lt[i].v[0][0]))
                sc->cand[t] |= bit;
        }
    }
    return 1;
}

/* Step 4 of a tile row: the nc candidates whose centres all agree are
 * uniform; the others are MIXED, their bits packed to the front. */
static void keep_mixed(const mesoi_scratch* sc, uint32_t nc, uint32_t R, mesoi_row_out* out)
{
    const uint64_t words = meso_voxel_tile_words(R);
    const uint64_t all = (uint64_t)R * R * R, tail = all % 64 ? ((uint64_t)1 << (all % 64)) - 1 : ~(uint64_t)0;
    for (uint32_t c = 0; c < nc; ++c) {
        const uint64_t* bits = out->bits + c * words;
        int zeros = bits[words - 1] == 0, ones = bits[words - 1] == tail;
        for (uint64_t w = 0; w + 1 < words && (zeros || ones); ++w) {
            zeros &= bits[w] == 0;
            ones &= bits[w] == ~(uint64_t)0;
        }
        const uint32_t t = sc->ctx[c];
        if (zeros || ones) {
            out->classes[t] = ones ? MESO_TILE_INSIDE : MESO_TILE_OUTSIDE;
            continue;
        }
        out->classes[t] = MESO_TILE_MIXED;
        if (out->mixed_count != c)
            memmove(out->bits + out->mixed_count * words, bits, words * sizeof(uint64_t));
        out->mixed_tx[out->mixed_count++] = t;
    }
}

/* One tile row: classes of its T0 tiles and bits of its MIXED ones. */
void mesoi_process_row(const mesoi_job* jb, mesoi_scratch* sc, mesoi_row_out* out)
{
    const mesoi_grid* g = jb->g;
    const mesoi_soup* s = jb->s;
    const uint32_t R = g->R, T0 = g->T[0];
    const uint64_t words = meso_voxel_tile_words(R);
    memset(sc->cand, 0, T0);
    memset(out->classes, MESO_TILE_OUTSIDE, T0);
    out->mixed_count = 0;

    /* 1. Candidates. */
    if (!mark_candidates(jb, sc)) {
        sc->oom = 1;
        return;
    }

    /* 2. The other tiles, from one representative row. */
    const uint32_t jr = jb->ty * R + R / 2, kr = jb->tz * R + R / 2;
    if (jb->list_count || jb->method == MESO_VOXELIZE_WINDING) {
        const long nx = trace(jb, sc, jr, kr, NULL, jb->list_count);
        if (nx < 0) {
            sc->oom = 1;
            return;
        }
        if (jb->method == MESO_VOXELIZE_PARITY) {
            for (uint32_t t = 0; t < T0; ++t)
                if (!(sc->cand[t] & 1))
                    out->classes[t] = (crossings_ahead(sc->xs, nx, (int64_t)t * R + R / 2) & 1) ? MESO_TILE_INSIDE
                                                                                              : MESO_TILE_OUTSIDE;
        } else {
            for (uint32_t t = 0; t < T0;) {
                if (sc->cand[t] & 1) {
                    ++t;
                    continue;
                }
                uint32_t e = t;
                while (e < T0 && !(sc->cand[e] & 1))
                    ++e;
                certify(jb, sc, sc->xs, nx, jr, kr, t, e, out->classes);
                t = e;
            }
        }
    }
    uint32_t nc = 0;
    for (uint32_t t = 0; t < T0; ++t)
        if (sc->cand[t] & 3)
            sc->ctx[nc++] = t;
    if (nc == 0)
        return;
    sc->n.candidates += nc;

    /* 3. Candidate tiles, centre by centre along every voxel row. X is
     * constant between crossings, so without a cone whole runs of bits are
     * set at once. With one, w = X - w_C; in a tile no cone triangle meets,
     * w_C is harmonic and within spread of its value at the tile's centre,
     * so a run is decided at once unless X - w_C(centre) is within spread of
     * 1/2; the rest (and tiles the cone meets) evaluate w_C centre by centre. */
    const int cone = s->count > s->surface;
    for (uint32_t c = 0; cone && c < nc; ++c) {
        const uint32_t t = sc->ctx[c];
        sc->twc[c] = NAN;
        sc->tspread[c] = 0.0;
        if (!(sc->cand[t] & 4))
            sc->twc[c] = -winding_at(jb, sc, 0, (int64_t)t * R + R / 2, jr, kr, t, t + 1, &sc->tspread[c]);
    }
    if (!bin_rows(jb, sc)) {
        sc->oom = 1;
        return;
    }
    out->mixed_tx = malloc(sizeof(uint32_t) * nc);
    out->bits = calloc(nc * words, sizeof(uint64_t));
    if (!out->mixed_tx || !out->bits) {
        sc->oom = 1;
        return;
    }
    for (uint32_t lz = 0; lz < R; ++lz)
        for (uint32_t ly = 0; ly < R; ++ly) {
            const uint32_t cell = ly + R * lz, j = jb->ty * R + ly, k = jb->tz * R + lz;
            const long n = trace(jb, sc, j, k, sc->bucket + sc->bstart[cell], sc->bstart[cell + 1] - sc->bstart[cell]);
            if (n < 0) {
                sc->oom = 1;
                return;
            }
            long ptr = 0, acc = 0;
            for (long t = 0; t < n; ++t)
                acc += sc->xs[t].s;
            for (uint32_t c = 0; c < nc; ++c) {
                const int64_t i0 = (int64_t)sc->ctx[c] * R, i1 = i0 + R;
                const uint64_t base = (uint64_t)R * cell; /* bit of (0, ly, lz) */
                uint64_t* bits = out->bits + c * words;
                while (ptr < n && sc->xs[ptr].k <= (uint64_t)i0)
                    acc -= sc->xs[ptr++].s;
                for (int64_t i = i0; i < i1;) { /* X = acc on [i, next) */
                    const int64_t next = ptr < n && sc->xs[ptr].k < (uint64_t)i1 ? (int64_t)sc->xs[ptr].k : i1;
                    const double v = cone ? (double)acc - sc->twc[c] : 0.0; /* w near the tile's centre */
                    if (!cone) {
                        if (jb->method == MESO_VOXELIZE_PARITY ? (acc & 1) : acc >= 1)
                            set_bits(bits, base + (uint64_t)(i - i0), base + (uint64_t)(next - i0));
                    } else if (fabs(v - MESO_WINDING_INSIDE) > sc->tspread[c]) { /* NaN (cone tile) is not */
                        if (v > MESO_WINDING_INSIDE)
                            set_bits(bits, base + (uint64_t)(i - i0), base + (uint64_t)(next - i0));
                    } else {
                        for (int64_t x = i; x < next; ++x) {
                            const double q[3] = {mesoi_centre_coord(g, 0, x), mesoi_centre_coord(g, 1, j),
                                                 mesoi_centre_coord(g, 2, k)};
                            if (meso_winding_inside((double)acc - mesoi_cone_winding(s, q, &sc->n.exact)))
                                set_bits(bits, base + (uint64_t)(x - i0), base + (uint64_t)(x - i0) + 1);
                        }
                    }
                    i = next;
                    while (ptr < n && sc->xs[ptr].k <= (uint64_t)i)
                        acc -= sc->xs[ptr++].s;
                }
            }
        }
    sc->n.evaluated += (uint64_t)nc * R * R * R;

    /* 4. Candidates whose centres all agree are uniform; keep the others. */
    keep_mixed(sc, nc, R, out);
}
