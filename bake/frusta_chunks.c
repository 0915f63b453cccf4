/*
 * frusta_chunks.c — frustum model → frusta object records
 * (frusta_chunks.h states the decisions).
 */
#include "frusta_chunks.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso_bake.h"
#include "meso_layout.h"

#define TAU 6.283185307179586
#define BBOX_SAMPLES 256

void meso_frusta_object_free(meso_frusta_object* o)
{
    if (!o)
        return;
    free(o->recs);
    free(o->balls);
    free(o->skel);
    free(o->node_pos);
    free(o->skel_of_input);
    memset(o, 0, sizeof(*o));
}

static void put_f32(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    for (int i = 0; i < 4; ++i)
        p[i] = (uint8_t)(u >> (8 * i));
}

static void put_u32(uint8_t* p, uint32_t u)
{
    for (int i = 0; i < 4; ++i)
        p[i] = (uint8_t)(u >> (8 * i));
}

/* SKEL in topological order: breadth-first from the roots, in input order. */
static void skel_order(const meso_skeleton* sk, meso_frusta_object* o)
{
    uint32_t n = sk->node_count, head = 0, tail = 0;
    uint32_t* queue = o->skel_of_input; /* reused: first the order, then inverted */
    uint32_t* order = malloc((size_t)n * sizeof(*order));
    if (!order)
        return;
    for (uint32_t i = 0; i < n; ++i)
        if (sk->nodes[i].parent < 0)
            order[tail++] = i;
    while (head < tail) {
        const meso_skeleton_node* nd = &sk->nodes[order[head++]];
        for (uint32_t c = 0; c < nd->child_count; ++c)
            order[tail++] = sk->children[nd->first_child + c];
    }
    for (uint32_t k = 0; k < n; ++k)
        queue[order[k]] = k;
    for (uint32_t k = 0; k < n; ++k) {
        const meso_skeleton_node* nd = &sk->nodes[order[k]];
        uint8_t* r = o->skel + (size_t)k * MESO_SKEL_RECORD_SIZE;
        for (int i = 0; i < 3; ++i) {
            o->node_pos[3 * (size_t)k + i] = (float)nd->pos[i];
            put_f32(r + MESO_SKEL_OFF_POSITION + 4 * i, (float)nd->pos[i]);
        }
        put_f32(r + MESO_SKEL_OFF_RADIUS, (float)nd->radius);
        put_u32(r + MESO_SKEL_OFF_PARENT, nd->parent < 0 ? 0xFFFFFFFFu : queue[nd->parent]);
        put_u32(r + MESO_SKEL_OFF_NODE_TYPE, nd->child_count == 0 ? 2u : nd->child_count >= 2 ? 1u : 0u);
    }
    free(order);
}

static void grow(float lo[3], float hi[3], const double p[3], double pad)
{
    for (int i = 0; i < 3; ++i) {
        lo[i] = fminf(lo[i], (float)(p[i] - pad));
        hi[i] = fmaxf(hi[i], (float)(p[i] + pad));
    }
}

/* Both cut curves of the outer cone of record r (frusta_chunks.h). */
static void bbox_frustum(const meso_frustum_rec* r, float lo[3], float hi[3])
{
    meso_frustum_frame f;
    meso_frustum_rec_frame(r, &f);
    const double depth = r->relief_depth, h = f.h;
    double rmax = fmax(r->radius[0], r->radius[1]) + depth;
    double pad = 0;
    for (int j = 0; j < BBOX_SAMPLES; ++j) {
        double w[3], p[3];
        meso_frustum_frame_radial(&f, TAU * j / BBOX_SAMPLES, w);
        for (int e = 0; e < 2; ++e) {
            double y = meso_frustum_rec_cut(r, &f, depth, w, e, p);
            pad = fmax(pad, fabs(y) * 1e-6);
            grow(lo, hi, p, 0);
        }
    }
    /* Chord sagitta of the sampled curves, and float rounding. */
    pad += rmax * (1 - cos(TAU / BBOX_SAMPLES / 2)) / cos(TAU / BBOX_SAMPLES / 2) + 1e-6 * (rmax + h);
    for (int i = 0; i < 3; ++i) {
        lo[i] -= (float)pad;
        hi[i] += (float)pad;
    }
}

