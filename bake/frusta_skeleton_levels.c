/*
 * frusta_skeleton_levels.c — coarser skeletons of a frusta object
 * (frusta_skeleton_levels.h; relief-mapped-conical-frusta.md §2–3 for the
 * frusta, issue 14 for the levels). The paper builds one skeleton; a level
 * of detail needs fewer frusta where a chain of them is nearly one cone.
 *
 * Which nodes a level keeps. Anchors always stay: roots, tips, branch
 * points, level 0's ball nodes (a ball at a removed node would vanish) and
 * nodes at zero-length segments. Between two anchors a chain of joint
 * nodes is cut Douglas–Peucker style on (position, radius): a node's
 * deviation from the chain's straight cone is its distance to the segment
 * between the two nodes kept around it plus its radius's distance to the
 * radius interpolated there; while the worst deviation in a piece exceeds
 * the level's target τ, the piece is split at its worst node. Each level
 * keeps a subset of the level before's nodes (it may split only at them),
 * and τ doubles from try to try, from 1/16 of the room left below the
 * stand-in's error. The deviation only orders nodes: the error is
 * measured on the frusta built. A level is kept when it has at most 3/4
 * of the frusta of the level before (else τ doubles) and its error is
 * below the stand-in's (else the chain stops).
 *
 * The level's frusta are frustum_model.c's for the coarse skeleton with
 * level 0's options: its §2.2 joint planes and minor-axis fit, ball rules
 * and §2.3 u frames, with level 0's balls kept as balls (named joints
 * become ball joints after the fit, so every other joint fits as it would
 * without them). Where a kept joint the coarse frusta cannot fit (short,
 * fat segments: neurons) becomes a ball level 0 has not, the nearest
 * dropped node above and below it is kept again and the level rebuilt,
 * up to BALL_RETRIES times; a level whose balls still differ is not kept.
 * Then:
 *  - their node indices are mapped to level 0's SKEL, which the level
 *    shares (one SKEL in the file; a host's pose moves every level);
 *  - a coarse frustum spanning level 0's chain i1..ik takes the chain's
 *    relief coordinates: v_offset of i1, v_scale the sum of the chain's
 *    (t continues across joints, frusta_chunks.h), so t runs over the same
 *    range and meets its neighbours' t at the kept nodes as level 0's does.
 *
 * The error (decided: a correspondence, as frusta_standin.h's). Pair each
 * point of level 0 with the point of the level with the same relief
 * coordinates (s, t) at the same relief height: frustum j of the chain at
 * (u, v) with the coarse frustum at (u, v_c), v_c = (t_j(v) − v_offset_c)
 * / v_scale_c. The pairing maps each lateral surface onto the other, so its
 * largest distance bounds the Hausdorff distance both ways. Without twist,
 * for a fixed u both points are affine in v (a generator) and v_c is affine
 * in v, so the distance is convex in v on each of level 0's frusta: its
 * largest value is at v = 0 or 1. For a fixed (u, v) both points are affine
 * in the height δ (frusta_tessellation.h), so it is at δ's extremes: the
 * relief's lowest and highest texel times the depth (down to 0 where a tip
 * has a cap: the wall from the cap's rim up to the relief). So the sup is
 * over u alone, on each of level 0's frustum ends: sampled at U_SAMPLES
 * values of u, plus 1.5 times the largest change between neighbouring
 * samples over two (the sampled Lipschitz constant, with a margin, times
 * half a step). Caps: a cap point (centre + ρ (rim − centre)) is affine in
 * ρ, so its pairing is bounded by its centre's (the tip node, on both) and
 * its rim's (the lateral end above). Balls sit at the same nodes on both
 * (a level whose balls differ is not kept): |r_0 − r_level|. Plus float
 * rounding: 4 ulps of the largest coordinate.
 * Where nothing is drawn by the relief coordinates (no relief, no colour
 * map) any pairing that maps each surface onto the other bounds the
 * distance, so a better one is taken: frustum j's u turned by the angle
 * between its u = 0 direction and the coarse frustum's, and v_c at j's
 * nodes where they lie along the coarse axis (0 and 1 at the chain's
 * ends, affine in between: still continuous, so still onto). On the
 * neuron this took the first try from 1.57 to 0.89.
 * Twisted frusta get no coarser skeleton: with twist a generator is not a
 * line of constant u, and u's turn along a merged chain would need its own
 * bound.
 * tests/integration/test_frusta_skeleton_levels.c checks the error against the
 * exact reference's hits, both ways.
 */
