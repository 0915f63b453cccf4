/*
 * frustum_model.c — skeleton → conical frusta (frustum_model.h, which
 * states every construction and the decisions taken where the paper is
 * vague).
 */
#include "frustum_model.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frusta_pose.h"
#include "meso_bake.h"
#include "vec3d.h"

#define TAU 6.283185307179586
#define CUT_SAMPLES 512
#define SEAM_SAMPLES 128
#define SEAM_TOLERANCE 1e-6 /* of the joint radius: a closed seam */
#define FIT_RANGE 1.25 /* the §2.2 fit may scale a radius by 1/1.25 .. 1.25 */

/* >>vectors ---------------------------------------------------------------- */

/* >>segment geometry ------------------------------------------------------- */

static double seg_axis(const meso_frustum_segment* s, double a[3])
{
    for (int i = 0; i < 3; ++i)
        a[i] = s->c1[i] - s->c0[i];
    return normalize3(a);
}

int meso_frustum_generator_plane(const meso_frustum_segment* s, int e, const double w[3], double* y)
{
    double a[3];
    double h = seg_axis(s, a);
    double k = h > 0 ? (s->r1 - s->r0) / h : 0.0;
    const double* n = s->plane_n[e];
    double nw = dot3(n, w);
    double den = dot3(n, a) + k * nw;
    if (fabs(den) < 1e-300)
        return 0;
    *y = (s->plane_d[e] - dot3(n, s->c0) - s->r0 * nw) / den;
    return 1;
}

/* Unit radial direction of angle φ in a frame (x, z = x × a). */
static void radial_dir(const double a[3], const double x[3], double phi, double w[3])
{
    double z[3];
    cross3(x, a, z);
    for (int i = 0; i < 3; ++i)
        w[i] = sin(phi) * x[i] + cos(phi) * z[i];
}

/* Point of the generator with direction w at axial coordinate y. */
static void generator_point(const meso_frustum_segment* s, const double a[3], double k, const double w[3], double y,
    double p[3])
{
    double r = s->r0 + k * y;
    for (int i = 0; i < 3; ++i)
        p[i] = s->c0[i] + y * a[i] + r * w[i];
}

/* Validity of a segment's cut (frustum_model.h, "Cap intersections").
 * Returns the margin min(y1 − y0) in world units, or −1 when an orientation
 * or nappe condition fails. */
static double cut_margin(const meso_frustum_segment* s)
{
    double a[3];
    double h = seg_axis(s, a);
    double k = (s->r1 - s->r0) / h;
    double ext[2][2];
    for (int e = 0; e < 2; ++e) {
        const double* n = s->plane_n[e];
        double m = dot3(n, a);
        double np[3] = {n[0] - m * a[0], n[1] - m * a[1], n[2] - m * a[2]};
        double sa = sqrt(dot3(np, np));
        double dn[2] = {m + k * sa, m - k * sa};
        double en = s->plane_d[e] - dot3(n, s->c0);
        for (int j = 0; j < 2; ++j) {
            if (e == 0 ? dn[j] >= 0 : dn[j] <= 0)
                return -1;
            ext[e][j] = (en - (j == 0 ? 1 : -1) * s->r0 * sa) / dn[j];
            if (s->r0 + k * ext[e][j] < -1e-12 * (h + s->r0 + s->r1))
                return -1;
        }
    }
    double x[3];
    any_perp3(a, x);
    double margin = DBL_MAX;
    for (int j = 0; j < CUT_SAMPLES; ++j) {
        double w[3], y0, y1;
        radial_dir(a, x, TAU * j / CUT_SAMPLES, w);
        if (!meso_frustum_generator_plane(s, 0, w, &y0) || !meso_frustum_generator_plane(s, 1, w, &y1))
            return -1;
        margin = fmin(margin, y1 - y0);
    }
    return margin * sqrt(1 + k * k);
}

