/* Every prefix at a level boundary of every bundled file draws (issue 14,
 * Deliver 5): each mesh the repo bundles (the .obj files of tests/data, the
 * glTF files of tests/data/gltf but the bad_ ones) baked by mesobake (argv[1])
 * as a mesh, a brick shell and a cells object (a glTF holding another
 * bundled file's geometry in another container: as a mesh, its reader's
 * path), and each skeleton
 * (the .skel and .swc files) as a frusta object with a brick relief; the
 * file of each bake read into memory and, for every object and every
 * level L, cut at L's prefix_bytes (FORMAT.md §7.10) and given to libmeso
 * through a reader for which nothing past the cut has arrived yet
 * (prefix_io.h, MESO_IO_PENDING):
 *  - meso_rt_load_object_levels succeeds, and a draw asking for the finest
 *    level everywhere (pixel_error -1) covers pixels (none for a cells
 *    object with no voxel inside: listed below) and draws L, the
 *    finest that has arrived; an object stored in parts may draw parts
 *    instead, each with an error no larger than L's (the whole level L,
 *    which has arrived, is otherwise the better picture);
 *  - it read no more than the cut, and what its uploads hold on the GPU is
 *    no more than libmeso's estimate before them (the memory budget makes
 *    room by the estimate);
 *  - one byte short of the coarsest level's prefix, the load is refused
 *    cleanly (no object).
 * A bake the data cannot make is listed with the exit code mesobake gives
 * it (wingnut.obj intersects itself: no shell over it can be valid, 3),
 * and every bundled mesh and skeleton must have its bakes in the list
 * below, so a file added to tests/data is not left out silently.
 * preview_stream.sh checks the same through `mesoinspect preview
 * --stream-bytes` for a mesh, a shell and a cells bake, with the stats it
 * prints.
 * usage: test_rt_prefixes MESOBAKE */
#include "test_util.h"

#include <dirent.h>
#include <string.h>
#include <sys/wait.h>

#include "camera.h"
#include "egl_context.h"
#include "gl_api.h"
#include "gl_fbo.h"
#include "meso_rt.h"
#include "prefix_io.h"

enum { W = 96, H = 72, MAXL = 16, MAXP = 256 };

/* The bundled inputs and what each is baked as ("mesh", "shell", "cells",
 * "frusta"; refused: mesobake's exit code, 0 when it bakes). */
typedef struct input {
    const char* path; /* under tests/data */
    int skeleton;
    int shell_refused;
    int cells_empty;  /* no voxel inside: the cells object draws nothing (mesobake warns) */
    int mesh_only;    /* another container of a bundled file's geometry (tests/data/gltf/README.md): its
                         reader's path is the mesh bake's; its shell and cells are that file's */
} input;
static const input inputs[] = {
    {"blub_fish_low_resolution.obj", 0, 0, 0, 0},
    {"cube_no_bottom.obj", 0, 0, 0, 0},
    {"saddle.obj", 0, 0, 1, 0}, /* an open sheet: no voxel inside */
    {"sphere.obj", 0, 0, 0, 0},
    {"spot_low_resolution.obj", 0, 0, 0, 0},
    {"spot_uv.obj", 0, 0, 0, 0},
    {"torus.obj", 0, 0, 0, 0},
    {"torus_uv.obj", 0, 0, 0, 0},
    {"wingnut.obj", 0, 3, 0, 0}, /* E3114: the surface intersects itself */
    {"gltf/big_texture.gltf", 0, 0, 0, 1}, /* box.gltf with a larger texture */
    {"gltf/box.glb", 0, 0, 0, 1}, /* box.gltf as .glb */
    {"gltf/box.gltf", 0, 0, 0, 0},
    {"gltf/box_draco.glb", 0, 0, 0, 1}, /* box.gltf, Draco-compressed */
    {"gltf/box_embedded.gltf", 0, 0, 0, 1}, /* box.gltf, its buffer a data: URI */
    {"gltf/cube8.gltf", 0, 0, 0, 0},
    {"gltf/scene.gltf", 0, 0, 0, 0},
    {"gltf/sphere.glb", 0, 0, 0, 1}, /* sphere.obj as .glb */
    {"saguaro.skel", 1, 0, 0, 0},
    {"vine.skel", 1, 0, 0, 0},
    {"morphio_soma_single_frustum.swc", 1, 0, 0, 0},
    {"morphio_three_point_soma.swc", 1, 0, 0, 0},
    {"neurom_Neuron.swc", 1, 0, 0, 0},
    {"neurom_fat_end.swc", 1, 0, 0, 0},
    {"neurom_simple.swc", 1, 0, 0, 0},
};
enum { INPUTS = sizeof inputs / sizeof inputs[0] };

