/*
 * frusta_tessellate.c — see frusta_tessellate.h: the reference's grid rule
 * and relief sampler over formats/frusta_tessellation.c.
 */
#include "frusta_tessellate.h"

#include <math.h>
#include <stdlib.h>

static double relief_height(const void* ctx, double s, double t)
{
    return meso_ref_texfn_value(ctx, s, t, 0);
}

static meso_frusta_height_fn height_of(const meso_ref_texfn* rel)
{
    return rel && rel->kind == 1 && rel->values ? relief_height : NULL;
}

void meso_ref_tess_point(const meso_frustum_rec* f, const meso_ref_texfn* relief, double u, double v, double p[3])
{
    meso_frusta_tess_point(f, height_of(relief), relief, u, v, p);
}

int meso_ref_frusta_tessellate(const meso_frustum_rec* recs, uint32_t count, const meso_frustum_ball_rec* balls,
    uint32_t ball_count, const meso_ref_texfn* relief, uint32_t nu, meso_ref_tess_mesh* out)
{
    meso_frusta_tess_mesh empty = {0};
    *out = empty;
    if (nu == 0 || nu > MESO_REF_TESS_MAX_GRID)
        return 0;
    uint32_t* grids = malloc(sizeof(uint32_t) * (2 * (size_t)count + ball_count + 1));
    if (!grids)
        return 0;
    for (uint32_t f = 0; f < count; ++f) {
        const double ratio = recs[f].u_scale > 0 ? recs[f].v_scale / recs[f].u_scale : 1;
        /* a long thin frustum gets at most 64 nu rings (a valid file must
         * not fail for its proportions; its cells are then longer than wide) */
        grids[f] = nu;
        grids[count + f] = (uint32_t)fmin(fmax(2.0, ceil(nu * ratio)), 64.0 * nu);
    }
    for (uint32_t i = 0; i < ball_count; ++i)
        grids[2 * (size_t)count + i] = nu;
    const meso_frusta_tess_grid g = {.nu = grids, .nv = grids + count, .ball_nu = grids + 2 * (size_t)count,
                                     .height = height_of(relief), .height_ctx = relief};
    const int ok = meso_frusta_tessellate(recs, count, balls, ball_count, &g, out);
    free(grids);
    return ok;
}

void meso_ref_tess_free(meso_ref_tess_mesh* m)
{
    meso_frusta_tess_free(m);
}
