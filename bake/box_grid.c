/*
 * box_grid.c — see box_grid.h.
 *
 * Cells are hashed (open addressing on the packed cell coordinates), each a
 * singly linked list of entries in one pool. Setting a box unlinks the
 * item's entries from the cells of its old box and appends entries in the
 * cells the new one covers; a query tests every item it meets against the
 * item's current box, and an item met twice is reported once (a per-query
 * stamp). Unlinked entries stay in the pool until they outnumber the
 * linked ones, when it is rebuilt from the present items (counting them:
 * the pool's doubling since the last rebuild, the rule before, also
 * rebuilt a grid being filled, whose pool holds nothing unlinked, ~12
 * times on the way to 400k boxes; with the table's own doublings that made
 * filling the checker's grids 0.75 s of a 423k-triangle bake). (They were left
 * linked until then, as harmless as they are slow: repair and regrow move
 * the same few thousand directors a hundred times, so the cells where the
 * queries are filled with the boxes those directors had before, and on a
 * 467k-triangle shell a query walked 600 entries to report 17.)
 *
 * Boxes that span BIG or more cells along an axis go to a coarser level of
 * the same hash, whose cells are BIG times larger (LEVELS levels in all),
 * and only what spans BIG cells of the coarsest to one list every query
 * scans (a few huge triangles must not cost a million cells). The list
 * was all there was above level 0 until the stretched offset triangles of
 * a 467k-triangle shell put 735 items in it: 972,500 queries scanned 401
 * million entries, 7 s of a 30 s bake. A query visits each level that has
 * had an item since the last rebuild.
 */
#include "box_grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { BIG = 8, LEVELS = 4 };

typedef struct entry {
    uint32_t item, next;
} entry;

struct meso_box_grid {
    double cell;
    uint32_t count;
    double* box;       /* 6 per item: lo, hi */
    uint8_t* present;  /* item has a box */
    uint8_t* big;      /* item is (also) in the big list */
    uint32_t* stamp;   /* per item: the query that last reported it */
    uint32_t query;
    /* hash: keys[s] (UINT64_MAX = empty) -> head[s] (entry index + 1, 0 = none) */
    uint64_t* keys;
    uint32_t* head;
    size_t slots, used;
    entry* pool;
    size_t entries, pool_cap;            /* entries in the pool (linked or not) */
    size_t unlinked;                     /* of them, unlinked since the last rebuild */
    uint8_t level_used[LEVELS];          /* a level has had entries since the last rebuild */
    uint32_t* bigs;
    size_t big_count, big_cap;
};

/* 20 bits per axis and the level above them. Coordinates past 2^19 cells
 * wrap: distant cells then share a key, which costs time, never an answer
 * (every item met is tested against its box). */
static uint64_t pack(int64_t i, int64_t j, int64_t k, int level)
{
    const int64_t o = (int64_t)1 << 19;
    return ((uint64_t)(i + o) & 0xfffff) | (((uint64_t)(j + o) & 0xfffff) << 20) |
           (((uint64_t)(k + o) & 0xfffff) << 40) | ((uint64_t)level << 60);
}

static size_t slot_of(const meso_box_grid* g, uint64_t key)
{
    uint64_t h = key * 0x9E3779B97F4A7C15ull;
    size_t s = (size_t)(h >> 17) & (g->slots - 1);
    while (g->keys[s] != UINT64_MAX && g->keys[s] != key)
        s = (s + 1) & (g->slots - 1);
    return s;
}

/* The head of a cell's list (entry index + 1, 0 = none), NULL when the
 * cell has never had an entry. */
static uint32_t* cell_list(meso_box_grid* g, int64_t x, int64_t y, int64_t z, int level)
{
    const uint64_t key = pack(x, y, z, level);
    const size_t s = slot_of(g, key);
    return g->keys[s] == key ? &g->head[s] : NULL;
}

static int grow_table(meso_box_grid* g)
{
    const size_t old_slots = g->slots;
    uint64_t* ok = g->keys;
    uint32_t* oh = g->head;
    g->slots = old_slots ? old_slots * 2 : 1024;
    g->keys = malloc(sizeof(uint64_t) * g->slots);
    g->head = calloc(g->slots, sizeof(uint32_t));
    if (!g->keys || !g->head) {
        free(ok), free(oh);
        return 0;
    }
    memset(g->keys, 0xff, sizeof(uint64_t) * g->slots);
    for (size_t s = 0; s < old_slots; ++s)
        if (ok[s] != UINT64_MAX) {
            const size_t t = slot_of(g, ok[s]);
            g->keys[t] = ok[s];
            g->head[t] = oh[s];
        }
    free(ok), free(oh);
    return 1;
}