#include "frusta_skeleton_levels.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "frusta_tessellation.h"
#include "vec3d.h"

enum { U_SAMPLES = 512, TAU_TRIES = 12, BALL_RETRIES = 32 };

void mesoi_skeleton_levels_free(mesoi_skeleton_level* levels, uint32_t count)
{
    if (!levels)
        return;
    for (uint32_t k = 0; k < count; ++k)
        meso_frusta_object_free(&levels[k].obj);
    free(levels);
}

/* >>distance ---------------------------------------------------------------- */

static void point(const meso_frustum_rec* r, double h, double u, double v, double p[3])
{
    meso_frusta_tess_point(r, meso_frusta_height_constant, &h, u, v, p);
}

/* Largest |p_f(u, vf) − p_c(u, vc)| over u at relief height h (sampled, with
 * the slack of the header comment). */
static double end_distance(const meso_frustum_rec* f, double vf, const meso_frustum_rec* c, double vc, double h,
                           double shift)
{
    double worst = 0, step = 0, prev[3] = {0, 0, 0}, first[3] = {0, 0, 0};
    for (int k = 0; k <= U_SAMPLES; ++k) {
        double d[3];
        if (k < U_SAMPLES) {
            const double u = (double)k / U_SAMPLES;
            double pf[3], pc[3];
            point(f, h, u, vf, pf);
            point(c, h, u + shift, vc, pc);
            for (int i = 0; i < 3; ++i)
                d[i] = pf[i] - pc[i];
        } else {
            memcpy(d, first, sizeof d); /* u = 1 is u = 0 */
        }
        if (k < U_SAMPLES)
            worst = fmax(worst, len3(d));
        if (k > 0)
            step = fmax(step, dist3(d, prev));
        else
            memcpy(first, d, sizeof first);
        memcpy(prev, d, sizeof prev);
    }
    return worst + 0.75 * step;
}

static int node_cmp(const void* a, const void* b)
{
    const meso_frustum_ball_rec *x = a, *y = b;
    return (x->node > y->node) - (x->node < y->node);
}

/* Ball term: the same nodes, |Δr| each; -1 when the nodes differ. */
static double ball_distance(const meso_frusta_object* f, const meso_frusta_object* c)
{
    if (f->ball_count != c->ball_count)
        return -1;
    const uint32_t n = f->ball_count;
    meso_frustum_ball_rec* a = malloc(sizeof(*a) * (2 * (size_t)n + 1));
    if (!a)
        return -1;
    memcpy(a, f->balls, sizeof(*a) * n);
    memcpy(a + n, c->balls, sizeof(*a) * n);
    qsort(a, n, sizeof(*a), node_cmp);
    qsort(a + n, n, sizeof(*a), node_cmp);
    double worst = 0;
    for (uint32_t b = 0; b < n && worst >= 0; ++b)
        worst = a[b].node != a[n + b].node ? -1 : fmax(worst, fabs((double)a[b].radius - a[n + b].radius));
    free(a);
    return worst;
}

/* Level 0's frustum ending at each SKEL node (-1: none); NULL when out of
 * memory. */
static int32_t* records_by_child(const meso_frusta_object* fine)
{
    int32_t* of_child = malloc(sizeof(int32_t) * (fine->node_count + (size_t)1));
    if (!of_child)
        return NULL;
    for (uint32_t i = 0; i < fine->node_count; ++i)
        of_child[i] = -1;
    for (uint32_t j = 0; j < fine->count; ++j)
        if (fine->recs[j].node[1] < fine->node_count)
            of_child[fine->recs[j].node[1]] = (int32_t)j;
    return of_child;
}

/* Level 0's frusta from c's node0 to node1, the one at node1 first, into
 * chain (room for all of level 0's); how many, 0 when they do not link up
 * (zero-length pieces). */
static uint32_t chain_of(const meso_frusta_object* fine, const int32_t* of_child, const meso_frustum_rec* c,
                         uint32_t* chain)
{
    uint32_t m = 0, y = c->node[1];
    while (y != c->node[0]) {
        const int32_t j = y < fine->node_count ? of_child[y] : -1;
        if (j < 0 || m == fine->count)
            return 0;
        chain[m++] = (uint32_t)j;
        y = fine->recs[j].node[0];
    }
    return m;
}