static test_fbo fb;
static int prefixes, files;

static int ends_with(const char* s, const char* tail)
{
    const size_t n = strlen(s), m = strlen(tail);
    return n >= m && !strcmp(s + n - m, tail);
}

/* Every mesh and skeleton in tests/data (and gltf/, bad_* aside) is listed. */
static void every_bundled_file_listed(const char* sub)
{
    char dir[512];
    snprintf(dir, sizeof dir, "%s%s%s", MESO_TEST_DATA, *sub ? "/" : "", sub);
    DIR* d = opendir(dir);
    assert(d);
    for (struct dirent* e; (e = readdir(d));) {
        const char* n = e->d_name;
        if (!strncmp(n, "bad_", 4) || !(ends_with(n, ".obj") || ends_with(n, ".gltf") || ends_with(n, ".glb") ||
                                       ends_with(n, ".skel") || ends_with(n, ".swc")))
            continue;
        char rel[600];
        snprintf(rel, sizeof rel, "%s%s%s", sub, *sub ? "/" : "", n);
        int found = 0;
        for (int i = 0; i < INPUTS; ++i)
            found |= !strcmp(inputs[i].path, rel);
        if (!found)
            fprintf(stderr, "test_rt_prefixes: %s is bundled but not baked here\n", rel);
        assert(found);
    }
    closedir(d);
}

/* Draws `obj` from a corner of its bounds' sphere; returns the pixels covered. */
static int draw(meso_rt* rt, meso_rt_object obj, const meso_object_record* rec)
{
    double c[3], r = 0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)rec->bbox_min[k] + rec->bbox_max[k]);
        r += 0.25 * pow((double)rec->bbox_max[k] - rec->bbox_min[k], 2);
    }
    r = sqrt(r);
    meso_rt_draw_desc d = {.pixel_error = -1.0f};
    const double eye[3] = {c[0] + 1.6 * r, c[1] + 1.0 * r, c[2] + 1.9 * r}, up[3] = {0, 1, 0};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, 40.0 * M_PI / 180.0, (double)W / H, 0.05 * r, 100.0 * r);
    test_fbo_clear(&fb, 0, 0, 0);
    assert(meso_rt_draw(rt, obj, &d) == MESO_OK);
    float depth[W * H];
    test_fbo_read(&fb, NULL, depth);
    int n = 0;
    for (int i = 0; i < W * H; ++i)
        n += depth[i] < 1.0f;
    return n;
}

