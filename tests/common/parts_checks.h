/* parts_checks.h — what the parts tests (test_rt_parts, test_rt_shell_parts)
 * check of a draw in parts (runtime/rt_parts.c; issue 14: "each part ...
 * draws the coarsest level whose projected error is ≤ τ; neighbouring
 * parts may differ by at most one level and never crack"), header-only,
 * for an image of PC_W x PC_H pixels (defined by the includer) seen with
 * a vertical field of view of PC_FOV degrees. */
#ifndef MESO_TEST_PARTS_CHECKS_H
#define MESO_TEST_PARTS_CHECKS_H

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "camera.h"
#include "egl_context.h"
#include "meso_file.h"
#include "meso_rt.h"
#include "near_end_view.h"

/* An object's parts table (meso_file_parts): pl[first[q]..first[q + 1])
 * are part q + 1's levels. */
typedef struct parts_table {
    meso_part_level* pl;
    uint32_t* edges;
    uint32_t* first;
    uint32_t nl, np, ne;
} parts_table;

static inline parts_table parts_table_read(meso_file* f, uint32_t object)
{
    parts_table t = {0};
    assert(meso_file_parts(f, object, NULL, 0, &t.nl, &t.np, NULL, 0, &t.ne, NULL) == MESO_OK);
    assert(t.np >= 2 && t.nl > t.np);
    t.pl = malloc(sizeof(meso_part_level) * t.nl);
    t.edges = malloc(sizeof(uint32_t) * 2 * (t.ne ? t.ne : 1));
    t.first = calloc(t.np + 1, sizeof(uint32_t));
    assert(t.pl && t.edges && t.first);
    assert(meso_file_parts(f, object, t.pl, t.nl, &t.nl, &t.np, t.edges, t.ne, &t.ne, NULL) == MESO_OK);
    for (uint32_t i = 0; i < t.nl; ++i)
        t.first[t.pl[i].rec.object]++;
    for (uint32_t q = 1; q <= t.np; ++q)
        t.first[q] += t.first[q - 1]; /* first[q]: the end of part q (1-based) = the start of part q + 1 */
    return t;
}

static inline void parts_table_free(parts_table* t)
{
    free(t->pl);
    free(t->edges);
    free(t->first);
}

/* What check_part_levels found. */
typedef struct parts_drawn {
    uint32_t lo, hi;    /* the range of the part levels drawn */
    uint32_t at_0;      /* parts at level 0 (a shell's: its prisms) */
    uint64_t bytes;     /* of the part levels drawn */
    double worst_px;    /* the largest error projected at its level's nearest bound point */
    double worst_error; /* the largest stated error drawn (object units) */
} parts_drawn;

/* The part levels the last draw of obj drew (into lev, np of them):
 * each part's stated error within tau pixels at its level's nearest bound
 * point (the distance the runtime picks by, here from the eye in doubles),
 * neighbours (PRTS pairs) within one level. */
static inline parts_drawn check_part_levels(meso_rt* rt, meso_rt_object obj, const parts_table* t,
                                            const double eye[3], double tau, uint8_t* lev)
{
    const meso_part_level* pl = t->pl;
    const uint32_t *first = t->first, *edges = t->edges, np = t->np, ne = t->ne;
    uint32_t count = 0;
    assert(meso_rt_parts_state_get(rt, obj, lev, np, &count) == MESO_OK && count == np);
    parts_drawn r = {.lo = UINT32_MAX};
    const double focal = 0.5 * PC_H / tan(0.5 * PC_FOV * M_PI / 180.0);
    for (uint32_t q = 0; q < np; ++q) {
        const meso_part_level* L = &pl[first[q] + lev[q]];
        assert(L->rec.object == q + 1 && L->rec.lod == lev[q]);
        r.lo = lev[q] < r.lo ? lev[q] : r.lo;
        r.hi = lev[q] > r.hi ? lev[q] : r.hi;
        r.at_0 += lev[q] == 0;
        r.bytes += L->bytes;
        const double dist = box_distance(eye, L->rec.bbox_min, L->rec.bbox_max);
        const double px = L->rec.error * focal / dist;
        r.worst_px = px > r.worst_px ? px : r.worst_px;
        r.worst_error = L->rec.error > r.worst_error ? L->rec.error : r.worst_error;
        printf("  part %u: level %u of %u, error %.4g (level 1: %.4g), %.2f px at its nearest bound point %.3g away\n",
               q + 1, lev[q], first[q + 1] - first[q], (double)L->rec.error, (double)pl[first[q] + 1].rec.error, px,
               dist);
    }
    for (uint32_t e = 0; e < ne; ++e) {
        const int a = lev[edges[2 * e] - 1], b = lev[edges[2 * e + 1] - 1];
        assert(abs(a - b) <= 1);
    }
    printf("parts at %g px: %u parts at levels %u..%u; largest projected error %.2f px; %u neighbour pairs within one "
           "level\n",
           tau, np, r.lo, r.hi, r.worst_px, ne);
    assert(r.worst_px <= tau * (1.0 + 1e-6)); /* the runtime finds the eye from float matrices */
    return r;
}

