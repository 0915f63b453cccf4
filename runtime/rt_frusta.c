/*
 * rt_frusta.c — FRUSTA objects (FORMAT.md §7.2 kind 4): streaming one
 * object's FRUS, FSEG, SKEL, BALL and RELF chunks into GL and ray casting
 * its relief-mapped conical frusta and balls
 * (papers/relief-mapped-conical-frusta.md §2.5, §2.6, §3; the shaders are
 * runtime/shaders/frusta_*.glsl, the reference they are measured against
 * runtime/reference/frustum_reference.h).
 *
 * GL layout: one RGBA32F texture buffer, MESO_FRUSTA_TEXELS (16) texels per
 * primitive — frusta first, in FRUS order, then balls:
 *   0 c0.xyz, r0          4 frame_x.xyz, u_offset
 *   1 a.xyz (unit), h     5 twist, u_scale, v_offset, v_scale
 *   2 plane0.xyz, k       6 kind (0 frustum, 1 ball), cap0, cap1, 0
 *   3 plane1.xyz, D       7 bounding sphere centre.xyz, radius
 *   8..15 the 8 corners of the bounding geometry (xyz)
 * (a ball: texel 0 is centre, radius), plus the relief map as a 2D texture
 * (linear, repeat) and the colour map (COLR) as an SRGB8_ALPHA8 2D texture,
 * so fetches return linear colour; the shader interpolates both by hand.
 * Balls have no relief coordinates: with a colour map they take its mean
 * linear colour (FORMAT.md §7.2 kind 4), computed here in double precision
 * as the reference does. The 12 bounding triangles per primitive are generated
 * from gl_VertexID (36 vertices each), so an animation step uploads 256
 * bytes per primitive and nothing else.
 *
 * Bounding geometry (§2.6, computed on the CPU in double precision): the
 * square pyramid around the outer cone r(y) + D (half-width r(y) + D, the
 * paper's (±r, y, ±r) corner lines) cut by the two cutting planes: each of
 * its 4 edge lines is intersected with both planes, giving 8 corners and 12
 * triangles. That hexahedron is exactly the pyramid ∩ both half-spaces when
 * every edge line enters plane 0's half-space and leaves plane 1's, on the
 * cone's nappe, with the entry before the exit; at a sharp joint of an
 * animated pose (or a baked file that kept crossing caps) that fails, and
 * the bound falls back to the pyramid ∩ planes' exact bounding box in the
 * frustum's frame (the polytope's vertices enumerated: every 3 of its 8
 * planes), still 8 corners and 12 triangles. Everything is padded outwards
 * by 1e-5 of the frustum's size plus a few float ulps of its coordinates,
 * so rasterisation never clips a silhouette. Balls get their bounding cube.
 * The draw culls front faces: each primitive yields one fragment per pixel
 * whether the camera is outside or inside its bound (inside, the back faces
 * still surround the eye).
 */
#include "file_internal.h"
#include "frusta_pose.h"
#include "rt_internal.h"
#include "shaders_embedded.h"
#include "vec3d.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define TEXELS 16  /* per primitive (MESO_FRUSTA_TEXELS in the shaders) */
#define CORNER0 8  /* first corner texel */
#define FLOATS (4 * TEXELS)

typedef struct mesoi_frusta {
    uint32_t count, ball_count, node_count;
    meso_frustum_rec* recs;         /* the current pose (FRUS + FSEG) */
    meso_frustum_rec* scratch;      /* set_pose rebuilds here, then swaps */
    meso_frustum_ball_rec* balls;   /* current pose */
    meso_frustum_ball_rec* balls_scratch;
    float* rest;                    /* SKEL positions, 3 per node */
    int32_t* parents;               /* SKEL parents */
    float* texels;                  /* FLOATS per primitive per pose slot (host copy of the buffer) */
    uint32_t slots;                 /* pose slots (meso_rt_frusta_pose_slots), >= 1; slot 0 is recs/balls */
    meso_frustum_rec* slot_recs;    /* slots 1.., count each */
    meso_frustum_ball_rec* slot_balls; /* slots 1.., ball_count each */
    GLuint prim_buf, prim_tex, relief_tex, color_tex;
    int relief_w, relief_h;         /* 0 without RELF */
    int relief_w0;                  /* level 0's RELF width (this level's at level 0) */
    int color_w, color_h;           /* 0 without COLR */
    float ball_color[3];            /* COLR's mean linear colour (balls) */
    uint32_t boxed;                 /* frusta whose bound fell back to a box (last build) */
} mesoi_frusta;

enum { UNIT_PRIMS = 0, UNIT_RELIEF, UNIT_COLOR, UNIT_COUNT, UNIT_INSTANCES = UNIT_COUNT };

/* >>bounds ----------------------------------------------------------------- */

/* A frustum in double precision: origin c0, right-handed frame
 * (X, a, Z = X × a), outer radius R0 + k y (with the padding), planes. */
typedef struct geo {
    double c0[3], a[3], X[3], Z[3];
    double h, k, R0;
    double n[2][3]; /* unit outward normals */
    double e[2];    /* plane e: n[e]·(p − c0) ≤ e[e] (padded) */
} geo;

/* Corner j (0..3) of the pyramid's cross-section: signs along X and Z,
 * counter-clockwise seen from outside end 0 (from −a) in the right-handed
 * frame (X, a, Z); frusta_vert.glsl's triangle table relies on it. */
static const double corner_sx[4] = {1, -1, -1, 1}, corner_sz[4] = {1, 1, -1, -1};

