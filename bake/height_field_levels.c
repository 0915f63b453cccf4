/*
 * height_field_levels.c — native coarser levels of an object drawn from a
 * height field (height_field_levels.h; FORMAT.md §7.10; issue 14:
 * "prefiltered pyramids of the texture function ... the distance map of
 * each level conservative for that level's function", and a frusta
 * object's "relief-map mip levels"). Written for shells below; a frusta
 * object's relief is sampled the same way (bilinear, wrapping in s and t,
 * FORMAT.md §7.2 kind 4), so the same sup holds, and bake/bake_frusta.c
 * turns it into object units through the stand-in's gain
 * (frusta_standin.h, term 1).
 *
 * The pyramid. Level l halves level l - 1: texel (i, j) is the mean of
 * texels (2i..2i+1, 2j..2j+1), quantised to the nearest stored value
 * (meso_texfn_from_values). That is the box filter the runtime's own mip
 * levels use (rt_mip_box.c), so a far shell drawn from level l looks as
 * level 0 drawn at that footprint would. Each level gets the distance map
 * of its own function (distance_map.h: conservative for exactly what is
 * sampled), with level 0's dims halved.
 *
 * The error, exact. The runtime and the reference sample a height field
 * bilinearly between texel centres, wrapping in s and t (distance_map.h).
 * Level 0's centres are at (i + 1/2) / W0, level l's at
 * (i + 1/2) 2^l / W0 = (2^(l+1) i + 2^l) / (2 W0): both on the lattice
 * a / (2 W0) (the "half-texel lattice" of level 0), and so are level 0's
 * texel edges. Between two neighbouring lattice lines neither function
 * has a break, so on each lattice cell both are bilinear, their difference
 * is too (c0 + c1 s + c2 t + c3 s t), and a bilinear function takes its
 * extremes over a rectangle at the corners. Hence
 *
 *     sup |h_l - h_0| = max over the lattice points of |h_l - h_0|,
 *
 * 4 W0 H0 evaluations per level, in doubles from the stored values.
 * bake_shell.c turns it into an object-space error: in a prism a point of
 * the surface is Phi(u, v, h(s, t)) = B(u, v) + h D(u, v), D the convex
 * combination of the corners' top - bottom (FORMAT.md §7.2; the smooth
 * mapping, as the stand-in's error assumes), so the two levels' surface
 * points over the same (u, v) are |h_l - h_0| |D| apart, at most
 * sup |h_l - h_0| max_k |top_k - bottom_k|, each way. Where the texture
 * jumps between two prisms (a uv seam) the surface also has a wall on
 * their shared face, between the two sides' heights; a point of level l's
 * wall at w between h_l on one side and h_l on the other is within
 * max over the sides of |h_l - h_0| |D| of level 0's wall, so the bound
 * holds there too (tests/integration/test_shell_native_levels.c meets
 * such walls on spot's seams).
 *
 * What this bounds: the surfaces of the smooth mapping Phi as the
 * reference samples them (doubles; the stand-in's error assumes as much).
 * A GPU's bilinear filter weighs texels in fixed point (often 8 bits), an
 * error of level 0's own drawing too; under the curved mapping Phi_c a
 * column is reparametrised in w (w-bar, shell_map.h) and the bound holds
 * where |d w-bar / d w| <= 1, which is not proved (nor for the stand-in).
 *
 * Decided here: the same 2 x 2 box as the runtime (not a wider filter that
 * would alias less and move the surface more); levels stop at
 * MESOI_HEIGHT_MIN_LEVEL_RES texels a side or an odd side (no half texels
 * to average), and where the sup reaches the highest texel (the base mesh
 * is then no farther). The distance map's w resolution halves too but
 * stays at least 8, the default's own lower clamp (distance_map.c).
 */
#include "height_field_levels.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "bake_threads.h"

double mesoi_height_sup_diff(const meso_texfn* a, const meso_texfn* b, int threads)
{
    const int64_t W = 2 * (int64_t)b->dims[0], H = 2 * (int64_t)b->dims[1];
    double sup = 0.0;
    const int nt = meso_bake_thread_count(threads);
    (void)nt;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(max : sup)
    for (int64_t y = 0; y < H; ++y) {
        const double t = (double)y / (double)H;
        for (int64_t x = 0; x < W; ++x) {
            const double s = (double)x / (double)W;
            const double d = fabs(meso_texfn_sample(a, s, t, 0.0) - meso_texfn_sample(b, s, t, 0.0));
            sup = d > sup ? d : sup;
        }
    }
    return sup;
}

/* Level `prev` halved (its sides even), quantised to its dtype: 2 x 2
 * means for a height field, 2 x 2 x 2 for a volume (volume_levels.h). */