meso_result meso_frusta_object_build(const meso_skeleton* sk, const meso_frustum_model* m,
    const meso_frusta_relief_params* relief, meso_frusta_object* out, meso_error* err)
{
    if (!sk || !m || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "frusta: NULL argument");
    memset(out, 0, sizeof(*out));
    meso_frusta_object o = {0};
    uint32_t ns = m->segment_count, nn = sk->node_count;
    double depth = relief ? fmax(0, relief->depth) : 0;
    double u_repeat = relief && relief->u_repeat > 0 ? relief->u_repeat : 1;
    o.count = ns;
    o.ball_count = m->ball_count;
    o.node_count = nn;
    o.recs = calloc(ns ? ns : 1, sizeof(*o.recs));
    o.balls = calloc(m->ball_count ? m->ball_count : 1, sizeof(*o.balls));
    o.skel = calloc(nn ? nn : 1, MESO_SKEL_RECORD_SIZE);
    o.node_pos = calloc(3 * (size_t)(nn ? nn : 1), sizeof(float));
    o.skel_of_input = calloc(nn ? nn : 1, sizeof(uint32_t));
    uint32_t* file_of = calloc(ns ? ns : 1, sizeof(uint32_t));
    if (!o.recs || !o.balls || !o.skel || !o.node_pos || !o.skel_of_input || !file_of || !m->order) {
        free(file_of);
        meso_frusta_object_free(&o);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frusta: out of memory (%u segments)", ns);
    }
    skel_order(sk, &o);
    for (uint32_t f = 0; f < ns; ++f)
        file_of[m->order[f]] = f;
    for (uint32_t f = 0; f < ns; ++f) {
        const meso_frustum_segment* s = &m->segments[m->order[f]];
        meso_frustum_rec* r = &o.recs[f];
        uint32_t kind[2];
        for (int e = 0; e < 2; ++e) {
            r->node[e] = o.skel_of_input[s->node[e]];
            r->node_radius[e] = (float)(e ? s->r1 : s->r0);
            kind[e] = s->end_kind[e] == MESO_FRUSTUM_END_JOINT  ? MESO_FSEG_END_JOINT
                      : s->end_kind[e] == MESO_FRUSTUM_END_BALL ? MESO_FSEG_END_BALL
                                                                : MESO_FSEG_END_TIP;
            r->other[e] = -1;
            if (kind[e] == MESO_FSEG_END_JOINT) {
                const meso_frustum_joint* j = &m->joints[s->joint[e]];
                uint32_t other = j->segment[0] == m->order[f] ? j->segment[1] : j->segment[0];
                r->other[e] = (int32_t)file_of[other];
            }
        }
        r->flags = kind[0] << MESO_FSEG_KIND0_SHIFT | kind[1] << MESO_FSEG_KIND1_SHIFT |
                   (s->cap[0] ? MESO_FSEG_CAP0 : 0u) | (s->cap[1] ? MESO_FSEG_CAP1 : 0u);
        r->align_from = s->align_from < 0 ? -1 : (int32_t)file_of[s->align_from];
        if (s->align_from >= 0)
            r->flags |= (s->align_end ? MESO_FSEG_ALIGN_END : 0u) | (s->align_from_end ? MESO_FSEG_ALIGN_FROM_END : 0u);
        for (int i = 0; i < 3; ++i)
            r->frame_x[i] = (float)s->frame_x[i];
        r->u_offset = (float)s->u_offset;
        r->twist = (float)s->twist;
        r->skel_node = r->node[1];
        double len = sqrt((s->c1[0] - s->c0[0]) * (s->c1[0] - s->c0[0]) + (s->c1[1] - s->c0[1]) * (s->c1[1] - s->c0[1]) +
                          (s->c1[2] - s->c0[2]) * (s->c1[2] - s->c0[2]));
        double rbar = 0.5 * (s->r0 + s->r1) + 0.5 * depth;
        double v_scale = rbar > 0 ? u_repeat * len / (TAU * rbar) : 1.0;
        double v_offset = 0;
        if (r->align_from >= 0) {
            const meso_frustum_rec* fr = &o.recs[r->align_from];
            double t = s->align_from_end ? (double)fr->v_offset + fr->v_scale : (double)fr->v_offset;
            v_offset = s->align_end ? t - v_scale : t;
            v_offset -= floor(v_offset);
        }
        r->u_scale = (float)u_repeat;
        r->v_scale = (float)v_scale;
        r->v_offset = (float)v_offset;
        r->relief_depth = (float)depth;
    }
    for (uint32_t b = 0; b < m->ball_count; ++b) {
        o.balls[b].node = o.skel_of_input[m->balls[b].node];
        o.balls[b].radius = (float)m->balls[b].radius;
    }
    free(file_of);
    if (meso_frusta_pose(o.recs, o.count, o.balls, o.ball_count, o.node_pos, o.node_count) != 0) {
        meso_frusta_object_free(&o);
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 3149u, "frusta: the pose rebuild refused the model");
    }
    for (int i = 0; i < 3; ++i) {
        o.bbox_min[i] = FLT_MAX;
        o.bbox_max[i] = -FLT_MAX;
    }
    for (uint32_t f = 0; f < ns; ++f)
        bbox_frustum(&o.recs[f], o.bbox_min, o.bbox_max);
    for (uint32_t b = 0; b < o.ball_count; ++b) {
        double c[3] = {o.balls[b].center[0], o.balls[b].center[1], o.balls[b].center[2]};
        grow(o.bbox_min, o.bbox_max, c, o.balls[b].radius * (1 + 1e-6));
    }
    *out = o;
    return MESO_OK;
}

meso_result meso_frusta_object_encode(const meso_frusta_object* o, uint8_t** frus, uint8_t** fseg, uint8_t** ball,
    meso_error* err)
{
    *frus = calloc(o->count ? o->count : 1, MESO_FRUS_RECORD_SIZE);
    *fseg = calloc(o->count ? o->count : 1, MESO_FSEG_RECORD_SIZE);
    *ball = calloc(o->ball_count ? o->ball_count : 1, MESO_BALL_RECORD_SIZE);
    if (!*frus || !*fseg || !*ball) {
        free(*frus);
        free(*fseg);
        free(*ball);
        *frus = *fseg = *ball = NULL;
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frusta: out of memory");
    }
    for (uint32_t f = 0; f < o->count; ++f)
        meso_frustum_rec_encode(&o->recs[f], *frus + (size_t)f * MESO_FRUS_RECORD_SIZE,
            *fseg + (size_t)f * MESO_FSEG_RECORD_SIZE);
    for (uint32_t b = 0; b < o->ball_count; ++b)
        meso_frustum_ball_encode(&o->balls[b], *ball + (size_t)b * MESO_BALL_RECORD_SIZE);
    return MESO_OK;
}
