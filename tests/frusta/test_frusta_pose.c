/*
 * test_frusta_pose.c — the frusta object records and the pose rebuild
 * (formats/frusta_pose.c, bake/frusta_chunks.c), against expectations that
 * do not come from the code under test:
 *  - rest pose: every record's planes and radii equal the double-precision
 *    model's (bake/frustum_model.c) to float rounding; each centre lies on
 *    its plane and on the axis; joints share one plane (n0 = −n1);
 *  - a rigid motion of the skeleton (rotation ⟂ the root axis + translation)
 *    moves every plane, centre and frame by that motion and keeps radii and
 *    u offsets;
 *  - bending a joint: the rebuilt plane still contains the §2.2 points A
 *    and B, which lie on both cones (recomputed here from the definition);
 *  - u alignment after the bend: the u = 0 generator of align_from meets
 *    the joint plane at a point whose u in the next frustum's frame is 0;
 *  - record codecs round-trip, and bad node indices are refused.
 */
#include <string.h>

#include "frusta_chunks.h"
#include "frusta_pose.h"
#include "frustum_model.h"
#include "skeleton_swc.h"
#include "test_util.h"
#include "vec3d.h"

#define TAU 6.283185307179586

static void f2d(const float f[3], double d[3])
{
    for (int i = 0; i < 3; ++i)
        d[i] = f[i];
}

/* A bent, tapered arm with a side branch and a straight tail. */
static const char* const arm_text = "0 0 0 0.30\n"
                                    "0 2 0 0.30\n"
                                    "1.2 3.4 0.3 0.22\n"
                                    "1.6 5.0 0.9 0.12\n"
                                    "-1 3 0 0.15 2\n"
                                    "-2 4.2 0.4 0.08\n";

typedef struct built {
    meso_skeleton sk;
    meso_frustum_model m;
    meso_frusta_object o;
} built;

static built build(const char* text)
{
    built b;
    meso_error err;
    assert(meso_skeleton_parse(text, strlen(text), MESO_SKELETON_TEXT, &b.sk, &err) == MESO_OK);
    assert(meso_frustum_model_build(&b.sk, NULL, &b.m, &err) == MESO_OK);
    meso_frusta_relief_params rp = {.depth = 0.05, .u_repeat = 2};
    assert(meso_frusta_object_build(&b.sk, &b.m, &rp, &b.o, &err) == MESO_OK);
    return b;
}

static void built_free(built* b)
{
    meso_frusta_object_free(&b->o);
    meso_frustum_model_free(&b->m);
    meso_skeleton_free(&b->sk);
}

/* Cone residual |q| − r(y) of p against record r's cone (from its nodes). */
static double cone_residual(const meso_frustum_rec* r, const float* pos, const double p[3])
{
    double c0[3], c1[3], a[3], q[3];
    f2d(pos + 3 * r->node[0], c0);
    f2d(pos + 3 * r->node[1], c1);
    for (int i = 0; i < 3; ++i)
        a[i] = c1[i] - c0[i];
    double h = sqrt(dot3(a, a));
    for (int i = 0; i < 3; ++i)
        a[i] /= h;
    double y = 0;
    for (int i = 0; i < 3; ++i)
        y += (p[i] - c0[i]) * a[i];
    for (int i = 0; i < 3; ++i)
        q[i] = p[i] - c0[i] - y * a[i];
    return sqrt(dot3(q, q)) - (r->node_radius[0] + (r->node_radius[1] - r->node_radius[0]) * y / h);
}

static void check_record_geometry(const meso_frusta_object* o, const float* pos)
{
    for (uint32_t f = 0; f < o->count; ++f) {
        const meso_frustum_rec* r = &o->recs[f];
        double c[2][3], n[2][3];
        for (int e = 0; e < 2; ++e) {
            f2d(r->center[e], c[e]);
            f2d(r->plane[e], n[e]);
            /* the centre is on the axis, its radius the cone's there */
            double on_cone[3], x[3];
            f2d(r->frame_x, x);
            for (int i = 0; i < 3; ++i)
                on_cone[i] = c[e][i] + r->radius[e] * x[i];
            assert(fabs(cone_residual(r, pos, on_cone)) < 1e-5);
            assert(fabs(sqrt(dot3(n[e], n[e])) - 1) < 1e-6);
        }
        double ax[3] = {c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]};
        assert(dot3(n[0], ax) < 0 && dot3(n[1], ax) > 0); /* outward */
        for (int e = 0; e < 2; ++e) {
            if (meso_frustum_rec_end_kind(r, e) != MESO_FSEG_END_JOINT)
                continue;
            const meso_frustum_rec* o2 = &o->recs[r->other[e]];
            int oe = o2->other[1] == (int32_t)f && meso_frustum_rec_end_kind(o2, 1) == MESO_FSEG_END_JOINT ? 1 : 0;
            double n2[3], c2[3];
            f2d(o2->plane[oe], n2);
            f2d(o2->center[oe], c2);
            for (int i = 0; i < 3; ++i)
                assert(fabs(n[e][i] + n2[i]) < 1e-6); /* one plane, opposite sides */
            double d[3] = {c2[0] - c[e][0], c2[1] - c[e][1], c2[2] - c[e][2]};
            assert(fabs(dot3(n[e], d)) < 1e-5);       /* both centres on it */
        }
    }
}

