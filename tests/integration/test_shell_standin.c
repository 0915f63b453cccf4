/* A shell's mesh stand-ins (FORMAT.md §7.10): level 1 the shell's
 * mid-surface over a height field (the base mesh over a volume) drawn in
 * the shell's place, levels 2.. the base mesh's simplifications, each with the error
 * mesobake states for it. Checked against the exact CPU reference: every
 * surface point the reference ray caster hits, from several views, lies
 * within the stated error of level 1's and of the coarsest level's mesh
 * (brute force over its triangles), and the bound is not loose: the
 * farthest hit reaches half of it or more (brick tops and volume surfaces
 * do rise that far, and the coarsest level's sum of two bounds,
 * standin_levels.h, stays near the truth). Errors never decrease, each
 * coarser level lies in a shorter prefix. Level 1 is checked against its
 * definition from level 0's MESH, SDIR and TX2D too. Exterior height field,
 * exterior volume and envelope shells, and a height field on an open mesh;
 * `--levels 1` writes no level, `--levels 2` the base mesh only.
 * usage: test_shell_standin MESOBAKE */
#include "test_util.h"

#include <string.h>

#include "standin_check.h"
#include "meso_file.h"
#include "meso_layout.h"
#include "shell_hits.h"
#include "shell_reference.h"

/* The farthest reference hit from level L's mesh, against its stated error. */
static void check_level(meso_file* f, const meso_level_info* li, uint32_t L, const char* name)
{
    const double err = li[L].rec.error;
    meso_mesh_view mv;
    uint8_t* mb = test_read_level_mesh(f, (uint16_t)L, &mv);
    const uint32_t tris = mv.layout.index_count / 3;
    meso_ref_shell rs;
    assert(meso_ref_shell_load(f, 1, &rs, NULL) == MESO_OK);
    double worst = 0;
    static const double eyes[3][3] = {{0, 0.3, 3.2}, {2.6, 1.4, -1.2}, {-1.8, -2.2, 1.5}};
    cloud h = {0};
    test_shell_hits(&rs, eyes, 3, 40, 40.0, &h);
    for (size_t i = 0; i < h.n; ++i) {
        const double* q = h.p + 3 * i;
        double d = INFINITY;
        for (uint32_t k = 0; k < tris; ++k)
            d = fmin(d, point_triangle(q, mv.positions + 3 * mv.indices[3 * k], mv.positions + 3 * mv.indices[3 * k + 1],
                                       mv.positions + 3 * mv.indices[3 * k + 2]));
        worst = fmax(worst, d);
    }
    const size_t hits = h.n;
    cloud_free(&h);
    printf("  %-9s level %u (%u triangles): stated error %.6g, farthest of %zu reference hits %.6g (%.0f %%)\n", name,
           L, tris, err, hits, worst, 100.0 * worst / err);
    fflush(stdout);
    assert(hits > 1000);
    assert(worst <= err * (1 + 1e-5) + 1e-7); /* the stated error holds */
    assert(worst >= 0.5 * err);               /* and is not a loose guess */
    meso_ref_shell_free(&rs);
    free(mb);
}

static void* read_level0(meso_file* f, uint32_t type, const meso_chunk_info** ci)
{
    const int32_t i = meso_file_find_level(f, type, 1, 0);
    if (i < 0)
        return NULL;
    *ci = meso_file_chunk(f, (uint32_t)i);
    void* data = malloc((size_t)(*ci)->decoded_size);
    assert(data && meso_file_read_chunk(f, (uint32_t)i, data, (size_t)(*ci)->decoded_size, NULL) == MESO_OK);
    return data;
}

/* Level S, the first stand-in: over a height field the shell's
 * mid-surface, from level 0's own chunks: vertex k at bottom_k + m (top_k
 * - bottom_k) (FORMAT.md §7.2's SDIR layers), m halfway between the
 * lowest and highest texel (the lowest taken as 0 on an open mesh, whose
 * border walls reach w = 0), with the error (highest - lowest) / 2 times
 * the longest top - bottom; over a volume the base mesh itself. */