/* Where node n lies along c's axis, from 0 at centre 0 to 1 at centre 1,
 * clamped. */
static double along(const meso_frustum_rec* c, const float* node_pos, uint32_t n)
{
    double a[3], q[3], aa = 0, aq = 0;
    for (int i = 0; i < 3; ++i) {
        a[i] = (double)c->center[1][i] - c->center[0][i];
        q[i] = (double)node_pos[3 * (size_t)n + i] - c->center[0][i];
        aa += a[i] * a[i];
        aq += a[i] * q[i];
    }
    return aa > 0 ? fmin(1, fmax(0, aq / aa)) : 0;
}

/* The turn that takes f's u = 0 direction to c's u: f's u + it is c's u
 * of the same radial direction (projected ⟂ c's axis). */
static double u_shift(const meso_frustum_rec* f, const meso_frustum_rec* c)
{
    meso_frustum_frame ff, fc;
    meso_frustum_rec_frame(f, &ff);
    meso_frustum_rec_frame(c, &fc);
    double w[3];
    meso_frustum_frame_radial(&ff, 2 * M_PI * f->u_offset, w);
    return atan2(dot3(w, fc.x), dot3(w, fc.z)) / (2 * M_PI) - c->u_offset;
}

double mesoi_skeleton_level_distance(const meso_frusta_object* fine, const meso_frusta_object* coarse, double h_lo,
                                     double h_hi, int free_u)
{
    if (fine->node_count != coarse->node_count)
        return -1;
    double worst = ball_distance(fine, coarse);
    int32_t* of_child = records_by_child(fine);
    uint32_t* chain = malloc(sizeof(uint32_t) * (fine->count + (size_t)1));
    if (!of_child || !chain)
        worst = -1;
    for (uint32_t j = 0; worst >= 0 && j < fine->count; ++j)
        if (fine->recs[j].twist != 0)
            worst = -1;
    const int relief = h_hi > h_lo || h_hi > 0;
    for (uint32_t ci = 0; worst >= 0 && ci < coarse->count; ++ci) {
        const meso_frustum_rec* c = &coarse->recs[ci];
        const uint32_t m = chain_of(fine, of_child, c, chain);
        if (m == 0 || c->twist != 0) {
            worst = -1;
            break;
        }
        const meso_frustum_rec* first = &fine->recs[chain[m - 1]];
        const meso_frustum_rec* last = &fine->recs[chain[0]];
        const int caps = (first->flags & MESO_FSEG_CAP0) || (last->flags & MESO_FSEG_CAP1);
        const double hs[2] = {relief ? (caps ? 0 : h_lo) : 0, relief ? h_hi : 0};
        double S = c->v_offset;
        for (uint32_t k = m; k-- > 0;) {
            const meso_frustum_rec* f = &fine->recs[chain[k]];
            /* t continues along the chain (mod 1) and u means the same. */
            const double gap = S - f->v_offset;
            if (fabs(gap - round(gap)) > 1e-4 || f->u_scale != c->u_scale) {
                worst = -1;
                break;
            }
            for (int e = 0; e < 2; ++e) {
                double vc = (S + e * (double)f->v_scale - c->v_offset) / c->v_scale;
                if (free_u) /* v too may be any continuous map: where the node lies along the axis */
                    vc = (k == m - 1 && e == 0) ? 0 : (k == 0 && e == 1) ? 1 : along(c, fine->node_pos, f->node[e]);
                for (int q = 0; q < (relief ? 2 : 1); ++q)
                    worst = fmax(worst, end_distance(f, e, c, vc, hs[q], free_u ? u_shift(f, c) : 0));
            }
            S += f->v_scale;
        }
        /* Cap centres (the tip nodes). */
        for (int e = 0; worst >= 0 && e < 2; ++e) {
            const meso_frustum_rec* f = e ? last : first;
            const double a[3] = {f->center[e][0], f->center[e][1], f->center[e][2]};
            const double b[3] = {c->center[e][0], c->center[e][1], c->center[e][2]};
            if (f->flags & (e ? MESO_FSEG_CAP1 : MESO_FSEG_CAP0))
                worst = fmax(worst, dist3(a, b));
        }
    }
    free(of_child);
    free(chain);
    if (worst < 0)
        return -1;
    double big = 0;
    for (int i = 0; i < 3; ++i)
        big = fmax(big, fmax(fabs((double)coarse->bbox_min[i]), fabs((double)coarse->bbox_max[i])));
    return worst + 4 * FLT_EPSILON * big;
}

