/* A frusta object's levels (FORMAT.md §7.10).
 *
 * Native relief levels (the relief map halved, bake/height_field_levels.h):
 * every point of a level the reference hits lies within the level's stated
 * error of level 0's surface over the same (u, v) (found by Newton's method
 * on the reference's own relief coordinates, not the bake's bound), and the
 * other way; the farthest reaches a fair part of it.
 *
 * Mesh stand-ins (bake/frusta_standin.h, bake/standin_levels.h): the
 * first the triangle tessellation drawn in the frusta's place, the next
 * its simplifications, each with the error mesobake states for it; the
 * first and the coarsest are checked against the exact CPU reference both
 * ways:
 *  - native to stand-in: every surface point the reference ray caster hits,
 *    from several views, lies within the stated error of the stand-in mesh
 *    (brute force over its triangles);
 *  - stand-in to native: from points spread over the stand-in's triangles
 *    (corners, edge midpoints, centroids), a reference ray along the
 *    triangle's normal, forwards and backwards, meets the native surface
 *    within the stated error (the distance to the surface is at most that
 *    ray's length).
 * And the bound is not loose (the farthest of either reaches a good part of
 * it), the file validates in the full tier, the stand-in is small, and
 * `--levels 1` writes one level and no LODS while the report lists
 * "levels". Bundled skeletons: the saguaro with a brick relief and a
 * twist, a neuron plain.
 * usage: test_frusta_standin MESOBAKE */
#include "test_util.h"

#include <string.h>

#include "frusta_views.h"
#include "meso_file.h"
#include "meso_layout.h"
#include "standin_check.h"

static double standin_distance(const double q[3], const meso_mesh_view* mv)
{
    double d = INFINITY;
    const uint32_t tris = mv->layout.index_count / 3;
    for (uint32_t k = 0; k < tris; ++k)
        d = fmin(d, point_triangle(q, mv->positions + 3 * mv->indices[3 * k],
                                        mv->positions + 3 * mv->indices[3 * k + 1],
                                        mv->positions + 3 * mv->indices[3 * k + 2]));
    return d;
}

/* Shortest reference ray from q along ±n to the native surface (INFINITY
 * when neither meets it within tmax). */
static double native_distance(const meso_ref_frusta* m, const double q[3], const double n[3], double tmax)
{
    double best = INFINITY;
    for (int s = -1; s <= 1; s += 2) {
        const double d[3] = {s * n[0], s * n[1], s * n[2]};
        meso_ref_frustum_hit h;
        if (meso_ref_frusta_intersect_relief(m->segs, m->seg_count, m->balls, m->ball_count, &m->relief, q, d, 0,
                                             tmax, &h))
            best = fmin(best, h.t);
    }
    return best;
}

/* Level L's mesh against the native surface, both ways. The first
 * stand-in's (level `first`, after any native relief levels) points are
 * taken to the native surface by reference rays along their normals; a
 * coarser level's, which may span gaps the normal ray misses, to the first
 * stand-in's mesh (brute force) plus its error, checked here too: the
 * triangle inequality makes the sum a distance bound to the native
 * surface. */