static void check_midsurface(meso_file* f, const meso_level_info* li, uint32_t S, int open, const char* name)
{
    const meso_chunk_info *mc, *sc, *tc = NULL;
    uint8_t* mb = read_level0(f, MESO_CHUNK_MESH, &mc);
    float* sdir = read_level0(f, MESO_CHUNK_SDIR, &sc);
    const uint8_t* tex = read_level0(f, MESO_CHUNK_TX2D, &tc);
    meso_mesh_view base, mv;
    assert(mb && sdir && meso_mesh_parse(mb, (size_t)mc->decoded_size, &base, NULL) == MESO_OK);
    uint8_t* lb = test_read_level_mesh(f, (uint16_t)S, &mv);
    const uint32_t nv = base.layout.vertex_count, layers = sc->dims[1];
    assert(mv.layout.vertex_count == nv && mv.layout.index_count == base.layout.index_count &&
           !memcmp(mv.indices, base.indices, sizeof(uint32_t) * base.layout.index_count) && sc->dims[0] == nv);
    double lo = 1, hi = 0, m = 0;
    if (tex) {
        const size_t n = (size_t)tc->dims[0] * tc->dims[1] * tc->dims[2];
        const double full = tc->dtype == MESO_DTYPE_U16 ? 65535.0 : 255.0;
        for (size_t i = 0; i < n; ++i) {
            const double h = (tc->dtype == MESO_DTYPE_U16 ? (double)(tex[2 * i] | tex[2 * i + 1] << 8) : tex[i]) / full;
            lo = fmin(lo, h);
            hi = fmax(hi, h);
        }
        lo = open ? 0.0 : lo;
        m = 0.5 * (lo + hi);
    }
    double dmax = 0, off = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
            const double p = base.positions[3 * v + k], top = p + sdir[3 * v + k],
                         bottom = p + (layers == 2 ? sdir[3 * ((size_t)nv + v) + k] : 0.0f);
            const double want = tex ? (double)(float)(bottom + m * (top - bottom)) : p;
            off = fmax(off, fabs(mv.positions[3 * v + k] - want));
            d2 += (top - bottom) * (top - bottom);
        }
        dmax = fmax(dmax, sqrt(d2));
    }
    const double want_err = 0.5 * (hi - lo) * dmax, err = li[S].rec.error;
    printf("  %-9s level %u: %s, %u vertices %.3g from it; error %.6g%s%.6g\n", name, S,
           tex ? "the mid-surface" : "the base mesh", nv, off, err, tex ? ", (highest - lowest texel) / 2 x longest span " : "", tex ? want_err : 0.0);
    assert(off <= 1e-6 * (1 + fabs(m))); /* the same f32 rounding, give or take an ulp */
    if (tex)
        assert(err >= want_err && err <= want_err * (1 + 1e-5) + 1e-5 * dmax);
    free(mb);
    free(sdir);
    free((void*)tex);
    free(lb);
}

static void check(const char* mesobake, const char* dir, const char* mesh, const char* name, const char* args)
{
    meso_file* f = test_bake_open(mesobake, "shell", test_data(mesh), args, dir, name, NULL);
    meso_level_info li[16];
    uint32_t S = 1;
    const uint32_t n = test_standin_chain(f, li, 4, &S);
    check_midsurface(f, li, S, !strcmp(mesh, "saddle.obj"), name);
    check_level(f, li, S, name);
    check_level(f, li, n - 1, name);
    meso_file_close(f);
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "standin");
    check(argv[1], dir, "spot_uv.obj", "bricks", "--texture bricks:32 --thickness-rel 0.04");
    check(argv[1], dir, "spot_uv.obj", "volume", "--texture weave:32 --thickness-rel 0.04");
    check(argv[1], dir, "spot_uv.obj", "envelope", "--texture bricks:32 --kind envelope --thickness-rel 0.02");
    /* An open mesh: its border prisms' side walls are drawn down to w = 0. */
    check(argv[1], dir, "saddle.obj", "open", "--texture bricks:32 --thickness-rel 0.1");
    /* --levels 1: the file of earlier bakes, one level. */
    char path[512], cmd[10240];
    snprintf(path, sizeof path, "%s/one.meso", dir);
    snprintf(cmd, sizeof cmd, "'%s' shell -i '%s' --texture bricks:32 --levels 1 -o '%s' >/dev/null", argv[1],
             test_data("spot_low_resolution.obj"), path);
    assert(system(cmd) == 0);
    test_assert_one_level(path);
    /* --levels 2: the base mesh only. */
    snprintf(cmd, sizeof cmd, "'%s' shell -i '%s' --texture bricks:32 --levels 2 -o '%s' >/dev/null", argv[1],
             test_data("spot_low_resolution.obj"), path);
    assert(system(cmd) == 0);
    test_assert_base_mesh_only(path);
    test_temp_dir_remove(dir);
    puts("test_shell_standin: ok");
    return 0;
}