static void local_to_world(const geo* g, double x, double y, double z, double out[3])
{
    for (int i = 0; i < 3; ++i)
        out[i] = g->c0[i] + x * g->X[i] + y * g->a[i] + z * g->Z[i];
}

/* The §2.6 hexahedron; 0 when the cut is not a proper one (see the top). */
static int pyramid_corners(const geo* g, double out[8][3])
{
    for (int j = 0; j < 4; ++j) {
        double s[3];
        for (int i = 0; i < 3; ++i)
            s[i] = corner_sx[j] * g->X[i] + corner_sz[j] * g->Z[i];
        double y[2];
        for (int e = 0; e < 2; ++e) {
            /* n·(y a + (R0 + k y) s) = e  →  y (n·a + k n·s) = e − R0 n·s */
            const double ns = dot3(g->n[e], s), den = dot3(g->n[e], g->a) + g->k * ns;
            if (e == 0 ? !(den < -1e-9) : !(den > 1e-9))
                return 0;
            y[e] = (g->e[e] - g->R0 * ns) / den;
        }
        if (!(y[0] < y[1]) || g->R0 + g->k * y[0] < 0 || g->R0 + g->k * y[1] < 0)
            return 0;
        for (int e = 0; e < 2; ++e) {
            const double R = g->R0 + g->k * y[e];
            local_to_world(g, corner_sx[j] * R, y[e], corner_sz[j] * R, out[4 * e + j]);
        }
    }
    return 1;
}

/* Solve the 3×3 system rows·x = rhs (Cramer); 0 when near singular. */
static int solve3(const double m[3][3], const double rhs[3], double x[3])
{
    double c0[3], c1[3], c2[3];
    for (int i = 0; i < 3; ++i) {
        c0[i] = m[i][0];
        c1[i] = m[i][1];
        c2[i] = m[i][2];
    }
    double t[3], u[3], v[3];
    cross3(c1, c2, t);
    const double det = dot3(c0, t);
    if (fabs(det) < 1e-12)
        return 0;
    cross3(rhs, c2, u);
    cross3(c0, c1, v);
    x[0] = dot3(rhs, t) / det; /* det[b c1 c2] */
    x[1] = dot3(c0, u) / det;  /* det[c0 b c2] */
    x[2] = dot3(rhs, v) / det; /* det[c0 c1 b] */
    return 1;
}

/* The box fallback: the exact bounding box, in the frustum's frame, of
 * pyramid ∩ both half-spaces (∩ a slab of ±4 sizes along the axis, in case
 * the planes leave it open), from its vertices. 0 when it is empty. */
static int box_corners(const geo* g, double out[8][3])
{
    double rows[8][3], rhs[8];
    const double size = g->h + fabs(g->R0) + fabs(g->k) * g->h + 1e-30;
    /* local coordinates (x, y, z): |x|, |z| ≤ R0 + k y */
    static const double side[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}}; /* ±x, ±z − k y ≤ R0 */
    for (int j = 0; j < 4; ++j) {
        rows[j][0] = side[j][0];
        rows[j][1] = -g->k;
        rows[j][2] = side[j][1];
        rhs[j] = g->R0;
    }
    for (int e = 0; e < 2; ++e) {
        rows[4 + e][0] = dot3(g->n[e], g->X);
        rows[4 + e][1] = dot3(g->n[e], g->a);
        rows[4 + e][2] = dot3(g->n[e], g->Z);
        rhs[4 + e] = g->e[e];
    }
    rows[6][0] = 0, rows[6][1] = 1, rows[6][2] = 0, rhs[6] = 0.5 * g->h + 4 * size;
    rows[7][0] = 0, rows[7][1] = -1, rows[7][2] = 0, rhs[7] = -(0.5 * g->h - 4 * size);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 8; ++i)
        for (int j = i + 1; j < 8; ++j)
            for (int l = j + 1; l < 8; ++l) {
                const double m[3][3] = {{rows[i][0], rows[i][1], rows[i][2]},
                                        {rows[j][0], rows[j][1], rows[j][2]},
                                        {rows[l][0], rows[l][1], rows[l][2]}};
                const double b[3] = {rhs[i], rhs[j], rhs[l]};
                double x[3];
                if (!solve3(m, b, x))
                    continue;
                int ok = 1;
                for (int c = 0; c < 8 && ok; ++c)
                    ok = dot3(rows[c], x) <= rhs[c] + 1e-9 * size;
                for (int c = 0; ok && c < 3; ++c) {
                    lo[c] = fmin(lo[c], x[c]);
                    hi[c] = fmax(hi[c], x[c]);
                }
            }
    if (!(lo[0] <= hi[0]))
        return 0;
    for (int e = 0; e < 2; ++e)
        for (int j = 0; j < 4; ++j)
            local_to_world(g, corner_sx[j] > 0 ? hi[0] : lo[0], e ? hi[1] : lo[1], corner_sz[j] > 0 ? hi[2] : lo[2],
                           out[4 * e + j]);
    return 1;
}

/* Padding of a bound: 1e-5 of the primitive's size plus 8 float ulps of its
 * largest coordinate (the corners are stored as floats). */
static double padding(const double c[3], double size)
{
    const double m = fmax(fabs(c[0]), fmax(fabs(c[1]), fabs(c[2]))) + size;
    return 1e-5 * size + 8.0 * m * 1.1920928955078125e-07;
}

