/*
 * test_frusta_seams.c — seams and holes of skinned skeletons (issue #7:
 * "render bent and branching chains and count background pixels inside the
 * silhouette (zero holes); cap intersections at sharp angles reproduced and
 * handled").
 *
 * Every case goes the way a file does: SWC text → frustum model
 * (bake/frustum_model.h) → FRUS/FSEG/BALL records (bake/frusta_chunks.h,
 * which poses them with formats/frusta_pose.c) → the exact CPU reference
 * (meso_ref_frustum_from_rec, meso_ref_frusta_render), no GL.
 *
 * "Inside the silhouette" is defined without the frusta's planes, caps and
 * balls: the ideal shape is the skeleton swept by its cones — per segment
 * the cone between its two nodes with the records' node radii, closed by
 * flat discs ⟂ its axis (the exact signed distance of a capped cone) — plus,
 * at every node that is not a tip, a sphere of the smallest cone radius
 * there (what any closing of the joint must cover). Each pixel's ray (the
 * reference's own, mesoi_ref_pixel_ray) is sphere-traced against the
 * minimum of those distances. A hole is a pixel that the ideal shape covers
 * together with its 8 neighbours (the silhouette minus a 1-pixel border)
 * and the reference leaves background. Reported too: "pokes", covered
 * pixels outside the ideal silhouette grown by one pixel (mitre corners on
 * the outside of a bend do that by construction; a sharp fold with the
 * paper's planes does it a lot).
 *
 * Cases: bent chains of 30°, 60°, 90° and 120° (each bending twice, in and
 * out of plane, with the radius changing along), a node with 3 and one with
 * 4 children, the tapered neurom_fat_end.swc (a radius jump of 0.5 → 13),
 * the 90° chain with relief, and a fold of ~160°: with the paper's planes
 * (keep_cap_intersections = 1) the caps cross and the render shows it;
 * the default handling (a ball joint) removes it.
 *
 * Also: the records through a .meso file and meso_ref_frusta_load give the
 * same model and image (the path `mesoinspect preview --reference` takes).
 *
 * `test_frusta_seams --png FILE` renders at 192 instead of 128 pixels and
 * also writes a picture of some cases (the README's
 * examples/images/frusta_seams.png): holes and inside views tinted red,
 * pokes blue. In the relief
 * case the ideal shape is the cones without relief (relief only adds), so
 * its pokes are the relief itself.
 */
#include <string.h>

#include "frusta_chunks.h"
#include "frustum_model.h"
#include "frustum_reference.h"
#include "png_io.h"
#include "ref_common.h"
#include "skeleton_swc.h"
#include "test_util.h"

#define PI 3.14159265358979323846

static int g_res = 128; /* pixels across a view (192 for the picture) */

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void normalize3(double v[3])
{
    const double l = sqrt(dot3(v, v));
    for (int i = 0; i < 3; ++i)
        v[i] /= l;
}

/* >>scene ------------------------------------------------------------------ */

typedef struct seam_scene {
    meso_ref_frusta fr;  /* the reference's model, from the records */
    float* relief_values;
    uint32_t ncone, nsph;
    double (*cone)[8];   /* ideal shape: node 0, node 1, radius 0, radius 1 */
    double (*sph)[4];    /* ideal shape: centre, radius */
    double lo[3], hi[3]; /* bounds of the ideal shape */
    meso_frustum_stats stats;
} seam_scene;

static void scene_free(seam_scene* s)
{
    meso_ref_frusta_free(&s->fr);
    free(s->cone);
    free(s->sph);
    memset(s, 0, sizeof(*s));
}

/* A smooth relief: bumps of a sum of sines, 32 × 32. */
static float* bumps(void)
{
    float* v = malloc(sizeof(float) * 32 * 32);
    assert(v);
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 32; ++i)
            v[j * 32 + i] = (float)(0.5 + 0.25 * sin(2 * PI * 3 * i / 32) + 0.25 * sin(2 * PI * 2 * j / 32));
    return v;
}