/* No crack: every pixel of `ref`'s silhouette with all pixels within
 * `margin` covered is covered in `got` too. */
static inline void check_no_crack(const float* ref, const float* got, int margin, double tau)
{
    long interior = 0, holes = 0;
    for (int y = margin; y < PC_H - margin; ++y)
        for (int x = margin; x < PC_W - margin; ++x) {
            int all = 1;
            for (int j = -margin; j <= margin; ++j)
                for (int i = -margin; i <= margin; ++i)
                    all &= ref[(y + j) * PC_W + x + i] < 1.0f;
            if (!all)
                continue;
            ++interior;
            if (got[y * PC_W + x] >= 1.0f)
                ++holes;
        }
    printf("  no crack: %ld pixels inside the silhouette (%d px in), %ld not covered at %g px\n", interior, margin,
           holes, tau);
    assert(interior > 1000 && holes == 0);
}

/* Where the whole object would draw a level coarser than 0 (from twice as
 * far as the near-end view, at each pixel error of taus), the parts draw
 * instead when their own levels hold fewer bytes: the same object baked
 * without parts (`without`) draws its whole level L, and with parts:
 *  - wherever the parts drew, each part is within the pixel error at its
 *    nearest bound point and neighbours are within one level;
 *  - at L >= 1, and wherever every part drew a level >= 1 (a shell's
 *    patches without its native level), it never holds more bytes than the
 *    whole level, and where it holds fewer the whole level's silhouette
 *    (less a margin of the pixel error) has no hole;
 *  - at some L >= 1 it holds fewer (the parts drew instead).
 * Each draw in a fresh context, so what is resident is what it drew. */
static inline void parts_coarser_than_level_0(const uint8_t* with, size_t with_size, const uint8_t* without,
                                              size_t without_size, const float* taus, size_t tau_count,
                                              void (*view)(const meso_object_record*, meso_rt_draw_desc*, double*),
                                              float* (*draw)(meso_rt*, meso_rt_object, const meso_rt_draw_desc*))
{
    meso_file* f[2] = {NULL, NULL};
    assert(meso_file_open_memory(with, with_size, NULL, &f[0], NULL) == MESO_OK);
    assert(meso_file_open_memory(without, without_size, NULL, &f[1], NULL) == MESO_OK);
    meso_object_record rec;
    uint32_t n = 0;
    assert(meso_file_objects(f[0], &rec, 1, &n, NULL) == MESO_OK && n == 1);
    parts_table pt = parts_table_read(f[0], rec.id);
    uint8_t* lev = malloc(pt.np);
    assert(lev);
    int fewer = 0;
    for (size_t t = 0; t < tau_count; ++t) {
        meso_rt_levels_state st[2];
        float* depth[2];
        parts_drawn pd = {.lo = UINT32_MAX}; /* the part levels drawn, if the parts drew */
        for (int k = 1; k >= 0; --k) { /* without parts first */
            meso_rt* rt = NULL;
            assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
            meso_rt_object obj;
            assert(meso_rt_load_object_levels(rt, f[k], rec.id, &obj) == MESO_OK);
            meso_rt_draw_desc d = {0};
            double eye[3];
            view(&rec, &d, eye);
            double c[3];
            for (int a = 0; a < 3; ++a) { /* 2x as far from the centre as the near-end view */
                c[a] = 0.5 * ((double)rec.bbox_min[a] + rec.bbox_max[a]);
                eye[a] = c[a] + 2.0 * (eye[a] - c[a]);
            }
            const double up[3] = {0, 1, 0};
            meso_camera_look_at(d.view, eye, c, up);
            d.pixel_error = taus[t];
            depth[k] = draw(rt, obj, &d);
            assert(meso_rt_levels_state_get(rt, obj, &st[k]) == MESO_OK);
            if (k == 0 && st[0].bytes_resident != st[1].bytes_resident) /* the parts drew: their levels */
                pd = check_part_levels(rt, obj, &pt, eye, taus[t], lev);
            meso_rt_release_object(rt, obj);
            meso_rt_destroy(rt);
        }
        printf("at %g px: without parts level %u, %llu bytes resident; with parts %llu\n", (double)taus[t],
               st[1].last_drawn, (unsigned long long)st[1].bytes_resident, (unsigned long long)st[0].bytes_resident);
        if (st[1].last_drawn >= 1 || (pd.lo >= 1 && pd.lo != UINT32_MAX)) {
            assert(st[0].bytes_resident <= st[1].bytes_resident);
            if (st[0].bytes_resident < st[1].bytes_resident)
                check_no_crack(depth[1], depth[0], (int)ceil(taus[t]), taus[t]);
            fewer |= st[1].last_drawn >= 1 && st[0].bytes_resident < st[1].bytes_resident;
        }
        free(depth[0]);
        free(depth[1]);
    }
    assert(fewer); /* the parts drew instead of some whole level L >= 1 */
    parts_table_free(&pt);
    free(lev);
    meso_file_close(f[0]);
    meso_file_close(f[1]);
}

#endif /* MESO_TEST_PARTS_CHECKS_H */