static meso_result halve(const meso_texfn* prev, meso_texfn* out, meso_error* err)
{
    const int volume = prev->kind == MESO_TEXFN_DENSITY;
    const uint32_t W = prev->dims[0] / 2, H = prev->dims[1] / 2, D = volume ? prev->dims[2] / 2 : 1;
    const uint32_t dims[3] = {W, H, D};
    float* v = malloc(sizeof(float) * (size_t)W * H * D);
    if (!v)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture levels: out of memory");
    const size_t PW = prev->dims[0], PS = PW * prev->dims[1];
    for (uint32_t k = 0; k < D; ++k)
        for (uint32_t j = 0; j < H; ++j)
            for (uint32_t i = 0; i < W; ++i) {
                const float* p = prev->values + 2 * (size_t)k * PS + 2 * (size_t)j * PW + 2 * (size_t)i;
                const double sum = (double)p[0] + p[1] + p[PW] + p[PW + 1];
                v[((size_t)k * H + j) * W + i] =
                    volume ? (float)(0.125 * (sum + p[PS] + p[PS + 1] + p[PS + PW] + p[PS + PW + 1]))
                           : (float)(0.25 * sum);
            }
    const meso_result r = meso_texfn_from_values(prev->kind, dims, v, prev->dtype, out, err);
    free(v);
    if (r == MESO_OK)
        memcpy(out->source, prev->source, sizeof out->source);
    return r;
}

/* Level l's distance map: d0's dims halved l times (s and t at least 1, w
 * at least 8, or d0's when smaller), d0's dtype. */
static meso_result level_distmap(const meso_texfn* fn, const meso_distmap* d0, uint32_t l, int threads,
                                 meso_distmap* out, meso_error* err)
{
    uint32_t dd[3];
    for (int k = 0; k < 3; ++k) {
        dd[k] = d0->dims[k] >> l;
        dd[k] = dd[k] ? dd[k] : 1;
    }
    if (dd[2] < 8)
        dd[2] = d0->dims[2] < 8 ? d0->dims[2] : 8;
    return meso_distmap_build(fn, dd, d0->dtype, threads, out, err);
}

meso_result mesoi_height_levels_build(const meso_texfn* f0, const meso_distmap* d0, uint32_t want, double stop_sup,
                                         int threads, mesoi_height_level* out, uint32_t* count, meso_error* err)
{
    *count = 0;
    memset(out, 0, sizeof(*out) * (want < MESOI_HEIGHT_MAX_NATIVE ? want : MESOI_HEIGHT_MAX_NATIVE));
    if (f0->kind != MESO_TEXFN_HEIGHT && f0->kind != MESO_TEXFN_DENSITY)
        return MESO_OK;
    const int axes = f0->kind == MESO_TEXFN_DENSITY ? 3 : 2;
    const meso_texfn* prev = f0;
    meso_result r = MESO_OK;
    for (uint32_t l = 1; r == MESO_OK && l <= want && l <= MESOI_HEIGHT_MAX_NATIVE; ++l) {
        int even = 1;
        for (int k = 0; k < axes; ++k)
            even &= prev->dims[k] % 2 == 0 && prev->dims[k] / 2 >= MESOI_HEIGHT_MIN_LEVEL_RES;
        if (!even)
            break;
        mesoi_height_level* lv = &out[l - 1];
        if ((r = halve(prev, &lv->fn, err)) != MESO_OK)
            break;
        if (axes == 2) { /* a volume's error needs the shell: volume_levels.h */
            lv->sup = mesoi_height_sup_diff(&lv->fn, f0, threads);
            if (l > 1 && lv->sup < out[l - 2].sup) /* errors never decrease (FORMAT.md §7.10): still a bound */
                lv->sup = out[l - 2].sup;
            if (lv->sup >= stop_sup) {
                meso_texfn_free(&lv->fn);
                break;
            }
        }
        if (d0 && (r = level_distmap(&lv->fn, d0, l, threads, &lv->dist, err)) != MESO_OK) {
            meso_texfn_free(&lv->fn);
            break;
        }
        *count = l;
        prev = &lv->fn;
    }
    if (r != MESO_OK) {
        mesoi_height_levels_free(out, *count);
        *count = 0;
    }
    return r;
}

uint32_t mesoi_height_levels_trim(mesoi_height_level* l, uint32_t count, uint64_t shared, uint64_t level0)
{
    uint64_t prev = level0;
    uint32_t keep = 0;
    for (; keep < count; ++keep) {
        const uint64_t bytes = shared + l[keep].fn.encoded_size + l[keep].dist.encoded_size;
        if (10 * bytes > 9 * prev)
            break;
        prev = bytes;
    }
    mesoi_height_levels_free(l + keep, count - keep);
    return keep;
}

void mesoi_height_levels_free(mesoi_height_level* l, uint32_t count)
{
    for (uint32_t k = 0; k < count; ++k) {
        meso_texfn_free(&l[k].fn);
        meso_distmap_free(&l[k].dist);
    }
}