static void check_level(meso_file* f, const meso_level_info* li, uint32_t L, uint32_t first, const char* name,
                        const meso_mesh_view* level1)
{
    const double err = li[L].rec.error;
    meso_mesh_view mv;
    uint8_t* mb = test_read_level_mesh(f, (uint16_t)L, &mv);
    const uint32_t tris = mv.layout.index_count / 3;
    assert(tris > 0 && tris < 20000); /* cheap: a polygon stand-in, not the 256k of the paper's Figure 6 */

    meso_ref_frusta rm;
    assert(meso_ref_frusta_load(f, 1, &rm, NULL) == MESO_OK);
    double radius = 0;
    for (int k = 0; k < 3; ++k)
        radius += 0.25 * ((double)rm.bbox_max[k] - rm.bbox_min[k]) * ((double)rm.bbox_max[k] - rm.bbox_min[k]);
    radius = sqrt(radius);
    /* Native to stand-in. */
    double worst_native = 0;
    size_t hits = 0;
    for (int e = 0; e < 3; ++e) {
        const meso_ref_view v = test_frusta_view(&rm, e, 40, 1);
        meso_ref_image img;
        assert(meso_ref_frusta_render(&rm, &v, &img) == MESO_OK);
        for (int p = 0; p < v.width * v.height; ++p) {
            if (!img.coverage[p])
                continue;
            const double q[3] = {img.hit[3 * p], img.hit[3 * p + 1], img.hit[3 * p + 2]};
            worst_native = fmax(worst_native, standin_distance(q, &mv));
            ++hits;
        }
        meso_ref_image_free(&img);
    }
    /* Stand-in to native: corners, edge midpoints and centroid of every
     * k-th triangle (about 300 triangles); on a mesh of fewer than 100
     * triangles, a grid of 21 points on each (barycentric fifths). */
    double worst_standin = 0;
    size_t samples = 0;
    const uint32_t stride = tris / 300 + 1;
    static const double few[7][3] = {{1, 0, 0},   {0, 1, 0},   {0, 0, 1},               {.5, .5, 0},
                                     {0, .5, .5}, {.5, 0, .5}, {1. / 3, 1. / 3, 1. / 3}};
    double bary[21][3];
    int nb = 0;
    if (tris >= 100) {
        memcpy(bary, few, sizeof few);
        nb = 7;
    } else {
        for (int i = 0; i <= 5; ++i)
            for (int j = 0; i + j <= 5; ++j) {
                bary[nb][0] = i / 5.0;
                bary[nb][1] = j / 5.0;
                bary[nb++][2] = (5 - i - j) / 5.0;
            }
    }
    for (uint32_t t = 0; t < tris; t += stride) {
        const float* P[3] = {mv.positions + 3 * mv.indices[3 * t], mv.positions + 3 * mv.indices[3 * t + 1],
                             mv.positions + 3 * mv.indices[3 * t + 2]};
        double e1[3], e2[3], nrm[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)P[1][k] - P[0][k];
            e2[k] = (double)P[2][k] - P[0][k];
        }
        nrm[0] = e1[1] * e2[2] - e1[2] * e2[1];
        nrm[1] = e1[2] * e2[0] - e1[0] * e2[2];
        nrm[2] = e1[0] * e2[1] - e1[1] * e2[0];
        const double nl = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        assert(nl > 0); /* the bake drops degenerate triangles */
        for (int s = 0; s < nb; ++s) {
            double q[3], nn[3];
            for (int k = 0; k < 3; ++k) {
                q[k] = bary[s][0] * P[0][k] + bary[s][1] * P[1][k] + bary[s][2] * P[2][k];
                nn[k] = nrm[k] / nl;
            }
            worst_standin = fmax(worst_standin, !level1 ? native_distance(&rm, q, nn, 4 * err)
                                                        : standin_distance(q, level1) + li[first].rec.error);
            ++samples;
        }
    }
    printf("  %-8s level %u, %u triangles, stated error %.6g (%.3g %% of the radius); native hits %zu, farthest "
           "%.6g (%.0f %%); stand-in samples %zu, farthest %.6g (%.0f %%)\n",
           name, L, tris, err, 100 * err / radius, hits, worst_native, 100 * worst_native / err, samples,
           worst_standin, 100 * worst_standin / err);
    fflush(stdout);
    assert(hits > 500 && samples > 500);
    assert(worst_native <= err * (1 + 1e-5)); /* the stated error holds, */
    assert(worst_standin <= err * (1 + 1e-5)); /* both ways */
    assert(fmax(worst_native, worst_standin) >= 0.3 * err); /* and is not a loose guess */
    meso_ref_frusta_free(&rm);
    free(mb);
}

/* >>native relief levels (bake/height_field_levels.h, bake/bake_frusta.c):
 * the point over the same (u, v) of the same frustum at relief height w,
 * found by Newton's method on meso_ref_frustum_relief_coords (the
 * reference's own parametrisation, not the bake's gain): q with
 * (s, t, w)(q) = (s_p, t_p, w), s compared modulo the frustum's u_scale.
 * Returns 0 when it does not converge. */
