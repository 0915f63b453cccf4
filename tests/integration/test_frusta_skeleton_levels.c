/* A frusta object's coarser skeletons (bake/frusta_skeleton_levels.c,
 * FORMAT.md §7.10): each is a native level with its own FRUS, FSEG and
 * BALL over level 0's SKEL and fewer frusta, and its stated error holds
 * against the exact reference both ways, measured independently of the
 * bake's correspondence:
 *  - hits: the CPU reference ray caster's hits on one level, from three
 *    views;
 *  - the other level's surface: sampled densely on its own records (every
 *    frustum's (u, v) grid at the relief height the reference's height
 *    field gives there, the tip caps and the walls up to the relief at
 *    their rims, every ball), into a point cloud. The distance from a hit
 *    to the nearest sample is at most its distance to the surface plus
 *    the samples' spacing, which is measured and allowed for.
 * The farthest hit reaches a fair part of the stated error (it is not a
 * loose guess). Bundled skeletons: vine.skel with a brick relief (the
 * correspondence by relief coordinates) and without (u and v free), and
 * the neuron (balls and unfitted joints). Also: the report says how many
 * levels were made.
 * usage: test_frusta_skeleton_levels MESOBAKE */
#include "test_util.h"

#include <string.h>

#include "frusta_tessellation.h"
#include "frusta_views.h"
#include "frustum_reference.h"
#include "meso_file.h"
#include "meso_layout.h"
#include "point_cloud.h"
#include "standin_check.h"
#include "vec3d.h"

/* The reference's frustum as the format's record (frusta_pose.h), for
 * meso_frusta_tess_point. */
static meso_frustum_rec as_rec(const meso_ref_frustum* f)
{
    meso_frustum_rec r = {0};
    for (int i = 0; i < 3; ++i) {
        r.center[0][i] = (float)f->c0[i];
        r.center[1][i] = (float)f->c1[i];
        r.frame_x[i] = (float)f->frame_x[i];
        for (int e = 0; e < 2; ++e)
            r.plane[e][i] = (float)f->plane_n[e][i];
    }
    r.radius[0] = (float)f->r0;
    r.radius[1] = (float)f->r1;
    r.u_offset = (float)f->u_offset;
    r.twist = (float)f->twist;
    r.u_scale = (float)f->u_scale;
    r.v_offset = (float)f->v_offset;
    r.v_scale = (float)f->v_scale;
    r.relief_depth = (float)f->relief_depth;
    return r;
}

static double relief_at(const void* ctx, double s, double t)
{
    return meso_ref_relief_height(ctx, s, t, NULL, NULL);
}

enum { WALL = 8, MAX_CELLS = 1024 };

static int cells(double length, double h)
{
    const double n = ceil(length / h);
    return n < 8 ? 8 : n > MAX_CELLS ? MAX_CELLS : (int)n;
}

/* Samples of m's surface about h apart into c; *gap gets the largest
 * distance between grid neighbours over two (so every surface point lies
 * within about *gap of a sample). */
static void surface_samples(const meso_ref_frusta* m, double h, cloud* c, double* gap)
{
    const int relief = m->relief.height.kind == 1;
    const void* hctx = relief ? (const void*)&m->relief.height : NULL;
    double worst = 0;
    double(*prev_row)[3] = malloc(sizeof(double) * 3 * (MAX_CELLS + 1));
    assert(prev_row);
    for (uint32_t j = 0; j < m->seg_count; ++j) {
        const meso_ref_frustum* f = &m->segs[j];
        const meso_frustum_rec r = as_rec(f);
        const int NU = cells(2 * M_PI * (fmax(f->r0, f->r1) + f->relief_depth), h);
        const int NV = cells(dist3(f->c0, f->c1) + 2 * fmax(f->r0, f->r1), h);
        for (int b = 0; b <= NV; ++b) {
            double left[3] = {0, 0, 0};
            for (int a = 0; a <= NU; ++a) {
                double p[3];
                meso_frusta_tess_point(&r, relief ? relief_at : NULL, hctx, (double)a / NU, (double)b / NV, p);
                cloud_add(c, p);
                if (a > 0)
                    worst = fmax(worst, dist3(p, left));
                if (b > 0)
                    worst = fmax(worst, dist3(p, prev_row[a]));
                memcpy(left, p, sizeof left);
                memcpy(prev_row[a], p, sizeof left);
            }
        }
        /* Caps: the disc at w = 0, and the wall from its rim up to the
         * relief. */
        for (int e = 0; e < 2; ++e) {
            if (!f->cap[e])
                continue;
            const double* ce = e ? f->c1 : f->c0;
            const int NR = cells(e ? f->r1 : f->r0, h);
            for (int a = 0; a < NU; ++a) {
                const double u = (double)a / NU, zero = 0;
                double rim[3], top[3];
                meso_frusta_tess_point(&r, meso_frusta_height_constant, &zero, u, e, rim);
                meso_frusta_tess_point(&r, relief ? relief_at : NULL, hctx, u, e, top);
                for (int k = 0; k <= NR; ++k) {
                    const double l = (double)k / NR;
                    const double q[3] = {ce[0] + l * (rim[0] - ce[0]), ce[1] + l * (rim[1] - ce[1]),
                                         ce[2] + l * (rim[2] - ce[2])};
                    cloud_add(c, q);
                }
                worst = fmax(worst, dist3(ce, rim) / NR);
                for (int k = 1; k <= WALL; ++k) {
                    const double l = (double)k / WALL;
                    const double q[3] = {rim[0] + l * (top[0] - rim[0]), rim[1] + l * (top[1] - rim[1]),
                                         rim[2] + l * (top[2] - rim[2])};
                    cloud_add(c, q);
                }
                worst = fmax(worst, dist3(rim, top) / WALL);
            }
        }
    }
    for (uint32_t b = 0; b < m->ball_count; ++b) {
        const meso_ref_ball* s = &m->balls[b];
        const int NU = cells(2 * M_PI * s->radius, h), NV = NU / 2 > 4 ? NU / 2 : 4;
        for (int i = 0; i <= NV; ++i)
            for (int a = 0; a < NU; ++a) {
                const double th = M_PI * i / NV, ph = 2 * M_PI * a / NU;
                const double q[3] = {s->center[0] + s->radius * sin(th) * cos(ph),
                                     s->center[1] + s->radius * sin(th) * sin(ph), s->center[2] + s->radius * cos(th)};
                cloud_add(c, q);
            }
        worst = fmax(worst, s->radius * M_PI / NV);
    }
    free(prev_row);
    *gap = worst / 2;
}

