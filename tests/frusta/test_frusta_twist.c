/*
 * test_frusta_twist.c — twisted frusta (relief-mapped-conical-frusta.md
 * §2.3: "A twist in the parametrization can be handled by adding vθ to the
 * u coordinate"; `mesobake frusta --twist DEG` and the .skel `twist=DEG`
 * field, bake/frustum_model.h "Twist"). Every model here is baked by
 * meso_bake_frusta (the bake behind mesobake) from a .skel file, copied to
 * memory and loaded by the exact CPU reference (frustum_reference.h), whose
 * (u, v) is FORMAT.md's parametrisation.
 *
 *  1. Analytic helix: a straight cylinder skeleton (collinear nodes, equal
 *     radii, unequal spacing) twisted at a rate of T degrees per unit
 *     length. At a surface point at distance s along the axis from the
 *     first node and right-handed angle φ about the axis (any fixed frame),
 *     u(P) − u(P_ref) = (φ − φ_ref + Θ(s) − Θ(s_ref)) / 2π (mod 1) with
 *     Θ(s) = T·s·π/180: a line u = const is the helix φ = const − Θ(s),
 *     pitch 360/|T| per turn (left-handed for T > 0). Checked at sampled
 *     surface points and at ray hits, for a rate, a negative rate, and a
 *     rate with one segment's twist= replacing it (Θ then piecewise linear).
 *  2. Continuity across joints: on bent chains (planar 60° bends, a tapered
 *     non-planar chain with and without twist= fields, the bundled
 *     saguaro's joints), at 256 points of every joint's seam (on the
 *     arriving segment's cone and the joint plane), the jump
 *     u_in(X) − u_out(X) is measured twisted and untwisted. At the §2.3
 *     aligned point it is 0 (< 1e-5 turns). Along the seam the paper's
 *     one-point alignment leaves a jump wherever the two segments' angles
 *     about their axes do not differ by a constant (the tapered chain and
 *     the saguaro: up to ~2e-2 turns, twisted or not; the planar 60° chain,
 *     frame normal to its plane, equal radii: 0, checked). On the joint plane v is exactly 1 and 0, so the
 *     twist only adds constants: the twisted jump minus the untwisted one
 *     must be the same at every seam point (the aligned point moved by the
 *     twist), to 1e-5 turns — the twist never makes u less continuous.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frusta_scene.h"
#include "frustum_reference.h"
#include "meso_bake.h"
#include "meso_file.h"
#include "test_util.h"
#include "vec3d.h"

#define TAU 6.283185307179586

static char tmp_dir[256];

static double wrap(double x) /* to [-1/2, 1/2) */
{
    return x - floor(x + 0.5);
}

typedef struct baked {
    uint8_t* bytes;
    size_t size;
    meso_ref_frusta ref;
    meso_frustum_rec* recs;
    meso_frustum_ball_rec* balls;
    uint32_t count, ball_count;
} baked;

/* meso_bake_frusta of `skel` (text format) at `twist` degrees per unit
 * length, with the ribs relief; loaded by the reference. */
static baked bake(const char* skel, double twist)
{
    char path[512];
    snprintf(path, sizeof(path), "%s/in.skel", tmp_dir);
    FILE* f = fopen(path, "w");
    assert(f && fputs(skel, f) >= 0 && fclose(f) == 0);
    meso_bake_frusta_options o = meso_bake_frusta_defaults();
    o.input = path;
    o.twist = twist;
    o.relief = "ribs:32";
    o.relief_repeat = 6;
    meso_bake_output* out = NULL;
    meso_error err = {0};
    meso_result r = meso_bake_frusta(&o, &out, NULL, &err);
    if (r != MESO_OK)
        fprintf(stderr, "bake: %s\n", err.message);
    assert(r == MESO_OK);
    baked b = {0};
    size_t need = 0;
    meso_bake_output_copy(out, NULL, 0, &need);
    b.bytes = malloc(need);
    assert(b.bytes && meso_bake_output_copy(out, b.bytes, need, &b.size) == MESO_OK && b.size == need);
    meso_bake_output_free(out);
    meso_file* mf = NULL;
    assert(meso_file_open_memory(b.bytes, b.size, NULL, &mf, &err) == MESO_OK);
    assert(meso_ref_frusta_load(mf, 1, &b.ref, &err) == MESO_OK);
    meso_file_close(mf);
    frusta_file_records(b.bytes, b.size, &b.recs, &b.count, &b.balls, &b.ball_count);
    assert(b.count == b.ref.seg_count);
    return b;
}

