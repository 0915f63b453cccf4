/*
 * split_cells.c — split cells by union-find, cells by union-find with tile
 * offsets. See split_cells.h for the definitions and the method.
 */
#include "split_cells.h"

#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"

/* Voxel labels share the parent array: a processed voxel holds LABELLED | its
 * provisional split id (R <= 1024, so voxel indices stay below 2^30). */
#define LABELLED 0x80000000u

/* >>voxel union-find ----------------------------------------------------------
 * Roots are the smallest voxel index of their set, so every parent pointer
 * points backwards in scan order (path halving keeps that). */
static uint32_t vfind(uint32_t* parent, uint32_t v)
{
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

static void vunion(uint32_t* parent, uint32_t a, uint32_t b)
{
    a = vfind(parent, a);
    b = vfind(parent, b);
    if (a < b)
        parent[b] = a;
    else if (b < a)
        parent[a] = b;
}

/* >>split-cell union-find with offsets ----------------------------------------
 * off[s] = tile of s minus tile of parent[s] (in one connected copy). */
typedef struct sets {
    uint32_t* parent;
    int32_t (*off)[3];
    uint8_t* wraps;
} sets;

static uint32_t sfind(sets* u, uint32_t s, int32_t o[3])
{
    int32_t acc[3] = {0, 0, 0};
    uint32_t r = s;
    while (u->parent[r] != r) {
        for (int a = 0; a < 3; ++a)
            acc[a] += u->off[r][a];
        r = u->parent[r];
    }
    /* Path compression: each node on the path gets its total offset to r. */
    int32_t t[3] = {acc[0], acc[1], acc[2]};
    uint32_t x = s;
    while (x != r && u->parent[x] != r) {
        const uint32_t next = u->parent[x];
        int32_t tn[3];
        for (int a = 0; a < 3; ++a) {
            tn[a] = t[a] - u->off[x][a];
            u->off[x][a] = t[a];
        }
        u->parent[x] = r;
        x = next;
        memcpy(t, tn, sizeof(t));
    }
    memcpy(o, acc, sizeof(acc));
    return r;
}

/* b's copy sits in tile(a) + w. */
static void slink(sets* u, uint32_t a, uint32_t b, const int32_t w[3])
{
    int32_t oa[3], ob[3];
    const uint32_t ra = sfind(u, a, oa), rb = sfind(u, b, ob);
    if (ra == rb) {
        if (ob[0] != oa[0] + w[0] || ob[1] != oa[1] + w[1] || ob[2] != oa[2] + w[2])
            u->wraps[ra] = 1;
        return;
    }
    if (ra < rb) {
        u->parent[rb] = ra;
        for (int k = 0; k < 3; ++k)
            u->off[rb][k] = w[k] + oa[k] - ob[k];
        u->wraps[ra] |= u->wraps[rb];
    } else {
        u->parent[ra] = rb;
        for (int k = 0; k < 3; ++k)
            u->off[ra][k] = ob[k] - oa[k] - w[k];
        u->wraps[rb] |= u->wraps[ra];
    }
}

/* >>numbering ----------------------------------------------------------------- */
typedef struct key {
    uint32_t major; /* cell, or tile index for cells */
    uint32_t minor; /* face code, or 0 */
    uint32_t prov;  /* provisional id: first-voxel order */
} key;

static int cmp_key(const void* pa, const void* pb)
{
    const key *a = pa, *b = pb;
    if (a->major != b->major)
        return a->major < b->major ? -1 : 1;
    if (a->minor != b->minor)
        return a->minor < b->minor ? -1 : 1;
    return a->prov < b->prov ? -1 : a->prov > b->prov;
}

void meso_split_cells_free(meso_split_cells* sc)
{
    if (!sc)
        return;
    free(sc->voxel_split);
    free(sc->splits);
    free(sc->cells);
    memset(sc, 0, sizeof(*sc));
}

/* Provisional per-split data gathered in the labelling scan. */
typedef struct prov {
    uint32_t first_voxel;
    uint32_t voxel_count;
    uint16_t tile_index;
    uint8_t face_code;
} prov;

static uint8_t face_bits(uint32_t x, uint32_t y, uint32_t z, uint32_t R)
{
    return (uint8_t)((x == 0 ? MESO_FACE_X0 : 0) | (x == R - 1 ? MESO_FACE_X1 : 0) | (y == 0 ? MESO_FACE_Y0 : 0) |
                     (y == R - 1 ? MESO_FACE_Y1 : 0) | (z == 0 ? MESO_FACE_Z0 : 0) | (z == R - 1 ? MESO_FACE_Z1 : 0));
}

meso_result meso_split_cells_compute(const meso_tile_map* m, int threads, meso_split_cells* out, meso_error* err)
{
    if (!m || !out || !m->cells)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "split cells: NULL argument");
    memset(out, 0, sizeof(*out));
    if (m->res < 1 || m->res > MESO_TILE_MAP_MAX_RES)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "split cells: resolution %u is not in 1..%u", m->res, MESO_TILE_MAP_MAX_RES);
    const uint32_t R = m->res;
    const size_t n = (size_t)R * R * R, RR = (size_t)R * R;
    const uint16_t* cells = m->cells;
    /* Everything below is freed at `done`; on failure `out` too. */
    meso_result r = MESO_OK;
    prov* pv = NULL;
    sets u = {NULL, NULL, NULL};
    key* keys = NULL;
    uint32_t *final_id = NULL, *cell_of_root = NULL;
    uint32_t S = 0, C = 0;
    uint32_t* lab = malloc(n * sizeof(uint32_t));
    if (!lab) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "split cells: out of memory (R = %u)", R);
        goto done;
    }

    /* 1. Split cells: join each voxel with its 13 earlier 26-neighbours. */
    for (size_t v = 0; v < n; ++v)
        lab[v] = (uint32_t)v;
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                const size_t v = x + R * (y + (size_t)R * z);
                const uint16_t c = cells[v];
                if (!c)
                    continue;
                for (int dz = -1; dz <= 0; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0)))
                                continue; /* later in scan order, or v itself */
                            const int64_t qx = (int64_t)x + dx, qy = (int64_t)y + dy, qz = (int64_t)z + dz;
                            if (qx < 0 || qy < 0 || qz < 0 || qx >= R || qy >= R)
                                continue;
                            const size_t q = (size_t)qx + R * ((size_t)qy + (size_t)R * (size_t)qz);
                            if (cells[q] == c)
                                vunion(lab, (uint32_t)v, (uint32_t)q);
                        }
            }

    /* Label in scan order: a root opens a split cell; any other voxel's
     * parent is earlier and already labelled with its set's id. */
    size_t cap = 64;
    pv = malloc(cap * sizeof(prov));
    if (!pv) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "split cells: out of memory");
        goto done;
    }
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                const size_t v = x + R * (y + (size_t)R * z);
                if (!cells[v]) {
                    lab[v] = LABELLED;
                    continue;
                }
                uint32_t id;
                if (lab[v] == v) {
                    if (S == cap) {
                        prov* grown = realloc(pv, 2 * cap * sizeof(prov));
                        if (!grown) {
                            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "split cells: out of memory");
                            goto done;
                        }
                        pv = grown;
                        cap *= 2;
                    }
                    pv[S] = (prov){.first_voxel = (uint32_t)v, .tile_index = cells[v]};
                    id = ++S;
                } else {
                    id = lab[lab[v]] & ~LABELLED;
                }
                lab[v] = LABELLED | id;
                pv[id - 1].voxel_count++;
                pv[id - 1].face_code |= face_bits(x, y, z, R);
            }

    /* 2. Cells: join split cells across the border, with tile offsets. */
    u.parent = malloc((S + 1) * sizeof(uint32_t));
    u.off = malloc((S + 1) * sizeof(*u.off));
    u.wraps = calloc(S + 1, 1);
    keys = malloc((S + 1) * sizeof(key));
    final_id = malloc((S + 1) * sizeof(uint32_t));
    cell_of_root = calloc(S + 1, sizeof(uint32_t));
    out->splits = calloc(S ? S : 1, sizeof(meso_split_cell));
    if (!u.parent || !u.off || !u.wraps || !keys || !final_id || !cell_of_root || !out->splits) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "split cells: out of memory (%u split cells)", S);
        goto done;
    }
    for (uint32_t s = 0; s <= S; ++s) { /* ids 1..S; 0 unused */
        u.parent[s] = s;
        memset(u.off[s], 0, sizeof(u.off[s]));
    }
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y) {
            const int yz_border = z == 0 || z == R - 1 || y == 0 || y == R - 1;
            const uint32_t step = yz_border ? 1 : (R > 1 ? R - 1 : 1);
            for (uint32_t x = 0; x < R; x += step) {
                const size_t v = x + R * (y + (size_t)R * z);
                const uint16_t c = cells[v];
                if (!c)
                    continue;
                for (int dz = -1; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const int64_t q[3] = {(int64_t)x + dx, (int64_t)y + dy, (int64_t)z + dz};
                            int32_t w[3];
                            size_t qi = 0, mul = 1;
                            int across = 0;
                            for (int a = 0; a < 3; ++a) {
                                w[a] = q[a] < 0 ? -1 : q[a] >= R ? 1 : 0;
                                across |= w[a];
                                qi += (size_t)(q[a] - (int64_t)w[a] * R) * mul;
                                mul *= R;
                            }
                            if (!across || cells[qi] != c)
                                continue; /* inside the tile: step 1 did it */
                            slink(&u, lab[v] & ~LABELLED, lab[qi] & ~LABELLED, w);
                        }
            }
        }

    /* 3. Number cells by (tile index, first voxel); roots are the smallest
     * provisional id of their set, i.e. the cell's first split cell. */
    for (uint32_t s = 1; s <= S; ++s)
        if (u.parent[s] == s)
            keys[C++] = (key){pv[s - 1].tile_index, 0, s};
    qsort(keys, C, sizeof(key), cmp_key);
    out->cells = calloc(C ? C : 1, sizeof(meso_cell));
    if (!out->cells) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "split cells: out of memory (%u cells)", C);
        goto done;
    }
    for (uint32_t c = 0; c < C; ++c) {
        cell_of_root[keys[c].prov] = c + 1;
        out->cells[c].tile_index = (uint16_t)keys[c].major;
        out->cells[c].wraps = u.wraps[keys[c].prov];
        out->wrapping_cells += u.wraps[keys[c].prov];
    }
    for (uint32_t s = 1; s <= S; ++s) {
        int32_t o[3];
        const uint32_t root = sfind(&u, s, o);
        keys[s - 1] = (key){cell_of_root[root], pv[s - 1].face_code, s};
    }
    qsort(keys, S, sizeof(key), cmp_key);
    for (uint32_t i = 0; i < S; ++i) {
        const uint32_t s = keys[i].prov, c = keys[i].major;
        final_id[s] = i + 1;
        meso_cell* cell = &out->cells[c - 1];
        if (cell->split_count == 0)
            cell->first_split = i + 1;
        const uint32_t rank = cell->split_count++;
        cell->voxel_count += pv[s - 1].voxel_count;
        meso_split_cell* sp = &out->splits[i];
        sp->cell = c;
        sp->voxel_count = pv[s - 1].voxel_count;
        sp->first_voxel = pv[s - 1].first_voxel;
        sp->tile_index = pv[s - 1].tile_index;
        sp->face_code = pv[s - 1].face_code;
        sp->rank = (uint8_t)(rank < 255 ? rank : 255);
        sp->thesis_slot = 8 * (c - 1) + rank;
        sfind(&u, s, sp->offset); /* relative to the root: the cell's first split cell */
        if (cell->split_count > out->max_splits_per_cell)
            out->max_splits_per_cell = cell->split_count;
    }
    final_id[0] = 0;

    /* Relabel the voxels with final ids. */
    const int nt = meso_bake_thread_count(threads);
    (void)nt;