static void test_rest_pose(void)
{
    built b = build(arm_text);
    assert(b.o.count == 5 && b.o.node_count == 6);
    check_record_geometry(&b.o, b.o.node_pos);
    double worst = 0;
    for (uint32_t f = 0; f < b.o.count; ++f) {
        const meso_frustum_segment* s = &b.m.segments[b.m.order[f]];
        const meso_frustum_rec* r = &b.o.recs[f];
        for (int e = 0; e < 2; ++e) {
            double n[3], c[3];
            f2d(r->plane[e], n);
            f2d(r->center[e], c);
            for (int i = 0; i < 3; ++i)
                worst = fmax(worst, fabs(n[i] - s->plane_n[e][i]));
            worst = fmax(worst, fabs(dot3(s->plane_n[e], c) - s->plane_d[e]));
        }
        if (f > 0)
            assert(r->align_from >= 0 && r->align_from < (int32_t)f);
    }
    fprintf(stderr, "    rest pose vs the double model: worst plane difference %.2e\n", worst);
    assert(worst < 1e-5);
    /* Rebuilding the rest pose again changes nothing (idempotent). */
    meso_frustum_rec* again = malloc(b.o.count * sizeof(*again));
    meso_frustum_ball_rec* balls = malloc((b.o.ball_count + 1) * sizeof(*balls));
    memcpy(again, b.o.recs, b.o.count * sizeof(*again));
    memcpy(balls, b.o.balls, b.o.ball_count * sizeof(*balls));
    assert(meso_frusta_pose(again, b.o.count, balls, b.o.ball_count, b.o.node_pos, b.o.node_count) == 0);
    for (uint32_t f = 0; f < b.o.count; ++f) {
        uint8_t fa[MESO_FRUS_RECORD_SIZE], fb[MESO_FRUS_RECORD_SIZE], sa[MESO_FSEG_RECORD_SIZE], sb[MESO_FSEG_RECORD_SIZE];
        meso_frustum_rec_encode(&again[f], fa, sa);
        meso_frustum_rec_encode(&b.o.recs[f], fb, sb);
        assert(!memcmp(fa, fb, sizeof(fa)) && !memcmp(sa, sb, sizeof(sa)));
    }
    free(again);
    free(balls);
    built_free(&b);
}

static void rotate(const double R[3][3], const double t[3], const double p[3], double o[3])
{
    for (int i = 0; i < 3; ++i)
        o[i] = R[i][0] * p[0] + R[i][1] * p[1] + R[i][2] * p[2] + t[i];
}

static void test_rigid_motion(void)
{
    built b = build(arm_text);
    const double ang = 0.7, t[3] = {3, -1, 2};
    /* About z, ⟂ the root frustum's axis (y): then the minimal rotation that
     * carries the root's frame (frusta_pose.h) is this rotation. A turn
     * about the root's own axis is invisible in node positions, so frames
     * could not follow it. */
    const double R[3][3] = {{cos(ang), -sin(ang), 0}, {sin(ang), cos(ang), 0}, {0, 0, 1}};
    const double zero[3] = {0, 0, 0};
    float* pos = malloc(3 * sizeof(float) * b.o.node_count);
    for (uint32_t k = 0; k < b.o.node_count; ++k) {
        double p[3], q[3];
        f2d(b.o.node_pos + 3 * k, p);
        rotate(R, t, p, q);
        for (int i = 0; i < 3; ++i)
            pos[3 * k + i] = (float)q[i];
    }
    meso_frustum_rec* rec = malloc(b.o.count * sizeof(*rec));
    memcpy(rec, b.o.recs, b.o.count * sizeof(*rec));
    meso_frustum_ball_rec* balls = malloc((b.o.ball_count + 1) * sizeof(*balls));
    memcpy(balls, b.o.balls, b.o.ball_count * sizeof(*balls));
    assert(meso_frusta_pose(rec, b.o.count, balls, b.o.ball_count, pos, b.o.node_count) == 0);
    double worst = 0;
    for (uint32_t f = 0; f < b.o.count; ++f) {
        const meso_frustum_rec* r0 = &b.o.recs[f];
        const meso_frustum_rec* r1 = &rec[f];
        double a[3], want[3], got[3];
        for (int e = 0; e < 2; ++e) {
            f2d(r0->plane[e], a);
            rotate(R, zero, a, want);
            f2d(r1->plane[e], got);
            for (int i = 0; i < 3; ++i)
                worst = fmax(worst, fabs(want[i] - got[i]));
            f2d(r0->center[e], a);
            rotate(R, t, a, want);
            f2d(r1->center[e], got);
            for (int i = 0; i < 3; ++i)
                worst = fmax(worst, fabs(want[i] - got[i]));
            worst = fmax(worst, fabs(r0->radius[e] - r1->radius[e]));
        }
        f2d(r0->frame_x, a);
        rotate(R, zero, a, want);
        f2d(r1->frame_x, got);
        for (int i = 0; i < 3; ++i)
            worst = fmax(worst, fabs(want[i] - got[i]));
        double du = fabs(r0->u_offset - r1->u_offset);
        worst = fmax(worst, fmin(du, 1 - du));
    }
    for (uint32_t k = 0; k < b.o.ball_count; ++k) {
        double c[3], want[3];
        f2d(b.o.balls[k].center, c);
        rotate(R, t, c, want);
        for (int i = 0; i < 3; ++i)
            worst = fmax(worst, fabs(want[i] - balls[k].center[i]));
    }
    fprintf(stderr, "    rigid motion: worst difference from the moved rest pose %.2e\n", worst);
    assert(worst < 2e-5);
    meso_frusta_object moved = b.o;
    moved.recs = rec;
    check_record_geometry(&moved, pos);
    free(pos);
    free(rec);
    free(balls);
    built_free(&b);
}