static void baked_free(baked* b)
{
    meso_ref_frusta_free(&b->ref);
    free(b->recs);
    free(b->balls);
    free(b->bytes);
}

/* >>analytic helix ---------------------------------------------------------- */

enum { CHAIN = 6 };
static const double chain_s[CHAIN] = {0, 0.7, 1.1, 2.5, 3.0, 4.2}; /* node distances along the axis */
static const double chain_r = 0.4;
static const double chain_o[3] = {0.2, -1.0, 0.5};

/* Θ(s) in radians: `rate` degrees per unit, except segment `special`
 * (ending at node special + 1; -1: none), which twists `special_deg`. */
static double theta(double s, double rate, int special, double special_deg)
{
    double t = 0;
    for (int i = 0; i + 1 < CHAIN; ++i) {
        const double len = chain_s[i + 1] - chain_s[i];
        const double f = fmin(fmax((s - chain_s[i]) / len, 0), 1);
        t += f * (i == special ? special_deg : rate * len) * (TAU / 360);
    }
    return t;
}

/* u of P on whichever segment holds it (axial coordinate within [0, h]). */
static double u_at(const meso_ref_frusta* m, const double p[3])
{
    for (uint32_t i = 0; i < m->seg_count; ++i) {
        const meso_ref_frustum* f = &m->segs[i];
        double a[3] = {f->c1[0] - f->c0[0], f->c1[1] - f->c0[1], f->c1[2] - f->c0[2]};
        const double h = sqrt(dot3(a, a));
        const double d[3] = {p[0] - f->c0[0], p[1] - f->c0[1], p[2] - f->c0[2]};
        const double y = dot3(d, a) / h;
        if (y >= -1e-9 * h && y <= h * (1 + 1e-9)) {
            double u, v;
            meso_ref_frustum_uv(f, p, &u, &v, NULL);
            return u;
        }
    }
    assert(!"point on no segment");
    return 0;
}

static double helix_case(const char* what, double rate, int special, double special_deg)
{
    double a[3] = {0.3, 1.0, 0.2};
    const double l = sqrt(dot3(a, a));
    for (int k = 0; k < 3; ++k)
        a[k] /= l;
    char skel[1024];
    size_t n = 0;
    for (int i = 0; i < CHAIN; ++i) {
        n += (size_t)snprintf(skel + n, sizeof(skel) - n, "%.17g %.17g %.17g %g", chain_o[0] + chain_s[i] * a[0],
                              chain_o[1] + chain_s[i] * a[1], chain_o[2] + chain_s[i] * a[2], chain_r);
        if (special >= 0 && i == special + 1)
            n += (size_t)snprintf(skel + n, sizeof(skel) - n, " twist=%.17g", special_deg);
        n += (size_t)snprintf(skel + n, sizeof(skel) - n, "\n");
    }
    baked b = bake(skel, rate);
    assert(b.count == CHAIN - 1);
    /* The records carry rate x length (or the node's twist), in radians. */
    for (uint32_t i = 0; i < b.count; ++i) {
        const int seg = (int)b.recs[i].node[1] - 1; /* straight chain: SKEL order = input order */
        const double len = chain_s[seg + 1] - chain_s[seg];
        const double want = (seg == special ? special_deg : rate * len) * (TAU / 360);
        assert(fabs(b.recs[i].twist - want) <= 1e-6 * fmax(1, fabs(want)));
    }
    /* A fixed frame of our own: φ right-handed about a. */
    double e[3], z[3];
    const double ex[3] = {1, 0, 0};
    cross3(a, ex, e);
    const double el = sqrt(dot3(e, e));
    for (int k = 0; k < 3; ++k)
        e[k] /= el;
    cross3(e, a, z);
    const double s_ref = 0.35, phi_ref = 0;
    double p[3];
    for (int k = 0; k < 3; ++k)
        p[k] = chain_o[k] + s_ref * a[k] + chain_r * (sin(phi_ref) * e[k] + cos(phi_ref) * z[k]);
    const double u_ref = u_at(&b.ref, p);
    uint64_t rng = 0x7157u;
    double worst = 0, worst_hit = 0;
    int hits = 0;
    for (int i = 0; i < 4000; ++i) {
        const double s = test_rng_uniform(&rng, 0, chain_s[CHAIN - 1]);
        const double phi = test_rng_uniform(&rng, 0, TAU);
        double w[3];
        for (int k = 0; k < 3; ++k) {
            w[k] = sin(phi) * e[k] + cos(phi) * z[k];
            p[k] = chain_o[k] + s * a[k] + chain_r * w[k];
        }
        const double want = (phi - phi_ref + theta(s, rate, special, special_deg) -
                             theta(s_ref, rate, special, special_deg)) / TAU;
        worst = fmax(worst, fabs(wrap(u_at(&b.ref, p) - u_ref - want)));
        /* A ray from outside towards the axis, a little oblique: its hit's
         * u against the analytic u at the hit's (s, φ). */
        double o[3], d[3];
        for (int k = 0; k < 3; ++k) {
            o[k] = p[k] + 3 * w[k] + 0.4 * a[k];
            d[k] = p[k] - o[k];
        }
        meso_ref_frustum_hit hit;
        if (!meso_ref_frusta_intersect(b.ref.segs, b.ref.seg_count, b.ref.balls, b.ref.ball_count, o, d, 0, 10, &hit) ||
            hit.part != MESO_REF_PART_LATERAL)
            continue;
        const double q[3] = {hit.p[0] - chain_o[0], hit.p[1] - chain_o[1], hit.p[2] - chain_o[2]};
        const double hs = dot3(q, a);
        double qr[3];
        for (int k = 0; k < 3; ++k)
            qr[k] = q[k] - hs * a[k];
        const double hphi = atan2(dot3(qr, e), dot3(qr, z));
        const double hwant = (hphi - phi_ref + theta(hs, rate, special, special_deg) -
                              theta(s_ref, rate, special, special_deg)) / TAU;
        worst_hit = fmax(worst_hit, fabs(wrap(hit.u - u_ref - hwant)));
        ++hits;
    }
    fprintf(stderr, "    %-34s %u segments: max |u - analytic| %.2e turns at 4000 surface points, %.2e at %d ray hits\n",
            what, b.count, worst, worst_hit, hits);
    assert(hits > 3000);
    assert(worst < 1e-5 && worst_hit < 1e-5);
    baked_free(&b);
    return fmax(worst, worst_hit);
}