/* Texels 7..15 (bounding sphere, corners) from 8 world corners. */
static void put_corners(double corners[8][3], float* t)
{
    double c[3] = {0, 0, 0}, r2 = 0;
    for (int k = 0; k < 8; ++k)
        for (int i = 0; i < 3; ++i)
            c[i] += corners[k][i] / 8;
    for (int k = 0; k < 8; ++k) {
        double d[3] = {corners[k][0] - c[0], corners[k][1] - c[1], corners[k][2] - c[2]};
        r2 = fmax(r2, dot3(d, d));
        for (int i = 0; i < 3; ++i)
            t[4 * (CORNER0 + k) + i] = (float)corners[k][i];
        t[4 * (CORNER0 + k) + 3] = 0.0f;
    }
    for (int i = 0; i < 3; ++i)
        t[28 + i] = (float)c[i];
    t[31] = (float)(sqrt(r2) * (1 + 1e-6));
}

/* All 16 texels of frustum r; `relief`: the object has a RELF map (else
 * depths are ignored, also by the bound). Returns 1 when the bound is the
 * box fallback. */
static int frustum_texels(const meso_frustum_rec* r, int relief, float* t)
{
    geo g;
    double c1[3];
    for (int i = 0; i < 3; ++i) {
        g.c0[i] = r->center[0][i];
        c1[i] = r->center[1][i];
        g.a[i] = c1[i] - g.c0[i];
    }
    g.h = normalize3(g.a);
    const double r0 = r->radius[0], r1 = r->radius[1];
    g.k = g.h > 0 ? (r1 - r0) / g.h : 0.0;
    const double D = relief ? r->relief_depth : 0.0;
    memset(t, 0, sizeof(float) * FLOATS);
    for (int i = 0; i < 3; ++i) {
        t[i] = (float)g.c0[i];
        t[4 + i] = (float)g.a[i];
        t[8 + i] = r->plane[0][i];
        t[12 + i] = r->plane[1][i];
        t[16 + i] = r->frame_x[i];
    }
    t[3] = (float)r0;
    t[7] = (float)g.h;
    t[11] = (float)g.k;
    t[15] = r->relief_depth;
    t[19] = r->u_offset;
    t[20] = r->twist;
    t[21] = r->u_scale;
    t[22] = r->v_offset;
    t[23] = r->v_scale;
    t[24] = 0.0f;
    t[25] = (r->flags & MESO_FSEG_CAP0) ? 1.0f : 0.0f;
    t[26] = (r->flags & MESO_FSEG_CAP1) ? 1.0f : 0.0f;

    const double size = g.h + r0 + r1 + 2 * D;
    const double pad = padding(g.c0, size);
    double fx[3] = {r->frame_x[0], r->frame_x[1], r->frame_x[2]};
    const double m = dot3(fx, g.a);
    for (int i = 0; i < 3; ++i)
        g.X[i] = fx[i] - m * g.a[i];
    if (normalize3(g.X) < 1e-6)
        any_perp3(g.a, g.X);
    cross3(g.X, g.a, g.Z);
    g.R0 = r0 + D + pad;
    for (int e = 0; e < 2; ++e) {
        for (int i = 0; i < 3; ++i)
            g.n[e][i] = r->plane[e][i];
        normalize3(g.n[e]);
        g.e[e] = (e ? g.h * dot3(g.n[1], g.a) : 0.0) + pad;
    }
    double corners[8][3];
    int boxed = 0;
    if (!(g.h > 0) || !pyramid_corners(&g, corners)) {
        boxed = 1;
        if (!(g.h > 0) || !box_corners(&g, corners))
            for (int k = 0; k < 8; ++k) /* empty: no area, no fragments */
                memcpy(corners[k], g.c0, sizeof(g.c0));
    }
    put_corners(corners, t);
    return boxed;
}

static void ball_texels(const meso_frustum_ball_rec* b, float* t)
{
    memset(t, 0, sizeof(float) * FLOATS);
    double c[3] = {b->center[0], b->center[1], b->center[2]};
    for (int i = 0; i < 3; ++i)
        t[i] = b->center[i];
    t[3] = b->radius;
    t[24] = 1.0f;
    const double R = b->radius + padding(c, b->radius);
    double corners[8][3];
    for (int e = 0; e < 2; ++e)
        for (int j = 0; j < 4; ++j) {
            corners[4 * e + j][0] = c[0] + corner_sx[j] * R;
            corners[4 * e + j][1] = c[1] + (e ? R : -R);
            corners[4 * e + j][2] = c[2] + corner_sz[j] * R;
        }
    put_corners(corners, t);
}

/* Every primitive's texels from one pose's records; returns the boxed count. */
static uint32_t build_pose_texels(const mesoi_frusta* s, const meso_frustum_rec* recs,
                                  const meso_frustum_ball_rec* balls, float* texels)
{
    uint32_t boxed = 0;
    for (uint32_t i = 0; i < s->count; ++i)
        boxed += (uint32_t)frustum_texels(&recs[i], s->relief_w > 0, texels + (size_t)FLOATS * i);
    for (uint32_t b = 0; b < s->ball_count; ++b)
        ball_texels(&balls[b], texels + (size_t)FLOATS * (s->count + b));
    return boxed;
}

/* Slot 0's texels from the current records. */
static void build_texels(mesoi_frusta* s)
{
    s->boxed = build_pose_texels(s, s->recs, s->balls, s->texels);
}

/* Bytes of one slot's texels. */
static size_t slot_bytes(const mesoi_frusta* s)
{
    return sizeof(float) * FLOATS * ((size_t)s->count + s->ball_count);
}