/* The cells of `level` (edge cell * BIG^level) that [lo, hi] covers. */
static void cell_range(const meso_box_grid* g, int level, const double* lo, const double* hi, int64_t a[3],
                       int64_t b[3])
{
    double cell = g->cell;
    for (int l = 0; l < level; ++l)
        cell *= BIG;
    for (int k = 0; k < 3; ++k) {
        a[k] = (int64_t)floor(lo[k] / cell);
        b[k] = (int64_t)floor(hi[k] / cell);
    }
}

static int spans_big(const int64_t a[3], const int64_t b[3], int64_t big)
{
    return b[0] - a[0] >= big || b[1] - a[1] >= big || b[2] - a[2] >= big;
}

static int add_entry(meso_box_grid* g, uint64_t key, uint32_t item)
{
    if (2 * (g->used + 1) > g->slots && !grow_table(g))
        return 0;
    if (g->entries == g->pool_cap) {
        const size_t cap = g->pool_cap ? 2 * g->pool_cap : 4096;
        entry* p = realloc(g->pool, sizeof(entry) * cap);
        if (!p)
            return 0;
        g->pool = p;
        g->pool_cap = cap;
    }
    const size_t s = slot_of(g, key);
    if (g->keys[s] == UINT64_MAX) {
        g->keys[s] = key;
        g->used++;
    }
    g->pool[g->entries] = (entry){item, g->head[s]};
    g->head[s] = (uint32_t)++g->entries;
    return 1;
}

/* The level item i's present box goes to and the cells it covers there;
 * LEVELS: the big list. */
static int level_of(const meso_box_grid* g, uint32_t i, int64_t a[3], int64_t b[3])
{
    const double* lo = g->box + 6 * (size_t)i;
    int level = 0;
    cell_range(g, 0, lo, lo + 3, a, b);
    while (level < LEVELS && spans_big(a, b, BIG))
        if (++level < LEVELS)
            cell_range(g, level, lo, lo + 3, a, b);
    return level;
}

/* Unlink item i's entries from the cells of its present box. */
static void unlink_item(meso_box_grid* g, uint32_t i)
{
    int64_t a[3], b[3];
    const int level = level_of(g, i, a, b);
    if (level == LEVELS)
        return; /* in the big list: no entries */
    for (int64_t z = a[2]; z <= b[2]; ++z)
        for (int64_t y = a[1]; y <= b[1]; ++y)
            for (int64_t x = a[0]; x <= b[0]; ++x)
                for (uint32_t* link = cell_list(g, x, y, z, level); link && *link;) {
                    entry* e = &g->pool[*link - 1];
                    if (e->item == i) {
                        *link = e->next;
                        g->unlinked++;
                    } else
                        link = &e->next;
                }
}

static int insert(meso_box_grid* g, uint32_t i)
{
    int64_t a[3], b[3];
    const int level = level_of(g, i, a, b);
    if (level == LEVELS) {
        if (g->big[i])
            return 1;
        if (g->big_count == g->big_cap) {
            const size_t cap = g->big_cap ? 2 * g->big_cap : 64;
            uint32_t* p = realloc(g->bigs, sizeof(uint32_t) * cap);
            if (!p)
                return 0;
            g->bigs = p;
            g->big_cap = cap;
        }
        g->bigs[g->big_count++] = i;
        g->big[i] = 1;
        return 1;
    }
    g->level_used[level] = 1;
    for (int64_t z = a[2]; z <= b[2]; ++z)
        for (int64_t y = a[1]; y <= b[1]; ++y)
            for (int64_t x = a[0]; x <= b[0]; ++x) {
                if (!add_entry(g, pack(x, y, z, level), i))
                    return 0;
            }
    return 1;
}

/* Drop every entry and insert the present items again. */
static int rebuild(meso_box_grid* g)
{
    memset(g->keys, 0xff, sizeof(uint64_t) * g->slots);
    memset(g->head, 0, sizeof(uint32_t) * g->slots);
    g->used = g->entries = g->unlinked = g->big_count = 0;
    memset(g->level_used, 0, sizeof g->level_used);
    memset(g->big, 0, g->count ? g->count : 1);
    for (uint32_t i = 0; i < g->count; ++i)
        if (g->present[i] && !insert(g, i))
            return 0;
    return 1;
}

