/* A shell's mesh stand-ins (FORMAT.md §7.10): level 1 the base mesh drawn
 * in the shell's place, levels 2.. its simplifications, each with the error
 * mesobake states for it. Checked against the exact CPU reference: every
 * surface point the reference ray caster hits, from several views, lies
 * within the stated error of level 1's and of the coarsest level's mesh
 * (brute force over its triangles), and the bound is not loose: the
 * farthest hit reaches half of it or more (brick tops and volume surfaces
 * do rise that far, and the coarsest level's sum of two bounds,
 * standin_levels.h, stays near the truth). Errors never decrease, each
 * coarser level lies in a shorter prefix. Exterior height field, exterior volume and envelope shells;
 * `--levels 1` writes no level, `--levels 2` the base mesh only.
 * usage: test_shell_standin MESOBAKE */
#include "test_util.h"

#include <string.h>

#include "camera.h"
#include "standin_check.h"
#include "meso_file.h"
#include "meso_layout.h"
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
    size_t hits = 0;
    static const double eyes[3][3] = {{0, 0.3, 3.2}, {2.6, 1.4, -1.2}, {-1.8, -2.2, 1.5}};
    for (int e = 0; e < 3; ++e) {
        meso_ref_view v = {.width = 40, .height = 40, .samples_per_prism = 256};
        static const double at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
        meso_camera_look_at_d(v.view, eyes[e], at, up);
        meso_camera_perspective_d(v.proj, 40.0 * M_PI / 180.0, 1.0, 0.1, 20.0);
        meso_ref_image img;
        assert(meso_ref_render(&rs, &v, &img) == MESO_OK);
        for (int p = 0; p < v.width * v.height; ++p) {
            if (!img.coverage[p])
                continue;
            const double q[3] = {img.hit[3 * p], img.hit[3 * p + 1], img.hit[3 * p + 2]};
            double d = INFINITY;
            for (uint32_t k = 0; k < tris; ++k)
                d = fmin(d, point_triangle(q, mv.positions + 3 * mv.indices[3 * k], mv.positions + 3 * mv.indices[3 * k + 1],
                                           mv.positions + 3 * mv.indices[3 * k + 2]));
            worst = fmax(worst, d);
            ++hits;
        }
        meso_ref_image_free(&img);
    }
    printf("  %-9s level %u (%u triangles): stated error %.6g, farthest of %zu reference hits %.6g (%.0f %%)\n", name,
           L, tris, err, hits, worst, 100.0 * worst / err);
    fflush(stdout);
    assert(hits > 1000);
    assert(worst <= err * (1 + 1e-5) + 1e-7); /* the stated error holds */
    assert(worst >= 0.5 * err);               /* and is not a loose guess */
    meso_ref_shell_free(&rs);
    free(mb);
}

static void check(const char* mesobake, const char* dir, const char* name, const char* args)
{
    meso_file* f = test_bake_open(mesobake, "shell", test_data("spot_uv.obj"), args, dir, name, NULL);
    meso_level_info li[16];
    uint32_t S = 1;
    const uint32_t n = test_standin_chain(f, li, 4, &S);
    check_level(f, li, S, name);
    check_level(f, li, n - 1, name);
    meso_file_close(f);
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "standin");
    check(argv[1], dir, "bricks", "--texture bricks:32 --thickness-rel 0.04");
    check(argv[1], dir, "volume", "--texture weave:32 --thickness-rel 0.04");
    check(argv[1], dir, "envelope", "--texture bricks:32 --kind envelope --thickness-rel 0.02");
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