static seam_scene scene_build_obj(const char* swc_text, const char* swc_path, int keep, double relief_depth,
    meso_frusta_object* keep_obj)
{
    meso_skeleton sk;
    meso_error err;
    meso_result r = swc_text ? meso_skeleton_parse_swc(swc_text, strlen(swc_text), &sk, &err)
                             : meso_skeleton_load_swc(swc_path, &sk, &err);
    if (r != MESO_OK)
        fprintf(stderr, "%s\n", err.message);
    assert(r == MESO_OK);
    meso_frustum_model m;
    const meso_frustum_options opt = {.keep_cap_intersections = keep};
    assert(meso_frustum_model_build(&sk, &opt, &m, &err) == MESO_OK);
    meso_frusta_object o;
    const meso_frusta_relief_params rp = {.depth = relief_depth, .u_repeat = 2};
    r = meso_frusta_object_build(&sk, &m, relief_depth > 0 ? &rp : NULL, &o, &err);
    if (r != MESO_OK)
        fprintf(stderr, "%s\n", err.message);
    assert(r == MESO_OK);
    seam_scene s;
    memset(&s, 0, sizeof(s));
    s.stats = m.stats;
    s.fr.seg_count = o.count;
    s.fr.ball_count = o.ball_count;
    s.fr.segs = calloc(o.count, sizeof(*s.fr.segs));
    s.fr.balls = calloc(o.ball_count + 1, sizeof(*s.fr.balls));
    s.cone = calloc(o.count, sizeof(*s.cone));
    s.sph = calloc(2 * (size_t)o.count, sizeof(*s.sph));
    assert(s.fr.segs && s.fr.balls && s.cone && s.sph);
    for (int k = 0; k < 3; ++k) {
        s.lo[k] = INFINITY;
        s.hi[k] = -INFINITY;
    }
    for (uint32_t i = 0; i < o.count; ++i) {
        const meso_frustum_rec* rec = &o.recs[i];
        meso_ref_frustum_from_rec(rec, &s.fr.segs[i]);
        for (int e = 0; e < 2; ++e) {
            const float* P = &o.node_pos[3 * (size_t)rec->node[e]];
            for (int k = 0; k < 3; ++k) {
                s.cone[i][3 * e + k] = P[k];
                s.lo[k] = fmin(s.lo[k], P[k] - rec->node_radius[e] - relief_depth);
                s.hi[k] = fmax(s.hi[k], P[k] + rec->node_radius[e] + relief_depth);
            }
            s.cone[i][6 + e] = rec->node_radius[e];
            if (meso_frustum_rec_end_kind(rec, e) == MESO_FSEG_END_TIP)
                continue;
            /* one sphere per node, of the smallest cone radius there */
            uint32_t k = 0;
            while (k < s.nsph && !(s.sph[k][0] == P[0] && s.sph[k][1] == P[1] && s.sph[k][2] == P[2]))
                ++k;
            if (k == s.nsph) {
                s.sph[k][0] = P[0];
                s.sph[k][1] = P[1];
                s.sph[k][2] = P[2];
                s.sph[k][3] = INFINITY;
                ++s.nsph;
            }
            s.sph[k][3] = fmin(s.sph[k][3], rec->node_radius[e]);
        }
    }
    s.ncone = o.count;
    for (uint32_t b = 0; b < o.ball_count; ++b)
        meso_ref_ball_from_rec(&o.balls[b], &s.fr.balls[b]);
    if (relief_depth > 0) {
        s.relief_values = bumps();
        s.fr.relief_values = s.relief_values; /* freed by meso_ref_frusta_free */
        s.fr.relief.height = (meso_ref_texfn){.kind = 1, .w = 32, .h = 32, .d = 1, .values = s.relief_values};
    }
    if (keep_obj)
        *keep_obj = o;
    else
        meso_frusta_object_free(&o);
    meso_frustum_model_free(&m);
    meso_skeleton_free(&sk);
    return s;
}

static seam_scene scene_build(const char* swc_text, const char* swc_path, int keep, double relief_depth)
{
    return scene_build_obj(swc_text, swc_path, keep, relief_depth, NULL);
}