static void test_analytic_helix(void)
{
    helix_case("rate 37 deg/unit", 37, -1, 0);
    helix_case("rate -250 deg/unit", -250, -1, 0);
    helix_case("rate 20, segment 3 twist=120", 20, 2, 120);
    helix_case("no rate, segment 2 twist=-400", 0, 1, -400);
}

/* >>continuity across joints ------------------------------------------------ */

/* Point of segment f's cone on its plane `end` along the generator at angle
 * φ (turns) of f's own frame. */
static void seam_point(const meso_ref_frustum* f, int end, double phi, double X[3])
{
    double a[3] = {f->c1[0] - f->c0[0], f->c1[1] - f->c0[1], f->c1[2] - f->c0[2]}, z[3], w[3];
    const double h = sqrt(dot3(a, a));
    for (int k = 0; k < 3; ++k)
        a[k] /= h;
    cross3(f->frame_x, a, z);
    for (int k = 0; k < 3; ++k)
        w[k] = sin(TAU * phi) * f->frame_x[k] + cos(TAU * phi) * z[k];
    const double kk = (f->r1 - f->r0) / h;
    const double* n = f->plane_n[end];
    const double y = (f->plane_d[end] - dot3(n, f->c0) - f->r0 * dot3(n, w)) / (dot3(n, a) + kk * dot3(n, w));
    for (int k = 0; k < 3; ++k)
        X[k] = f->c0[k] + y * a[k] + (f->r0 + kk * y) * w[k];
}

static double jump(const baked* b, uint32_t fi, uint32_t gi, const double X[3])
{
    double uf, vf, ug, vg;
    meso_ref_frustum_uv(&b->ref.segs[fi], X, &uf, &vf, NULL);
    meso_ref_frustum_uv(&b->ref.segs[gi], X, &ug, &vg, NULL);
    return wrap(uf - ug);
}

/* Every joint where one segment arrives and the next leaves (u runs the
 * same way on both sides), for an untwisted and a twisted bake. `exact`:
 * the untwisted jump is 0 along the whole seam (planar bends), so the
 * twisted one must be too. */
