/* shell_hits.h — the surface points the exact reference ray caster
 * (runtime/reference/shell_reference.h) hits on a shell from a few views:
 * what the shell level tests (test_shell_standin, test_shell_native_levels,
 * test_shell_volume_levels) measure a level's stated error at. Each view
 * looks from an eye at the origin, y up, in a square image (near 0.1, far
 * 20). Include after test_util.h. */
#ifndef MESO_TEST_SHELL_HITS_H
#define MESO_TEST_SHELL_HITS_H

#include <math.h>

#include "camera.h"
#include "point_cloud.h"
#include "shell_reference.h"

/* The hits of `s` from views[0..count-1], size x size pixels each, fovy in
 * degrees, appended to *out. */
static inline void test_shell_hits(const meso_ref_shell* s, const double views[][3], int count, int size,
                                   double fovy_deg, cloud* out)
{
    for (int e = 0; e < count; ++e) {
        meso_ref_view v = {.width = size, .height = size, .samples_per_prism = 256};
        static const double at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
        meso_camera_look_at_d(v.view, views[e], at, up);
        meso_camera_perspective_d(v.proj, fovy_deg * M_PI / 180.0, 1.0, 0.1, 20.0);
        meso_ref_image img;
        assert(meso_ref_render(s, &v, &img) == MESO_OK);
        for (int p = 0; p < v.width * v.height; ++p)
            if (img.coverage[p]) {
                const double q[3] = {img.hit[3 * p], img.hit[3 * p + 1], img.hit[3 * p + 2]};
                cloud_add(out, q);
            }
        meso_ref_image_free(&img);
    }
}

#endif /* MESO_TEST_SHELL_HITS_H */