/* >>ideal shape ------------------------------------------------------------ */

/* Exact signed distance to a cone between a and b (radii ra, rb) closed by
 * flat discs ⟂ its axis (Quílez's capped cone). */
static double sd_capped_cone(const double p[3], const double c[8])
{
    const double ba[3] = {c[3] - c[0], c[4] - c[1], c[5] - c[2]}, pa[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const double ra = c[6], rb = c[7], rba = rb - ra, baba = dot3(ba, ba), papa = dot3(pa, pa);
    const double paba = dot3(pa, ba) / baba;
    const double x = sqrt(fmax(0.0, papa - paba * paba * baba));
    const double cax = fmax(0.0, x - (paba < 0.5 ? ra : rb)), cay = fabs(paba - 0.5) - 0.5;
    const double k = rba * rba + baba;
    const double f = fmin(fmax((rba * (x - ra) + paba * baba) / k, 0.0), 1.0);
    const double cbx = x - ra - f * rba, cby = paba - f;
    const double sg = (cbx < 0 && cay < 0) ? -1.0 : 1.0;
    return sg * sqrt(fmin(cax * cax + cay * cay * baba, cbx * cbx + cby * cby * baba));
}

static double sd_ideal(const seam_scene* s, const double p[3])
{
    double d = INFINITY;
    for (uint32_t i = 0; i < s->ncone; ++i)
        d = fmin(d, sd_capped_cone(p, s->cone[i]));
    for (uint32_t i = 0; i < s->nsph; ++i) {
        const double q[3] = {p[0] - s->sph[i][0], p[1] - s->sph[i][1], p[2] - s->sph[i][2]};
        d = fmin(d, sqrt(dot3(q, q)) - s->sph[i][3]);
    }
    return d;
}

/* Sphere tracing of the ray o + t d, t ∈ [0, 1]: 1 when it reaches the
 * ideal shape (distance below 1e-7 of the scene's size). */
static int trace_ideal(const seam_scene* s, const double o[3], const double d[3], double scale)
{
    const double dl = sqrt(dot3(d, d));
    double t = 0;
    for (int it = 0; it < 4000 && t <= dl; ++it) {
        const double p[3] = {o[0] + t / dl * d[0], o[1] + t / dl * d[1], o[2] + t / dl * d[2]};
        const double sd = sd_ideal(s, p);
        if (sd < 1e-7 * scale)
            return 1;
        t += sd;
    }
    return 0;
}

/* >>renders ---------------------------------------------------------------- */

typedef struct seam_stats {
    int ideal;  /* pixels the ideal shape covers */
    int covered;/* pixels the reference covers */
    int holes;  /* ideal with all 8 neighbours, reference background */
    int border; /* ideal but not with all neighbours, reference background (not holes) */
    int pokes;  /* reference covered, ideal grown by 1 px not */
    int inside; /* the first hit is a surface seen from inside (a crack or open end seen through) */
} seam_stats;

/* Orthographic view along `dir` framing the scene's bounds. */
static meso_ref_view ortho_view(const seam_scene* s, const double dir_in[3])
{
    double f[3] = {dir_in[0], dir_in[1], dir_in[2]}, up0[3] = {0, 1, 0}, ctr[3], ext = 0;
    normalize3(f);
    if (fabs(f[1]) > 0.9) {
        up0[1] = 0;
        up0[2] = 1;
    }
    double r[3] = {f[1] * up0[2] - f[2] * up0[1], f[2] * up0[0] - f[0] * up0[2], f[0] * up0[1] - f[1] * up0[0]};
    normalize3(r);
    const double u[3] = {r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]};
    for (int k = 0; k < 3; ++k) {
        ctr[k] = 0.5 * (s->lo[k] + s->hi[k]);
        ext += (s->hi[k] - s->lo[k]) * (s->hi[k] - s->lo[k]);
    }
    ext = 0.5 * sqrt(ext) * 1.05;
    meso_ref_view v;
    memset(&v, 0, sizeof(v));
    v.width = v.height = g_res;
    for (int k = 0; k < 3; ++k) { /* rows of the view matrix: r, u, −f; eye at ctr − 2 ext f */
        v.view[4 * k + 0] = r[k];
        v.view[4 * k + 1] = u[k];
        v.view[4 * k + 2] = -f[k];
    }
    const double eye[3] = {ctr[0] - 2 * ext * f[0], ctr[1] - 2 * ext * f[1], ctr[2] - 2 * ext * f[2]};
    v.view[12] = -dot3(r, eye);
    v.view[13] = -dot3(u, eye);
    v.view[14] = dot3(f, eye);
    v.view[15] = 1;
    const double zn = ext, zf = 3 * ext; /* glOrtho(−ext, ext, −ext, ext, zn, zf) */
    v.proj[0] = v.proj[5] = 1 / ext;
    v.proj[10] = -2 / (zf - zn);
    v.proj[14] = -(zf + zn) / (zf - zn);
    v.proj[15] = 1;
    return v;
}

