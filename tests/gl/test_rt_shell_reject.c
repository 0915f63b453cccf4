/* Hull rejection (issue 14, runtime/rt_shell.c): the same shell drawn with
 * meso_rt_shell_draw.no_hull_reject = 1 (every hull fragment ray casts, the
 * behaviour before) and 0, on the bundled sphere with a height field
 * (smooth, curved, tetra, segment only) and with the camera inside a thick
 * shell (smooth). Asserted, against the draw without rejection:
 *  - the images, colour and depth, are equal (a rejected fragment's hit
 *    lies behind a hit already in the depth buffer, so it would have failed
 *    the depth test; the entry faces cover the pixels the exit faces cover)
 *    except where two prisms' hits tie within the depth buffer's resolution
 *    and the draw order, sorted now, picks the other (measured: none; 4
 *    pixels of 5192 at equal depth when tetra was sorted too, rt_shell.c):
 *    at most 0.5 % of the covered pixels, depth within 4 steps of a 24-bit
 *    buffer, colour within 5 % there;
 *  - outside the shell every hull fragment is either ray cast or rejected:
 *    ray-casting + rejected = the ray-casting count without rejection;
 *  - a closed shell is crossed twice by every ray that hits it, the second
 *    crossing behind the hit: with the prisms sorted front to back (smooth,
 *    curved) fewer than half the fragments ray cast; fewer steps for all;
 *  - nothing is rejected under a depth function that does not let the
 *    nearer fragment win (GL_ALWAYS), and the image is unchanged there too.
 * With MESO_TEST_NO_HULL_REJECT set (meson runs it with GL_ARB_clear_texture
 * hidden), the fallback: nothing rejected, the counts equal.
 * Accuracy against the exact reference, with rejection (the default), is
 * tests/gl/test_rt_shell.c's. */
#include "test_util.h"

#include <stdlib.h>
#include <string.h>

#include "adapters.h"
#include "gl_api.h"
#include "gl_fbo.h"
#include "meso_rt.h"
#include "shell_scene.h"

enum { W = 128, H = 96 };

typedef struct frame {
    uint8_t rgba[W * H * 4];
    float depth[W * H];
    meso_rt_draw_stats st;
} frame;

static void draw(meso_rt* rt, test_fbo* fbo, meso_rt_object obj, const camera* cam, meso_rt_draw_desc d, frame* out)
{
    camera_matrices(cam, d.view, d.proj);
    d.stats = &out->st;
    test_fbo_clear(fbo, 0.0f, 0.0f, 0.0f);
    CHECK(meso_rt_draw(rt, obj, &d) == MESO_OK);
    test_fbo_read(fbo, out->rgba, out->depth);
    CHECK(out->st.supported);
}

static long covered(const frame* f)
{
    long n = 0;
    for (int i = 0; i < W * H; ++i)
        n += f->depth[i] < 1.0f;
    return n;
}

