/* A density-volume shell's native coarser levels (bake/volume_levels.h;
 * FORMAT.md §7.10; issue 14): the volume halved, each level with the error
 * mesobake states for it.
 *
 * Against the exact CPU reference (runtime/reference), with its own sampler
 * and mapping, not the baker's: for every native level L, both ways, every
 * surface point the reference ray caster hits on one level, from three
 * views, lies within the stated error of the other level's surface. The
 * other level's surface is sampled densely and independently of the bake:
 * in every prism, a grid of 2 points per level-0 texel along s and t (over
 * the prism's texture triangle) and 2 per texel along w, classified solid or
 * not by meso_ref_texfn_solid; where two neighbouring grid points differ,
 * the surface crosses the segment between them, and its midpoint, mapped by
 * Phi, is a sample within half the segment of the surface (so are the grid
 * points on the shell's faces that are solid). The distance from a hit to
 * the nearest sample is at most its distance to the surface plus the
 * samples' spacing, and it must be at most the stated error plus the
 * longest half segment: the bound holds to the sampling's resolution. The
 * farthest must reach a fair part of the error (it is a bound, not a
 * guess of ten times the truth).
 *
 * The mesh is tests/data/torus_uv.obj: texture coordinates without
 * degenerate triangles and seams that an integer tiling wraps (the bound's
 * assumptions, volume_levels.c). Plus: TX3D dims halve, errors increase and
 * stay below the base mesh stand-in's, prefixes shrink, the file validates
 * in full, 1 and 2 threads give the same bytes, and spot_uv, whose texture
 * coordinates hold a sliver triangle, keeps no native level.
 * usage: test_shell_volume_levels MESOBAKE */
#include "test_util.h"

#include <string.h>

#include "standin_check.h"
#include "meso_file.h"
#include "meso_layout.h"
#include "point_cloud.h"
#include "shell_hits.h"
#include "shell_map.h"
#include "shell_reference.h"

enum { PER_TEXEL = 2 }; /* grid points per level-0 texel, each axis */

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* The surface samples of level `s` (its own texture), the comment above;
 * *half the longest half segment that made a sample. */
static void surface_samples(const meso_ref_shell* s, const meso_ref_texfn* t0, cloud* c, double* half)
{
    const meso_ref_texfn* tx = &s->tex;
    assert(tx->kind == 2);
    const int nw = (int)t0->d * PER_TEXEL;
    for (uint32_t f = 0; f < s->triangle_count; ++f) {
        meso_prism P;
        meso_ref_shell_prism(s, f, 1.0, &P);
        double e = 0;
        for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3;
            e = fmax(e, fmax(fabs(P.uv[a][0] - P.uv[b][0]) * t0->w, fabs(P.uv[a][1] - P.uv[b][1]) * t0->h));
        }
        const int n = (int)ceil(e * PER_TEXEL) + 1;
        const size_t cols = (size_t)(n + 1) * (n + 2) / 2;
        uint8_t* solid = malloc(cols * (size_t)(nw + 1));
        assert(solid);
        /* column (i, j), i + j <= n, at index i * (n + 1) - i (i - 1) / 2 + j */
#define COL(i, j) ((size_t)(i) * (size_t)(n + 1) - (size_t)(i) * (size_t)((i)-1) / 2 + (size_t)(j))
        for (int i = 0; i <= n; ++i)
            for (int j = 0; i + j <= n; ++j) {
                const double u = (double)i / n, v = (double)j / n, l0 = 1 - u - v;
                const double st[2] = {l0 * P.uv[0][0] + u * P.uv[1][0] + v * P.uv[2][0],
                                      l0 * P.uv[0][1] + u * P.uv[1][1] + v * P.uv[2][1]};
                for (int k = 0; k <= nw; ++k)
                    solid[COL(i, j) * (size_t)(nw + 1) + (size_t)k] =
                        (uint8_t)meso_ref_texfn_solid(tx, st[0], st[1], (double)k / nw);
            }
        /* Segments: along w, along u, along v and along the third side. */
        static const int step[4][3] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {1, -1, 0}};
        for (int i = 0; i <= n; ++i)
            for (int j = 0; i + j <= n; ++j)
                for (int k = 0; k <= nw; ++k) {
                    const uint8_t here = solid[COL(i, j) * (size_t)(nw + 1) + (size_t)k];
                    const double a[3] = {(double)i / n, (double)j / n, (double)k / nw};
                    if (here && (k == 0 || k == nw)) { /* on the shell's face, solid: surface */
                        double p[3];
                        meso_phi(&P, a[0], a[1], a[2], p);
                        cloud_add(c, p);
                    }
                    for (int d = 0; d < 4; ++d) {
                        const int i2 = i + step[d][0], j2 = j + step[d][1], k2 = k + step[d][2];
                        if (j2 < 0 || i2 + j2 > n || k2 > nw)
                            continue;
                        if (solid[COL(i2, j2) * (size_t)(nw + 1) + (size_t)k2] == here)
                            continue;
                        const double b[3] = {(double)i2 / n, (double)j2 / n, (double)k2 / nw};
                        double pa[3], pb[3], m[3];
                        meso_phi(&P, a[0], a[1], a[2], pa);
                        meso_phi(&P, b[0], b[1], b[2], pb);
                        for (int q = 0; q < 3; ++q)
                            m[q] = 0.5 * (pa[q] + pb[q]);
                        cloud_add(c, m);
                        *half = fmax(*half, 0.5 * dist3(pa, pb));
                    }
                }