double meso_frustum_lateral_area(const meso_frustum_segment* s, uint32_t samples)
{
    if (samples == 0)
        samples = 1024;
    double a[3], x[3];
    double h = seg_axis(s, a);
    double k = (s->r1 - s->r0) / h;
    any_perp3(a, x);
    double sum = 0;
    for (uint32_t j = 0; j < samples; ++j) {
        double w[3], y0, y1;
        radial_dir(a, x, TAU * j / samples, w);
        if (!meso_frustum_generator_plane(s, 0, w, &y0) || !meso_frustum_generator_plane(s, 1, w, &y1))
            continue;
        /* ∫ r(y) dy from y0 to y1; the area element is r dφ · √(1+k²) dy. */
        sum += s->r0 * (y1 - y0) + 0.5 * k * (y1 * y1 - y0 * y0);
    }
    return sum * sqrt(1 + k * k) * TAU / samples;
}

/* >>joint planes ----------------------------------------------------------- */

typedef struct end_ref {
    uint32_t seg;
    int end;
} end_ref;

static const double* seg_end_point(const meso_frustum_segment* s, int e)
{
    return e == 0 ? s->c0 : s->c1;
}

static double seg_end_radius(const meso_frustum_segment* s, int e)
{
    return e == 0 ? s->r0 : s->r1;
}

static void set_perpendicular_plane(meso_frustum_segment* s, int e)
{
    double a[3];
    seg_axis(s, a);
    double sg = e == 0 ? -1.0 : 1.0;
    for (int i = 0; i < 3; ++i)
        s->plane_n[e][i] = sg * a[i];
    s->plane_d[e] = dot3(s->plane_n[e], seg_end_point(s, e));
}

/* The §2.2 plane of joint j (frustum_model.h, "Joint plane"). */
static void joint_plane(meso_frustum_model* m, meso_frustum_joint* j)
{
    const meso_frustum_segment* s1 = &m->segments[j->segment[0]];
    const meso_frustum_segment* s2 = &m->segments[j->segment[1]];
    int e1 = j->end[0], e2 = j->end[1];
    meso_frustum_joint_plane(seg_end_point(s1, 1 - e1), seg_end_radius(s1, 1 - e1), seg_end_point(s1, e1),
        seg_end_radius(s1, e1), seg_end_point(s2, e2), seg_end_radius(s2, e2), seg_end_point(s2, 1 - e2),
        seg_end_radius(s2, 1 - e2), j->plane_n, &j->plane_d, j->a, j->b);
}

/* Minor semi-axis of the ellipse where the plane through A, B (⟂ the
 * medial plane) cuts the cone of segment s: at the ellipse's centre M (the
 * midpoint of AB) the minor axis runs along Nm, ⟂ the medial plane that
 * holds the axis, so b² = r(y_M)² − dist(M, axis)². */
static double minor_semi_axis(const meso_frustum_segment* s, const double A[3], const double B[3])
{
    double a[3], M[3], q[3];
    double h = seg_axis(s, a);
    double y = 0;
    for (int i = 0; i < 3; ++i)
        M[i] = 0.5 * (A[i] + B[i]);
    for (int i = 0; i < 3; ++i)
        y += (M[i] - s->c0[i]) * a[i];
    for (int i = 0; i < 3; ++i)
        q[i] = M[i] - s->c0[i] - y * a[i];
    double r = s->r0 + (s->r1 - s->r0) * y / h;
    return sqrt(fmax(0.0, r * r - dot3(q, q)));
}

/* Minor-axis mismatch b2 − b1 of joint j when segment 2's radius at the
 * joint is set to `rj2`. */
static double minor_mismatch(meso_frustum_model* m, meso_frustum_joint* j, double rj2)
{
    meso_frustum_segment* s2 = &m->segments[j->segment[1]];
    double* rp = j->end[1] == 0 ? &s2->r0 : &s2->r1;
    double keep = *rp;
    *rp = rj2;
    joint_plane(m, j);
    double d = minor_semi_axis(s2, j->a, j->b) - minor_semi_axis(&m->segments[j->segment[0]], j->a, j->b);
    *rp = keep;
    return d;
}

