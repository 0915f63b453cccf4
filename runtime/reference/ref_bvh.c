/*
 * ref_bvh.c — the CPU references' bounding-volume hierarchy (ref_bvh.h).
 *
 * The build sorts by box centre along the axis in which the centres spread
 * most and splits at the median, so the tree is balanced (depth
 * ⌈log₂(n / 4)⌉ + 1, far below the trace stack's 128 for any item count a
 * uint32_t holds).
 */
#include "ref_bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct sort_key {
    double key;
    uint32_t item;
} sort_key;

static int cmp_key(const void* a, const void* b)
{
    const sort_key *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->item > y->item) - (x->item < y->item);
}

typedef struct build_ctx {
    mesoi_ref_bvh* b;
    const double (*box)[6];
    sort_key* tmp;
} build_ctx;

static void build(build_ctx* c, uint32_t node, uint32_t first, uint32_t count)
{
    mesoi_ref_bvh* b = c->b;
    mesoi_ref_bvh_node* nd = &b->nodes[node];
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < 3; ++k) {
        nd->lo[k] = INFINITY;
        nd->hi[k] = -INFINITY;
    }
    for (uint32_t i = first; i < first + count; ++i) {
        const double* bx = c->box[b->items[i]];
        for (int k = 0; k < 3; ++k) {
            nd->lo[k] = fmin(nd->lo[k], bx[k]);
            nd->hi[k] = fmax(nd->hi[k], bx[3 + k]);
            const double m = 0.5 * (bx[k] + bx[3 + k]);
            clo[k] = fmin(clo[k], m);
            chi[k] = fmax(chi[k], m);
        }
    }
    if (count <= 4) {
        nd->first = first;
        nd->count = count;
        return;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (chi[k] - clo[k] > chi[axis] - clo[axis])
            axis = k;
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t it = b->items[first + i];
        c->tmp[i].key = c->box[it][axis] + c->box[it][3 + axis];
        c->tmp[i].item = it;
    }
    qsort(c->tmp, count, sizeof(*c->tmp), cmp_key);
    for (uint32_t i = 0; i < count; ++i)
        b->items[first + i] = c->tmp[i].item;
    const uint32_t half = count / 2, left = b->node_count;
    b->node_count += 2;
    nd->first = left;
    nd->count = 0;
    build(c, left, first, half);
    build(c, left + 1, first + half, count - half);
}

meso_result mesoi_ref_bvh_build(mesoi_ref_bvh* b, const double (*box)[6], const uint32_t* items, uint32_t n)
{
    memset(b, 0, sizeof(*b));
    if (n == 0)
        return MESO_OK;
    b->nodes = malloc(sizeof(*b->nodes) * 2 * (size_t)n);
    b->items = malloc(sizeof(*b->items) * n);
    sort_key* tmp = malloc(sizeof(*tmp) * n);
    if (!b->nodes || !b->items || !tmp) {
        free(tmp);
        mesoi_ref_bvh_free(b);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    memcpy(b->items, items, sizeof(*items) * n);
    b->item_count = n;
    b->node_count = 1;
    build_ctx c = {b, box, tmp};
    build(&c, 0, 0, n);
    free(tmp);
    return MESO_OK;
}

void mesoi_ref_bvh_free(mesoi_ref_bvh* b)
{
    free(b->nodes);
    free(b->items);
    memset(b, 0, sizeof(*b));
}

int mesoi_ref_box_interval(const double lo[3], const double hi[3], const double o[3], const double d[3],
    const double inv[3], double* t0, double* t1)
{
    double a = *t0, b = *t1;
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) {
            if (o[k] < lo[k] || o[k] > hi[k])
                return 0;
            continue;
        }
        double ta = (lo[k] - o[k]) * inv[k], tb = (hi[k] - o[k]) * inv[k];
        if (ta > tb) {
            const double x = ta;
            ta = tb;
            tb = x;
        }
        a = fmax(a, ta);
        b = fmin(b, tb);
        if (a > b)
            return 0;
    }
    *t0 = a;
    *t1 = b;
    return 1;
}

void mesoi_ref_bvh_trace(const mesoi_ref_bvh* b, const double o[3], const double d[3], const double inv[3],
    double* tmax, mesoi_ref_bvh_leaf_fn leaf, const void* user)
{
    if (!b->nodes)
        return;
    uint32_t stack[128];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const mesoi_ref_bvh_node* nd = &b->nodes[stack[--sp]];
        double t0 = 0, t1 = *tmax;
        if (!mesoi_ref_box_interval(nd->lo, nd->hi, o, d, inv, &t0, &t1))
            continue;
        if (nd->count == 0) {
            /* Nearer child last, so it is popped first. */
            const mesoi_ref_bvh_node *l = &b->nodes[nd->first], *r = &b->nodes[nd->first + 1];
            double la = 0, lb = *tmax, ra = 0, rb = *tmax;
            const int hl = mesoi_ref_box_interval(l->lo, l->hi, o, d, inv, &la, &lb);
            const int hr = mesoi_ref_box_interval(r->lo, r->hi, o, d, inv, &ra, &rb);
            const int l_first = !hr || (hl && la <= ra);
            stack[sp++] = l_first ? nd->first + 1 : nd->first;
            stack[sp++] = l_first ? nd->first : nd->first + 1;
            continue;
        }
        leaf(user, &b->items[nd->first], nd->count, tmax);
    }
}