/* Renders one view; `rgba` (g_res × g_res, rows top to bottom) gets the picture
 * with holes red and pokes blue when non-NULL. */
static seam_stats render_view(const seam_scene* s, const double dir[3], uint8_t* rgba)
{
    const meso_ref_view v = ortho_view(s, dir);
    meso_ref_image img;
    assert(meso_ref_frusta_render(&s->fr, &v, &img) == MESO_OK);
    mesoi_ref_camera cam;
    assert(mesoi_ref_camera_init(&v, &cam));
    double scale = 0;
    for (int k = 0; k < 3; ++k)
        scale = fmax(scale, s->hi[k] - s->lo[k]);
    uint8_t* ideal = malloc((size_t)g_res * g_res);
    assert(ideal);
    for (int y = 0; y < g_res; ++y)
        for (int x = 0; x < g_res; ++x) {
            double o[3], d[3];
            mesoi_ref_pixel_ray(&cam, x, y, g_res, g_res, o, d);
            ideal[y * g_res + x] = (uint8_t)trace_ideal(s, o, d, scale);
        }
    seam_stats st = {0};
    for (int y = 0; y < g_res; ++y)
        for (int x = 0; x < g_res; ++x) {
            const int i = y * g_res + x;
            int all = 1, any = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    const int in = xx >= 0 && yy >= 0 && xx < g_res && yy < g_res && ideal[yy * g_res + xx];
                    all &= in;
                    any |= in;
                }
            const int cov = img.coverage[i] != 0;
            double o[3], d[3];
            mesoi_ref_pixel_ray(&cam, x, y, g_res, g_res, o, d);
            meso_ref_frustum_hit h;
            const int got = meso_ref_frusta_intersect_relief(s->fr.segs, s->fr.seg_count, s->fr.balls,
                s->fr.ball_count, &s->fr.relief, o, d, 0, 1, &h);
            assert(got == cov); /* the render's hierarchy and the plain loop agree */
            const int inside = got && dot3(h.normal, d) > 0;
            st.inside += inside;
            st.ideal += ideal[i];
            st.covered += cov;
            const int hole = all && !cov, poke = cov && !any && !inside;
            st.holes += hole;
            st.border += ideal[i] && !all && !cov;
            st.pokes += poke;
            if (rgba) {
                uint8_t* p = rgba + 4 * ((size_t)(g_res - 1 - y) * g_res + (size_t)x); /* top row first */
                for (int k = 0; k < 3; ++k) {
                    const double bg[3] = {0.18, 0.20, 0.24};
                    p[k] = (uint8_t)lrint(255 * fmin(1.0, cov ? img.rgb[3 * i + k] : bg[k]));
                }
                p[3] = 255;
                if (hole || inside || poke) { /* tinted: red defects, blue pokes */
                    const int k = poke && !hole && !inside ? 2 : 0;
                    for (int c = 0; c < 3; ++c)
                        p[c] = (uint8_t)(c == k ? 128 + p[c] / 2 : p[c] / 3);
                }
            }
        }
    meso_ref_image_free(&img);
    free(ideal);
    return st;
}

