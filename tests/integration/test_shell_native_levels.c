/* A height-field shell's native coarser levels (bake/height_field_levels.h;
 * FORMAT.md §7.10; issue 14): the height field halved, each level with the
 * error mesobake states for it.
 *
 * Against the exact CPU reference (runtime/reference), for every native
 * level L, with the reference's own sampler and mapping, not the baker's:
 *  - texture space: on a grid of 4 x 4 points per level-0 texel (which
 *    holds level 0's half-texel lattice, where the bake says the sup is
 *    reached, and points between), sup |h_L - h_0| times the longest
 *    top - bottom of the shell's vertices is what the level states, to f32
 *    rounding: the bound holds and it is exact, not loose; random points
 *    never exceed it;
 *  - object space, both ways: every surface point the reference ray caster
 *    hits on level L, from three views, lies within the stated error of
 *    level 0's surface (the point over the same (u, v) of the prism that
 *    holds it: Phi(u, v, h_0(s, t)), found by inverting Phi exactly; on a
 *    uv seam, where the texture jumps, the wall between the two sides'
 *    heights), and every point it hits on level 0 within it of level L's;
 *    the farthest reaches a fair part of the error.
 * Plus: errors increase level by level and stay below the base-mesh
 * stand-in's, each level lies in a shorter prefix, the file validates in
 * full, the levels' texture functions halve, and a --levels 2 bake has no
 * native level. Exterior, envelope and interior shells; an update of a file
 * with native levels keeps them and OLD's simplified stand-ins. Closed meshes only: on an open mesh the shell's side walls
 * are surface too, not over a column point of the other level.
 * usage: test_shell_native_levels MESOBAKE */
#include "test_util.h"

#include <string.h>

#include "standin_check.h"
#include "meso_file.h"
#include "meso_layout.h"
#include "shell_map.h"
#include "shell_hits.h"
#include "shell_reference.h"

/* Prisms bucketed by bounding box on a G^3 grid over the shell's box. */
enum { G = 24 };
typedef struct buckets {
    double lo[3], cell[3];
    uint32_t* start; /* G^3 + 1 */
    uint32_t* items;
} buckets;

static void prism_box(const meso_prism* P, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; ++k) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
        for (int v = 0; v < 3; ++v) {
            lo[k] = fmin(lo[k], fmin(P->b[v][k], P->b[v][k] + P->n[v][k]));
            hi[k] = fmax(hi[k], fmax(P->b[v][k], P->b[v][k] + P->n[v][k]));
        }
    }
}

static int cell_of(const buckets* b, double x, int k)
{
    const int c = (int)floor((x - b->lo[k]) / b->cell[k]);
    return c < 0 ? 0 : c >= G ? G - 1 : c;
}

static void buckets_build(const meso_ref_shell* s, buckets* b)
{
    for (int k = 0; k < 3; ++k) {
        const double pad = 1e-3 * ((double)s->bbox_max[k] - s->bbox_min[k]) + 1e-9;
        b->lo[k] = (double)s->bbox_min[k] - pad;
        b->cell[k] = ((double)s->bbox_max[k] + pad - b->lo[k]) / G;
    }
    b->start = calloc((size_t)G * G * G + 1, sizeof(uint32_t));
    for (int pass = 0; pass < 2; ++pass) {
        uint32_t* fill = pass ? calloc((size_t)G * G * G, sizeof(uint32_t)) : NULL;
        for (uint32_t f = 0; f < s->triangle_count; ++f) {
            meso_prism P;
            meso_ref_shell_prism(s, f, 1.0, &P);
            double lo[3], hi[3];
            prism_box(&P, lo, hi);
            for (int k = 0; k < 3; ++k) { /* a point on a shared face is in both prisms' buckets */
                lo[k] -= 1e-3 * b->cell[k];
                hi[k] += 1e-3 * b->cell[k];
            }
            for (int z = cell_of(b, lo[2], 2); z <= cell_of(b, hi[2], 2); ++z)
                for (int y = cell_of(b, lo[1], 1); y <= cell_of(b, hi[1], 1); ++y)
                    for (int x = cell_of(b, lo[0], 0); x <= cell_of(b, hi[0], 0); ++x) {
                        const size_t c = (size_t)x + G * ((size_t)y + G * (size_t)z);
                        if (pass)
                            b->items[b->start[c] + fill[c]++] = f;
                        else
                            ++b->start[c + 1];
                    }
        }
        if (!pass) {
            for (size_t c = 0; c < (size_t)G * G * G; ++c)
                b->start[c + 1] += b->start[c];
            b->items = malloc(sizeof(uint32_t) * (b->start[(size_t)G * G * G] + 1));
        }
        free(fill);
    }
}