/* The §2.2 fit of one joint (frustum_model.h, "Minor-axis fit"): segment
 * 2's radius at the joint such that both cut ellipses have the same minor
 * axis, by bisection on a bracket around its node radius. Returns the
 * radius change, or NaN when no radius within FIT_RANGE of it fits. */
static double minor_axis_fit(meso_frustum_model* m, meso_frustum_joint* j)
{
    meso_frustum_segment* s2 = &m->segments[j->segment[1]];
    double* rp = j->end[1] == 0 ? &s2->r0 : &s2->r1;
    double r_in = *rp;
    if (r_in <= 0)
        return NAN;
    double lo = r_in / FIT_RANGE, hi = r_in * FIT_RANGE;
    double flo = minor_mismatch(m, j, lo), fhi = minor_mismatch(m, j, hi), f0 = minor_mismatch(m, j, r_in);
    if (fabs(f0) <= 1e-12 * r_in) {
        joint_plane(m, j);
        return 0;
    }
    /* The bracket nearest r_in. */
    if ((f0 < 0) == (flo < 0)) {
        lo = r_in;
        flo = f0;
    } else {
        hi = r_in;
        fhi = f0;
    }
    if ((flo < 0) == (fhi < 0)) {
        joint_plane(m, j);
        return NAN;
    }
    for (int it = 0; it < 100 && hi - lo > 1e-13 * r_in; ++it) {
        double mid = 0.5 * (lo + hi), fm = minor_mismatch(m, j, mid);
        if ((fm < 0) == (flo < 0)) {
            lo = mid;
            flo = fm;
        } else
            hi = mid;
    }
    *rp = 0.5 * (lo + hi);
    joint_plane(m, j);
    return *rp - r_in;
}

/* Applies joint j's plane (or its ball) to its two segments. */
static void joint_apply(meso_frustum_model* m, uint32_t ji)
{
    meso_frustum_joint* j = &m->joints[ji];
    for (int k = 0; k < 2; ++k) {
        meso_frustum_segment* s = &m->segments[j->segment[k]];
        int e = j->end[k];
        s->cap[e] = 0;
        if (j->ball) {
            set_perpendicular_plane(s, e);
            s->end_kind[e] = MESO_FRUSTUM_END_BALL;
            continue;
        }
        /* Outward: the first segment arrives along +Nc, the second leaves. */
        double sg = k == 0 ? 1.0 : -1.0;
        for (int i = 0; i < 3; ++i)
            s->plane_n[e][i] = sg * j->plane_n[i];
        s->plane_d[e] = sg * j->plane_d;
        s->end_kind[e] = MESO_FRUSTUM_END_JOINT;
    }
}

/* Seam gap of a §2.2 joint (frustum_model.h). */
static double seam_gap(const meso_frustum_model* m, const meso_frustum_joint* j)
{
    double gap = 0;
    for (int dir = 0; dir < 2; ++dir) {
        const meso_frustum_segment* sa = &m->segments[j->segment[dir]];
        const meso_frustum_segment* sb = &m->segments[j->segment[1 - dir]];
        int ea = j->end[dir], eb = j->end[1 - dir];
        double aa[3], ab[3], xa[3];
        double ha = seg_axis(sa, aa), hb = seg_axis(sb, ab);
        double ka = (sa->r1 - sa->r0) / ha, kb = (sb->r1 - sb->r0) / hb;
        any_perp3(aa, xa);
        for (int t = 0; t < SEAM_SAMPLES; ++t) {
            double w[3], y, X[3], q[3], X2[3];
            radial_dir(aa, xa, TAU * t / SEAM_SAMPLES, w);
            if (!meso_frustum_generator_plane(sa, ea, w, &y))
                return INFINITY;
            generator_point(sa, aa, ka, w, y, X);
            double yb = 0;
            for (int i = 0; i < 3; ++i)
                yb += (X[i] - sb->c0[i]) * ab[i];
            for (int i = 0; i < 3; ++i)
                q[i] = X[i] - sb->c0[i] - yb * ab[i];
            if (normalize3(q) == 0)
                any_perp3(ab, q);
            if (!meso_frustum_generator_plane(sb, eb, q, &yb))
                return INFINITY;
            generator_point(sb, ab, kb, q, yb, X2);
            double d[3] = {X[0] - X2[0], X[1] - X2[1], X[2] - X2[2]};
            gap = fmax(gap, sqrt(dot3(d, d)));
        }
    }
    return gap;
}