static const double views[3][3] = {{0, 0, -1}, {0.3, -0.2, -1}, {-1, 0.4, 0.2}};

/* Renders the three views (view `tile_view` into `tile`); returns the
 * totals and asserts nothing. */
static seam_stats render_case(const char* name, const seam_scene* s, uint8_t* tile, int tile_view)
{
    seam_stats tot = {0};
    for (int v = 0; v < 3; ++v) {
        const seam_stats st = render_view(s, views[v], v == tile_view ? tile : NULL);
        fprintf(stderr,
            "    %-26s view %d: ideal %5d px, covered %5d, holes %3d (border misses %3d), seen from inside %3d, "
            "pokes %4d\n",
            name, v, st.ideal, st.covered, st.holes, st.border, st.inside, st.pokes);
        assert(st.ideal > 300);
        tot.ideal += st.ideal;
        tot.covered += st.covered;
        tot.holes += st.holes;
        tot.border += st.border;
        tot.pokes += st.pokes;
        tot.inside += st.inside;
    }
    return tot;
}

/* >>cases ------------------------------------------------------------------ */

/* The picture: tiles of the middle view, 4 across. */
#define TILES 8
static uint8_t* g_tiles[TILES];
static const char* g_tile_names[TILES];
static int g_tile_count;

static uint8_t* next_tile(const char* name)
{
    if (g_tile_count == TILES)
        return NULL;
    g_tile_names[g_tile_count] = name;
    g_tiles[g_tile_count] = calloc((size_t)g_res * g_res, 4);
    return g_tiles[g_tile_count++];
}

/* A chain O → J1 → J2 → E bending by `deg` at J1 (in the xy plane) and
 * again at J2 (out of it), radii 0.35, 0.3, 0.22, 0.28. */
static void bent_chain_swc(double deg, char* out, size_t n)
{
    const double a = deg * PI / 180;
    const double j1[3] = {1.6, 0, 0};
    const double d1[3] = {cos(a), sin(a), 0};
    const double j2[3] = {j1[0] + 1.4 * d1[0], j1[1] + 1.4 * d1[1], 0};
    /* second bend: d1 turned by `deg` towards +z */
    const double zz[3] = {0, 0, 1};
    double d2[3];
    for (int k = 0; k < 3; ++k)
        d2[k] = cos(a) * d1[k] + sin(a) * zz[k];
    const double e[3] = {j2[0] + 1.5 * d2[0], j2[1] + 1.5 * d2[1], j2[2] + 1.5 * d2[2]};
    snprintf(out, n,
        "1 1 0 0 0 0.35 -1\n2 1 %.6f %.6f %.6f 0.3 1\n3 1 %.6f %.6f %.6f 0.22 2\n4 1 %.6f %.6f %.6f 0.28 3\n", j1[0],
        j1[1], j1[2], j2[0], j2[1], j2[2], e[0], e[1], e[2]);
}

static void test_bent_chains(void)
{
    const double angles[4] = {30, 60, 90, 120};
    for (int i = 0; i < 4; ++i) {
        char swc[512], name[64];
        bent_chain_swc(angles[i], swc, sizeof(swc));
        seam_scene s = scene_build(swc, NULL, 0, 0);
        snprintf(name, sizeof(name), "bent chain %.0f deg", angles[i]);
        fprintf(stderr, "    %s: %u joints, %u ball joints, cap intersections found %u\n", name, s.stats.joints,
            s.stats.ball_joints, s.stats.cap_intersections_found);
        const seam_stats st = render_case(name, &s, i % 2 ? next_tile(i == 1 ? "bent 60" : "bent 120") : NULL, 1);
        assert(st.holes == 0 && st.inside == 0);
        scene_free(&s);
    }
}