/* A and B of the joint between records r1 (arriving) and r2, recomputed
 * from the §2.2 definition in the medial plane. */
static void test_bend(void)
{
    built b = build(arm_text);
    float* pos = malloc(3 * sizeof(float) * b.o.node_count);
    memcpy(pos, b.o.node_pos, 3 * sizeof(float) * b.o.node_count);
    /* swing the tip node (SKEL order keeps the chain 0-1-2-3) */
    pos[3 * 3 + 0] += 0.8f;
    pos[3 * 3 + 2] -= 0.6f;
    pos[3 * 2 + 1] += 0.3f;
    meso_frustum_rec* rec = malloc(b.o.count * sizeof(*rec));
    memcpy(rec, b.o.recs, b.o.count * sizeof(*rec));
    assert(meso_frusta_pose(rec, b.o.count, NULL, 0, pos, b.o.node_count) == 0);
    meso_frusta_object moved = b.o;
    moved.recs = rec;
    check_record_geometry(&moved, pos);
    int joints = 0;
    double worst_ab = 0, worst_u = 0;
    for (uint32_t f = 0; f < b.o.count; ++f) {
        const meso_frustum_rec* r = &rec[f];
        if (meso_frustum_rec_end_kind(r, 1) != MESO_FSEG_END_JOINT)
            continue;
        const meso_frustum_rec* r2 = &rec[r->other[1]];
        /* Medial plane of the two axes; the cones' outlines in it. */
        double O1[3], J[3], O2[3], M1[3], M2[3], Nm[3];
        f2d(pos + 3 * r->node[0], O1);
        f2d(pos + 3 * r->node[1], J);
        f2d(pos + 3 * (r2->node[0] == r->node[1] ? r2->node[1] : r2->node[0]), O2);
        for (int i = 0; i < 3; ++i) {
            M1[i] = J[i] - O1[i];
            M2[i] = O2[i] - J[i];
        }
        cross3(M1, M2, Nm);
        double ln = sqrt(dot3(Nm, Nm));
        if (ln < 1e-9)
            continue;
        for (int i = 0; i < 3; ++i)
            Nm[i] /= ln;
        /* A and B: where the plane meets the medial-plane outline of cone 1
         * (two points on the line c ± t·(n × Nm)) — both must lie on cone 2. */
        double n[3], c[3], dir[3];
        f2d(r->plane[1], n);
        f2d(r->center[1], c);
        cross3(n, Nm, dir);
        for (int side = -1; side <= 1; side += 2) {
            /* bisection on t for cone 1's surface along c + t·side·dir */
            double lo = 0, hi = 10 * (r->node_radius[0] + r->node_radius[1]);
            for (int it = 0; it < 200; ++it) {
                double mid = 0.5 * (lo + hi), p[3];
                for (int i = 0; i < 3; ++i)
                    p[i] = c[i] + side * mid * dir[i];
                if (cone_residual(r, pos, p) < 0)
                    lo = mid;
                else
                    hi = mid;
            }
            double p[3];
            for (int i = 0; i < 3; ++i)
                p[i] = c[i] + side * lo * dir[i];
            worst_ab = fmax(worst_ab, fabs(cone_residual(r2, pos, p)));
        }
        /* u alignment: r2 carried from r? Then r's u = 0 generator meets the
         * plane where r2's u is 0. */
        if (r2->align_from == (int32_t)f) {
            double a[3], x[3], z[3], w[3], c0[3];
            f2d(pos + 3 * r->node[0], c0);
            for (int i = 0; i < 3; ++i)
                a[i] = J[i] - c0[i];
            double h = sqrt(dot3(a, a));
            for (int i = 0; i < 3; ++i)
                a[i] /= h;
            f2d(r->frame_x, x);
            cross3(x, a, z);
            double ang = TAU * (r->u_offset - r->twist / TAU);
            for (int i = 0; i < 3; ++i)
                w[i] = sin(ang) * x[i] + cos(ang) * z[i];
            double k = (r->node_radius[1] - r->node_radius[0]) / h;
            /* generator c0 + y a + (r0 + k y) w against the plane n·(p − c) = 0 */
            double y = (dot3(n, c) - dot3(n, c0) - r->node_radius[0] * dot3(n, w)) / (dot3(n, a) + k * dot3(n, w));
            double X[3];
            for (int i = 0; i < 3; ++i)
                X[i] = c0[i] + y * a[i] + (r->node_radius[0] + k * y) * w[i];
            double a2[3], x2[3], z2[3], q[3], c20[3];
            f2d(pos + 3 * r2->node[0], c20);
            double c21[3];
            f2d(pos + 3 * r2->node[1], c21);
            for (int i = 0; i < 3; ++i)
                a2[i] = c21[i] - c20[i];
            double h2 = sqrt(dot3(a2, a2));
            for (int i = 0; i < 3; ++i)
                a2[i] /= h2;
            f2d(r2->frame_x, x2);
            cross3(x2, a2, z2);
            double y2 = 0;
            for (int i = 0; i < 3; ++i)
                y2 += (X[i] - c20[i]) * a2[i];
            for (int i = 0; i < 3; ++i)
                q[i] = X[i] - c20[i] - y2 * a2[i];
            double u = atan2(dot3(q, x2), dot3(q, z2)) / TAU - r2->u_offset;
            u -= floor(u + 0.5);
            worst_u = fmax(worst_u, fabs(u));
        }
        ++joints;
    }
    fprintf(stderr, "    bent pose: %d joints, A/B off the other cone by %.2e, u misalignment %.2e turns\n", joints,
        worst_ab, worst_u);
    assert(joints >= 2);
    assert(worst_ab < 1e-4 && worst_u < 1e-5);
    free(pos);
    free(rec);
    built_free(&b);
}

