/*
 * frusta_pose.c — the frusta records' codecs and the pose rebuild
 * (frusta_pose.h states the rules).
 */
#include "frusta_pose.h"

#include <math.h>
#include <string.h>

#include "file_internal.h"
#include "vec3d.h"

#define TAU 6.283185307179586

/* >>codecs ----------------------------------------------------------------- */

static void ld3(const uint8_t* p, float v[3])
{
    for (int i = 0; i < 3; ++i)
        v[i] = mesoi_ldf32(p + 4 * i);
}

static void st3(uint8_t* p, const float v[3])
{
    for (int i = 0; i < 3; ++i)
        mesoi_stf32(p + 4 * i, v[i]);
}

void meso_frustum_rec_decode(const uint8_t frus[MESO_FRUS_RECORD_SIZE], const uint8_t fseg[MESO_FSEG_RECORD_SIZE],
    meso_frustum_rec* out)
{
    memset(out, 0, sizeof(*out));
    ld3(frus + MESO_FRUS_OFF_CENTER0, out->center[0]);
    ld3(frus + MESO_FRUS_OFF_CENTER1, out->center[1]);
    out->radius[0] = mesoi_ldf32(frus + MESO_FRUS_OFF_RADIUS0);
    out->radius[1] = mesoi_ldf32(frus + MESO_FRUS_OFF_RADIUS1);
    ld3(frus + MESO_FRUS_OFF_PLANE0, out->plane[0]);
    ld3(frus + MESO_FRUS_OFF_PLANE1, out->plane[1]);
    out->skel_node = mesoi_ld32(frus + MESO_FRUS_OFF_SKEL_NODE);
    out->node[0] = mesoi_ld32(fseg + MESO_FSEG_OFF_NODE0);
    out->node[1] = mesoi_ld32(fseg + MESO_FSEG_OFF_NODE1);
    out->node_radius[0] = mesoi_ldf32(fseg + MESO_FSEG_OFF_NODE_RADIUS0);
    out->node_radius[1] = mesoi_ldf32(fseg + MESO_FSEG_OFF_NODE_RADIUS1);
    out->other[0] = (int32_t)mesoi_ld32(fseg + MESO_FSEG_OFF_OTHER0);
    out->other[1] = (int32_t)mesoi_ld32(fseg + MESO_FSEG_OFF_OTHER1);
    out->flags = mesoi_ld32(fseg + MESO_FSEG_OFF_FLAGS);
    out->align_from = (int32_t)mesoi_ld32(fseg + MESO_FSEG_OFF_ALIGN_FROM);
    ld3(fseg + MESO_FSEG_OFF_FRAME_X, out->frame_x);
    out->u_offset = mesoi_ldf32(fseg + MESO_FSEG_OFF_U_OFFSET);
    out->twist = mesoi_ldf32(fseg + MESO_FSEG_OFF_TWIST);
    out->u_scale = mesoi_ldf32(fseg + MESO_FSEG_OFF_U_SCALE);
    out->v_offset = mesoi_ldf32(fseg + MESO_FSEG_OFF_V_OFFSET);
    out->v_scale = mesoi_ldf32(fseg + MESO_FSEG_OFF_V_SCALE);
    out->relief_depth = mesoi_ldf32(fseg + MESO_FSEG_OFF_RELIEF_DEPTH);
}