static void test_branches(void)
{
    /* a node (2) with a parent and 3 children; a node (2) with 4 children */
    const char* three = "1 1 0 0 0 0.3 -1\n2 1 1.5 0 0 0.32 1\n3 1 2.6 0.9 0.2 0.2 2\n4 1 2.5 -1.0 -0.1 0.25 2\n"
                        "5 1 2.7 0.1 1.0 0.15 2\n";
    const char* four = "1 1 0 0 0 0.3 -1\n2 1 1.5 0 0 0.35 1\n3 1 2.6 0.9 0.2 0.2 2\n4 1 2.5 -1.0 -0.1 0.25 2\n"
                       "5 1 2.7 0.1 1.0 0.15 2\n6 1 2.2 0.2 -1.1 0.22 2\n";
    seam_scene s = scene_build(three, NULL, 0, 0);
    assert(s.stats.branch_points == 1 && s.fr.ball_count == 1);
    seam_stats st = render_case("node with 3 children", &s, next_tile("3 children"), 1);
    assert(st.holes == 0 && st.inside == 0);
    scene_free(&s);
    s = scene_build(four, NULL, 0, 0);
    assert(s.stats.branch_points == 1 && s.fr.ball_count == 1);
    st = render_case("node with 4 children", &s, next_tile("4 children"), 1);
    assert(st.holes == 0 && st.inside == 0);
    scene_free(&s);
    /* An arrowhead: two children fold back at 150° from the parent. Most
     * branch points close themselves (every cone starts with the node's
     * radius there); this one needs its ball. */
    s = scene_build("1 1 0 0 0 0.3 -1\n2 1 1.5 0 0 0.3 1\n3 1 0.4 0.64 0 0.25 2\n4 1 0.4 -0.64 0 0.25 2\n", NULL, 0,
        0);
    assert(s.stats.branch_points == 1 && s.fr.ball_count == 1);
    st = render_case("arrowhead", &s, NULL, 1);
    assert(st.holes == 0 && st.inside == 0);
    /* The counts see defects: without its ball the parent's open end shows. */
    s.fr.ball_count = 0;
    st = render_case("arrowhead, ball removed", &s, NULL, 1);
    assert(st.inside >= 20);
    scene_free(&s);
}

static void test_tapered(void)
{
    seam_scene s = scene_build(NULL, test_data("neurom_fat_end.swc"), 0, 0);
    const seam_stats st = render_case("neurom_fat_end.swc", &s, next_tile("fat end"), 2);
    assert(st.holes == 0 && st.inside == 0);
    scene_free(&s);
}

static void test_relief(void)
{
    char swc[512];
    bent_chain_swc(90, swc, sizeof(swc));
    seam_scene s = scene_build(swc, NULL, 0, 0.08);
    const seam_stats st = render_case("bent chain 90 deg, relief", &s, next_tile("relief"), 1);
    assert(st.holes == 0 && st.inside == 0);
    scene_free(&s);
}

/* A fold of ~160° with thick, short segments: the paper's joint plane
 * crosses both segments' other planes inside their cones. */
static void test_cap_intersection(void)
{
    const char* fold = "1 1 0 0 0 0.4 -1\n2 1 1 0 0 0.4 1\n3 1 0.06 0.35 0 0.4 2\n";
    seam_scene keep = scene_build(fold, NULL, 1, 0);
    fprintf(stderr, "    fold, paper's planes: cap intersections found %u, unhandled %u\n",
        keep.stats.cap_intersections_found, keep.stats.cap_intersections_unhandled);
    assert(keep.stats.cap_intersections_found >= 1 && keep.fr.ball_count == 0);
    const seam_stats bad = render_case("fold, paper's planes", &keep, next_tile("fold, paper's planes"), 2);
    seam_scene fixed = scene_build(fold, NULL, 0, 0);
    fprintf(stderr, "    fold, handled: ball joints %u, balls %u\n", fixed.stats.ball_joints, fixed.fr.ball_count);
    assert(fixed.stats.ball_joints == 1 && fixed.fr.ball_count == 1);
    const seam_stats good = render_case("fold, handled", &fixed, next_tile("fold, handled"), 2);
    fprintf(stderr, "    fold: holes %d -> %d, seen from inside %d -> %d, pokes %d -> %d (three views)\n", bad.holes,
        good.holes, bad.inside, good.inside, bad.pokes, good.pokes);
    /* The defect is visible — pixels missing inside the silhouette, the
     * inside of a segment seen through its crossed caps, surface far outside
     * the silhouette — and the handling removes it. */
    assert(bad.holes > 0 && bad.inside >= 50 && bad.pokes >= 50);
    assert(good.holes == 0 && good.inside == 0 && good.pokes == 0);
    scene_free(&keep);
    scene_free(&fixed);
}