/* >>u alignment ------------------------------------------------------------ */

/* u of point p in segment s's frame, offsets excluded (turns). */
static double raw_u(const meso_frustum_segment* s, const double p[3])
{
    double a[3], z[3], q[3];
    seg_axis(s, a);
    double y = 0;
    for (int i = 0; i < 3; ++i)
        y += (p[i] - s->c0[i]) * a[i];
    for (int i = 0; i < 3; ++i)
        q[i] = p[i] - s->c0[i] - y * a[i];
    cross3(s->frame_x, a, z);
    return atan2(dot3(q, s->frame_x), dot3(q, z)) / TAU;
}

static void project_frame(meso_frustum_segment* s, const double x[3])
{
    double a[3];
    seg_axis(s, a);
    double m = dot3(x, a);
    for (int i = 0; i < 3; ++i)
        s->frame_x[i] = x[i] - m * a[i];
    if (normalize3(s->frame_x) < 1e-6)
        any_perp3(a, s->frame_x);
}

/* Frames segment `to` from `from` across joint j (or a ball when j < 0). */
static void align_across(meso_frustum_model* m, uint32_t from, int from_end, uint32_t to, int to_end, int32_t ji)
{
    meso_frustum_segment* sf = &m->segments[from];
    meso_frustum_segment* st = &m->segments[to];
    project_frame(st, sf->frame_x);
    st->u_offset = 0;
    if (ji < 0 || m->joints[ji].ball)
        return;
    /* The u = 0 generator of `from` at its joint end: raw angle =
     * u_offset − v·twist/2π with v = from_end. */
    double a[3], w[3];
    double h = seg_axis(sf, a);
    double k = (sf->r1 - sf->r0) / h;
    double ang = sf->u_offset - (double)from_end * sf->twist / TAU;
    radial_dir(a, sf->frame_x, TAU * ang, w);
    double y, X[3];
    if (!meso_frustum_generator_plane(sf, from_end, w, &y))
        return;
    generator_point(sf, a, k, w, y, X);
    double ut = raw_u(st, X) + (double)to_end * st->twist / TAU;
    st->u_offset = ut - floor(ut);
}

/* >>build ------------------------------------------------------------------ */

static uint32_t find_rep(uint32_t* rep, uint32_t i)
{
    while (rep[i] != i) {
        rep[i] = rep[rep[i]];
        i = rep[i];
    }
    return i;
}

void meso_frustum_model_free(meso_frustum_model* m)
{
    if (!m)
        return;
    free(m->segments);
    free(m->joints);
    free(m->balls);
    free(m->order);
    memset(m, 0, sizeof(*m));
}

/* The skeleton's nodes as the builder sees them: zero-length segments
 * merged (union-find), and per representative node the segment ends there. */
typedef struct incidence {
    uint32_t n;       /* skeleton nodes */
    uint32_t* rep;    /* n: representative (union-find; order-independent) */
    uint32_t* deg;    /* n: segment ends at each representative */
    uint32_t* first;  /* n + 1: the ends at v are ends[first[v] .. first[v + 1]) */
    end_ref* ends;    /* 2 n + 1 */
    uint32_t* queue;  /* n + 1: scratch (fill counters, then the breadth-first queue) */
} incidence;

/* Segments of non-zero length, with perpendicular planes, tip ends and
 * their twist (a node's own, else `twist_rate` times the length);
 * zero-length ones merge their nodes. Returns the bounding-box diagonal. */