static void continuity_case(const char* what, const char* skel, double rate, int exact)
{
    /* The untwisted bake: no rate and the twist= fields dropped. */
    char plain[8192];
    size_t n = 0;
    for (const char* c = skel; *c && n + 1 < sizeof(plain);) {
        if (!strncmp(c, "twist=", 6)) {
            while (*c && *c != ' ' && *c != '\n')
                ++c;
            continue;
        }
        plain[n++] = *c++;
    }
    plain[n] = '\0';
    baked b0 = bake(plain, 0), bt = bake(skel, rate);
    assert(b0.count == bt.count);
    int joints = 0;
    double aligned_max = 0, shift_spread_max = 0, jump0_max = 0, jumpt_max = 0, spread0_max = 0, spreadt_max = 0;
    for (uint32_t f = 0; f < bt.count; ++f)
        for (int e = 0; e < 2; ++e) {
            const meso_frustum_rec* r = &bt.recs[f];
            if (meso_frustum_rec_end_kind(r, e) != MESO_FSEG_END_JOINT)
                continue;
            const uint32_t g = (uint32_t)r->other[e];
            const int eg = bt.recs[g].other[0] == (int32_t)f ? 0 : 1;
            if (eg == e || bt.recs[g].align_from != (int32_t)f)
                continue; /* u runs opposite ways (both start or both end here), or not aligned from f */
            assert(fabs(bt.recs[f].twist) > 1e-3 && b0.recs[f].twist == 0);
            ++joints;
            /* The aligned point: f's u = 0 generator at its joint end. */
            const meso_ref_frustum* ft = &bt.ref.segs[f];
            double X[3];
            seam_point(ft, e, ft->u_offset - e * ft->twist / TAU, X);
            aligned_max = fmax(aligned_max, fabs(jump(&bt, f, g, X)));
            /* Along the seam: the twisted jump minus the untwisted one is
             * one constant (the aligned point moved), so the seam's u
             * mismatch keeps its shape and spread. */
            double shift_lo = 1, shift_hi = -1, lo0 = 1, hi0 = -1, lot = 1, hit = -1;
            for (int i = 0; i < 256; ++i) {
                seam_point(ft, e, i / 256.0, X); /* same point in both bakes: frames and planes agree */
                const double j0 = jump(&b0, f, g, X), jt = jump(&bt, f, g, X), d = wrap(jt - j0);
                shift_lo = fmin(shift_lo, d);
                shift_hi = fmax(shift_hi, d);
                lo0 = fmin(lo0, j0), hi0 = fmax(hi0, j0);
                lot = fmin(lot, jt), hit = fmax(hit, jt);
                jump0_max = fmax(jump0_max, fabs(j0));
                jumpt_max = fmax(jumpt_max, fabs(jt));
            }
            shift_spread_max = fmax(shift_spread_max, shift_hi - shift_lo);
            spread0_max = fmax(spread0_max, hi0 - lo0);
            spreadt_max = fmax(spreadt_max, hit - lot);
        }
    fprintf(stderr,
            "    %-20s %2d joints, twist %4g deg/unit: |jump| at the aligned point %.1e turns; max |jump| on the seam "
            "%.1e untwisted, %.1e twisted (spread %.1e / %.1e); twisted - untwisted varies by %.1e\n",
            what, joints, rate, aligned_max, jump0_max, jumpt_max, spread0_max, spreadt_max, shift_spread_max);
    assert(joints > 0);
    assert(aligned_max < 1e-5 && shift_spread_max < 1e-5);
    assert(!exact || (jump0_max < 1e-5 && jumpt_max < 1e-5));
    baked_free(&b0);
    baked_free(&bt);
}

static void test_joint_continuity(void)
{
    /* Three segments, each turned 60° from the previous, in a plane. */
    continuity_case("bent chain 60 deg", "0 0 0 0.22\n1 0 0 0.22\n1.5 0.8660254 0 0.22\n1 1.7320508 0 0.22\n", 90, 1);
    /* Tapered, non-planar (the §2.2 fit moves radii). */
    continuity_case("tapered chain", "0 0 0 0.3\n1.2 0 0 0.24\n1.8 1.0 0.1 0.18\n1.3 1.9 0.3 0.12\n", -140, 0);
    continuity_case("tapered, twist= too",
                    "0 0 0 0.3\n1.2 0 0 0.24 twist=200\n1.8 1.0 0.1 0.18\n1.3 1.9 0.3 0.12 twist=-35\n", 45, 0);
    /* The bundled saguaro: two arms (balls at the branch points). */
    FILE* f = fopen(test_data("saguaro.skel"), "rb");
    assert(f);
    static char text[8192];
    const size_t n = fread(text, 1, sizeof(text) - 1, f);
    fclose(f);
    text[n] = '\0';
    continuity_case("saguaro", text, 60, 0);
}

int main(void)
{
    test_temp_dir(tmp_dir, sizeof(tmp_dir), "twist");
    TEST_RUN(test_analytic_helix);
    TEST_RUN(test_joint_continuity);
    test_temp_dir_remove(tmp_dir);
    return 0;
}