/* >>files ------------------------------------------------------------------ */

static void add_chunk(meso_writer* w, uint32_t type, uint32_t flags, uint16_t dtype, uint32_t n0, uint32_t n1,
    const void* data, size_t size)
{
    meso_error err;
    const meso_chunk_desc d = {.type = type, .flags = flags, .object = type == MESO_CHUNK_OBJT ? 0 : 7,
        .dtype = dtype, .components = 1, .dims = {n0, n1, 1}};
    const meso_result r = meso_writer_add(w, &d, data, size, &err);
    if (r != MESO_OK)
        fprintf(stderr, "%s\n", err.message);
    assert(r == MESO_OK);
}

/* The records through a .meso file (FRUS, FSEG, BALL, RELF as U16, object
 * 7) and meso_ref_frusta_load: the same segments, balls and height field
 * as converting the records directly, hence the same image. */
static void test_file_round_trip(void)
{
    char swc[512];
    bent_chain_swc(60, swc, sizeof(swc));
    /* a branch too, so there is a ball */
    strcat(swc, "5 1 1.6 -1.2 0.3 0.2 2\n");
    meso_frusta_object o;
    seam_scene s = scene_build_obj(swc, NULL, 0, 0.08, &o);
    assert(o.ball_count >= 1);
    uint8_t *frus = NULL, *fseg = NULL, *ball = NULL;
    meso_error err;
    assert(meso_frusta_object_encode(&o, &frus, &fseg, &ball, &err) == MESO_OK);
    uint16_t relf[32 * 32];
    for (int i = 0; i < 32 * 32; ++i) /* the scene's bumps, quantised */
        relf[i] = (uint16_t)lrint(s.relief_values[i] * 65535.0);
    meso_object_record rec = {.id = 7, .kind = MESO_OBJECT_FRUSTA};
    for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = (float)s.lo[k];
        rec.bbox_max[k] = (float)s.hi[k];
    }
    snprintf(rec.name, sizeof(rec.name), "round trip");
    uint8_t objt[64];
    meso_object_record_encode(&rec, objt);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    add_chunk(w, MESO_CHUNK_OBJT, MESO_CHUNK_FLAG_REQUIRED, MESO_DTYPE_BYTES, 1, 1, objt, sizeof(objt));
    add_chunk(w, MESO_CHUNK_FRUS, MESO_CHUNK_FLAG_REQUIRED, MESO_DTYPE_BYTES, o.count, 1, frus,
        (size_t)o.count * MESO_FRUS_RECORD_SIZE);
    add_chunk(w, MESO_CHUNK_FSEG, MESO_CHUNK_FLAG_REQUIRED, MESO_DTYPE_BYTES, o.count, 1, fseg,
        (size_t)o.count * MESO_FSEG_RECORD_SIZE);
    add_chunk(w, MESO_CHUNK_BALL, MESO_CHUNK_FLAG_REQUIRED, MESO_DTYPE_BYTES, o.ball_count, 1, ball,
        (size_t)o.ball_count * MESO_BALL_RECORD_SIZE);
    add_chunk(w, MESO_CHUNK_RELF, 0, MESO_DTYPE_U16, 32, 32, relf, sizeof(relf));
    size_t size = 0;
    assert(meso_writer_finish(w, NULL, 0, &size) == MESO_OK);
    uint8_t* bytes = malloc(size);
    assert(bytes && meso_writer_finish(w, bytes, size, &size) == MESO_OK);
    meso_writer_destroy(w);
    meso_file* f = NULL;
    assert(meso_file_open_memory(bytes, size, NULL, &f, &err) == MESO_OK);
    meso_ref_frusta fr;
    assert(meso_ref_frusta_load(f, 7, &fr, &err) == MESO_OK);
    assert(fr.seg_count == s.fr.seg_count && fr.ball_count == s.fr.ball_count);
    assert(!memcmp(fr.segs, s.fr.segs, sizeof(*fr.segs) * fr.seg_count));
    assert(!memcmp(fr.balls, s.fr.balls, sizeof(*fr.balls) * fr.ball_count));
    assert(fr.relief.height.kind == 1 && fr.relief.height.w == 32 && fr.relief.height.h == 32);
    double qerr = 0;
    for (int i = 0; i < 32 * 32; ++i)
        qerr = fmax(qerr, fabs(fr.relief_values[i] - s.relief_values[i]));
    assert(qerr <= 0.5 / 65535 + 1e-7);
    for (int k = 0; k < 3; ++k)
        assert(fr.bbox_min[k] == rec.bbox_min[k] && fr.bbox_max[k] == rec.bbox_max[k]);
    /* the same image, once the height field is the quantised one */
    for (int i = 0; i < 32 * 32; ++i)
        s.relief_values[i] = fr.relief_values[i];
    const meso_ref_view v = ortho_view(&s, views[1]);
    meso_ref_image a, b;
    assert(meso_ref_frusta_render(&fr, &v, &a) == MESO_OK && meso_ref_frusta_render(&s.fr, &v, &b) == MESO_OK);
    const size_t npx = (size_t)v.width * (size_t)v.height;
    assert(!memcmp(a.rgb, b.rgb, sizeof(float) * 3 * npx) && !memcmp(a.depth, b.depth, sizeof(float) * npx));
    int covered = 0;
    for (size_t i = 0; i < npx; ++i)
        covered += a.coverage[i];
    fprintf(stderr, "    %u frusta, %u balls, RELF 32x32 U16 (quantisation %.1e): identical %dx%d image, %d px covered\n",
        fr.seg_count, fr.ball_count, qerr, v.width, v.height, covered);
    assert(covered > 500);
    meso_ref_image_free(&a);
    meso_ref_image_free(&b);
    /* refusals: no such object, no file */
    meso_ref_frusta none;
    assert(meso_ref_frusta_load(f, 8, &none, &err) == MESO_ERR_NOT_FOUND);
    assert(meso_ref_frusta_load(NULL, 7, &none, &err) == MESO_ERR_INVALID_ARG);
    meso_ref_frusta_free(&fr);
    meso_file_close(f);
    free(bytes);
    free(frus);
    free(fseg);
    free(ball);
    meso_frusta_object_free(&o);
    scene_free(&s);
}

