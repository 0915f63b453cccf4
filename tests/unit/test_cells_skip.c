/* test_cells_skip.c — the cells walk's skip radii (runtime/rt_cells_skip.c)
 * against brute force: for every voxel of a tile map, the cube around it
 * grown one voxel at a time while it stays in the tile and every voxel of
 * it has the centre's split id. Maps: Voronoi cells of random seeds with
 * empty voxels (id 0) among them, one id everywhere (one seed), 1^3, 2^3
 * and 5^3 maps; and a 70^3 map of one id, whose radii are the distance to
 * the tile's faces capped at 31 (analytic there: brute force is slow).
 * Then the packing: ids and radii read back from u16 and u32 maps, and
 * maps whose ids leave no room left untouched.
 */
#include "test_need.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "rt_cells_skip.h"

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static uint32_t next(uint32_t n)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (uint32_t)((rng >> 11) % n);
}

static uint32_t brute_radius(const uint32_t* ids, uint32_t R, uint32_t x, uint32_t y, uint32_t z)
{
    const uint32_t id = ids[x + (size_t)R * (y + (size_t)R * z)];
    uint32_t r = 0;
    for (;;) {
        const uint32_t q = r + 1; /* is the cube of radius q uniform? */
        if (q > MESOI_CELLS_SKIP_MAX || x < q || y < q || z < q || x + q >= R || y + q >= R || z + q >= R)
            return r;
        for (uint32_t k = z - q; k <= z + q; ++k)
            for (uint32_t j = y - q; j <= y + q; ++j)
                for (uint32_t i = x - q; i <= x + q; ++i)
                    if (ids[i + (size_t)R * (j + (size_t)R * k)] != id)
                        return r;
        r = q;
    }
}

/* Voronoi cells of `seeds` random points (ids 1..seeds), a share `empty`
 * of whose cells are id 0 instead; seeds 1: one id everywhere. */
static void voronoi(uint32_t* ids, uint32_t R, uint32_t seeds, double empty)
{
    enum { MAX_SEEDS = 64 };
    uint32_t p[MAX_SEEDS][3], id[MAX_SEEDS];
    for (uint32_t s = 0; s < seeds; ++s) {
        for (int a = 0; a < 3; ++a)
            p[s][a] = next(R);
        id[s] = next(1000) < (uint32_t)(empty * 1000) ? 0 : s + 1;
    }
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                uint32_t best = 0;
                int64_t bd = INT64_MAX;
                for (uint32_t s = 0; s < seeds; ++s) {
                    const int64_t dx = (int64_t)x - p[s][0], dy = (int64_t)y - p[s][1], dz = (int64_t)z - p[s][2];
                    const int64_t d = dx * dx + dy * dy + dz * dz;
                    if (d < bd)
                        bd = d, best = s;
                }
                ids[x + (size_t)R * (y + (size_t)R * z)] = id[best];
            }
}

/* One id everywhere: the distance to the nearest face, capped (analytic). */
static uint32_t face_radius(uint32_t R, uint32_t x, uint32_t y, uint32_t z)
{
    const uint32_t d[6] = {x, R - 1 - x, y, R - 1 - y, z, R - 1 - z};
    uint32_t r = MESOI_CELLS_SKIP_MAX;
    for (int k = 0; k < 6; ++k)
        r = d[k] < r ? d[k] : r;
    return r;
}

static void check_radii(const char* what, const uint32_t* ids, uint32_t R, int uniform)
{
    const size_t n = (size_t)R * R * R;
    uint8_t* radius = malloc(n);
    CHECK(radius != NULL);
    mesoi_cells_skip_radii(ids, R, radius);
    size_t wrong = 0, positive = 0;
    uint32_t largest = 0;
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                const size_t v = x + (size_t)R * (y + (size_t)R * z);
                const uint32_t want = uniform ? face_radius(R, x, y, z) : brute_radius(ids, R, x, y, z);
                if (radius[v] != want && wrong++ < 5)
                    printf("  %s: voxel (%u, %u, %u) radius %u, brute force %u\n", what, x, y, z, radius[v], want);
                positive += want > 0;
                largest = want > largest ? want : largest;
            }
    printf("%s: %u^3, %zu voxels with a cube to skip, largest radius %u, %zu wrong\n", what, R, positive, largest,
           wrong);
    need(wrong == 0, "%s: %zu radii differ from brute force", what, wrong);
    free(radius);
}