static int column_point(const meso_ref_frustum* f, const double p[3], double sp, double tp, double w, double q[3])
{
    double x[3] = {p[0], p[1], p[2]};
    const double eps = 1e-7 * (1 + fmax(f->r0, f->r1));
    for (int it = 0; it < 40; ++it) {
        double F[3], J[3][3];
        meso_ref_frustum_relief_coords(f, x, &F[0], &F[1], &F[2]);
        F[0] -= sp;
        F[0] -= f->u_scale * round(F[0] / f->u_scale);
        F[1] -= tp;
        F[2] -= w;
        if (fabs(F[0]) + fabs(F[1]) + fabs(F[2]) < 1e-12) {
            memcpy(q, x, sizeof x);
            return 1;
        }
        for (int k = 0; k < 3; ++k) {
            double y[3] = {x[0], x[1], x[2]}, G[3];
            y[k] += eps;
            meso_ref_frustum_relief_coords(f, y, &G[0], &G[1], &G[2]);
            G[0] -= sp;
            G[0] -= f->u_scale * round(G[0] / f->u_scale);
            G[1] -= tp;
            G[2] -= w;
            for (int r = 0; r < 3; ++r)
                J[r][k] = (G[r] - F[r]) / eps;
        }
        /* Solve J dx = -F (Cramer). */
        const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                           J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                           J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
        if (!(fabs(det) > 0))
            return 0;
        for (int k = 0; k < 3; ++k) {
            double M[3][3];
            memcpy(M, J, sizeof M);
            for (int r = 0; r < 3; ++r)
                M[r][k] = -F[r];
            x[k] += (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
                     M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0])) / det;
        }
    }
    return 0;
}

/* The farthest of `from`'s relief hits (rays from three views) from the
 * surface of `to` over the same (u, v): both levels share the frusta, so
 * a ball hit is on both and a lateral relief hit at height w_p has the
 * other's point at height h_to(s, t) in its column. Cap hits are counted
 * apart (a cap's relief is its rim's, not in a column). */
static double farthest_column(const meso_ref_frusta* from, const meso_ref_frusta* to, size_t* hits, size_t* skipped)
{
    double c[3], radius = 0, worst = 0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)from->bbox_min[k] + from->bbox_max[k]);
        radius += 0.25 * ((double)from->bbox_max[k] - from->bbox_min[k]) * ((double)from->bbox_max[k] - from->bbox_min[k]);
    }
    radius = sqrt(radius);
    static const double dirs[3][3] = {{0, 0.1, 1}, {0.8, 0.45, -0.4}, {-0.6, -0.7, 0.4}};
    enum { N = 80 };
    for (int e = 0; e < 3; ++e) {
        const double dl = sqrt(dirs[e][0] * dirs[e][0] + dirs[e][1] * dirs[e][1] + dirs[e][2] * dirs[e][2]);
        double eye[3], fw[3], rt[3], up[3];
        for (int k = 0; k < 3; ++k) {
            eye[k] = c[k] + 2.6 * radius * dirs[e][k] / dl;
            fw[k] = -dirs[e][k] / dl;
        }
        const double ref_up[3] = {0, 1, 0};
        rt[0] = fw[1] * ref_up[2] - fw[2] * ref_up[1];
        rt[1] = fw[2] * ref_up[0] - fw[0] * ref_up[2];
        rt[2] = fw[0] * ref_up[1] - fw[1] * ref_up[0];
        const double rl = sqrt(rt[0] * rt[0] + rt[1] * rt[1] + rt[2] * rt[2]);
        for (int k = 0; k < 3; ++k)
            rt[k] /= rl;
        up[0] = rt[1] * fw[2] - rt[2] * fw[1];
        up[1] = rt[2] * fw[0] - rt[0] * fw[2];
        up[2] = rt[0] * fw[1] - rt[1] * fw[0];
        for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i) {
                const double x = (2 * (i + 0.5) / N - 1) * 0.42, y = (2 * (j + 0.5) / N - 1) * 0.42;
                const double d[3] = {fw[0] + x * rt[0] + y * up[0], fw[1] + x * rt[1] + y * up[1],
                                     fw[2] + x * rt[2] + y * up[2]};
                meso_ref_frustum_hit h;
                if (!meso_ref_frusta_intersect_relief(from->segs, from->seg_count, from->balls, from->ball_count,
                                                      &from->relief, eye, d, 0, 1e30, &h))
                    continue;
                ++*hits;
                if (h.part == MESO_REF_PART_BALL)
                    continue; /* no relief: the same sphere */
                if (h.part != MESO_REF_PART_LATERAL || !h.relief) {
                    ++*skipped;
                    continue;
                }
                const double wt = meso_ref_relief_height(&to->relief.height, h.tex[0], h.tex[1], NULL, NULL);
                double q[3];
                if (!column_point(&from->segs[h.index], h.p, h.tex[0], h.tex[1], wt, q)) {
                    ++*skipped;
                    continue;
                }
                worst = fmax(worst, sqrt((h.p[0] - q[0]) * (h.p[0] - q[0]) + (h.p[1] - q[1]) * (h.p[1] - q[1]) +
                                         (h.p[2] - q[2]) * (h.p[2] - q[2])));
            }
    }
    return worst;
}