static double make_segments(const meso_skeleton* sk, double twist_rate, incidence* g, meso_frustum_model* m)
{
    const uint32_t n = g->n;
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (uint32_t i = 0; i < n; ++i) {
        g->rep[i] = i;
        for (int c = 0; c < 3; ++c) {
            lo[c] = fmin(lo[c], sk->nodes[i].pos[c]);
            hi[c] = fmax(hi[c], sk->nodes[i].pos[c]);
        }
    }
    double diag = n ? dist3(hi, lo) : 0;
    double eps_len = 1e-12 * diag;
    /* Segments and zero-length merges (union-find: order-independent). */
    for (uint32_t i = 0; i < n; ++i) {
        int32_t p = sk->nodes[i].parent;
        if (p < 0)
            continue;
        const meso_skeleton_node* a = &sk->nodes[p];
        const meso_skeleton_node* b = &sk->nodes[i];
        if (dist3(b->pos, a->pos) <= eps_len) {
            uint32_t ra = find_rep(g->rep, (uint32_t)p), rb = find_rep(g->rep, i);
            if (ra != rb)
                g->rep[rb] = ra;
            m->stats.degenerate_segments++;
            continue;
        }
        meso_frustum_segment* s = &m->segments[m->segment_count++];
        s->node[0] = (uint32_t)p;
        s->node[1] = i;
        memcpy(s->c0, a->pos, sizeof(s->c0));
        memcpy(s->c1, b->pos, sizeof(s->c1));
        s->r0 = a->radius;
        s->r1 = b->radius;
        s->joint[0] = s->joint[1] = s->ball[0] = s->ball[1] = -1;
        set_perpendicular_plane(s, 0);
        set_perpendicular_plane(s, 1);
        s->cap[0] = s->r0 > 0;
        s->cap[1] = s->r1 > 0;
        s->end_kind[0] = s->end_kind[1] = MESO_FRUSTUM_END_TIP;
        s->twist = b->has_twist ? b->twist_deg * (TAU / 360) : twist_rate * dist3(b->pos, a->pos);
    }
    return diag;
}

/* Incidence lists per representative node (counting sort), then tips,
 * branch points and the joints (nodes of two segment ends) with their
 * planes. */
static void find_joints(incidence* g, meso_frustum_model* m)
{
    const uint32_t n = g->n;
    for (uint32_t s = 0; s < m->segment_count; ++s)
        for (int e = 0; e < 2; ++e)
            g->deg[find_rep(g->rep, m->segments[s].node[e])]++;
    for (uint32_t i = 0; i < n; ++i)
        g->first[i + 1] = g->first[i] + g->deg[i];
    memset(g->queue, 0, (size_t)(n + 1) * sizeof(*g->queue)); /* fill counters */
    for (uint32_t s = 0; s < m->segment_count; ++s)
        for (int e = 0; e < 2; ++e) {
            uint32_t v = find_rep(g->rep, m->segments[s].node[e]);
            g->ends[g->first[v] + g->queue[v]++] = (end_ref){s, e};
        }
    for (uint32_t v = 0; v < n; ++v) {
        if (g->deg[v] == 1)
            m->stats.tips++;
        else if (g->deg[v] == 2) {
            meso_frustum_joint* j = &m->joints[m->joint_count];
            j->node = v;
            for (int k = 0; k < 2; ++k) {
                j->segment[k] = g->ends[g->first[v] + k].seg;
                j->end[k] = g->ends[g->first[v] + k].end;
                m->segments[j->segment[k]].joint[j->end[k]] = (int32_t)m->joint_count;
            }
            /* First segment arrives at the joint: if it starts there, swap
             * when the other one ends there (so a chain reads parent→child). */
            if (j->end[0] == 0 && j->end[1] == 1) {
                uint32_t ts = j->segment[0];
                int te = j->end[0];
                j->segment[0] = j->segment[1];
                j->end[0] = j->end[1];
                j->segment[1] = ts;
                j->end[1] = te;
            }
            joint_plane(m, j);
            joint_apply(m, m->joint_count);
            m->joint_count++;
        } else if (g->deg[v] >= 3)
            m->stats.branch_points++;
    }
}