/* The farthest of `from`'s reference hits (three views) from the cloud. */
static double farthest_hit(const meso_ref_frusta* from, const cloud* to, size_t* hits)
{
    double worst = 0;
    for (int e = 0; e < 3; ++e) {
        const meso_ref_view v = test_frusta_view(from, e, 200, 0);
        meso_ref_image img;
        assert(meso_ref_frusta_render(from, &v, &img) == MESO_OK);
        for (int p = 0; p < v.width * v.height; ++p) {
            if (!img.coverage[p])
                continue;
            const double q[3] = {img.hit[3 * p], img.hit[3 * p + 1], img.hit[3 * p + 2]};
            worst = fmax(worst, cloud_nearest(to, q));
            ++*hits;
        }
        meso_ref_image_free(&img);
    }
    return worst;
}

/* Every coarser skeleton of f against level 0, both ways. Returns how
 * many there are. */
static uint32_t check_levels(meso_file* f, const char* name, uint32_t min_levels)
{
    meso_level_info li[16];
    uint32_t S = 1;
    test_standin_chain(f, li, 2, &S);
    meso_ref_frusta r0;
    assert(meso_ref_frusta_load(f, 1, &r0, NULL) == MESO_OK);
    assert(meso_file_find(f, MESO_CHUNK_SKEL, 1, UINT16_MAX) >= 0);
    cloud c0 = {0};
    double gap0 = 0, h0 = INFINITY;
    for (uint32_t L = 1; L < S; ++L)
        h0 = fmin(h0, li[L].rec.error / 10);
    surface_samples(&r0, h0, &c0, &gap0);
    uint32_t count = 0, prev_frusta = r0.seg_count;
    for (uint32_t L = 1; L < S; ++L) {
        if (meso_file_find_level(f, MESO_CHUNK_FRUS, 1, (uint16_t)L) == meso_file_find_level(f, MESO_CHUNK_FRUS, 1, 0))
            continue; /* level 0's frusta: a relief level (test_frusta_standin) */
        ++count;
        const double err = li[L].rec.error;
        meso_ref_frusta rl;
        assert(meso_ref_frusta_load_level(f, 1, (uint16_t)L, &rl, NULL) == MESO_OK);
        assert(rl.seg_count < prev_frusta && rl.ball_count == r0.ball_count);
        prev_frusta = rl.seg_count;
        cloud cl = {0};
        double gapl = 0;
        surface_samples(&rl, err / 10, &cl, &gapl);
        cloud_grid(&c0, err);
        cloud_grid(&cl, err);
        size_t hl = 0, hz = 0;
        const double wl = farthest_hit(&rl, &c0, &hl), w0 = farthest_hit(&r0, &cl, &hz);
        printf("  %-7s level %u: %u frusta (level 0: %u), stated %.6g; farthest level-%u hit from level 0's "
               "samples %.6g (%.0f %%), level-0 hit from level %u's %.6g (%.0f %%); sample spacing %.3g / %.3g; "
               "%zu + %zu hits\n",
               name, L, rl.seg_count, r0.seg_count, err, L, wl, 100 * wl / err, L, w0, 100 * w0 / err, gap0, gapl,
               hl, hz);
        fflush(stdout);
        assert(hl > 2000 && hz > 2000);
        assert(wl <= err + gap0 && w0 <= err + gapl); /* the stated error holds, both ways */
        assert(fmax(wl, w0) >= 0.3 * err);            /* and is not a loose guess */
        cloud_free(&cl);
        meso_ref_frusta_free(&rl);
    }
    assert(count >= min_levels);
    cloud_free(&c0);
    meso_ref_frusta_free(&r0);
    return count;
}

/* The report's skeleton_levels.count. */
static int reported_levels(const char* report)
{
    static char json[65536];
    test_read_report(report, json, sizeof json);
    const char* k = strstr(json, "\"skeleton_levels\"");
    assert(k);
    k = strstr(k, "\"count\"");
    assert(k);
    return atoi(strchr(k, ':') + 1);
}

static void check(const char* mesobake, const char* dir, const char* name, const char* input, const char* args,
                  uint32_t min_levels)
{
    char report[512];
    meso_file* f = test_bake_open(mesobake, "frusta", test_data(input), args, dir, name, report);
    const uint32_t n = check_levels(f, name, min_levels);
    assert(reported_levels(report) == (int)n);
    meso_file_close(f);
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "frusta_skeleton_levels");
    check(argv[1], dir, "vine", "vine.skel", "--relief bricks:32", 2);
    check(argv[1], dir, "plain", "vine.skel", "", 2);
    check(argv[1], dir, "neuron", "neurom_Neuron.swc", "", 1);
    test_temp_dir_remove(dir);
    puts("test_frusta_skeleton_levels: ok");
    return 0;
}