/* >>node choice ------------------------------------------------------------- */

typedef struct chooser {
    const meso_skeleton* sk;
    uint8_t* anchor;    /* per input node: always kept */
    uint32_t* path;     /* scratch: one chain, bottom to top */
    uint32_t* stack;    /* scratch: pieces to look at, 2 per */
} chooser;

/* Deviation of node j from the cone between nodes a and b. */
static double deviation(const meso_skeleton* sk, uint32_t j, uint32_t a, uint32_t b)
{
    const double *pa = sk->nodes[a].pos, *pb = sk->nodes[b].pos, *pj = sk->nodes[j].pos;
    double ab[3], aj[3], len2 = 0, dot = 0;
    for (int i = 0; i < 3; ++i) {
        ab[i] = pb[i] - pa[i];
        aj[i] = pj[i] - pa[i];
        len2 += ab[i] * ab[i];
        dot += ab[i] * aj[i];
    }
    const double l = len2 > 0 ? fmin(1, fmax(0, dot / len2)) : 0;
    const double q[3] = {pa[0] + l * ab[0], pa[1] + l * ab[1], pa[2] + l * ab[2]};
    const double r = sk->nodes[a].radius + l * (sk->nodes[b].radius - sk->nodes[a].radius);
    return dist3(pj, q) + fabs(sk->nodes[j].radius - r);
}

/* keep: the nodes kept at target tau, a subset of prev (which holds every
 * anchor). Returns how many are kept. */
static uint32_t choose(const chooser* ch, const uint8_t* prev, double tau, uint8_t* keep)
{
    const meso_skeleton* sk = ch->sk;
    const uint32_t n = sk->node_count;
    uint32_t kept = 0;
    for (uint32_t i = 0; i < n; ++i)
        keep[i] = ch->anchor[i];
    for (uint32_t x = 0; x < n; ++x) {
        if (!ch->anchor[x] || sk->nodes[x].parent < 0)
            continue;
        /* The chain from x up to the next anchor: path[0] = x, path[m] = it. */
        uint32_t m = 0;
        ch->path[m++] = x;
        int32_t y = sk->nodes[x].parent;
        while (y >= 0 && !ch->anchor[y]) {
            ch->path[m++] = (uint32_t)y;
            y = sk->nodes[y].parent;
        }
        if (y < 0) /* cannot happen: roots are anchors */
            continue;
        ch->path[m] = (uint32_t)y;
        uint32_t top = 0;
        ch->stack[top++] = 0;
        ch->stack[top++] = m;
        while (top) {
            const uint32_t hi = ch->stack[--top], lo = ch->stack[--top];
            double worst = 0, split_worst = -1;
            uint32_t split = 0;
            for (uint32_t k = lo + 1; k < hi; ++k) {
                const double d = deviation(sk, ch->path[k], ch->path[lo], ch->path[hi]);
                worst = fmax(worst, d);
                if (prev[ch->path[k]] && d > split_worst) {
                    split_worst = d;
                    split = k;
                }
            }
            if (worst > tau && split_worst >= 0) {
                keep[ch->path[split]] = 1;
                ch->stack[top++] = lo;
                ch->stack[top++] = split;
                ch->stack[top++] = split;
                ch->stack[top++] = hi;
            }
        }
    }
    for (uint32_t i = 0; i < n; ++i)
        kept += keep[i];
    return kept;
}

/* Keeps again (in keep, from prev) the nearest dropped node above and below
 * every node where `o` has a ball level 0 has not (ball: per input node;
 * input_of: level 0's SKEL index -> input node), along its chain (not past
 * an anchor). Returns how many were added. */