/* The distance from hit p of one level's surface to the other level's
 * surface over the same (u, v): |Phi(u, v, w_p) - Phi(u, v, h_other(s, t))|.
 * Where p lies on a face two prisms share and the texture jumps there (a uv
 * seam), the surface has a wall between the two sides' heights, and so has
 * the other level's: there it is the distance from w_p to the interval
 * between the other's heights on the prisms holding p. -1 when no prism
 * holds p. */
static double column_distance(const meso_ref_shell* other, const meso_ref_shell* s, const buckets* b,
                              const double p[3])
{
    const size_t c = (size_t)cell_of(b, p[0], 0) + G * ((size_t)cell_of(b, p[1], 1) + G * (size_t)cell_of(b, p[2], 2));
    int found = 0;
    meso_prism first;
    double first_uvw[3] = {0, 0, 0}, lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = b->start[c]; i < b->start[c + 1]; ++i) {
        meso_prism P;
        meso_ref_shell_prism(s, b->items[i], 1.0, &P);
        double uvw[3];
        if (!meso_phi_inverse(&P, p, -1e-5, 1 + 1e-5, 1e-5, uvw))
            continue;
        const double l0 = 1 - uvw[0] - uvw[1];
        const double st[2] = {l0 * P.uv[0][0] + uvw[0] * P.uv[1][0] + uvw[1] * P.uv[2][0],
                              l0 * P.uv[0][1] + uvw[0] * P.uv[1][1] + uvw[1] * P.uv[2][1]};
        const double h = meso_ref_texfn_value(&other->tex, st[0], st[1], 0.0);
        lo = fmin(lo, h);
        hi = fmax(hi, h);

        if (!found++) {
            first = P;
            memcpy(first_uvw, uvw, sizeof first_uvw);
        }
    }
    if (!found)
        return -1;
    const double w = first_uvw[2], wq = w < lo ? lo : w > hi ? hi : w;

    double a[3], q[3];
    meso_phi(&first, first_uvw[0], first_uvw[1], w, a);
    meso_phi(&first, first_uvw[0], first_uvw[1], wq, q);
    return sqrt((a[0] - q[0]) * (a[0] - q[0]) + (a[1] - q[1]) * (a[1] - q[1]) + (a[2] - q[2]) * (a[2] - q[2]));
}

/* The farthest of `from`'s reference hits from `to`'s surface, three views. */
static double farthest_hit(const meso_ref_shell* from, const meso_ref_shell* to, const buckets* b, size_t* hits)
{
    static const double eyes[3][3] = {{0, 0.3, 3.2}, {2.6, 1.4, -1.2}, {-1.8, -2.2, 1.5}};
    cloud h = {0};
    test_shell_hits(from, eyes, 3, 48, 40.0, &h);
    double worst = 0;
    for (size_t i = 0; i < h.n; ++i) {
        const double d = column_distance(to, from, b, h.p + 3 * i);
        assert(d >= 0); /* a hit lies in a prism */
        worst = fmax(worst, d);
    }
    *hits += h.n;
    cloud_free(&h);
    return worst;
}

/* The longest top - bottom over the vertices (FORMAT.md §7.2 SDIR). */
static double longest_span(const meso_ref_shell* s)
{
    double m = 0;
    for (uint32_t v = 0; v < s->vertex_count; ++v) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
            const double top = s->directors[3 * v + (size_t)k];
            const double bottom = s->layers == 2 ? s->directors[3 * ((size_t)s->vertex_count + v) + (size_t)k] : 0;
            d2 += (top - bottom) * (top - bottom);
        }
        m = fmax(m, sqrt(d2));
    }
    return m;
}

