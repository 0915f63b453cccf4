/* mesh.c — the bake's in-memory mesh: ownership and bounds. */
#include "meso_bake.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void meso_mesh_free(meso_mesh* m)
{
    if (!m)
        return;
    free(m->positions);
    free(m->normals);
    free(m->uvs);
    free(m->indices);
    free(m->corner_uvs);
    memset(m, 0, sizeof(*m));
}

void meso_mesh_materials_free(meso_mesh_materials* m)
{
    if (!m)
        return;
    for (uint32_t i = 0; m->materials && i < m->material_count; ++i)
        free(m->materials[i].rgba);
    free(m->materials);
    free(m->triangle_materials);
    memset(m, 0, sizeof(*m));
}

double meso_mesh_face_normal(const meso_mesh* m, uint32_t f, double n[3])
{
    const uint32_t* ix = m->indices + 3 * (size_t)f;
    const float *a = m->positions + 3 * (size_t)ix[0], *b = m->positions + 3 * (size_t)ix[1],
                *c = m->positions + 3 * (size_t)ix[2];
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k)
        n[k] = l > 0 ? n[k] / l : 0.0;
    return l;
}

double meso_mesh_bounds(const meso_mesh* m, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; ++k) {
        lo[k] = m->vertex_count ? INFINITY : 0.0;
        hi[k] = m->vertex_count ? -INFINITY : 0.0;
    }
    for (uint32_t i = 0; i < m->vertex_count; ++i)
        for (int k = 0; k < 3; ++k) {
            double v = m->positions[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k)
        d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(d2);
}

meso_result meso_bake_fail(meso_error* err, meso_result r, uint32_t code, const char* fmt, ...)
{
    if (err) {
        err->result = r;
        err->code = code;
        err->offset = UINT64_MAX;
        err->chunk = -1;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof(err->message), fmt, ap);
        va_end(ap);
    }
    return r;
}