void meso_frustum_rec_encode(const meso_frustum_rec* in, uint8_t frus[MESO_FRUS_RECORD_SIZE],
    uint8_t fseg[MESO_FSEG_RECORD_SIZE])
{
    memset(frus, 0, MESO_FRUS_RECORD_SIZE);
    memset(fseg, 0, MESO_FSEG_RECORD_SIZE);
    st3(frus + MESO_FRUS_OFF_CENTER0, in->center[0]);
    st3(frus + MESO_FRUS_OFF_CENTER1, in->center[1]);
    mesoi_stf32(frus + MESO_FRUS_OFF_RADIUS0, in->radius[0]);
    mesoi_stf32(frus + MESO_FRUS_OFF_RADIUS1, in->radius[1]);
    st3(frus + MESO_FRUS_OFF_PLANE0, in->plane[0]);
    st3(frus + MESO_FRUS_OFF_PLANE1, in->plane[1]);
    mesoi_st32(frus + MESO_FRUS_OFF_SKEL_NODE, in->skel_node);
    mesoi_st32(fseg + MESO_FSEG_OFF_NODE0, in->node[0]);
    mesoi_st32(fseg + MESO_FSEG_OFF_NODE1, in->node[1]);
    mesoi_stf32(fseg + MESO_FSEG_OFF_NODE_RADIUS0, in->node_radius[0]);
    mesoi_stf32(fseg + MESO_FSEG_OFF_NODE_RADIUS1, in->node_radius[1]);
    mesoi_st32(fseg + MESO_FSEG_OFF_OTHER0, (uint32_t)in->other[0]);
    mesoi_st32(fseg + MESO_FSEG_OFF_OTHER1, (uint32_t)in->other[1]);
    mesoi_st32(fseg + MESO_FSEG_OFF_FLAGS, in->flags);
    mesoi_st32(fseg + MESO_FSEG_OFF_ALIGN_FROM, (uint32_t)in->align_from);
    st3(fseg + MESO_FSEG_OFF_FRAME_X, in->frame_x);
    mesoi_stf32(fseg + MESO_FSEG_OFF_U_OFFSET, in->u_offset);
    mesoi_stf32(fseg + MESO_FSEG_OFF_TWIST, in->twist);
    mesoi_stf32(fseg + MESO_FSEG_OFF_U_SCALE, in->u_scale);
    mesoi_stf32(fseg + MESO_FSEG_OFF_V_OFFSET, in->v_offset);
    mesoi_stf32(fseg + MESO_FSEG_OFF_V_SCALE, in->v_scale);
    mesoi_stf32(fseg + MESO_FSEG_OFF_RELIEF_DEPTH, in->relief_depth);
}

void meso_frustum_ball_decode(const uint8_t rec[MESO_BALL_RECORD_SIZE], meso_frustum_ball_rec* out)
{
    ld3(rec + MESO_BALL_OFF_CENTER, out->center);
    out->radius = mesoi_ldf32(rec + MESO_BALL_OFF_RADIUS);
    out->node = mesoi_ld32(rec + MESO_BALL_OFF_NODE);
}

void meso_frustum_ball_encode(const meso_frustum_ball_rec* in, uint8_t rec[MESO_BALL_RECORD_SIZE])
{
    memset(rec, 0, MESO_BALL_RECORD_SIZE);
    st3(rec + MESO_BALL_OFF_CENTER, in->center);
    mesoi_stf32(rec + MESO_BALL_OFF_RADIUS, in->radius);
    mesoi_st32(rec + MESO_BALL_OFF_NODE, in->node);
}

/* >>frames ----------------------------------------------------------------- */

void meso_frustum_rec_frame(const meso_frustum_rec* r, meso_frustum_frame* f)
{
    for (int i = 0; i < 3; ++i) {
        f->c0[i] = r->center[0][i];
        f->a[i] = (double)r->center[1][i] - r->center[0][i];
        f->x[i] = r->frame_x[i];
    }
    f->h = normalize3(f->a);
    f->k = f->h > 0 ? ((double)r->radius[1] - r->radius[0]) / f->h : 0.0;
    cross3(f->x, f->a, f->z);
}

void meso_frustum_frame_radial(const meso_frustum_frame* f, double phi, double w[3])
{
    for (int i = 0; i < 3; ++i)
        w[i] = sin(phi) * f->x[i] + cos(phi) * f->z[i];
}

double meso_frustum_rec_cut(const meso_frustum_rec* r, const meso_frustum_frame* f, double delta, const double w[3],
    int e, double p[3])
{
    const double n[3] = {r->plane[e][0], r->plane[e][1], r->plane[e][2]};
    const double ce[3] = {r->center[e][0], r->center[e][1], r->center[e][2]};
    const double r0 = r->radius[0] + delta;
    const double den = dot3(n, f->a) + f->k * dot3(n, w);
    /* plane e passes through center[e]: n·(p − c_e) = 0 */
    double rel = 0;
    for (int i = 0; i < 3; ++i)
        rel += n[i] * (ce[i] - f->c0[i]);
    const double y = fabs(den) > 1e-300 ? (rel - r0 * dot3(n, w)) / den : (e ? f->h : 0.0);
    if (p)
        for (int i = 0; i < 3; ++i)
            p[i] = f->c0[i] + y * f->a[i] + (r0 + f->k * y) * w[i];
    return y;
}