/* sup |h_a - h_b| on n x n points per texel of b (b the finer). */
static double grid_sup(const meso_ref_texfn* a, const meso_ref_texfn* b, int n)
{
    const uint32_t W = b->w * (uint32_t)n, H = b->h * (uint32_t)n;
    double sup = 0;
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
            const double s = (double)x / W, t = (double)y / H;
            sup = fmax(sup, fabs(meso_ref_texfn_value(a, s, t, 0) - meso_ref_texfn_value(b, s, t, 0)));
        }
    return sup;
}

static void check(const char* mesobake, const char* dir, const char* name, const char* args, uint32_t min_native)
{
    meso_file* f = test_bake_open(mesobake, "shell", test_data("spot_uv.obj"), args, dir, name, NULL);
    meso_level_info li[16];
    uint32_t n = 0, native = 0;
    assert(meso_file_levels(f, 1, li, 16, &n, NULL) == MESO_OK);
    while (native + 1 < n && li[native + 1].rec.form == MESO_LEVEL_NATIVE)
        ++native;
    printf("%s: %u native levels of %u\n", name, native, n);
    assert(native >= min_native && native + 1 < n && li[native + 1].rec.form == MESO_LEVEL_MESH);
    meso_ref_shell r0;
    assert(meso_ref_shell_load(f, 1, &r0, NULL) == MESO_OK && r0.tex.kind == 1);
    buckets b0 = {0};
    buckets_build(&r0, &b0);
    const double span = longest_span(&r0);
    double sup_before = 0;
    for (uint32_t L = 1; L <= native; ++L) {
        const double err = li[L].rec.error;
        assert(err > li[L - 1].rec.error && err < li[native + 1].rec.error);
        assert(li[L].prefix_bytes < li[L - 1].prefix_bytes && li[L].prefix_bytes > li[native + 1].prefix_bytes);
        meso_ref_shell rl;
        assert(meso_ref_shell_load_level(f, 1, (uint16_t)L, &rl, NULL) == MESO_OK);
        assert(rl.tex.kind == 1 && rl.tex.w << L == r0.tex.w && rl.tex.h << L == r0.tex.h);
        assert(rl.vertex_count == r0.vertex_count && longest_span(&rl) == span); /* the same prisms */
        /* Texture space: exact. */
        const double sup = fmax(grid_sup(&rl.tex, &r0.tex, 4), sup_before); /* errors never decrease */
        sup_before = sup;
        printf("  level %u (%ux%u): stated %.6g, sup |h_L - h_0| x longest span %.6g x %.6g = %.6g\n", L, rl.tex.w,
               rl.tex.h, err, sup, span, sup * span);
        assert(sup * span <= err * (1 + 1e-6)); /* the bound holds */
        assert(err <= (sup + 1e-5) * span);     /* and is the sup itself */
        uint64_t seed = 12345 + L;
        for (int i = 0; i < 200000; ++i) {
            const double s = test_rng_uniform(&seed, 0, 1), t = test_rng_uniform(&seed, 0, 1);
            const double d = fabs(meso_ref_texfn_value(&rl.tex, s, t, 0) - meso_ref_texfn_value(&r0.tex, s, t, 0));
            assert(d <= sup + 1e-6);
        }
        /* Object space, both ways. */
        buckets bl = {0};
        buckets_build(&rl, &bl);
        size_t hits_l = 0, hits_0 = 0;
        const double wl = farthest_hit(&rl, &r0, &bl, &hits_l), w0 = farthest_hit(&r0, &rl, &b0, &hits_0);
        printf("  level %u: farthest of %zu level-%u hits from level 0 %.6g (%.0f %%), of %zu level-0 hits from "
               "level %u %.6g (%.0f %%)\n",
               L, hits_l, L, wl, 100 * wl / err, hits_0, L, w0, 100 * w0 / err);
        fflush(stdout);
        assert(hits_l > 1500 && hits_0 > 1500);
        const double slack = 1e-6 * span; /* the reference's hit search */
        assert(wl <= err + slack && w0 <= err + slack);
        assert(fmax(wl, w0) >= 0.3 * err);
        free(bl.start);
        free(bl.items);
        meso_ref_shell_free(&rl);
    }
    free(b0.start);
    free(b0.items);
    meso_ref_shell_free(&r0);
    meso_file_close(f);
}