static void write_png(const char* path)
{
    const int cols = 4, rows = (g_tile_count + cols - 1) / cols, W = cols * g_res, H = rows * g_res;
    uint8_t* img = calloc((size_t)W * H, 4);
    assert(img);
    for (int t = 0; t < g_tile_count; ++t)
        for (int y = 0; y < g_res; ++y)
            memcpy(img + 4 * ((size_t)(t / cols * g_res + y) * W + (size_t)(t % cols * g_res)),
                g_tiles[t] + 4 * (size_t)y * g_res, 4 * (size_t)g_res);
    char why[256];
    assert(meso_png_write_rgba8(path, img, W, H, 0, why, sizeof(why)) == 0);
    fprintf(stderr, "  wrote %s:", path);
    for (int t = 0; t < g_tile_count; ++t)
        fprintf(stderr, " [%s]", g_tile_names[t]);
    fprintf(stderr, "\n");
    free(img);
}

int main(int argc, char** argv)
{
    const int png = argc == 3 && !strcmp(argv[1], "--png");
    if (png)
        g_res = 192;
    TEST_RUN(test_bent_chains);
    TEST_RUN(test_branches);
    TEST_RUN(test_tapered);
    TEST_RUN(test_relief);
    TEST_RUN(test_cap_intersection);
    TEST_RUN(test_file_round_trip);
    if (png)
        write_png(argv[2]);
    for (int t = 0; t < g_tile_count; ++t)
        free(g_tiles[t]);
    return 0;
}