/* Object bounds: the corners' box (slot 0). */
static void corner_bounds(const mesoi_frusta* s, float lo[3], float hi[3])
{
    const uint32_t n = s->count + s->ball_count;
    for (int k = 0; k < 3; ++k) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (uint32_t p = 0; p < n; ++p)
        for (int c = 0; c < 8; ++c)
            for (int k = 0; k < 3; ++k) {
                const float v = s->texels[(size_t)FLOATS * p + 4 * (CORNER0 + c) + (size_t)k];
                lo[k] = fminf(lo[k], v);
                hi[k] = fmaxf(hi[k], v);
            }
}

/* >>loading ---------------------------------------------------------------- */

static void frusta_free(meso_rt* rt, mesoi_frusta* s)
{
    if (!s)
        return;
    mesoi_gl* gl = &rt->gl;
    GLuint tex[3] = {s->prim_tex, s->relief_tex, s->color_tex};
    gl->DeleteTextures(3, tex);
    gl->DeleteBuffers(1, &s->prim_buf);
    mesoi_rt_free(rt, s->recs);
    mesoi_rt_free(rt, s->scratch);
    mesoi_rt_free(rt, s->balls);
    mesoi_rt_free(rt, s->balls_scratch);
    mesoi_rt_free(rt, s->rest);
    mesoi_rt_free(rt, s->parents);
    mesoi_rt_free(rt, s->texels);
    mesoi_rt_free(rt, s->slot_recs);
    mesoi_rt_free(rt, s->slot_balls);
    mesoi_rt_free(rt, s);
}

void mesoi_frusta_release(meso_rt* rt, mesoi_object* o)
{
    frusta_free(rt, o->frusta);
    o->frusta = NULL;
}

/* What FORMAT.md 1.0 leaves to the reader: counts that agree across
 * chunks, node indices inside SKEL, frusta of non-zero length. */
static meso_result check_records(meso_rt* rt, uint32_t id, const mesoi_frusta* s)
{
    for (uint32_t i = 0; i < s->count; ++i) {
        const meso_frustum_rec* r = &s->recs[i];
        double d2 = 0;
        for (int k = 0; k < 3; ++k)
            d2 += ((double)r->center[1][k] - r->center[0][k]) * ((double)r->center[1][k] - r->center[0][k]);
        const char* why = NULL;
        if (r->node[0] >= s->node_count || r->node[1] >= s->node_count)
            why = "a node index outside SKEL";
        else if (!(d2 > 0))
            why = "zero length (center0 = center1)";
        if (why) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "frusta %u: frustum %u has %s", id, i, why);
            return MESO_ERR_CORRUPT;
        }
    }
    for (uint32_t b = 0; b < s->ball_count; ++b)
        if (s->balls[b].node >= s->node_count) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "frusta %u: ball %u has a node outside SKEL",
                      id, b);
            return MESO_ERR_CORRUPT;
        }
    return MESO_OK;
}

/* Reads FRUS + FSEG, SKEL and BALL into the host copies. */
static meso_result read_records(meso_rt* rt, meso_file* f, uint32_t id, const int32_t ci[4], mesoi_frusta* s)
{
    void *frus = NULL, *fseg = NULL, *skel = NULL, *ball = NULL;
    size_t nf = 0, ns = 0, nk = 0, nb = 0;
    meso_result r = mesoi_read_whole(rt, f, ci[0], &frus, &nf);
    if (r == MESO_OK)
        r = mesoi_read_whole(rt, f, ci[1], &fseg, &ns);
    if (r == MESO_OK)
        r = mesoi_read_whole(rt, f, ci[2], &skel, &nk);
    if (r == MESO_OK && ci[3] >= 0)
        r = mesoi_read_whole(rt, f, ci[3], &ball, &nb);
    if (r == MESO_OK) {
        s->count = (uint32_t)(nf / MESO_FRUS_RECORD_SIZE);
        s->node_count = (uint32_t)(nk / MESO_SKEL_RECORD_SIZE);
        s->ball_count = (uint32_t)(nb / MESO_BALL_RECORD_SIZE);
        if (s->count == 0 || ns / MESO_FSEG_RECORD_SIZE != s->count || s->node_count == 0) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "frusta %u: FRUS has %u records, FSEG %zu, SKEL %u nodes; FORMAT.md §7.2 wants FRUS = FSEG > 0 "
                      "and a skeleton",
                      id, s->count, ns / MESO_FSEG_RECORD_SIZE, s->node_count);
            r = MESO_ERR_CORRUPT;
        }
    }
    if (r == MESO_OK) {
        const size_t rb = sizeof(meso_frustum_rec) * s->count, bb = sizeof(meso_frustum_ball_rec) * s->ball_count;
        s->recs = mesoi_rt_alloc(rt, rb);
        s->scratch = mesoi_rt_alloc(rt, rb);
        s->balls = mesoi_rt_alloc(rt, bb);
        s->balls_scratch = mesoi_rt_alloc(rt, bb);
        s->rest = mesoi_rt_alloc(rt, sizeof(float) * 3 * s->node_count);
        s->parents = mesoi_rt_alloc(rt, sizeof(int32_t) * s->node_count);
        s->texels = mesoi_rt_alloc(rt, sizeof(float) * FLOATS * ((size_t)s->count + s->ball_count));
        if (!s->recs || !s->scratch || !s->balls || !s->balls_scratch || !s->rest || !s->parents || !s->texels)
            r = MESO_ERR_OUT_OF_MEMORY;
    }
    if (r == MESO_OK) {
        for (uint32_t i = 0; i < s->count; ++i)
            meso_frustum_rec_decode((const uint8_t*)frus + (size_t)MESO_FRUS_RECORD_SIZE * i,
                                    (const uint8_t*)fseg + (size_t)MESO_FSEG_RECORD_SIZE * i, &s->recs[i]);
        for (uint32_t b = 0; b < s->ball_count; ++b)
            meso_frustum_ball_decode((const uint8_t*)ball + (size_t)MESO_BALL_RECORD_SIZE * b, &s->balls[b]);
        for (uint32_t n = 0; n < s->node_count; ++n) {
            const uint8_t* rec = (const uint8_t*)skel + (size_t)MESO_SKEL_RECORD_SIZE * n;
            for (int k = 0; k < 3; ++k)
                s->rest[3 * (size_t)n + k] = mesoi_ldf32(rec + MESO_SKEL_OFF_POSITION + 4 * k);
            s->parents[n] = (int32_t)mesoi_ld32(rec + MESO_SKEL_OFF_PARENT);
        }
        r = check_records(rt, id, s);
    }
    mesoi_rt_free(rt, frus);
    mesoi_rt_free(rt, fseg);
    mesoi_rt_free(rt, skel);
    mesoi_rt_free(rt, ball);
    return r;
}