/* Joints at a node `ball_nodes` names are ball joints too: last, after the
 * fit and the cap-intersection handling, so every other joint is fitted as
 * without them. */
static void ball_named_joints(meso_frustum_model* m, const uint8_t* ball_nodes)
{
    for (uint32_t ji = 0; ji < m->joint_count; ++ji) {
        meso_frustum_joint* j = &m->joints[ji];
        if (!j->ball && ball_nodes[j->node]) {
            j->ball = 1;
            m->stats.ball_joints++;
            joint_apply(m, ji);
        }
    }
}

/* Joints bending more than max_deg (> 0) are ball joints. */
static void ball_sharp_joints(meso_frustum_model* m, double max_deg)
{
    for (uint32_t ji = 0; ji < m->joint_count; ++ji) {
        meso_frustum_joint* j = &m->joints[ji];
        const meso_frustum_segment* s1 = &m->segments[j->segment[0]];
        const meso_frustum_segment* s2 = &m->segments[j->segment[1]];
        double m1[3], m2[3];
        for (int i = 0; i < 3; ++i) {
            m1[i] = seg_end_point(s1, j->end[0])[i] - seg_end_point(s1, 1 - j->end[0])[i];
            m2[i] = seg_end_point(s2, 1 - j->end[1])[i] - seg_end_point(s2, j->end[1])[i];
        }
        normalize3(m1);
        normalize3(m2);
        double bend = acos(fmax(-1.0, fmin(1.0, dot3(m1, m2)))) * 360.0 / TAU;
        if (bend > max_deg) {
            j->ball = 1;
            m->stats.sharp_joints++;
            m->stats.ball_joints++;
            joint_apply(m, ji);
        }
    }
}

/* §2.2 minor-axis fit: joints in breadth-first order would converge in
 * one sweep; sweeping until nothing moves needs no order. Then how far the
 * radii at the nodes moved from the skeleton's. */
static void fit_minor_axes(const meso_skeleton* sk, meso_frustum_model* m, int fit, double diag)
{
    for (int sweep = 0; fit && sweep < 32; ++sweep) {
        double moved = 0;
        for (uint32_t ji = 0; ji < m->joint_count; ++ji) {
            if (m->joints[ji].ball)
                continue;
            double dr = minor_axis_fit(m, &m->joints[ji]);
            if (isnan(dr)) {
                m->joints[ji].ball = 1;
                m->stats.unfitted_joints++;
                m->stats.ball_joints++;
            } else
                moved = fmax(moved, fabs(dr));
            joint_apply(m, ji);
        }
        for (uint32_t ji = 0; ji < m->joint_count; ++ji) {
            if (!m->joints[ji].ball)
                joint_plane(m, &m->joints[ji]);
            joint_apply(m, ji);
        }
        if (moved <= 1e-12 * diag)
            break;
    }
    double dr_sum = 0;
    for (uint32_t s = 0; s < m->segment_count; ++s)
        for (int e = 0; e < 2; ++e) {
            const meso_skeleton_node* nd = &sk->nodes[m->segments[s].node[e]];
            double dr = fabs((e ? m->segments[s].r1 : m->segments[s].r0) - nd->radius);
            m->stats.radius_change_max = fmax(m->stats.radius_change_max, dr);
            dr_sum += dr;
        }
    m->stats.radius_change_mean = dr_sum / (2.0 * m->segment_count);
}

/* Cap intersections: find, then (unless kept) turn joints at failing
 * segments into ball joints until nothing changes. */