#ifdef _OPENMP
#pragma omp parallel for schedule(static) num_threads(nt)
#endif
    for (long zl = 0; zl < (long)R; ++zl)
        for (size_t i = (size_t)zl * RR; i < (size_t)(zl + 1) * RR; ++i)
            lab[i] = final_id[lab[i] & ~LABELLED];

    out->res = R;
    out->split_count = S;
    out->cell_count = C;
    out->voxel_split = lab;
    lab = NULL;
done:
    free(u.parent);
    free(u.off);
    free(u.wraps);
    free(keys);
    free(final_id);
    free(cell_of_root);
    free(pv);
    free(lab);
    if (r != MESO_OK)
        meso_split_cells_free(out);
    return r;
}

/* >>packing ------------------------------------------------------------------ */

meso_split_packing meso_split_cells_packing(const meso_split_cells* sc)
{
    if (sc->cell_count <= 8 && sc->max_splits_per_cell <= 8)
        return MESO_SPLIT_PACK_THESIS;
    return sc->split_count <= 64 ? MESO_SPLIT_PACK_DENSE64 : MESO_SPLIT_PACK_WIDE;
}

meso_result meso_split_cells_check_packing(const meso_split_cells* sc, meso_split_packing packing, meso_error* err)
{
    if (!sc || packing < 0 || packing >= MESO_SPLIT_PACK_COUNT)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "split cells: bad argument");
    if (meso_split_cells_packing(sc) <= packing)
        return MESO_OK;
    if (packing == MESO_SPLIT_PACK_THESIS)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PACKING,
                              "tile map: %u split cells in %u cells, up to %u in one cell; the thesis's 128-bit "
                              "tile code holds at most 8 cells of at most 8 split cells each",
                              sc->split_count, sc->cell_count, sc->max_splits_per_cell);
    return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PACKING,
                          "tile map: %u split cells in %u cells; a 128-bit tile code holds at most 64",
                          sc->split_count, sc->cell_count);
}