static double srgb_to_linear(double x)
{
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

/* COLR (U8 x 4, W x H x 1, sRGB) as an SRGB8_ALPHA8 2D texture with its mip
 * levels (the shader fetches texels of the footprint's levels), and its mean
 * linear colour. */
static meso_result upload_color(meso_rt* rt, meso_file* f, uint32_t id, int32_t ci, mesoi_frusta* s)
{
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    mesoi_gl* gl = &rt->gl;
    GLint limit = 0;
    gl->GetIntegerv(GL_MAX_TEXTURE_SIZE, &limit);
    if (c->dtype != MESO_DTYPE_U8 || c->components != 4 || c->dims[2] != 1 || c->dims[0] == 0 || c->dims[1] == 0 ||
        c->dims[0] > (uint32_t)limit || c->dims[1] > (uint32_t)limit) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "frusta %u: COLR is dtype %u x %u, %ux%ux%u; FORMAT.md §7.2 wants U8 x 4, W x H x 1 (this context: "
                  "at most %d a side)",
                  id, c->dtype, c->components, c->dims[0], c->dims[1], c->dims[2], (int)limit);
        return MESO_ERR_UNSUPPORTED;
    }
    void* data = NULL;
    size_t size = 0;
    meso_result r = mesoi_read_whole(rt, f, ci, &data, &size);
    if (r != MESO_OK)
        return r;
    const uint8_t* px = data;
    const size_t n = (size_t)c->dims[0] * c->dims[1];
    double lut[256], sum[3] = {0, 0, 0};
    for (int i = 0; i < 256; ++i)
        lut[i] = srgb_to_linear(i / 255.0);
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k)
            sum[k] += lut[px[4 * i + (size_t)k]];
    for (int k = 0; k < 3; ++k)
        s->ball_color[k] = (float)(sum[k] / (double)n);
    r = mesoi_upload_srgba8(rt, c->dims, 0, data, &s->color_tex); /* with its mip levels (shading's footprint); logs */
    mesoi_rt_free(rt, data);
    if (r != MESO_OK)
        return r;
    s->color_w = (int)c->dims[0];
    s->color_h = (int)c->dims[1];
    return MESO_OK;
}

meso_result mesoi_frusta_load(meso_rt* rt, meso_file* f, uint32_t id, mesoi_object* o)
{
    static const uint32_t types[4] = {MESO_CHUNK_FRUS, MESO_CHUNK_FSEG, MESO_CHUNK_SKEL, MESO_CHUNK_BALL};
    static const char* const names[3] = {"FRUS", "FSEG", "SKEL"};
    int32_t ci[4];
    for (int k = 0; k < 4; ++k)
        ci[k] = mesoi_find_chunk(rt, f, types[k], id);
    for (int k = 0; k < 3; ++k)
        if (ci[k] < 0) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND, "frusta %u lacks its %s chunk", id, names[k]);
            return MESO_ERR_NOT_FOUND;
        }
    const int32_t ri = mesoi_find_chunk(rt, f, MESO_CHUNK_RELF, id);
    const int32_t coli = mesoi_find_chunk(rt, f, MESO_CHUNK_COLR, id);
    mesoi_frusta* s = mesoi_rt_alloc(rt, sizeof(*s));
    if (!s)
        return MESO_ERR_OUT_OF_MEMORY;
    memset(s, 0, sizeof(*s));
    s->slots = 1;
    meso_result r = read_records(rt, f, id, ci, s);
    const uint64_t prims = (uint64_t)s->count + s->ball_count;
    GLint max_texels = 0;
    rt->gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    if (r == MESO_OK && (prims * TEXELS > (uint64_t)max_texels || prims * 36 > (uint64_t)INT32_MAX)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "frusta %u: %u frusta and %u balls exceed this context's texture buffer size (%d texels)", id,
                  s->count, s->ball_count, max_texels);
        r = MESO_ERR_UNSUPPORTED;
    }
    if (r == MESO_OK && ri >= 0) {
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ri);
        if (c->components != 1 || (c->dtype != MESO_DTYPE_U8 && c->dtype != MESO_DTYPE_U16) || c->dims[2] != 1) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "frusta %u: RELF is dtype %u x %u, %u deep; FORMAT.md §7.2 wants U8 or U16 x 1, W x H x 1", id,
                      c->dtype, c->components, c->dims[2]);
            r = MESO_ERR_UNSUPPORTED;
        } else {
            s->relief_w = (int)c->dims[0];
            s->relief_h = (int)c->dims[1];
            const int32_t r0 = meso_file_find(f, MESO_CHUNK_RELF, id, 0);
            s->relief_w0 = r0 >= 0 ? (int)meso_file_chunk(f, (uint32_t)r0)->dims[0] : s->relief_w;
        }
    }
    const GLint prev_tex_buffer = mesoi_upload_begin(rt);
    if (r == MESO_OK && ri >= 0)
        r = mesoi_upload_texture(rt, f, ri, 0, 0, &s->relief_tex); /* the march fetches level 0, shading its footprint's */
    if (r == MESO_OK && coli >= 0)
        r = upload_color(rt, f, id, coli, s);
    if (r == MESO_OK) {
        build_texels(s);
        s->prim_tex = mesoi_texture_buffer(rt, GL_RGBA32F, s->texels, sizeof(float) * FLOATS * (size_t)prims,
                                           &s->prim_buf);
        if (!s->prim_tex)
            r = MESO_ERR_GL;
    }
    char what[48];
    snprintf(what, sizeof(what), "uploading frusta %u", id);
    r = mesoi_upload_end(rt, prev_tex_buffer, r, what);
    if (r != MESO_OK) {
        frusta_free(rt, s);
        return r;
    }
    o->frusta = s;
    return MESO_OK;
}