static uint32_t restore_joints(const meso_frusta_object* o, const uint8_t* ball, const uint32_t* input_of,
                               const chooser* ch, const uint8_t* prev, uint8_t* keep)
{
    const meso_skeleton* sk = ch->sk;
    uint32_t added = 0;
    for (uint32_t b = 0; b < o->ball_count; ++b) {
        const uint32_t x = input_of[o->balls[b].node];
        if (ball[x])
            continue;
        for (int dir = 0; dir < 2; ++dir) {
            int32_t y = (int32_t)x;
            for (;;) {
                const meso_skeleton_node* nd = &sk->nodes[y];
                y = dir ? (nd->child_count == 1 ? (int32_t)sk->children[nd->first_child] : -1) : nd->parent;
                if (y < 0 || ch->anchor[y])
                    break;
                if (prev[y] && !keep[y]) {
                    keep[y] = 1;
                    ++added;
                    break;
                }
            }
        }
    }
    return added;
}

/* >>building ---------------------------------------------------------------- */

/* The skeleton of the kept nodes (input order; a node's parent its nearest
 * kept ancestor). */
static meso_result sub_skeleton(const meso_skeleton* sk, const uint8_t* keep, uint32_t* index, meso_skeleton* out,
                                meso_error* err)
{
    memset(out, 0, sizeof *out);
    uint32_t n = 0, roots = 0;
    for (uint32_t i = 0; i < sk->node_count; ++i)
        index[i] = keep[i] ? n++ : UINT32_MAX;
    out->nodes = calloc(n ? n : 1, sizeof *out->nodes);
    out->children = calloc(n ? n : 1, sizeof *out->children);
    if (!out->nodes || !out->children) {
        meso_skeleton_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton levels: out of memory (%u nodes)", n);
    }
    for (uint32_t i = 0; i < sk->node_count; ++i) {
        if (!keep[i])
            continue;
        meso_skeleton_node* nd = &out->nodes[index[i]];
        *nd = sk->nodes[i];
        int32_t p = sk->nodes[i].parent;
        while (p >= 0 && !keep[p])
            p = sk->nodes[p].parent;
        nd->parent = p >= 0 ? (int32_t)index[p] : -1;
        nd->child_count = 0;
        roots += p < 0;
    }
    uint32_t* cnt = calloc(n ? n : 1, sizeof *cnt);
    if (!cnt) {
        meso_skeleton_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton levels: out of memory (%u nodes)", n);
    }
    out->node_count = n;
    meso_skeleton_group_children(out, cnt);
    free(cnt);
    out->root_count = roots;
    return MESO_OK;
}

/* The level of the kept nodes over level 0's SKEL (the header's "then").
 * MESO_ERR_UNSUPPORTED: the coarse skeleton makes no frusta object. */