meso_box_grid* meso_box_grid_create(uint32_t count, double cell)
{
    meso_box_grid* g = calloc(1, sizeof(*g));
    if (!g)
        return NULL;
    g->cell = cell > 0 && isfinite(cell) ? cell : 1.0;
    g->count = count;
    g->box = malloc(sizeof(double) * 6 * (size_t)(count ? count : 1));
    g->present = calloc(count ? count : 1, 1);
    g->big = calloc(count ? count : 1, 1);
    g->stamp = calloc(count ? count : 1, sizeof(uint32_t));
    if (!g->box || !g->present || !g->big || !g->stamp || !grow_table(g)) {
        meso_box_grid_destroy(g);
        return NULL;
    }
    return g;
}

void meso_box_grid_destroy(meso_box_grid* g)
{
    if (!g)
        return;
    free(g->box), free(g->present), free(g->big), free(g->stamp);
    free(g->keys), free(g->head), free(g->pool), free(g->bigs);
    free(g);
}

int meso_box_grid_set(meso_box_grid* g, uint32_t i, const double* lo, const double* hi)
{
    double* b = g->box + 6 * (size_t)i;
    if (!lo) {
        if (g->present[i])
            unlink_item(g, i);
        g->present[i] = 0;
        return 1;
    }
    /* Entries already cover this box when it did not move. */
    if (g->present[i] && memcmp(b, lo, 3 * sizeof(double)) == 0 && memcmp(b + 3, hi, 3 * sizeof(double)) == 0)
        return 1;
    if (g->present[i])
        unlink_item(g, i);
    memcpy(b, lo, 3 * sizeof(double));
    memcpy(b + 3, hi, 3 * sizeof(double));
    g->present[i] = 1;
    if (!insert(g, i))
        return 0;
    /* Compact when unlinked entries outnumber the linked ones (amortised
     * O(1) per unlinked entry). */
    if (g->unlinked > g->entries - g->unlinked + 4096)
        return rebuild(g);
    return 1;
}

static int overlaps(const double* b, const double lo[3], const double hi[3])
{
    return b[0] <= hi[0] && lo[0] <= b[3] && b[1] <= hi[1] && lo[1] <= b[4] && b[2] <= hi[2] && lo[2] <= b[5];
}

static int report(meso_box_grid* g, uint32_t i, const double lo[3], const double hi[3], uint32_t** out, size_t* n,
                  size_t* cap)
{
    if (!g->present[i] || g->stamp[i] == g->query || !overlaps(g->box + 6 * (size_t)i, lo, hi))
        return 1;
    g->stamp[i] = g->query;
    if (*n == *cap) {
        const size_t c = *cap ? 2 * *cap : 256;
        uint32_t* p = realloc(*out, sizeof(uint32_t) * c);
        if (!p)
            return 0;
        *out = p;
        *cap = c;
    }
    (*out)[(*n)++] = i;
    return 1;
}

int meso_box_grid_query(meso_box_grid* g, const double lo[3], const double hi[3], uint32_t** out, size_t* n,
                        size_t* cap)
{
    if (++g->query == 0) { /* stamps wrapped: forget them all */
        memset(g->stamp, 0, sizeof(uint32_t) * (g->count ? g->count : 1));
        g->query = 1;
    }
    for (size_t k = 0; k < g->big_count; ++k)
        if (!report(g, g->bigs[k], lo, hi, out, n, cap))
            return 0;
    int64_t a[3], b[3];
    cell_range(g, 0, lo, hi, a, b);
    if (spans_big(a, b, 4 * BIG + 1)) {
        /* a query box far larger than a cell: every item is cheaper */
        for (uint32_t i = 0; i < g->count; ++i)
            if (!report(g, i, lo, hi, out, n, cap))
                return 0;
        return 1;
    }
    for (int level = 0; level < LEVELS; ++level) {
        if (!g->level_used[level])
            continue;
        if (level)
            cell_range(g, level, lo, hi, a, b);
        for (int64_t z = a[2]; z <= b[2]; ++z)
            for (int64_t y = a[1]; y <= b[1]; ++y)
                for (int64_t x = a[0]; x <= b[0]; ++x) {
                    const uint32_t* head = cell_list(g, x, y, z, level);
                    for (uint32_t e = head ? *head : 0; e; e = g->pool[e - 1].next)
                        if (!report(g, g->pool[e - 1].item, lo, hi, out, n, cap))
                            return 0;
                }
    }
    return 1;
}

size_t meso_box_grid_linked(const meso_box_grid* g)
{
    size_t n = 0;
    for (size_t s = 0; s < g->slots; ++s)
        for (uint32_t e = g->keys[s] != UINT64_MAX ? g->head[s] : 0; e; e = g->pool[e - 1].next)
            ++n;
    return n;
}