static void test_codecs_and_errors(void)
{
    built b = build(arm_text);
    for (uint32_t f = 0; f < b.o.count; ++f) {
        uint8_t fr[MESO_FRUS_RECORD_SIZE], fs[MESO_FSEG_RECORD_SIZE];
        meso_frustum_rec d;
        meso_frustum_rec_encode(&b.o.recs[f], fr, fs);
        meso_frustum_rec_decode(fr, fs, &d);
        assert(!memcmp(&d, &b.o.recs[f], sizeof(d)));
    }
    meso_frustum_ball_rec ball = {{1, 2, 3}, 0.5f, 7}, back;
    uint8_t br[MESO_BALL_RECORD_SIZE];
    meso_frustum_ball_encode(&ball, br);
    meso_frustum_ball_decode(br, &back);
    assert(!memcmp(&ball, &back, sizeof(ball)));
    /* fewer nodes than the records name, and a ball past the end */
    meso_frustum_rec* rec = malloc(b.o.count * sizeof(*rec));
    memcpy(rec, b.o.recs, b.o.count * sizeof(*rec));
    assert(meso_frusta_pose(rec, b.o.count, NULL, 0, b.o.node_pos, 2) == -1);
    ball.node = 99;
    assert(meso_frusta_pose(rec, b.o.count, &ball, 1, b.o.node_pos, b.o.node_count) == -1);
    /* a zero-length frustum */
    float* pos = malloc(3 * sizeof(float) * b.o.node_count);
    memcpy(pos, b.o.node_pos, 3 * sizeof(float) * b.o.node_count);
    memcpy(pos + 3 * rec[0].node[1], pos + 3 * rec[0].node[0], 3 * sizeof(float));
    assert(meso_frusta_pose(rec, b.o.count, NULL, 0, pos, b.o.node_count) == -1);
    free(pos);
    free(rec);
    built_free(&b);
}

int main(void)
{
    TEST_RUN(test_rest_pose);
    TEST_RUN(test_rigid_motion);
    TEST_RUN(test_bend);
    TEST_RUN(test_codecs_and_errors);
    return 0;
}
