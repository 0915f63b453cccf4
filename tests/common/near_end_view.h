/* near_end_view.h — the view the parts tests draw from (test_rt_parts,
 * test_rt_shell_parts): close to one end of an object's long (z) axis,
 * looking at its box's centre, so that end is near and the other far; and
 * the distance from the eye to a box, the bound the parts' levels are
 * checked at. */
#ifndef MESO_TEST_NEAR_END_VIEW_H
#define MESO_TEST_NEAR_END_VIEW_H

#include <math.h>

#include "camera.h"
#include "meso_file.h"
#include "meso_rt.h"

static inline void near_end_view(const meso_object_record* rec, double fovy_deg, double aspect,
                                 meso_rt_draw_desc* d, double eye[3])
{
    double c[3], diag = 0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)rec->bbox_min[k] + rec->bbox_max[k]);
        diag += pow((double)rec->bbox_max[k] - rec->bbox_min[k], 2);
    }
    diag = sqrt(diag);
    const double up[3] = {0, 1, 0};
    eye[0] = c[0] + 0.05 * diag;
    eye[1] = c[1] + 0.15 * diag;
    eye[2] = rec->bbox_max[2] + 0.12 * diag;
    meso_camera_look_at(d->view, eye, c, up);
    meso_camera_perspective(d->proj, fovy_deg * M_PI / 180.0, aspect, 0.01, 100.0);
}

/* Distance from `eye` to the nearest point of the box lo..hi. */
static inline double box_distance(const double eye[3], const float lo[3], const float hi[3])
{
    double s = 0;
    for (int k = 0; k < 3; ++k) {
        const double q = eye[k] < lo[k] ? lo[k] - eye[k] : eye[k] > hi[k] ? eye[k] - hi[k] : 0.0;
        s += q * q;
    }
    return sqrt(s);
}

#endif