static meso_result build_level(const mesoi_skeleton_levels_input* in, const uint8_t* keep, const uint8_t* ball,
                               uint32_t* index, meso_frusta_object* out, meso_error* err)
{
    const meso_frusta_object* fine = in->fine;
    meso_skeleton sub;
    meso_result r = sub_skeleton(in->sk, keep, index, &sub, err);
    if (r != MESO_OK)
        return r;
    meso_frustum_model m = {0};
    meso_frusta_object o = {0};
    meso_error ignored = {0};
    /* Level 0's balls stay balls, whatever the joint's new angle. */
    uint8_t* sub_ball = calloc(sub.node_count + (size_t)1, 1);
    if (!sub_ball) {
        meso_skeleton_free(&sub);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton levels: out of memory");
    }
    for (uint32_t i = 0; i < in->sk->node_count; ++i)
        if (index[i] != UINT32_MAX)
            sub_ball[index[i]] = ball[i];
    meso_frustum_options fo = *in->fo;
    fo.ball_nodes = sub_ball;
    if (meso_frustum_model_build(&sub, &fo, &m, &ignored) != MESO_OK ||
        meso_frusta_object_build(&sub, &m, in->rp, &o, &ignored) != MESO_OK)
        r = MESO_ERR_UNSUPPORTED;
    meso_frustum_model_free(&m);
    free(sub_ball);
    /* Coarse SKEL index -> coarse input -> input -> level 0's SKEL index. */
    uint32_t* to_fine = r == MESO_OK ? malloc(sizeof(uint32_t) * (o.node_count + (size_t)1)) : NULL;
    float* pos = r == MESO_OK ? malloc(3 * sizeof(float) * (fine->node_count + (size_t)1)) : NULL;
    uint8_t* skel = r == MESO_OK ? malloc((size_t)MESO_SKEL_RECORD_SIZE * (fine->node_count + (size_t)1)) : NULL;
    uint32_t* soi = r == MESO_OK ? malloc(sizeof(uint32_t) * (fine->node_count + (size_t)1)) : NULL;
    if (r == MESO_OK && (!to_fine || !pos || !skel || !soi))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton levels: out of memory");
    if (r == MESO_OK) {
        for (uint32_t i = 0; i < in->sk->node_count; ++i)
            if (index[i] != UINT32_MAX)
                to_fine[o.skel_of_input[index[i]]] = fine->skel_of_input[i];
        for (uint32_t f = 0; f < o.count; ++f) {
            meso_frustum_rec* rec = &o.recs[f];
            for (int e = 0; e < 2; ++e)
                rec->node[e] = to_fine[rec->node[e]];
            rec->skel_node = to_fine[rec->skel_node];
        }
        for (uint32_t b = 0; b < o.ball_count; ++b)
            o.balls[b].node = to_fine[o.balls[b].node];
        memcpy(pos, fine->node_pos, 3 * sizeof(float) * fine->node_count);
        memcpy(skel, fine->skel, (size_t)MESO_SKEL_RECORD_SIZE * fine->node_count);
        memcpy(soi, fine->skel_of_input, sizeof(uint32_t) * fine->node_count);
        free(o.node_pos);
        free(o.skel);
        free(o.skel_of_input);
        o.node_pos = pos;
        o.skel = skel;
        o.skel_of_input = soi;
        o.node_count = fine->node_count;
        pos = NULL;
        skel = NULL;
        soi = NULL;
        /* The same float positions as before: the pose is the one built. */
        if (meso_frusta_pose(o.recs, o.count, o.balls, o.ball_count, o.node_pos, o.node_count) != 0)
            r = MESO_ERR_UNSUPPORTED;
    }
    /* Relief coordinates: each frustum its chain's (the header). */
    int32_t* of_child = r == MESO_OK ? records_by_child(fine) : NULL;
    uint32_t* chain = r == MESO_OK ? malloc(sizeof(uint32_t) * (fine->count + (size_t)1)) : NULL;
    if (r == MESO_OK && (!of_child || !chain))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton levels: out of memory");
    for (uint32_t f = 0; r == MESO_OK && f < o.count; ++f) {
        meso_frustum_rec* rec = &o.recs[f];
        const uint32_t links = chain_of(fine, of_child, rec, chain);
        double vs = 0;
        for (uint32_t k = 0; k < links; ++k)
            vs += fine->recs[chain[k]].v_scale;
        if (links == 0)
            r = MESO_ERR_UNSUPPORTED; /* no chain of level 0 (zero-length pieces) */
        else {
            rec->v_offset = fine->recs[chain[links - 1]].v_offset;
            rec->v_scale = (float)vs;
        }
    }
    free(chain);
    free(of_child);
    free(to_fine);
    free(pos);
    free(skel);
    free(soi);
    meso_skeleton_free(&sub);
    if (r != MESO_OK) {
        meso_frusta_object_free(&o);
        return r;
    }
    *out = o;
    return MESO_OK;
}