/* Native levels 1..S-1: the stated error holds both ways, and is tight. */
static void check_native(meso_file* f, const meso_level_info* li, uint32_t S, const char* name)
{
    if (S < 2)
        return;
    meso_ref_frusta r0;
    assert(meso_ref_frusta_load(f, 1, &r0, NULL) == MESO_OK && r0.relief.height.kind == 1);
    for (uint32_t L = 1; L < S; ++L) {
        const double err = li[L].rec.error;
        meso_ref_frusta rl;
        assert(meso_ref_frusta_load_level(f, 1, (uint16_t)L, &rl, NULL) == MESO_OK);
        assert(rl.relief.height.w << L == r0.relief.height.w && rl.relief.height.h << L == r0.relief.height.h);
        size_t hl = 0, sl = 0, h0 = 0, s0 = 0;
        const double wl = farthest_column(&rl, &r0, &hl, &sl), w0 = farthest_column(&r0, &rl, &h0, &s0);
        printf("  %-8s native level %u (relief %ux%u): stated %.6g, farthest level-%u hit from level 0 %.6g (%.0f %%), "
               "level-0 hit from level %u %.6g (%.0f %%); %zu + %zu hits, %zu + %zu caps or unsolved\n",
               name, L, rl.relief.height.w, rl.relief.height.h, err, L, wl, 100 * wl / err, L, w0, 100 * w0 / err, hl,
               h0, sl, s0);
        fflush(stdout);
        assert(hl > 2000 && h0 > 2000 && sl < hl / 20 && s0 < h0 / 20);
        assert(wl <= err * (1 + 1e-5) && w0 <= err * (1 + 1e-5));
        assert(fmax(wl, w0) >= 0.3 * err);
        meso_ref_frusta_free(&rl);
    }
    meso_ref_frusta_free(&r0);
}

static void check(const char* mesobake, const char* dir, const char* name, const char* input, const char* args)
{
    char report[512];
    meso_file* f = test_bake_open(mesobake, "frusta", test_data(input), args, dir, name, report);
    meso_level_info li[16];
    uint32_t S = 1;
    const uint32_t n = test_standin_chain(f, li, 3, &S);
    /* The report lists the levels with the stored error. */
    static char json[65536];
    test_read_report(report, json, sizeof json);
    const char* lv = strstr(json, "\"levels\"");
    assert(lv && strstr(lv, "\"mesh\"") && strstr(lv, "\"triangles\"") && strstr(lv, "\"chord_error\""));
    meso_mesh_view mv1;
    check_native(f, li, S, name);
    uint8_t* m1 = test_read_level_mesh(f, (uint16_t)S, &mv1);
    check_level(f, li, S, S, name, NULL);
    check_level(f, li, n - 1, S, name, &mv1);
    free(m1);
    meso_file_close(f);
}

/* Native relief levels only, on a finer relief (three of them). Its
 * stand-in is not checked here: at bricks:128 the stand-in-to-native rays
 * along the normals run down the mortar grooves, measuring far more than
 * the distance to the nearby brick edge. */
static void check_relief_levels(const char* mesobake, const char* dir, const char* name, const char* args)
{
    meso_file* f = test_bake_open(mesobake, "frusta", test_data("saguaro.skel"), args, dir, name, NULL);
    meso_level_info li[16];
    uint32_t S = 1;
    test_standin_chain(f, li, 2, &S);
    assert(S >= 3); /* at least two native levels */
    check_native(f, li, S, name);
    meso_file_close(f);
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "frusta_standin");
    check(argv[1], dir, "saguaro", "saguaro.skel", "--relief bricks:32 --relief-repeat 2 --twist 20");
    check_relief_levels(argv[1], dir, "sag128", "--relief bricks:128 --relief-repeat 2");
    check(argv[1], dir, "neuron", "neurom_simple.swc", "");
    /* --levels 1: the file of earlier bakes, one level, no LODS. */
    char path[512], cmd[10240];
    snprintf(path, sizeof path, "%s/one.meso", dir);
    snprintf(cmd, sizeof cmd, "'%s' frusta -i '%s' --relief bricks:32 --levels 1 -o '%s' >/dev/null", argv[1],
             test_data("saguaro.skel"), path);
    assert(system(cmd) == 0);
    test_assert_one_level(path);
    meso_file* f = NULL;
    assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_find(f, MESO_CHUNK_MESH, 1, UINT16_MAX) < 0);
    meso_file_close(f);
    test_temp_dir_remove(dir);
    puts("test_frusta_standin: ok");
    return 0;
}
