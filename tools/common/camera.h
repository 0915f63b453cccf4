/*
 * camera.h — the column-major (OpenGL convention) camera matrices every
 * program builds for meso_rt_draw_desc.view / .proj or the CPU references'
 * double views: gluPerspective and gluLookAt. Header-only; used by
 * mesoinspect preview, examples/mesoview and the tests.
 *
 * Each matrix is computed in double; the float versions round each element
 * of the double result once, so a program and a reference that use the
 * two versions see the same camera up to that rounding.
 */
#ifndef MESO_CAMERA_H
#define MESO_CAMERA_H

#include <math.h>
#include <string.h>

/* Eye -> clip: vertical field of view `fovy` (radians), width/height
 * `aspect`, near and far planes zn < zf (gluPerspective). */
static inline void meso_camera_perspective_d(double m[16], double fovy, double aspect, double zn, double zf)
{
    const double f = 1.0 / tan(fovy / 2);
    memset(m, 0, 16 * sizeof(double));
    m[0] = f / aspect;
    m[5] = f;
    m[10] = (zf + zn) / (zn - zf);
    m[11] = -1.0;
    m[14] = 2 * zf * zn / (zn - zf);
}

/* World -> eye: the eye at `eye` looking at `at`, `up` roughly up and not
 * parallel to at - eye (gluLookAt). */
static inline void meso_camera_look_at_d(double m[16], const double eye[3], const double at[3], const double up[3])
{
    double f[3] = {at[0] - eye[0], at[1] - eye[1], at[2] - eye[2]};
    const double fl = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int k = 0; k < 3; ++k)
        f[k] /= fl;
    double s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
    const double sl = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int k = 0; k < 3; ++k)
        s[k] /= sl;
    const double u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
    memset(m, 0, 16 * sizeof(double));
    for (int k = 0; k < 3; ++k) {
        m[4 * k + 0] = s[k];
        m[4 * k + 1] = u[k];
        m[4 * k + 2] = -f[k];
    }
    m[12] = -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    m[13] = -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    m[14] = f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2];
    m[15] = 1.0;
}

static inline void meso_camera_to_float(const double d[16], float m[16])
{
    for (int i = 0; i < 16; ++i)
        m[i] = (float)d[i];
}

static inline void meso_camera_perspective(float m[16], double fovy, double aspect, double zn, double zf)
{
    double d[16];
    meso_camera_perspective_d(d, fovy, aspect, zn, zf);
    meso_camera_to_float(d, m);
}

static inline void meso_camera_look_at(float m[16], const double eye[3], const double at[3], const double up[3])
{
    double d[16];
    meso_camera_look_at_d(d, eye, at, up);
    meso_camera_to_float(d, m);
}

#endif