/* >>animation -------------------------------------------------------------- */

static mesoi_frusta* live_frusta(const meso_rt* rt, meso_rt_object h, mesoi_object** obj)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (obj)
        *obj = o;
    return o && o->kind == MESO_OBJECT_FRUSTA ? o->frusta : NULL;
}

/* Checks a pose call; logs under `who`. */
static mesoi_frusta* pose_target(meso_rt* rt, meso_rt_object h, uint32_t slot, const float* node_positions,
                                 uint32_t node_count, const char* who, mesoi_object** o)
{
    mesoi_frusta* s = live_frusta(rt, h, o);
    if (!s || !node_positions || node_count != s->node_count || slot >= s->slots) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "%s: not a live frusta object, no positions, node_count %u differs, or slot %u of %u", who,
                      node_count, slot, s ? s->slots : 0);
        return NULL;
    }
    return s;
}

/* Rebuild a pose into the scratch copies (the pose carries frames over
 * from the previous pose), so a failure leaves the pose intact. */
static meso_result pose_scratch(meso_rt* rt, mesoi_frusta* s, const meso_frustum_rec* recs,
                                const meso_frustum_ball_rec* balls, const float* node_positions, const char* who)
{
    memcpy(s->scratch, recs, sizeof(meso_frustum_rec) * s->count);
    memcpy(s->balls_scratch, balls, sizeof(meso_frustum_ball_rec) * s->ball_count);
    if (meso_frusta_pose(s->scratch, s->count, s->balls_scratch, s->ball_count, node_positions, s->node_count) != 0) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "%s: the pose collapses a frustum to zero length",
                  who);
        return MESO_ERR_INVALID_ARG;
    }
    return MESO_OK;
}

meso_result mesoi_frusta_pose_host(meso_rt* rt, meso_rt_object h, const float* node_positions, uint32_t node_count)
{
    mesoi_object* o = NULL;
    mesoi_frusta* s = pose_target(rt, h, 0, node_positions, node_count, "meso_rt_frusta_set_pose", &o);
    if (!s)
        return MESO_ERR_INVALID_ARG;
    const meso_result r = pose_scratch(rt, s, s->recs, s->balls, node_positions, "meso_rt_frusta_set_pose");
    if (r != MESO_OK)
        return r;
    meso_frustum_rec* t = s->recs;
    s->recs = s->scratch;
    s->scratch = t;
    meso_frustum_ball_rec* tb = s->balls;
    s->balls = s->balls_scratch;
    s->balls_scratch = tb;
    build_texels(s);
    corner_bounds(s, o->bbox_min, o->bbox_max);
    return MESO_OK;
}

meso_result meso_rt_frusta_set_pose(meso_rt* rt, meso_rt_object h, const float* node_positions, uint32_t node_count)
{
    meso_result r = mesoi_frusta_pose_host(rt, h, node_positions, node_count);
    if (r != MESO_OK)
        return r;
    const mesoi_frusta* s = live_frusta(rt, h, NULL);
    return mesoi_buffer_update(rt, s->prim_buf, s->texels, slot_bytes(s), "meso_rt_frusta_set_pose");
}

meso_result meso_rt_frusta_set_pose_slot(meso_rt* rt, meso_rt_object h, uint32_t slot, const float* node_positions,
                                         uint32_t node_count)
{
    if (slot == 0)
        return meso_rt_frusta_set_pose(rt, h, node_positions, node_count);
    mesoi_object* o = NULL;
    mesoi_frusta* s = pose_target(rt, h, slot, node_positions, node_count, "meso_rt_frusta_set_pose_slot", &o);
    if (!s)
        return MESO_ERR_INVALID_ARG;
    meso_frustum_rec* recs = s->slot_recs + (size_t)(slot - 1) * s->count;
    meso_frustum_ball_rec* balls = s->slot_balls + (size_t)(slot - 1) * s->ball_count;
    const meso_result r = pose_scratch(rt, s, recs, balls, node_positions, "meso_rt_frusta_set_pose_slot");
    if (r != MESO_OK)
        return r;
    memcpy(recs, s->scratch, sizeof(meso_frustum_rec) * s->count);
    memcpy(balls, s->balls_scratch, sizeof(meso_frustum_ball_rec) * s->ball_count);
    float* texels = s->texels + (size_t)slot * FLOATS * ((size_t)s->count + s->ball_count);
    build_pose_texels(s, recs, balls, texels);
    const GLint prev = mesoi_upload_begin(rt);
    rt->gl.BindBuffer(GL_TEXTURE_BUFFER, s->prim_buf);
    rt->gl.BufferSubData(GL_TEXTURE_BUFFER, (GLintptr)(slot * slot_bytes(s)), (GLsizeiptr)slot_bytes(s), texels);
    return mesoi_upload_end(rt, prev, MESO_OK, "meso_rt_frusta_set_pose_slot");
}

