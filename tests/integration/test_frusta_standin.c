/* A frusta object's mesh stand-ins (FORMAT.md §7.10; bake/frusta_standin.h,
 * bake/standin_levels.h): level 1 the triangle tessellation drawn in the
 * frusta's place, levels 2.. its simplifications, each with the error
 * mesobake states for it; level 1 and the coarsest are checked against the
 * exact CPU reference both ways:
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

#include "camera.h"
#include "frustum_reference.h"
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

/* Level L's mesh against the native surface, both ways. Level 1's points
 * are taken to the native surface by reference rays along their normals;
 * a coarser level's, which may span gaps the normal ray misses, to level
 * 1's mesh (brute force) plus level 1's error, checked here too: the
 * triangle inequality makes the sum a distance bound to the native
 * surface. */
static void check_level(meso_file* f, const meso_level_info* li, uint32_t L, const char* name,
                        const meso_mesh_view* level1)
{
    const double err = li[L].rec.error;
    meso_mesh_view mv;
    uint8_t* mb = test_read_level_mesh(f, (uint16_t)L, &mv);
    const uint32_t tris = mv.layout.index_count / 3;
    assert(tris > 0 && tris < 20000); /* cheap: a polygon stand-in, not the 256k of the paper's Figure 6 */

    meso_ref_frusta rm;
    assert(meso_ref_frusta_load(f, 1, &rm, NULL) == MESO_OK);
    double c[3], radius = 0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)rm.bbox_min[k] + rm.bbox_max[k]);
        radius += 0.25 * ((double)rm.bbox_max[k] - rm.bbox_min[k]) * ((double)rm.bbox_max[k] - rm.bbox_min[k]);
    }
    radius = sqrt(radius);
    /* Native to stand-in. */
    double worst_native = 0;
    size_t hits = 0;
    static const double dirs[3][3] = {{0, 0.1, 1}, {0.8, 0.45, -0.4}, {-0.6, -0.7, 0.4}};
    for (int e = 0; e < 3; ++e) {
        meso_ref_view v = {.width = 40, .height = 40, .threads = 1};
        double eye[3];
        const double dl = sqrt(dirs[e][0] * dirs[e][0] + dirs[e][1] * dirs[e][1] + dirs[e][2] * dirs[e][2]);
        for (int k = 0; k < 3; ++k)
            eye[k] = c[k] + 2.6 * radius * dirs[e][k] / dl;
        static const double up[3] = {0, 1, 0};
        meso_camera_look_at_d(v.view, eye, c, up);
        meso_camera_perspective_d(v.proj, 45.0 * M_PI / 180.0, 1.0, 0.2 * radius, 5.0 * radius);
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
     * k-th triangle (about 300 triangles). */
    double worst_standin = 0;
    size_t samples = 0;
    const uint32_t stride = tris / 300 + 1;
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
        static const double bary[7][3] = {{1, 0, 0},     {0, 1, 0},     {0, 0, 1},          {.5, .5, 0},
                                          {0, .5, .5},   {.5, 0, .5},   {1. / 3, 1. / 3, 1. / 3}};
        for (int s = 0; s < 7; ++s) {
            double q[3], nn[3];
            for (int k = 0; k < 3; ++k) {
                q[k] = bary[s][0] * P[0][k] + bary[s][1] * P[1][k] + bary[s][2] * P[2][k];
                nn[k] = nrm[k] / nl;
            }
            worst_standin = fmax(worst_standin, L == 1 ? native_distance(&rm, q, nn, 4 * err)
                                                       : standin_distance(q, level1) + li[1].rec.error);
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

static void check(const char* mesobake, const char* dir, const char* name, const char* input, const char* args)
{
    char path[512], report[512], cmd[10240];
    snprintf(path, sizeof path, "%s/%s.meso", dir, name);
    snprintf(report, sizeof report, "%s/%s.json", dir, name);
    snprintf(cmd, sizeof cmd, "'%s' frusta -i '%s' %s -o '%s' --report '%s' >/dev/null", mesobake, test_data(input),
             args, path, report);
    assert(system(cmd) == 0);
    meso_file* f = NULL;
    assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_level_info li[16];
    const uint32_t n = test_standin_chain(f, li, 3);
    /* The report lists the levels with the stored error. */
    FILE* rf = fopen(report, "rb");
    assert(rf);
    char json[65536];
    const size_t jn = fread(json, 1, sizeof json - 1, rf);
    json[jn] = 0;
    fclose(rf);
    const char* lv = strstr(json, "\"levels\"");
    assert(lv && strstr(lv, "\"mesh\"") && strstr(lv, "\"triangles\"") && strstr(lv, "\"chord_error\""));
    meso_mesh_view mv1;
    uint8_t* m1 = test_read_level_mesh(f, 1, &mv1);
    check_level(f, li, 1, name, NULL);
    check_level(f, li, n - 1, name, &mv1);
    free(m1);
    meso_file_close(f);
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "frusta_standin");
    check(argv[1], dir, "saguaro", "saguaro.skel", "--relief bricks:32 --relief-repeat 2 --twist 20");
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