static void handle_cap_intersections(meso_frustum_model* m, int keep)
{
    for (uint32_t s = 0; s < m->segment_count; ++s) {
        m->segments[s].cut_margin = cut_margin(&m->segments[s]);
        if (m->segments[s].cut_margin <= 0)
            m->stats.cap_intersections_found++;
    }
    int changed = !keep;
    while (changed) {
        changed = 0;
        for (uint32_t s = 0; s < m->segment_count; ++s) {
            if (m->segments[s].cut_margin > 0)
                continue;
            for (int e = 0; e < 2; ++e) {
                int32_t ji = m->segments[s].joint[e];
                if (ji < 0 || m->joints[ji].ball)
                    continue;
                m->joints[ji].ball = 1;
                m->stats.ball_joints++;
                joint_apply(m, (uint32_t)ji);
                for (int k = 0; k < 2; ++k) {
                    meso_frustum_segment* t = &m->segments[m->joints[ji].segment[k]];
                    t->cut_margin = cut_margin(t);
                }
                changed = 1;
            }
        }
    }
    for (uint32_t s = 0; s < m->segment_count; ++s)
        if (m->segments[s].cut_margin <= 0)
            m->stats.cap_intersections_unhandled++;
}

/* A seam the fit left open (no radius closed it, or the cut is not an
 * ellipse) becomes a ball joint: a knob, never a crack. */
static void ball_open_seams(meso_frustum_model* m)
{
    for (uint32_t ji = 0; ji < m->joint_count; ++ji) {
        meso_frustum_joint* j = &m->joints[ji];
        if (j->ball)
            continue;
        const meso_frustum_segment* s1 = &m->segments[j->segment[0]];
        double scale = j->end[0] ? s1->r1 : s1->r0;
        if (!(seam_gap(m, j) <= SEAM_TOLERANCE * scale)) {
            j->ball = 1;
            m->stats.unfitted_joints++;
            m->stats.ball_joints++;
            joint_apply(m, ji);
        }
    }
}

/* Balls: branch points and ball joints. */
static void make_balls(const incidence* g, meso_frustum_model* m)
{
    const uint32_t *deg = g->deg, *first = g->first;
    const end_ref* ends = g->ends;
    for (uint32_t v = 0; v < g->n; ++v) {
        int is_ball = deg[v] >= 3;
        if (deg[v] == 2) {
            const end_ref* er = &ends[first[v]];
            int32_t ji = m->segments[er->seg].joint[er->end];
            is_ball = ji >= 0 && m->joints[ji].ball;
        }
        if (!is_ball)
            continue;
        meso_frustum_ball* b = &m->balls[m->ball_count];
        b->node = v;
        b->radius = 0;
        for (uint32_t k = first[v]; k < first[v + 1]; ++k) {
            meso_frustum_segment* s = &m->segments[ends[k].seg];
            if (k == first[v])
                memcpy(b->center, seg_end_point(s, ends[k].end), sizeof(b->center));
            b->radius = fmax(b->radius, seg_end_radius(s, ends[k].end));
            if (deg[v] >= 3) {
                set_perpendicular_plane(s, ends[k].end);
                s->cap[ends[k].end] = 0;
                s->end_kind[ends[k].end] = MESO_FRUSTUM_END_BALL;
            }
            s->ball[ends[k].end] = (int32_t)m->ball_count;
        }
        m->ball_count++;
    }
}

/* Seam gaps of the §2.2 joints. */
static void seam_gap_stats(meso_frustum_model* m)
{
    uint32_t gap_n = 0;
    double gap_sum = 0;
    for (uint32_t ji = 0; ji < m->joint_count; ++ji) {
        meso_frustum_joint* j = &m->joints[ji];
        if (j->ball)
            continue;
        j->seam_gap = seam_gap(m, j);
        m->stats.seam_gap_max = fmax(m->stats.seam_gap_max, j->seam_gap);
        gap_sum += j->seam_gap;
        gap_n++;
    }
    m->stats.seam_gap_mean = gap_n ? gap_sum / gap_n : 0;
}

/* Frames and u alignment: breadth-first over segments through nodes
 * (m->order gets the visiting order). */
