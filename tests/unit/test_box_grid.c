/* test_box_grid.c — the moving-box grid (bake/box_grid.c) against brute
 * force: random boxes of mixed sizes (a few spanning many cells, some
 * touching exactly, some degenerate to points), moved, removed and queried
 * over many rounds, past several pool rebuilds; every query's answer is
 * exactly the set of present items whose boxes meet the query box (closed),
 * and after each round the grid links exactly the entries a fresh grid of
 * the same boxes links (moved boxes' old entries are unlinked).
 */
#include "test_util.h"

#include <stdlib.h>
#include <string.h>

#include "box_grid.h"

static uint64_t rng = 88172645463325252ull;
static double uniform(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* A random box: mostly about one cell, 2 % huge (up to 12 cells: the
 * grid's level 1), 1 % long sticks along x (up to 100 cells: level 2)
 * and 0.5 % longer ones (up to 10,000 cells: most past the coarsest level, the
 * list every query scans), 5 % points on the lattice of cell corners (to
 * hit touching boundaries exactly). */
static void random_box(double lo[3], double hi[3])
{
    const double r = uniform();
    for (int k = 0; k < 3; ++k) {
        if (r < 0.05) {
            lo[k] = hi[k] = (double)(int)(uniform() * 20.0) * 0.5;
        } else {
            const double stick = k == 0 ? (r < 0.065 ? 5000.0 : r < 0.08 ? 50.0 : 0.0) : 0.0;
            const double size = stick > 0 ? stick * uniform() : r < 0.1 ? 6.0 * uniform() : 0.6 * uniform();
            lo[k] = -1.0 + 12.0 * uniform();
            hi[k] = lo[k] + size;
        }
    }
}

static int meets(const double* a, const double* b)
{
    for (int k = 0; k < 3; ++k)
        if (a[k] > b[3 + k] || b[k] > a[3 + k])
            return 0;
    return 1;
}

static int cmp_u32(const void* a, const void* b)
{
    const uint32_t x = *(const uint32_t*)a, y = *(const uint32_t*)b;
    return (x > y) - (x < y);
}

int main(void)
{
    enum { N = 3000, ROUNDS = 60, QUERIES = 200 };
    double* box = malloc(sizeof(double) * 6 * N);
    uint8_t* present = calloc(N, 1);
    uint32_t* expect = malloc(sizeof(uint32_t) * N);
    meso_box_grid* g = meso_box_grid_create(N, 0.5);
    assert(g && box && present && expect);
    uint32_t* out = NULL;
    size_t cap = 0;
    long checked = 0, hits = 0;
    for (int round = 0; round < ROUNDS; ++round) {
        /* move or remove a tenth of the items (all of them at first) */
        for (uint32_t i = 0; i < N; ++i) {
            if (round && uniform() > 0.1)
                continue;
            if (round && uniform() < 0.2) {
                present[i] = 0;
                assert(meso_box_grid_set(g, i, NULL, NULL));
                continue;
            }
            random_box(box + 6 * i, box + 6 * i + 3);
            present[i] = 1;
            assert(meso_box_grid_set(g, i, box + 6 * i, box + 6 * i + 3));
        }
        for (int q = 0; q < QUERIES; ++q) {
            double qb[6];
            random_box(qb, qb + 3);
            size_t n = 0, ne = 0;
            assert(meso_box_grid_query(g, qb, qb + 3, &out, &n, &cap));
            for (uint32_t i = 0; i < N; ++i)
                if (present[i] && meets(box + 6 * i, qb))
                    expect[ne++] = i;
            qsort(out, n, sizeof(uint32_t), cmp_u32);
            if (n != ne || memcmp(out, expect, sizeof(uint32_t) * n) != 0) {
                fprintf(stderr, "round %d query %d: grid %zu items, brute force %zu\n", round, q, n, ne);
                return 1;
            }
            ++checked;
            hits += (long)n;
        }
        /* Moving a box unlinks its old entries: the grid links exactly the
         * entries of a fresh grid holding the same boxes. */
        meso_box_grid* fresh = meso_box_grid_create(N, 0.5);
        assert(fresh);
        for (uint32_t i = 0; i < N; ++i)
            if (present[i])
                assert(meso_box_grid_set(fresh, i, box + 6 * i, box + 6 * i + 3));
        assert(meso_box_grid_linked(g) == meso_box_grid_linked(fresh));
        meso_box_grid_destroy(fresh);
    }
    printf("box_grid: %ld queries, %ld items reported, all equal to brute force\n", checked, hits);
    assert(hits > checked); /* the queries did meet boxes */
    free(out);
    meso_box_grid_destroy(g);
    free(box), free(present), free(expect);
    return 0;
}