static void test_radii(void)
{
    static const uint32_t sizes[] = {1, 2, 5, 16, 32};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; ++k) {
        const uint32_t R = sizes[k];
        uint32_t* ids = malloc(sizeof(uint32_t) * R * R * R);
        CHECK(ids != NULL);
        char what[64];
        for (uint32_t seeds = 1; seeds <= 64; seeds *= 8) {
            voronoi(ids, R, seeds, 0.25);
            snprintf(what, sizeof what, "voronoi %u seeds", seeds);
            check_radii(what, ids, R, 0);
        }
        free(ids);
    }
    /* Past the cap: one id in 70^3, the centre 34 voxels from every face. */
    const uint32_t R = 70;
    uint32_t* ids = calloc((size_t)R * R * R, sizeof(uint32_t));
    CHECK(ids != NULL);
    check_radii("uniform past the cap", ids, R, 1);
    free(ids);
}

static void test_pack(void)
{
    const uint32_t R = 16;
    const size_t n = (size_t)R * R * R;
    uint32_t* ids = malloc(sizeof(uint32_t) * n);
    uint8_t* radius = malloc(n);
    uint8_t* tile = malloc(4 * n);
    uint8_t* before = malloc(4 * n);
    void* scratch = malloc(mesoi_cells_skip_scratch(R));
    CHECK(ids != NULL && radius != NULL && tile != NULL && before != NULL && scratch != NULL);
    voronoi(ids, R, 40, 0.2);
    mesoi_cells_skip_radii(ids, R, radius);
    for (int wide = 0; wide <= 1; ++wide) {
        const int bits = wide ? 27 : 11;
        for (int room = 1; room >= 0; --room) {
            const uint32_t big = room ? (1u << bits) - 1u : 1u << bits; /* the largest id that fits, or one past */
            for (size_t v = 0; v < n; ++v) {
                const uint32_t id = v == 77 ? big : ids[v];
                if (wide)
                    memcpy(tile + 4 * v, &id, 4);
                else {
                    const uint16_t s = (uint16_t)id;
                    memcpy(tile + 2 * v, &s, 2);
                }
            }
            memcpy(before, tile, 4 * n);
            const int got = mesoi_cells_skip_pack(tile, wide, R, scratch);
            if (!room) {
                need(got == 0 && memcmp(before, tile, (wide ? 4 : 2) * n) == 0,
                          "%s map with id %u: no room, nothing packed", wide ? "u32" : "u16", big);
                continue;
            }
            need(got == bits, "%s map: %d id bits, expected %d", wide ? "u32" : "u16", got, bits);
            /* the radii of the map as it was, with its one large id */
            uint32_t* ids2 = malloc(sizeof(uint32_t) * n);
            uint8_t* radius2 = malloc(n);
            CHECK(ids2 != NULL && radius2 != NULL);
            memcpy(ids2, ids, sizeof(uint32_t) * n);
            ids2[77] = big;
            mesoi_cells_skip_radii(ids2, R, radius2);
            for (size_t v = 0; v < n; ++v) {
                uint32_t s;
                if (wide)
                    memcpy(&s, tile + 4 * v, 4);
                else {
                    uint16_t h;
                    memcpy(&h, tile + 2 * v, 2);
                    s = h;
                }
                CHECK((s & ((1u << bits) - 1u)) == ids2[v] && s >> bits == radius2[v]);
            }
            free(ids2);
            free(radius2);
        }
    }
    printf("pack: u16 and u32 maps read back; ids without room leave the map as it was\n");
    free(ids);
    free(radius);
    free(tile);
    free(before);
    free(scratch);
}

int main(void)
{
    test_radii();
    test_pack();
    printf("ok\n");
    return 0;
}
