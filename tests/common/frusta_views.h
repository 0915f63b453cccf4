/* frusta_views.h — the three views the frusta level tests cast reference
 * rays from (test_frusta_standin, test_frusta_skeleton_levels): from 2.6
 * bounding radii away along three spread directions, looking at the
 * centre of the object's bounding box. Include after test_util.h. */
#ifndef MESO_TEST_FRUSTA_VIEWS_H
#define MESO_TEST_FRUSTA_VIEWS_H

#include <math.h>

#include "camera.h"
#include "frustum_reference.h"

/* View e (0..2) of m at size x size pixels. */
static inline meso_ref_view test_frusta_view(const meso_ref_frusta* m, int e, int size, int threads)
{
    static const double dirs[3][3] = {{0, 0.1, 1}, {0.8, 0.45, -0.4}, {-0.6, -0.7, 0.4}};
    double c[3], radius = 0, eye[3];
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)m->bbox_min[k] + m->bbox_max[k]);
        radius += 0.25 * ((double)m->bbox_max[k] - m->bbox_min[k]) * ((double)m->bbox_max[k] - m->bbox_min[k]);
    }
    radius = sqrt(radius);
    meso_ref_view v = {.width = size, .height = size, .threads = threads};
    const double dl = sqrt(dirs[e][0] * dirs[e][0] + dirs[e][1] * dirs[e][1] + dirs[e][2] * dirs[e][2]);
    for (int k = 0; k < 3; ++k)
        eye[k] = c[k] + 2.6 * radius * dirs[e][k] / dl;
    static const double up[3] = {0, 1, 0};
    meso_camera_look_at_d(v.view, eye, c, up);
    meso_camera_perspective_d(v.proj, 45.0 * M_PI / 180.0, 1.0, 0.2 * radius, 5.0 * radius);
    return v;
}

#endif /* MESO_TEST_FRUSTA_VIEWS_H */