meso_result meso_rt_frusta_pose_slots(meso_rt* rt, meso_rt_object h, uint32_t slots)
{
    mesoi_frusta* s = live_frusta(rt, h, NULL);
    GLint max_texels = 0;
    if (s)
        rt->gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    const uint64_t prims = s ? (uint64_t)s->count + s->ball_count : 0;
    if (!s || slots == 0 || prims * TEXELS * slots > (uint64_t)max_texels ||
        prims * slots > (1u << 24) /* the slot's first primitive is a float in the instance data */) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_frusta_pose_slots: not a live frusta object, or %u slots of %llu primitives do not fit "
                      "(1..%llu)",
                      slots, (unsigned long long)prims,
                      prims ? (unsigned long long)((uint64_t)max_texels / (prims * TEXELS)) : 0ull);
        return MESO_ERR_INVALID_ARG;
    }
    if (slots == s->slots)
        return MESO_OK;
    const size_t one = slot_bytes(s);
    float* texels = mesoi_rt_alloc(rt, one * slots);
    meso_frustum_rec* recs = slots > 1 ? mesoi_rt_alloc(rt, sizeof(meso_frustum_rec) * s->count * (slots - 1)) : NULL;
    meso_frustum_ball_rec* balls =
        slots > 1 ? mesoi_rt_alloc(rt, sizeof(meso_frustum_ball_rec) * (s->ball_count ? s->ball_count : 1) *
                                           (slots - 1))
                  : NULL;
    if (!texels || (slots > 1 && (!recs || !balls))) {
        mesoi_rt_free(rt, texels);
        mesoi_rt_free(rt, recs);
        mesoi_rt_free(rt, balls);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    const uint32_t kept = slots < s->slots ? slots : s->slots;
    memcpy(texels, s->texels, one * kept);
    for (uint32_t k = 1; k < slots; ++k) { /* kept slots as they are, new ones a copy of slot 0 */
        const int old = k < kept;
        memcpy(recs + (size_t)(k - 1) * s->count, old ? s->slot_recs + (size_t)(k - 1) * s->count : s->recs,
               sizeof(meso_frustum_rec) * s->count);
        memcpy(balls + (size_t)(k - 1) * s->ball_count,
               old ? s->slot_balls + (size_t)(k - 1) * s->ball_count : s->balls,
               sizeof(meso_frustum_ball_rec) * s->ball_count);
        if (!old)
            memcpy((char*)texels + one * k, s->texels, one);
    }
    const GLint prev = mesoi_upload_begin(rt);
    GLuint buf = 0;
    const GLuint tex = mesoi_texture_buffer(rt, GL_RGBA32F, texels, one * slots, &buf);
    const meso_result r = mesoi_upload_end(rt, prev, tex ? MESO_OK : MESO_ERR_GL, "meso_rt_frusta_pose_slots");
    if (r != MESO_OK) {
        if (tex) {
            rt->gl.DeleteTextures(1, &tex);
            rt->gl.DeleteBuffers(1, &buf);
        }
        mesoi_rt_free(rt, texels);
        mesoi_rt_free(rt, recs);
        mesoi_rt_free(rt, balls);
        return r;
    }
    rt->gl.DeleteTextures(1, &s->prim_tex);
    rt->gl.DeleteBuffers(1, &s->prim_buf);
    s->prim_tex = tex;
    s->prim_buf = buf;
    mesoi_rt_free(rt, s->texels);
    mesoi_rt_free(rt, s->slot_recs);
    mesoi_rt_free(rt, s->slot_balls);
    s->texels = texels;
    s->slot_recs = recs;
    s->slot_balls = balls;
    s->slots = slots;
    return MESO_OK;
}

meso_result meso_rt_frusta_info(const meso_rt* rt, meso_rt_object h, uint32_t* frustum_count, uint32_t* node_count)
{
    mesoi_object* o = NULL;
    const mesoi_frusta* s = live_frusta(rt, h, &o);
    if (!o)
        return MESO_ERR_INVALID_ARG;
    if (frustum_count)
        *frustum_count = s ? s->count : 0;
    if (node_count)
        *node_count = s ? s->node_count : 0;
    return MESO_OK;
}

meso_result meso_rt_frusta_rest_pose(const meso_rt* rt, meso_rt_object h, float* positions, int32_t* parents,
                                     uint32_t node_count)
{
    const mesoi_frusta* s = live_frusta(rt, h, NULL);
    if (!s || !positions || node_count != s->node_count)
        return MESO_ERR_INVALID_ARG;
    memcpy(positions, s->rest, sizeof(float) * 3 * (size_t)node_count);
    if (parents)
        memcpy(parents, s->parents, sizeof(int32_t) * (size_t)node_count);
    return MESO_OK;
}

/* >>drawing ---------------------------------------------------------------- */

