/*
 * mesh_colour_grid.c — the base colour of a textured mesh at the nearest
 * surface point of each sample of a coarse grid (mesh_colour_grid.h states
 * the decisions; FORMAT.md §7.2 kind 3 the chunk).
 */
#include "mesh_colour_grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "srgb.h"
#include "triangle_grid.h"

void meso_mesh_colour_grid_dims(const double ext[3], uint32_t g, uint32_t dims[3])
{
    const double e = fmax(ext[0], fmax(ext[1], ext[2]));
    for (int k = 0; k < 3; ++k) {
        const double n = e > 0 ? ceil(g * ext[k] / e - 1e-9) : 1;
        dims[k] = n < 1 ? 1 : n > g ? g : (uint32_t)n;
    }
}

static int wrap(int i, int n)
{
    i %= n;
    return i < 0 ? i + n : i;
}

/* Material `mt`'s base colour at uv (linear RGBA). */
static void base_colour(const meso_mesh_material* mt, const double uv[2], double out[4])
{
    for (int k = 0; k < 4; ++k)
        out[k] = mt ? mt->base_color_factor[k] : 1.0;
    if (!mt || !mt->rgba || !mt->width || !mt->height)
        return;
    const int n[2] = {(int)mt->width, (int)mt->height};
    int i0[2], i1[2];
    double f[2];
    for (int a = 0; a < 2; ++a) {
        /* the mesh's v runs up (OBJ's convention; glTF's is flipped on load), rows top to bottom */
        double x = (a ? 1 - uv[1] : uv[0]) * n[a] - 0.5;
        x -= n[a] * floor(x / n[a]); /* keep the floor's argument small */
        const double fl = floor(x);
        f[a] = x - fl;
        i0[a] = wrap((int)fl, n[a]);
        i1[a] = wrap((int)fl + 1, n[a]);
    }
    const size_t W = mt->width;
    const uint8_t* t = mt->rgba;
    for (int k = 0; k < 4; ++k) {
#define TEXEL(x, y) (k < 3 ? meso_srgb_to_linear(t[4 * ((size_t)(y) * W + (size_t)(x)) + k] / 255.0) \
                           : t[4 * ((size_t)(y) * W + (size_t)(x)) + k] / 255.0)
        const double c = (1 - f[1]) * ((1 - f[0]) * TEXEL(i0[0], i0[1]) + f[0] * TEXEL(i1[0], i0[1])) +
                         f[1] * ((1 - f[0]) * TEXEL(i0[0], i1[1]) + f[0] * TEXEL(i1[0], i1[1]));
#undef TEXEL
        out[k] *= c;
    }
}

meso_result meso_mesh_colour_grid_build(const meso_mesh* m, const meso_mesh_materials* mats, const double lo[3],
                                        const double ext[3], const uint32_t dims[3], uint8_t* rgba, meso_error* err)
{
    if (!mats || mats->material_count == 0 || !mats->triangle_materials)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_MESH_COLOUR_ISSUE_NONE,
                              "--colour from-mesh: the input has no material with a base colour (a glTF input "
                              "with pbrMetallicRoughness baseColorFactor or baseColorTexture is needed)");
    int textured = 0;
    for (uint32_t i = 0; i < mats->material_count; ++i)
        textured |= mats->materials[i].rgba != NULL;
    if (textured && !m->uvs && !m->corner_uvs)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_MESH_COLOUR_ISSUE_NONE,
                              "--colour from-mesh: the mesh has a base-colour texture but no uvs (TEXCOORD_0)");
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    double* xyz = malloc(sizeof(double) * 3 * (nv ? nv : 1));
    if (!xyz)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "colour grid: out of memory");
    double blo[3], bhi[3];
    meso_mesh_bounds(m, blo, bhi);
    for (size_t i = 0; i < 3 * (size_t)nv; ++i)
        xyz[i] = m->positions[i];
    for (int k = 0; k < 3; ++k) {
        blo[k] = fmin(blo[k], lo[k]);
        bhi[k] = fmax(bhi[k], lo[k] + ext[k]);
    }
    mesoi_tri_grid g;
    meso_result r = mesoi_tri_grid_build(xyz, m->indices, nt, blo, bhi, &g, err);
    if (r != MESO_OK) {
        free(xyz);
        return r;
    }
    for (uint32_t z = 0; z < dims[2]; ++z)
        for (uint32_t y = 0; y < dims[1]; ++y)
            for (uint32_t x = 0; x < dims[0]; ++x) {
                const uint32_t c[3] = {x, y, z};
                double p[3], bw[2];
                for (int k = 0; k < 3; ++k)
                    p[k] = lo[k] + (c[k] + 0.5) * ext[k] / dims[k];
                uint32_t t = UINT32_MAX;
                mesoi_tri_grid_closest(&g, p, &t, bw);
                const uint32_t mi = t < nt ? mats->triangle_materials[t] : UINT32_MAX;
                const meso_mesh_material* mt = mi < mats->material_count ? &mats->materials[mi] : NULL;
                double uv[2] = {0, 0}, col[4];
                const double lam[3] = {1 - bw[0] - bw[1], bw[0], bw[1]};
                for (int j = 0; j < 3 && t < nt; ++j)
                    for (int a = 0; a < 2; ++a)
                        uv[a] += lam[j] * (m->corner_uvs ? m->corner_uvs[6 * (size_t)t + 2 * (size_t)j + a]
                                           : m->uvs  ? m->uvs[2 * (size_t)m->indices[3 * (size_t)t + j] + a]
                                                     : 0.0);
                base_colour(mt, uv, col);
                uint8_t* o = rgba + 4 * (((size_t)z * dims[1] + y) * dims[0] + x);
                for (int k = 0; k < 3; ++k)
                    o[k] = (uint8_t)lround(255 * meso_linear_to_srgb(col[k]));
                o[3] = (uint8_t)lround(255 * fmin(fmax(col[3], 0.0), 1.0));
            }
    mesoi_tri_grid_free(&g);
    free(xyz);
    return MESO_OK;
}