/* >>joint plane ------------------------------------------------------------ */

/* Intersection of the lines p + α u and q + β v lying in one plane (2-D
 * solve in the basis e1, e2 of that plane). Returns 0 when parallel. */
static int line_line(const double p[3], const double u[3], const double q[3], const double v[3], const double e1[3],
    const double e2[3], double out[3])
{
    double pu[2] = {dot3(u, e1), dot3(u, e2)}, pv[2] = {dot3(v, e1), dot3(v, e2)};
    double dq[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    double r[2] = {dot3(dq, e1), dot3(dq, e2)};
    double det = pu[0] * (-pv[1]) - pu[1] * (-pv[0]);
    double lu = sqrt(pu[0] * pu[0] + pu[1] * pu[1]), lv = sqrt(pv[0] * pv[0] + pv[1] * pv[1]);
    if (!(lu > 0 && lv > 0) || fabs(det) < 1e-9 * lu * lv)
        return 0;
    double alpha = (r[0] * (-pv[1]) - r[1] * (-pv[0])) / det;
    for (int i = 0; i < 3; ++i)
        out[i] = p[i] + alpha * u[i];
    return 1;
}

void meso_frustum_joint_plane(const double O1[3], double rO1, const double J1[3], double rJ1, const double J2[3],
    double rJ2, const double O2[3], double rO2, double n[3], double* d, double A[3], double B[3])
{
    double M1[3], M2[3], Nm[3], p1[3], p2[3];
    for (int i = 0; i < 3; ++i) {
        M1[i] = J1[i] - O1[i];
        M2[i] = O2[i] - J2[i];
    }
    normalize3(M1);
    normalize3(M2);
    cross3(M1, M2, Nm);
    if (normalize3(Nm) < 1e-9)
        any_perp3(M1, Nm);
    cross3(M1, Nm, p1);
    cross3(M2, Nm, p2);
    double e2d[3];
    cross3(Nm, M1, e2d); /* in-plane basis (M1, e2d) */
    double pts[2][3];
    for (int side = 0; side < 2; ++side) {
        double sg = side == 0 ? -1.0 : 1.0;
        double L1[3], L2[3], L3[3], L4[3], u[3], v[3];
        for (int i = 0; i < 3; ++i) {
            L1[i] = O1[i] + sg * rO1 * p1[i];
            L2[i] = J1[i] + sg * rJ1 * p1[i];
            L3[i] = J2[i] + sg * rJ2 * p2[i];
            L4[i] = O2[i] + sg * rO2 * p2[i];
            u[i] = L2[i] - L1[i];
            v[i] = L4[i] - L3[i];
        }
        if (!line_line(L1, u, L3, v, M1, e2d, pts[side]))
            for (int i = 0; i < 3; ++i)
                pts[side][i] = 0.5 * (L2[i] + L3[i]);
    }
    memcpy(A, pts[0], sizeof(pts[0]));
    memcpy(B, pts[1], sizeof(pts[1]));
    double ab[3] = {pts[0][0] - pts[1][0], pts[0][1] - pts[1][1], pts[0][2] - pts[1][2]};
    double scale = sqrt(dot3(ab, ab));
    double bis[3] = {M1[0] + M2[0], M1[1] + M2[1], M1[2] + M2[2]};
    cross3(ab, Nm, n);
    if (scale < 1e-12 * (rO1 + rO2 + 1e-300) || normalize3(n) == 0) {
        memcpy(n, bis, sizeof(bis));
        if (normalize3(n) == 0)
            memcpy(n, M1, sizeof(M1));
        *d = dot3(n, J1);
    } else {
        if (dot3(n, bis) < 0)
            for (int i = 0; i < 3; ++i)
                n[i] = -n[i];
        *d = dot3(n, pts[0]);
    }
}

/* >>pose ------------------------------------------------------------------- */

typedef struct seg_geo {
    double p[2][3]; /* node positions at the c0 and c1 ends */
    double r[2];    /* node radii */
    double a[3];    /* unit axis p0 -> p1 */
    double h;
} seg_geo;

static int seg_load(const meso_frustum_rec* r, const float* node_pos, uint32_t node_count, seg_geo* g)
{
    for (int e = 0; e < 2; ++e) {
        if (r->node[e] >= node_count)
            return -1;
        for (int i = 0; i < 3; ++i)
            g->p[e][i] = node_pos[3 * (size_t)r->node[e] + i];
        g->r[e] = r->node_radius[e];
    }
    for (int i = 0; i < 3; ++i)
        g->a[i] = g->p[1][i] - g->p[0][i];
    g->h = normalize3(g->a);
    return g->h > 0 ? 0 : -1;
}

/* The outward plane of end e of frustum `self` (n·p = d). */
static int end_plane(const meso_frustum_rec* recs, uint32_t count, uint32_t self, int e, const float* node_pos,
    uint32_t node_count, const seg_geo* g, double n[3], double* d)
{
    const meso_frustum_rec* r = &recs[self];
    if (meso_frustum_rec_end_kind(r, e) != MESO_FSEG_END_JOINT) {
        double sg = e == 0 ? -1.0 : 1.0;
        for (int i = 0; i < 3; ++i)
            n[i] = sg * g->a[i];
        *d = dot3(n, g->p[e]);
        return 0;
    }
    int32_t oi = r->other[e];
    if (oi < 0 || (uint32_t)oi >= count)
        return -1;
    const meso_frustum_rec* o = &recs[oi];
    seg_geo go;
    if (seg_load(o, node_pos, node_count, &go))
        return -1;
    /* The other frustum's end at this joint: the one whose `other` is self. */
    int oe = (o->other[1] == (int32_t)self && meso_frustum_rec_end_kind(o, 1) == MESO_FSEG_END_JOINT) ? 1 : 0;
    /* Segment 1 arrives (its c1 end is at the joint) when exactly one does;
     * else the lower index. */
    int self_first = (e == 1 && oe == 0) || (e == oe && self < (uint32_t)oi);
    const seg_geo* g1 = self_first ? g : &go;
    const seg_geo* g2 = self_first ? &go : g;
    int e1 = self_first ? e : oe, e2 = self_first ? oe : e;
    double A[3], B[3];
    meso_frustum_joint_plane(g1->p[1 - e1], g1->r[1 - e1], g1->p[e1], g1->r[e1], g2->p[e2], g2->r[e2], g2->p[1 - e2],
        g2->r[1 - e2], n, d, A, B);
    if (!self_first) {
        for (int i = 0; i < 3; ++i)
            n[i] = -n[i];
        *d = -*d;
    }
    return 0;
}

/* y where the generator of the frustum (c0, r0, axis a, slope k) with unit
 * radial direction w meets the plane n·p = d; 0 when parallel. */
static int generator_plane(const double c0[3], double r0, const double a[3], double k, const double w[3],
    const double n[3], double d, double* y)
{
    double nw = dot3(n, w);
    double den = dot3(n, a) + k * nw;
    if (fabs(den) < 1e-300)
        return 0;
    *y = (d - dot3(n, c0) - r0 * nw) / den;
    return 1;
}

static void minimal_rotation(const double from[3], const double to[3], double v[3])
{
    double c = dot3(from, to);
    double ax[3];
    cross3(from, to, ax);
    double s = normalize3(ax);
    if (s < 1e-12)
        return;
    /* Rodrigues. */
    double kv[3], kd = dot3(ax, v);
    cross3(ax, v, kv);
    for (int i = 0; i < 3; ++i)
        v[i] = v[i] * c + kv[i] * s + ax[i] * kd * (1 - c);
}

int meso_frusta_pose(meso_frustum_rec* recs, uint32_t count, meso_frustum_ball_rec* balls, uint32_t ball_count,
    const float* node_pos, uint32_t node_count)
{
    for (uint32_t b = 0; b < ball_count; ++b) {
        if (balls[b].node >= node_count)
            return -1;
        for (int i = 0; i < 3; ++i)
            balls[b].center[i] = node_pos[3 * (size_t)balls[b].node + i];
    }
    for (uint32_t s = 0; s < count; ++s) {
        meso_frustum_rec* r = &recs[s];
        seg_geo g;
        if (seg_load(r, node_pos, node_count, &g))
            return -1;
        double k = (g.r[1] - g.r[0]) / g.h;
        double n[2][3], d[2];
        for (int e = 0; e < 2; ++e)
            if (end_plane(recs, count, s, e, node_pos, node_count, &g, n[e], &d[e]))
                return -1;
        /* Previous axis (for the minimal rotation of root frames). */
        double prev[3] = {(double)r->center[1][0] - r->center[0][0], (double)r->center[1][1] - r->center[0][1],
            (double)r->center[1][2] - r->center[0][2]};
        int had_prev = normalize3(prev) > 0;
        for (int e = 0; e < 2; ++e) {
            double na = dot3(n[e], g.a);
            double y = fabs(na) > 1e-300 ? (d[e] - dot3(n[e], g.p[0])) / na : (e ? g.h : 0.0);
            for (int i = 0; i < 3; ++i) {
                r->center[e][i] = (float)(g.p[0][i] + y * g.a[i]);
                r->plane[e][i] = (float)n[e][i];
            }
            r->radius[e] = (float)fmax(0.0, g.r[0] + k * y);
        }
        /* Frames (§2.3). */
        double x[3];
        if (r->align_from < 0) {
            for (int i = 0; i < 3; ++i)
                x[i] = r->frame_x[i];
            if (had_prev)
                minimal_rotation(prev, g.a, x);
        } else {
            if ((uint32_t)r->align_from >= s)
                return -1;
            const meso_frustum_rec* f = &recs[r->align_from];
            for (int i = 0; i < 3; ++i)
                x[i] = f->frame_x[i];
        }
        double m = dot3(x, g.a);
        for (int i = 0; i < 3; ++i)
            x[i] -= m * g.a[i];
        if (normalize3(x) < 1e-6)
            any_perp3(g.a, x);
        for (int i = 0; i < 3; ++i)
            r->frame_x[i] = (float)x[i];
        if (r->align_from < 0)
            continue;
        int to_end = (r->flags & MESO_FSEG_ALIGN_END) ? 1 : 0;
        int from_end = (r->flags & MESO_FSEG_ALIGN_FROM_END) ? 1 : 0;
        r->u_offset = 0;
        if (meso_frustum_rec_end_kind(r, to_end) != MESO_FSEG_END_JOINT)
            continue;
        /* The u = 0 generator of align_from at its shared end meets the
         * joint plane at X; u_offset = u of X in this frame. */
        const meso_frustum_rec* f = &recs[r->align_from];
        seg_geo gf;
        if (seg_load(f, node_pos, node_count, &gf))
            return -1;
        double kf = (gf.r[1] - gf.r[0]) / gf.h;
        double fx[3] = {f->frame_x[0], f->frame_x[1], f->frame_x[2]}, fz[3], w[3];
        cross3(fx, gf.a, fz);
        double ang = TAU * ((double)f->u_offset - (double)from_end * f->twist / TAU);
        for (int i = 0; i < 3; ++i)
            w[i] = sin(ang) * fx[i] + cos(ang) * fz[i];
        double fn[3] = {f->plane[from_end][0], f->plane[from_end][1], f->plane[from_end][2]};
        double fc[3] = {f->center[from_end][0], f->center[from_end][1], f->center[from_end][2]};
        double yf;
        if (!generator_plane(gf.p[0], gf.r[0], gf.a, kf, w, fn, dot3(fn, fc), &yf))
            continue;
        double X[3], q[3], z[3];
        for (int i = 0; i < 3; ++i)
            X[i] = gf.p[0][i] + yf * gf.a[i] + (gf.r[0] + kf * yf) * w[i];
        double yy = 0;
        for (int i = 0; i < 3; ++i)
            yy += (X[i] - g.p[0][i]) * g.a[i];
        for (int i = 0; i < 3; ++i)
            q[i] = X[i] - g.p[0][i] - yy * g.a[i];
        cross3(x, g.a, z);
        double ut = atan2(dot3(q, x), dot3(q, z)) / TAU + (double)to_end * r->twist / TAU;
        r->u_offset = (float)(ut - floor(ut));
    }
    return 0;
}