/* Draws with and without rejection; checks what the header lists. */
static void compare_case(meso_rt* rt, test_fbo* fbo, const char* name, const uint8_t* file, size_t size,
                         const camera* cam, meso_shell_technique t, int outside, int expect_reject, int always)
{
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    CHECK(meso_rt_load_object(rt, f, 1, &obj) == MESO_OK);
    meso_file_close(f);
    static frame off, on, always_off, always_on;
    draw(rt, fbo, obj, cam, (meso_rt_draw_desc){.shell = {.technique = t, .no_hull_reject = 1}}, &off);
    draw(rt, fbo, obj, cam, (meso_rt_draw_desc){.shell = {.technique = t}}, &on);
    const long cov = covered(&on);
    printf("%-14s technique %d: covered %ld; without rejection %.2f fragments/px, %.1f steps/px; with %.2f "
           "fragments/px (+ %.2f rejected), %.1f steps/px\n",
           name, (int)t, cov, (double)off.st.fragments / cov, (double)off.st.steps / cov,
           (double)on.st.fragments / cov, (double)on.st.rejected / cov, (double)on.st.steps / cov);
    CHECK(cov > 1000);
    long diff = 0;
    double dmax = 0, cerr = 0;
    for (int i = 0; i < W * H; ++i)
        if (memcmp(off.rgba + 4 * i, on.rgba + 4 * i, 4) || off.depth[i] != on.depth[i]) {
            ++diff;
            dmax = fmax(dmax, fabs((double)off.depth[i] - on.depth[i]));
            for (int k = 0; k < 3; ++k)
                cerr += abs(off.rgba[4 * i + k] - on.rgba[4 * i + k]) / (3.0 * 255.0);
        }
    printf("  %ld pixels differ, depth by up to %.3g, colour by %.4f on average there\n", diff, dmax,
           diff ? cerr / diff : 0.0);
    CHECK_MSG(diff <= cov / 200 && dmax <= 0x1p-22 && cerr <= 0.05 * diff,
              "%s: %ld pixels changed with rejection, depth by up to %g", name, diff, dmax);
    CHECK(off.st.rejected == 0);
    if (!expect_reject) {
        CHECK(on.st.rejected == 0 && on.st.fragments == off.st.fragments && on.st.steps == off.st.steps);
    } else {
        if (outside)
            CHECK_MSG(on.st.fragments + on.st.rejected == off.st.fragments, "%s: %llu + %llu hull fragments, %llu before",
                      name, (unsigned long long)on.st.fragments, (unsigned long long)on.st.rejected,
                      (unsigned long long)off.st.fragments);
        CHECK(on.st.rejected > 0 && on.st.steps < off.st.steps);
        if (outside && (t == MESO_SHELL_SMOOTH || t == MESO_SHELL_CURVED)) /* sorted (rt_shell.c) */
            CHECK(2 * on.st.fragments < off.st.fragments);
    }
    /* GL_ALWAYS: the last fragment drawn wins; rejection would change that, so it is off. */
    if (!always) {
        meso_rt_release_object(rt, obj);
        return;
    }
    draw(rt, fbo, obj, cam, (meso_rt_draw_desc){.shell = {.technique = t, .no_hull_reject = 1}, .depth_func = GL_ALWAYS},
         &always_off);
    draw(rt, fbo, obj, cam, (meso_rt_draw_desc){.shell = {.technique = t}, .depth_func = GL_ALWAYS}, &always_on);
    CHECK(always_on.st.rejected == 0 && always_on.st.fragments == always_off.st.fragments);
    CHECK(memcmp(always_off.rgba, always_on.rgba, sizeof(on.rgba)) == 0 &&
          memcmp(always_off.depth, always_on.depth, sizeof(on.depth)) == 0);
    meso_rt_release_object(rt, obj);
}

int main(void)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof(why));
    CHECK_MSG(egl != NULL, "%s", why);
    test_fbo fbo;
    CHECK(test_fbo_create(&fbo, W, H));
    meso_rt* rt = NULL;
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
    const int expect_reject = getenv("MESO_TEST_NO_HULL_REJECT") == NULL;
    texture height = make_height(64);
    meso_mesh m;
    meso_error err;
    CHECK(meso_openmesh_read(MESO_TEST_DATA "/sphere.obj", &m, NULL, &err) == MESO_OK);
    planar_uvs(&m, 2.0);

    size_t size;
    uint8_t* file = shell_file(&m, 0.12, &height, 1, &size);
    const camera cam = {.eye = {1.6, 1.5, 2.6}, .at = {0, 0, 0}, .fovy = 0.75, .zn = 0.5, .zf = 10};
    const meso_shell_technique all[4] = {MESO_SHELL_SMOOTH, MESO_SHELL_CURVED, MESO_SHELL_TETRA,
                                         MESO_SHELL_SEGMENT_ONLY};
    /* The fallback (no rejection at all) on one technique: the others draw alike. */
    for (int t = 0; t < (expect_reject ? 4 : 1); ++t)
        compare_case(rt, &fbo, "sphere+height", file, size, &cam, all[t], 1, expect_reject, t == 0);
    free(file);

    /* The eye inside a thick shell: prisms reaching the near plane draw
     * their exit faces on it (shell_vert.glsl), never rejected. */
    file = shell_file(&m, 0.4, &height, 1, &size);
    const camera inside = {.eye = {0.0, 0.05, 1.3}, .at = {1.0, 0.2, 0.9}, .fovy = 1.2, .zn = 0.01, .zf = 10};
    compare_case(rt, &fbo, "inside-shell", file, size, &inside, MESO_SHELL_SMOOTH, 0, expect_reject, 0);
    free(file);

    meso_mesh_free(&m);
    free(height.texels);
    meso_rt_destroy(rt);
    test_fbo_destroy(&fbo);
    meso_egl_destroy(egl);
    printf("ok\n");
    return 0;
}