/* An update of the bricks bake with the mesh unchanged (bake/shell_update.c):
 * the same native levels with the same errors (the directors are the
 * same), and OLD's simplified stand-ins kept (report levels_kept), found
 * after the native levels. */
static void check_update(const char* mesobake, const char* dir)
{
    char old[512], upd[512], rep[512], cmd[10240];
    snprintf(old, sizeof old, "%s/bricks.meso", dir);
    snprintf(upd, sizeof upd, "%s/update.meso", dir);
    snprintf(rep, sizeof rep, "%s/update.json", dir);
    snprintf(cmd, sizeof cmd,
             "'%s' shell --update '%s' -i '%s' --texture bricks:256 --thickness-rel 0.02 -j 2 -o '%s' --report '%s' "
             ">/dev/null",
             mesobake, old, test_data("spot_uv.obj"), upd, rep);
    assert(system(cmd) == 0);
    meso_file *fo = NULL, *fu = NULL;
    assert(meso_file_open_path(old, NULL, &fo, NULL) == MESO_OK && meso_file_open_path(upd, NULL, &fu, NULL) == MESO_OK);
    assert(meso_file_validate(fu, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_level_info lo[16], lu[16];
    uint32_t no = 0, nu = 0;
    assert(meso_file_levels(fo, 1, lo, 16, &no, NULL) == MESO_OK && meso_file_levels(fu, 1, lu, 16, &nu, NULL) == MESO_OK);
    assert(no == nu);
    uint32_t native = 0;
    for (uint32_t L = 0; L < nu; ++L) {
        assert(lo[L].rec.form == lu[L].rec.form);
        native += L > 0 && lu[L].rec.form == MESO_LEVEL_NATIVE;
        if (L <= native + 1) /* native levels and the base mesh: measured again, the same */
            assert(lo[L].rec.error == lu[L].rec.error);
        else /* kept: OLD's bound, rounded up once more (bake_shell.c chain_take) */
            assert(lu[L].rec.error >= lo[L].rec.error && lu[L].rec.error <= lo[L].rec.error * (1 + 1e-6));
    }
    assert(native >= 2);
    FILE* fp = fopen(rep, "r");
    assert(fp);
    char text[65536];
    const size_t n = fread(text, 1, sizeof text - 1, fp);
    fclose(fp);
    text[n] = 0;
    const char* k = strstr(text, "\"levels_kept\"");
    unsigned kept = 0;
    assert(k && sscanf(strchr(k, ':') + 1, "%u", &kept) == 1);
    printf("update: %u levels, %u native, %u simplified stand-ins kept from OLD\n", nu, native, kept);
    assert(kept == nu - native - 2); /* every level after the base mesh's */
    meso_file_close(fo);
    meso_file_close(fu);
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "native_levels");
    check(argv[1], dir, "bricks", "--texture bricks:256 --thickness-rel 0.02 -j 2", 2);
    check(argv[1], dir, "envelope", "--texture cobble:128 --kind envelope --thickness-rel 0.02 -j 2", 1);
    check(argv[1], dir, "interior", "--texture bricks:128 --kind interior --thickness-rel 0.02 -j 2", 1);
    check_update(argv[1], dir);
    /* --levels 2: level 0 and the base mesh, no native level. */
    char path[512], cmd[10240];
    snprintf(path, sizeof path, "%s/two.meso", dir);
    snprintf(cmd, sizeof cmd, "'%s' shell -i '%s' --texture bricks:256 --levels 2 -o '%s' >/dev/null", argv[1],
             test_data("spot_uv.obj"), path);
    assert(system(cmd) == 0);
    test_assert_base_mesh_only(path);
    test_temp_dir_remove(dir);
    puts("test_shell_native_levels: ok");
    return 0;
}