/* Every level-boundary prefix of object `id` of the file data[0..size). */
static void object_prefixes(meso_rt* rt, const uint8_t* data, size_t size, const meso_object_record* rec,
                            const char* name, int empty)
{
    meso_file* whole = NULL;
    assert(meso_file_open_memory(data, size, NULL, &whole, NULL) == MESO_OK);
    meso_level_info li[MAXL];
    uint32_t n = 0;
    assert(meso_file_levels(whole, rec->id, li, MAXL, &n, NULL) == MESO_OK && n >= 1 && n <= MAXL);
    static meso_part_level pl[MAXP * MAXL];
    uint32_t plc = 0, parts = 0, edges = 0;
    assert(meso_file_parts(whole, rec->id, pl, MAXP * MAXL, &plc, &parts, NULL, 0, &edges, NULL) == MESO_OK);
    assert(plc <= MAXP * MAXL && parts <= MAXP);
    for (uint32_t L = 0; L < n; ++L) {
        prefix_io p = {data, li[L].prefix_bytes};
        const meso_io io = {.read_fn = prefix_read_pending, .size = size, .user = &p};
        meso_file* f = NULL;
        assert(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
        meso_rt_object obj;
        assert(meso_rt_load_object_levels(rt, f, rec->id, &obj) == MESO_OK);
        const int covered = draw(rt, obj, rec);
        meso_rt_levels_state st;
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        uint8_t drawn[MAXP];
        uint32_t pc = 0;
        assert(meso_rt_parts_state_get(rt, obj, drawn, MAXP, &pc) == MESO_OK);
        double worst = -1; /* the largest error of a part drawn, -1: a whole level drawn */
        for (uint32_t q = 0; q < pc; ++q) {
            if (drawn[q] == MESO_RT_PART_NOT_DRAWN)
                continue;
            for (uint32_t k = 0; k < plc; ++k)
                if (pl[k].rec.object == q + 1 && pl[k].rec.lod == drawn[q])
                    worst = fmax(worst, (double)pl[k].rec.error);
        }
        if ((covered > 0) == empty || (worst < 0 && st.last_drawn != (int)L) || worst > (double)li[L].rec.error ||
            st.bytes_read > li[L].prefix_bytes)
            fprintf(stderr, "test_rt_prefixes: %s object %u, the first %llu bytes (level %u): level %d drawn, "
                            "parts' worst error %g (level's %g), %d px, %llu bytes read\n",
                    name, rec->id, (unsigned long long)p.limit, L, st.last_drawn, worst, (double)li[L].rec.error,
                    covered, (unsigned long long)st.bytes_read);
        assert((covered > 0) != empty);
        assert(worst >= 0 || st.last_drawn == (int)L);
        assert(worst <= (double)li[L].rec.error);
        assert(st.bytes_read <= li[L].prefix_bytes);
        /* what the uploads hold on the GPU, never above what the budget made room for */
        assert(st.gpu_bytes_resident > 0 && st.gpu_bytes_resident <= st.gpu_bytes_estimated);
        meso_rt_release_object(rt, obj);
        meso_file_close(f);
        ++prefixes;
    }
    /* One byte short of the coarsest level: nothing of this object to draw. */
    prefix_io p = {data, li[n - 1].prefix_bytes - 1};
    const meso_io io = {.read_fn = prefix_read, .size = size, .user = &p};
    meso_file* f = NULL;
    if (meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK) { /* a one-level file may end inside its TOC */
        meso_rt_object obj = {7};
        assert(meso_rt_load_object_levels(rt, f, rec->id, &obj) != MESO_OK && obj.id == 0);
        meso_file_close(f);
    }
    printf("  %-44s object %u: %u levels%s, every prefix draws\n", name, rec->id, n, parts ? " and parts" : "");
    meso_file_close(whole);
}

static void bake_and_check(meso_rt* rt, const char* mesobake, const char* dir, const input* in, const char* kind,
                           const char* args, int refused, int empty)
{
    char out[600], cmd[4096], name[256];
    snprintf(out, sizeof out, "%s/bake.meso", dir);
    snprintf(name, sizeof name, "%s %s", kind, in->path);
    snprintf(cmd, sizeof cmd, "'%s' %s -i '%s/%s' %s -o '%s' >/dev/null 2>&1", mesobake, kind, MESO_TEST_DATA, in->path,
             args, out);
    const int st = system(cmd);
    assert(st != -1 && WIFEXITED(st));
    if (WEXITSTATUS(st) != refused)
        fprintf(stderr, "test_rt_prefixes: %s: exit %d, not %d\n", name, WEXITSTATUS(st), refused);
    assert(WEXITSTATUS(st) == refused);
    if (refused) {
        printf("  %-44s refused (exit %d), as it should be\n", name, refused);
        return;
    }
    size_t size = 0;
    uint8_t* data = test_read_file(out, &size);
    assert(data);
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    meso_object_record recs[64];
    uint32_t count = 0;
    assert(meso_file_objects(f, recs, 64, &count, NULL) == MESO_OK && count >= 1 && count <= 64);
    meso_file_close(f);
    for (uint32_t o = 0; o < count; ++o)
        object_prefixes(rt, data, size, &recs[o], name, empty);
    free(data);
    ++files;
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    every_bundled_file_listed("");
    every_bundled_file_listed("gltf");
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof why);
    if (!egl) {
        fprintf(stderr, "test_rt_prefixes: no EGL context: %s\n", why);
        return 1;
    }
    assert(test_fbo_create(&fb, W, H));
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
    char dir[256];
    test_temp_dir(dir, sizeof dir, "prefixes");
    for (int i = 0; i < INPUTS; ++i) {
        const input* in = &inputs[i];
        if (in->skeleton) {
            bake_and_check(rt, argv[1], dir, in, "frusta", "--relief bricks:16", 0, 0);
            continue;
        }
        bake_and_check(rt, argv[1], dir, in, "mesh", "", 0, 0);
        if (in->mesh_only)
            continue;
        bake_and_check(rt, argv[1], dir, in, "shell", "--texture bricks:16 -j 2", in->shell_refused, 0);
        /* 8 tiles of 16 voxels along the longest axis (the default 32):
         * the levels as the defaults make them, at a fraction of the
         * voxelisation */
        bake_and_check(rt, argv[1], dir, in, "cells", "--tiles 8 --tile-res 16", 0, in->cells_empty);
    }
    printf("test_rt_prefixes: %d files, %d prefixes drawn\n", files, prefixes);
    test_temp_dir_remove(dir);
    meso_rt_destroy(rt);
    test_fbo_destroy(&fb);
    meso_egl_destroy(egl);
    puts("test_rt_prefixes: ok");
    return 0;
}