static meso_result align_frames(incidence* g, meso_frustum_model* m, meso_error* err)
{
    uint8_t* seen = calloc(m->segment_count, 1);
    m->order = malloc(m->segment_count * sizeof(*m->order));
    uint32_t order_n = 0;
    if (!seen || !m->order) {
        free(seen);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frusta: out of memory");
    }
    uint32_t* queue = g->queue;
    for (uint32_t s0 = 0; s0 < m->segment_count; ++s0) {
        if (seen[s0])
            continue;
        meso_frustum_segment* s = &m->segments[s0];
        double a[3];
        seg_axis(s, a);
        any_perp3(a, s->frame_x);
        s->u_offset = 0;
        seen[s0] = 1;
        s->align_from = -1;
        uint32_t qh = 0, qt = 0;
        queue[qt++] = s0;
        while (qh < qt) {
            uint32_t cur = queue[qh++];
            m->order[order_n++] = cur;
            for (int e = 0; e < 2; ++e) {
                uint32_t v = find_rep(g->rep, m->segments[cur].node[e]);
                for (uint32_t k = g->first[v]; k < g->first[v + 1]; ++k) {
                    uint32_t nb = g->ends[k].seg;
                    if (seen[nb])
                        continue;
                    seen[nb] = 1;
                    align_across(m, cur, e, nb, g->ends[k].end, g->deg[v] == 2 ? m->segments[cur].joint[e] : -1);
                    m->segments[nb].align_from = (int32_t)cur;
                    m->segments[nb].align_end = g->ends[k].end;
                    m->segments[nb].align_from_end = e;
                    if (qt < g->n + 1)
                        queue[qt++] = nb;
                }
            }
        }
    }
    free(seen);
    return MESO_OK;
}

meso_result meso_frustum_model_build(const meso_skeleton* sk, const meso_frustum_options* opt, meso_frustum_model* out,
    meso_error* err)
{
    if (!sk || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "frusta: skeleton or out is NULL");
    memset(out, 0, sizeof(*out));
    meso_frustum_options o = {0};
    if (opt)
        o = *opt;
    uint32_t n = sk->node_count;
    meso_frustum_model m = {0};
    incidence g = {.n = n};
    g.rep = malloc((size_t)(n ? n : 1) * sizeof(*g.rep));
    g.deg = calloc(n ? n : 1, sizeof(*g.deg));
    g.first = calloc((size_t)n + 1, sizeof(*g.first));
    g.ends = malloc((size_t)(2 * n + 1) * sizeof(*g.ends));
    g.queue = malloc((size_t)(n + 1) * sizeof(*g.queue));
    m.segments = calloc(n ? n : 1, sizeof(*m.segments));
    m.joints = calloc(n ? n : 1, sizeof(*m.joints));
    m.balls = calloc(n ? n : 1, sizeof(*m.balls));
    meso_result r = MESO_OK;
    if (!g.rep || !g.deg || !g.first || !g.ends || !g.queue || !m.segments || !m.joints || !m.balls) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frusta: out of memory (%u nodes)", n);
        goto done;
    }
    const double diag = make_segments(sk, o.twist_per_length, &g, &m);
    if (m.segment_count == 0) {
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3149u, "frusta: the skeleton has no segment of non-zero length");
        goto done;
    }
    find_joints(&g, &m);
    if (o.max_joint_angle_deg > 0)
        ball_sharp_joints(&m, o.max_joint_angle_deg);
    fit_minor_axes(sk, &m, !o.no_minor_axis_fit, diag);
    handle_cap_intersections(&m, o.keep_cap_intersections);
    if (!o.no_minor_axis_fit)
        ball_open_seams(&m);
    if (o.ball_nodes)
        ball_named_joints(&m, o.ball_nodes);
    make_balls(&g, &m);
    m.stats.segments = m.segment_count;
    m.stats.joints = m.joint_count;
    seam_gap_stats(&m);
    r = align_frames(&g, &m, err);
    if (r == MESO_OK) {
        *out = m;
        memset(&m, 0, sizeof(m));
    }
done:
    free(g.rep);
    free(g.deg);
    free(g.first);
    free(g.ends);
    free(g.queue);
    meso_frustum_model_free(&m);
    return r;
}