meso_result mesoi_skeleton_levels_build(const mesoi_skeleton_levels_input* in, mesoi_skeleton_level** levels,
                                        uint32_t* count, const char** why, meso_error* err)
{
    *levels = NULL;
    *count = 0;
    *why = NULL;
    const meso_skeleton* sk = in->sk;
    const meso_frusta_object* fine = in->fine;
    const uint32_t n = sk->node_count;
    if (in->max_levels == 0)
        return MESO_OK;
    for (uint32_t j = 0; j < fine->count; ++j)
        if (fine->recs[j].twist != 0) {
            *why = "twisted frusta (u would turn differently along a merged chain)";
            return MESO_OK;
        }
    if (!(in->limit > 0)) {
        *why = "no error left below the stand-in's";
        return MESO_OK;
    }
    chooser ch = {.sk = sk};
    ch.anchor = calloc(n + (size_t)1, 1);
    ch.path = malloc(sizeof(uint32_t) * (n + (size_t)1));
    ch.stack = malloc(sizeof(uint32_t) * (4 * (size_t)n + 4));
    uint8_t* prev = malloc(n + (size_t)1);
    uint8_t* keep = malloc(n + (size_t)1);
    uint32_t* index = malloc(sizeof(uint32_t) * (n + (size_t)1));
    uint32_t* input_of = malloc(sizeof(uint32_t) * (fine->node_count + (size_t)1));
    uint8_t* ball = calloc(n + (size_t)1, 1); /* per input node: level 0 has a ball there */
    mesoi_skeleton_level* out = calloc(MESOI_SKELETON_LEVELS_MAX, sizeof *out);
    meso_result r = MESO_OK;
    if (!ch.anchor || !ch.path || !ch.stack || !prev || !keep || !index || !input_of || !ball || !out)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton levels: out of memory (%u nodes)", n);
    uint32_t kept = 0;
    if (r == MESO_OK) {
        for (uint32_t i = 0; i < n; ++i) {
            const meso_skeleton_node* nd = &sk->nodes[i];
            const int zero_up = nd->parent >= 0 && dist3(nd->pos, sk->nodes[nd->parent].pos) == 0;
            const int zero_down = nd->child_count == 1 && dist3(nd->pos, sk->nodes[sk->children[nd->first_child]].pos) == 0;
            ch.anchor[i] = nd->parent < 0 || nd->child_count != 1 || zero_up || zero_down;
            prev[i] = 1;
        }
        for (uint32_t i = 0; i < n; ++i)
            input_of[fine->skel_of_input[i]] = i;
        for (uint32_t b = 0; b < fine->ball_count; ++b)
            ball[input_of[fine->balls[b].node]] = ch.anchor[input_of[fine->balls[b].node]] = 1;
        kept = n;
    }
    uint32_t prev_frusta = fine->count, anchors = 0;
    for (uint32_t i = 0; r == MESO_OK && i < n; ++i)
        anchors += ch.anchor[i];
    double prev_distance = 0, tau = in->limit / 16;
    const uint32_t max_levels = in->max_levels < MESOI_SKELETON_LEVELS_MAX ? in->max_levels : MESOI_SKELETON_LEVELS_MAX;
    for (int t = 0; r == MESO_OK && t < TAU_TRIES && *count < max_levels; ++t, tau *= 2) {
        if (kept == anchors) {
            *why = "every chain between anchors is one frustum";
            break;
        }
        /* A joint the coarse frusta cannot fit (frustum_model.h) turns into
         * a ball level 0 does not have: its neighbours of level 0 are kept
         * again, so the joint is level 0's, and the level rebuilt. */
        meso_frusta_object o = {0};
        meso_result br = MESO_OK;
        uint32_t now = choose(&ch, prev, tau, keep);
        for (int retry = 0; retry < BALL_RETRIES; ++retry) {
            if (now == kept)
                break;
            br = build_level(in, keep, ball, index, &o, err);
            if (br != MESO_OK)
                break;
            const uint32_t added = restore_joints(&o, ball, input_of, &ch, prev, keep);
            if (!added)
                break;
            now += added;
            meso_frusta_object_free(&o);
        }
        if (now == kept) {
            meso_frusta_object_free(&o);
            continue;
        }
        if (br == MESO_ERR_UNSUPPORTED) {
            *why = "a coarser skeleton made no comparable frusta";
            continue;
        }
        if ((r = br) != MESO_OK)
            break;
        const double d = o.count ? mesoi_skeleton_level_distance(fine, &o, in->h_lo, in->h_hi, in->free_u) : -1;
        if (d < 0 || o.count * 4 > prev_frusta * 3) {
            *why = d < 0 ? "a coarser skeleton's balls differ from level 0's" : NULL;
            meso_frusta_object_free(&o);
            continue;
        }
        if (d >= in->limit) {
            *why = "the next skeleton reaches the stand-in's error";
            meso_frusta_object_free(&o);
            break;
        }
        mesoi_skeleton_level* l = &out[(*count)++];
        l->obj = o;
        l->distance = fmax(d, prev_distance);
        l->nodes = now;
        prev_distance = l->distance;
        prev_frusta = o.count;
        memcpy(prev, keep, n);
        kept = now;
        *why = NULL;
    }
    if (r == MESO_OK && *count < max_levels && !*why)
        *why = "no coarser skeleton drops a quarter of the frusta";
    free(ch.anchor);
    free(ch.path);
    free(ch.stack);
    free(prev);
    free(keep);
    free(index);
    free(input_of);
    free(ball);
    if (r != MESO_OK) {
        mesoi_skeleton_levels_free(out, *count);
        *count = 0;
        return r;
    }
    *levels = out;
    return MESO_OK;
}