#undef COL
        free(solid);
    }
}

/* The farthest of `from`'s reference hits, three views, from the samples of
 * the other level; *hits counts them. */
static double farthest_hit(const meso_ref_shell* from, const cloud* to, size_t* hits)
{
    static const double eyes[3][3] = {{0, 2.6, 2.2}, {3.0, 0.8, -0.6}, {-1.6, -2.4, 1.5}};
    cloud h = {0};
    test_shell_hits(from, eyes, 3, 64, 45.0, &h);
    double worst = 0;
    for (size_t i = 0; i < h.n; ++i)
        worst = fmax(worst, cloud_nearest(to, h.p + 3 * i));
    *hits += h.n;
    cloud_free(&h);
    return worst;
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "volume_levels");
    static const char* args = "--texture weave:64 --tiling 8,2 --thickness-rel 0.03";
    char a1[256], a2[256];
    snprintf(a1, sizeof a1, "%s -j 1", args);
    snprintf(a2, sizeof a2, "%s -j 2", args);
    meso_file* f = test_bake_open(argv[1], "shell", test_data("torus_uv.obj"), a2, dir, "torus", NULL);
    meso_file_close(test_bake_open(argv[1], "shell", test_data("torus_uv.obj"), a1, dir, "torus_j1", NULL));
    char p1[512], p2[512];
    snprintf(p1, sizeof p1, "%s/torus_j1.meso", dir);
    snprintf(p2, sizeof p2, "%s/torus.meso", dir);
    size_t n1 = 0, n2 = 0;
    uint8_t *b1 = test_read_file(p1, &n1), *b2 = test_read_file(p2, &n2);
    assert(n1 == n2 && memcmp(b1, b2, n1) == 0); /* rule 7: whatever the thread count */
    free(b1);
    free(b2);

    meso_level_info li[16];
    uint32_t n = 0, native = 0;
    assert(meso_file_levels(f, 1, li, 16, &n, NULL) == MESO_OK);
    while (native + 1 < n && li[native + 1].rec.form == MESO_LEVEL_NATIVE)
        ++native;
    printf("torus_uv, weave:64: %u native levels of %u\n", native, n);
    assert(native >= 2 && li[native + 1].rec.form == MESO_LEVEL_MESH);
    meso_ref_shell r0;
    assert(meso_ref_shell_load(f, 1, &r0, NULL) == MESO_OK && r0.tex.kind == 2);
    double half0 = 0;
    cloud c0 = {0};
    surface_samples(&r0, &r0.tex, &c0, &half0);
    for (uint32_t L = 1; L <= native; ++L) {
        const double err = li[L].rec.error;
        assert(err > li[L - 1].rec.error && err < li[native + 1].rec.error);
        assert(li[L].prefix_bytes < li[L - 1].prefix_bytes && li[L].prefix_bytes > li[native + 1].prefix_bytes);
        meso_ref_shell rl;
        assert(meso_ref_shell_load_level(f, 1, (uint16_t)L, &rl, NULL) == MESO_OK);
        assert(rl.tex.kind == 2 && rl.tex.w << L == r0.tex.w && rl.tex.h << L == r0.tex.h &&
               rl.tex.d << L == r0.tex.d);
        assert(rl.vertex_count == r0.vertex_count);
        double halfl = 0;
        cloud cl = {0};
        surface_samples(&rl, &r0.tex, &cl, &halfl);
        if (!c0.start)
            cloud_grid(&c0, err);
        cloud_grid(&cl, err);
        size_t hits_l = 0, hits_0 = 0;
        const double wl = farthest_hit(&rl, &c0, &hits_l), w0 = farthest_hit(&r0, &cl, &hits_0);
        printf("  level %u (%ux%ux%u): stated %.6g; farthest of %zu level-%u hits from level 0's %zu samples %.6g "
               "(%.0f %%), of %zu level-0 hits from level %u's %zu %.6g (%.0f %%); half segments %.3g, %.3g\n",
               L, rl.tex.w, rl.tex.h, rl.tex.d, err, hits_l, L, c0.n, wl, 100 * wl / err, hits_0, L, cl.n, w0,
               100 * w0 / err, half0, halfl);
        fflush(stdout);
        assert(hits_l > 4000 && hits_0 > 4000);
        assert(wl <= err + half0 && w0 <= err + halfl); /* the bound holds */
        assert(fmax(wl, w0) >= 0.25 * err);              /* and is not loose by more than 4x */
        cloud_free(&cl);
        meso_ref_shell_free(&rl);
    }
    cloud_free(&c0);
    meso_ref_shell_free(&r0);
    meso_file_close(f);

    /* spot_uv's texture coordinates hold a sliver (a triangle stretched 800
     * times the median): the bound through the largest stretch is farther
     * than the base mesh, so no native level. */
    f = test_bake_open(argv[1], "shell", test_data("spot_uv.obj"), "--texture weave:32 --thickness-rel 0.02", dir,
                       "spot", NULL);
    assert(meso_file_levels(f, 1, li, 16, &n, NULL) == MESO_OK && n >= 2 && li[1].rec.form == MESO_LEVEL_MESH);
    meso_file_close(f);
    test_temp_dir_remove(dir);
    puts("test_shell_volume_levels: ok");
    return 0;
}