/* With or without the work counters (atomics cost time). */
static const mesoi_program* frusta_program(meso_rt* rt, int stats, meso_rt_pass pass)
{
    mesoi_program* p = &rt->frusta_programs[pass][stats];
    if (p->id)
        return p;
    char head[512];
    snprintf(head, sizeof(head), "%s#define MESO_FRUSTA_TEXELS %d\n#define MESO_FRUSTA_CORNER0 %d\n",
             mesoi_glsl_prelude(rt, stats), TEXELS, CORNER0);
    const char* vs[5] = {head, MESOI_GLSL_VERTEX_STAGE, mesoi_glsl_instance, mesoi_glsl_frusta_common,
                         mesoi_glsl_frusta_vert};
    const char* pre[3] = {mesoi_glsl_instance, mesoi_glsl_frusta_common, mesoi_glsl_raycast_common};
    static const char* const samplers[UNIT_COUNT + 1] = {"u_prims", "u_relief", "u_color", "u_instances"};
    static const char* const names[MESO_PASS_COUNT] = {"frusta", "frusta depth", "frusta gbuffer"};
    const mesoi_program_src src = {.vs = vs, .vs_count = 5, .vs_file = "frusta_vert.glsl", .pre = pre,
                                   .pre_count = 3, .frag = mesoi_glsl_frusta_frag, .frag_file = "frusta_frag.glsl",
                                   .name = names[pass], .samplers = samplers, .sampler_count = UNIT_COUNT + 1};
    return mesoi_program_build(rt, p, pass, &src);
}

meso_result mesoi_frusta_prepare(meso_rt* rt, int stats, meso_rt_pass pass)
{
    return frusta_program(rt, stats, pass) ? MESO_OK : MESO_ERR_GL;
}

void mesoi_frusta_programs_destroy(meso_rt* rt)
{
    for (int pass = 0; pass < MESO_PASS_COUNT; ++pass)
        for (int st = 0; st < 2; ++st)
            mesoi_program_delete(rt, &rt->frusta_programs[pass][st]);
}

/* An instance's pose slot: the first primitive of its texels (texel 9.x). */
static meso_result instance_slot(meso_rt* rt, mesoi_object* o, const mesoi_draw* ds, const meso_rt_draw_desc* d,
                                 const meso_rt_instance* in, uint32_t index, float* texels, void* user)
{
    (void)ds, (void)d, (void)user;
    const mesoi_frusta* s = o->frusta;
    if (in->pose_slot >= s->slots) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw_instanced: instance %u: pose slot %u, the object has %u (meso_rt_frusta_pose_slots)",
                  index, in->pose_slot, s->slots);
        return MESO_ERR_INVALID_ARG;
    }
    texels[36] = (float)((uint64_t)in->pose_slot * (s->count + s->ball_count)); /* < 2^24: exact */
    return MESO_OK;
}

meso_result mesoi_frusta_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                              uint32_t count)
{
    const mesoi_frusta* s = o->frusta;
    const meso_rt_frusta_draw* k = &d->frusta;
    mesoi_draw ds;
    meso_result r = mesoi_draw_prepare(rt, d, 1, inst != NULL, &ds);
    if (r != MESO_OK)
        return r;
    const mesoi_program* prog = frusta_program(rt, ds.stats, ds.pass);
    if (!prog)
        return MESO_ERR_GL;
    mesoi_gl* gl = &rt->gl;
    static const GLenum targets[UNIT_COUNT + 1] = {GL_TEXTURE_BUFFER, GL_TEXTURE_2D, GL_TEXTURE_2D,
                                                   GL_TEXTURE_BUFFER};
    GLuint bind[UNIT_COUNT + 1] = {s->prim_tex, s->relief_tex, s->color_tex, 0};
    if (inst && (r = mesoi_instances_upload(rt, &ds, o, d, inst, NULL, count, 1, instance_slot, NULL,
                                            &bind[UNIT_INSTANCES])) != MESO_OK)
        return r;
    mesoi_draw_begin(rt, &ds, prog, 1, inst ? UNIT_COUNT + 1 : UNIT_COUNT, targets, bind);
    const GLint size[2] = {s->relief_w, s->relief_h};
    gl->Uniform2iv(prog->loc[MESOI_U_relief_size], 1, size);
    const GLint csize[2] = {s->color_w, s->color_h};
    gl->Uniform2iv(prog->loc[MESOI_U_color_size], 1, csize);
    gl->Uniform3fv(prog->loc[MESOI_U_ball_color], 1, s->ball_color);
    /* A native level's coarser relief map takes as many samples per texel
     * as level 0's (meso_rt_frusta_draw.relief_steps). */
    int steps = k->relief_steps > 0 ? k->relief_steps : 64;
    if (s->relief_w > 0 && s->relief_w0 > s->relief_w) {
        const int64_t scaled = ((int64_t)steps * s->relief_w + s->relief_w0 - 1) / s->relief_w0;
        steps = scaled > 8 ? (int)scaled : (steps < 8 ? steps : 8);
    }
    gl->Uniform1i(prog->loc[MESOI_U_relief_steps], steps);
    gl->Uniform1i(prog->loc[MESOI_U_bisect_steps], k->bisection_steps > 0 ? k->bisection_steps : 4);
    const GLsizei vertices = 36 * (GLsizei)(s->count + s->ball_count);
    if (inst)
        gl->DrawArraysInstanced(GL_TRIANGLES, 0, vertices, (GLsizei)count);
    else
        gl->DrawArrays(GL_TRIANGLES, 0, vertices);
    return mesoi_draw_end(rt, &ds, d->stats, "frusta");
}
