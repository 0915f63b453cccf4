/*
 * shell_hybrid.c — see shell_hybrid.h.
 *
 * Why validate-and-grow instead of a local test per vertex: what makes
 * normal displacement fail is either local (a prism whose Jacobian changes
 * sign: concavities, saddles) or global (an offset triangle reaching another
 * part of the surface: the bunny's ear over its back). The exact checks of
 * shell_validate.c find both and name the faces; a vertex keeps its normal
 * only if no face around it fails in the final shell. The price is one exact
 * check per round (CGAL box intersection + exact predicates; since issue 15
 * only of the faces whose directors moved, shell_checker.h). Before that
 * change every round checked the whole mesh, and hybrid was not cheaper
 * than tracing the Lp field everywhere: on the subdivided
 * bunny (tests/bench/results/shell_size.csv) hybrid took 0.78-1.28x the
 * time of lp (86 s against 68 s at 423k triangles, 2-12 rounds) and the
 * two shells keep the same thickness. Hybrid is the default for the shell
 * it draws — plain normal offsets wherever they are provably safe, the
 * field only where they fold or collide — not for speed.
 */
#include "shell_hybrid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shell_checker.h"

meso_result meso_shell_bad_faces(const meso_mesh* m, const float* d, int sign, uint8_t* bad, uint32_t* count,
                                 meso_error* err)
{
    meso_shell_checker* c = NULL;
    meso_result r = meso_shell_checker_create(m, sign, 1, &c, err);
    if (r == MESO_OK)
        r = meso_shell_checker_bad_faces(c, d, bad, count, err);
    meso_shell_checker_destroy(c);
    return r;
}

/* Laplacian smoothing of the directors of the masked vertices: each becomes
 * the mean of itself and its face neighbours, `iterations` times (Jacobi, so
 * the result does not depend on the vertex order or thread count).
 * Why: where triangles are small against h, neighbouring directors must
 * agree to within (edge length / h) radians or the prism top flips; the
 * field traced from a noisy surface (the bunny's filled base) disagrees by
 * 10-20 degrees between neighbours. Measured (Lp everywhere, no repair):
 * bunny at 10 % exterior goes from 89 inverted prisms / 277
 * self-intersections to 0 / 0 with 20 rounds; but on coarse meshes with thin
 * features (spot's horns, blub's fins) averaging across the feature turns
 * directors sideways and creates offset/base intersections (spot 10 %:
 * 0 -> 60). A cos^2 angle weight did not fix that. So it is off by default
 * (--smooth 0) and offered for finely tessellated, noisy surfaces. */
static meso_result smooth_directors(const meso_mesh* m, float* d, const uint8_t* mask, int iterations,
                                    meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    double* acc = malloc(sizeof(double) * 4 * (size_t)(nv ? nv : 1));
    if (!acc)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "smoothing: out of memory");
    for (int it = 0; it < iterations; ++it) {
        memset(acc, 0, sizeof(double) * 4 * (size_t)nv);
        for (uint32_t f = 0; f < nt; ++f) {
            const uint32_t* ix = m->indices + 3 * (size_t)f;
            for (int c = 0; c < 3; ++c) {
                const uint32_t v = ix[c];
                if (!mask[v])
                    continue;
                for (int o = 1; o < 3; ++o) {
                    const uint32_t u = ix[(c + o) % 3];
                    for (int k = 0; k < 3; ++k)
                        acc[4 * (size_t)v + k] += d[3 * (size_t)u + k];
                    acc[4 * (size_t)v + 3] += 1.0;
                }
            }
        }
        for (uint32_t v = 0; v < nv; ++v) {
            const double w = acc[4 * (size_t)v + 3];
            if (!mask[v] || w == 0.0)
                continue;
            float* dv = d + 3 * (size_t)v;
            /* Plain vector mean: where neighbours disagree the mean is also
             * shorter, i.e. the shell compresses there. Keeping each
             * director's length instead was tried: bunny at 10 %, 20
             * iterations, 32 inverted prisms left instead of 0. */
            for (int k = 0; k < 3; ++k)
                dv[k] = (float)(0.5 * dv[k] + 0.5 * acc[4 * (size_t)v + k] / w);
        }
    }
    free(acc);
    return MESO_OK;
}

/* add[v] = 1 for the vertices of faces with bad[f], then `rings` rings
 * more (each ring: every face touching a marked vertex marks its corners). */
static uint32_t grow(const meso_mesh* m, const uint8_t* bad, const uint8_t* have, int rings, uint8_t* add)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    memset(add, 0, nv);
    for (uint32_t f = 0; f < nt; ++f)
        if (bad[f])
            for (int k = 0; k < 3; ++k)
                add[m->indices[3 * (size_t)f + k]] = 1;
    uint8_t* ring = malloc(nv ? nv : 1);
    if (!ring)
        return 0;
    for (int r = 0; r < rings; ++r) {
        memcpy(ring, add, nv);
        for (uint32_t f = 0; f < nt; ++f) {
            const uint32_t* ix = m->indices + 3 * (size_t)f;
            if (ring[ix[0]] || ring[ix[1]] || ring[ix[2]])
                add[ix[0]] = add[ix[1]] = add[ix[2]] = 1;
        }
    }
    free(ring);
    uint32_t fresh = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        if (have[v])
            add[v] = 0;
        fresh += add[v];
    }
    return fresh;
}

/* Rings that span about the shell thickness: the Lp region grows by a
 * distance, not by one ring a round, so the number of validation rounds does
 * not grow with the resolution (it did: 6 rounds at 1.6k triangles, 43 at
 * 106k). Capped at 16. */
static int rings_for(const meso_mesh* m, double h)
{
    double sum = 0;
    const uint32_t nt = m->triangle_count;
    for (uint32_t f = 0; f < nt; ++f) {
        const float* a = m->positions + 3 * (size_t)m->indices[3 * (size_t)f];
        const float* b = m->positions + 3 * (size_t)m->indices[3 * (size_t)f + 1];
        double l = 0;
        for (int k = 0; k < 3; ++k)
            l += ((double)a[k] - b[k]) * ((double)a[k] - b[k]);
        sum += sqrt(l);
    }
    const double mean = nt ? sum / nt : 1.0;
    const double r = mean > 0 ? h / mean : 1.0;
    return r < 1.0 ? 1 : r > 16.0 ? 16 : (int)(r + 0.5);
}

meso_result meso_shell_side_directors(const meso_lp_field* field, const meso_mesh* m, const float* normals, int sign,
                                      const meso_trace_options* opt, meso_shell_directors mode, int threads, float* d,
                                      uint8_t* lp_mask, meso_hybrid_stats* hs, meso_trace_stats* ts,
                                      meso_error* err)
{
    return meso_shell_side_directors_in(field, m, normals, sign, opt, mode, threads, NULL, d, lp_mask, hs, ts, NULL,
                                        err);
}

meso_result meso_shell_side_directors_in(const meso_lp_field* field, const meso_mesh* m, const float* normals,
                                         int sign, const meso_trace_options* opt, meso_shell_directors mode,
                                         int threads, const uint8_t* redo, float* d, uint8_t* lp_mask,
                                         meso_hybrid_stats* hs, meso_trace_stats* ts, meso_shell_checker* shared,
                                         meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    memset(hs, 0, sizeof(*hs));
    uint8_t* mask = calloc(nv ? nv : 1, 1);
    uint8_t* add = calloc(nv ? nv : 1, 1);
    uint8_t* bad = calloc(nt ? nt : 1, 1);
    uint8_t* have = calloc(nv ? nv : 1, 1); /* Lp already, or kept (not in redo) */
    if (!mask || !add || !bad || !have) {
        free(mask), free(add), free(bad), free(have);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "directors: out of memory");
    }
    for (size_t i = 0; i < 3 * (size_t)nv; ++i)
        if (!redo || redo[i / 3])
            d[i] = (float)(sign * opt->thickness * normals[i]);
    meso_result r = MESO_OK;
    const int smooth = opt->smooth_iterations;
    if (mode == MESO_DIRECTORS_LP) {
        for (uint32_t v = 0; v < nv; ++v)
            mask[v] = !redo || redo[v];
        r = meso_shell_trace_all(field, m, normals, sign, opt, redo, threads, d, ts, err);
        if (r == MESO_OK && smooth)
            r = smooth_directors(m, d, mask, smooth, err);
    } else if (mode == MESO_DIRECTORS_HYBRID) {
        /* raw: traced (or normal) directors before smoothing; every round
         * smooths the current Lp region afresh from raw, so a vertex is
         * never smoothed twice over. */
        float* raw = malloc(sizeof(float) * 3 * (size_t)(nv ? nv : 1));
        if (!raw)
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "directors: out of memory");
        else
            memcpy(raw, d, sizeof(float) * 3 * (size_t)nv);
        uint32_t nbad = 0;
        const int rings = rings_for(m, opt->thickness);
        meso_shell_checker* ck = shared;
        if (r == MESO_OK && !ck)
            r = meso_shell_checker_create(m, sign, threads, &ck, err);
        if (r == MESO_OK && redo && !shared)
            r = meso_shell_checker_prime(ck, d, redo, err);
        const double checks0 = ck ? meso_shell_checker_seconds(ck) : 0;
        while (r == MESO_OK) {
            memcpy(d, raw, sizeof(float) * 3 * (size_t)nv);
            if (smooth && hs->vertices_lp && (r = smooth_directors(m, d, mask, smooth, err)) != MESO_OK)
                break;
            r = meso_shell_checker_bad_faces(ck, d, bad, &nbad, err);
            if (r != MESO_OK || nbad == 0)
                break;
            hs->rounds++;
            for (uint32_t v = 0; v < nv; ++v)
                have[v] = mask[v] || (redo && !redo[v]);
            const uint32_t fresh = grow(m, bad, have, rings, add);
            if (fresh == 0)
                break; /* every vertex near a bad face already follows the field */
            r = meso_shell_trace_all(field, m, normals, sign, opt, add, threads, raw, ts, err);
            for (uint32_t v = 0; v < nv; ++v) {
                mask[v] |= add[v];
                hs->vertices_lp += add[v];
            }
        }
        hs->vertices_lp = 0; /* recounted below */
        hs->bad_faces_left = nbad;
        hs->seconds_checks = ck ? meso_shell_checker_seconds(ck) - checks0 : 0;
        if (!shared)
            meso_shell_checker_destroy(ck);
        free(raw);
    }
    for (uint32_t v = 0; v < nv; ++v)
        hs->vertices_lp += mask[v];
    hs->vertices_normal = nv - hs->vertices_lp;
    if (lp_mask)
        memcpy(lp_mask, mask, nv);
    free(mask), free(add), free(bad), free(have);
    return r;
}

/* A unit direction that leaves every face around v on the shell's side
 * (d·n_f >= 0.2 for each adjacent face normal n_f, signed), found by
 * projecting onto the violated half-spaces in turn (a few sweeps suffice
 * for any vertex whose star is not folded over itself); starts from the
 * mean face normal. Returns 0 when no such direction was found. */
static int feasible_direction(const meso_mesh* m, const uint32_t* first, const uint32_t* faces, uint32_t v, int sign,
                              double out[3])
{
    double fn[64][3];
    uint32_t nf = 0;
    double dir[3] = {0, 0, 0};
    for (uint32_t i = first[v]; i < first[v + 1] && nf < 64; ++i) {
        double n[3];
        if (meso_mesh_face_normal(m, faces[i], n) == 0.0)
            continue;
        for (int k = 0; k < 3; ++k) {
            fn[nf][k] = sign * n[k];
            dir[k] += fn[nf][k];
        }
        ++nf;
    }
    for (int sweep = 0; sweep < 50; ++sweep) {
        double l = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        if (l == 0.0)
            return 0;
        for (int k = 0; k < 3; ++k)
            dir[k] /= l;
        int ok = 1;
        for (uint32_t f = 0; f < nf; ++f) {
            const double dp = dir[0] * fn[f][0] + dir[1] * fn[f][1] + dir[2] * fn[f][2];
            if (dp < 0.2) {
                ok = 0;
                for (int k = 0; k < 3; ++k)
                    dir[k] += (0.25 - dp) * fn[f][k];
            }
        }
        if (ok) {
            memcpy(out, dir, sizeof(dir));
            return 1;
        }
    }
    return 0;
}

meso_result meso_shell_repair(const meso_mesh* m, float* d, int sign, uint32_t max_rounds, int threads,
                              uint32_t* shortened, uint32_t* rounds, uint32_t* bad_left, meso_error* err)
{
    return meso_shell_repair_in(m, d, sign, max_rounds, threads, NULL, shortened, rounds, bad_left, NULL, err);
}

meso_result meso_shell_repair_in(const meso_mesh* m, float* d, int sign, uint32_t max_rounds, int threads,
                                 const uint8_t* redo, uint32_t* shortened, uint32_t* rounds, uint32_t* bad_left,
                                 meso_shell_checker* shared, meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    uint8_t* bad = calloc(nt ? nt : 1, 1);
    uint8_t* touched = calloc(nv ? nv : 1, 1);
    uint8_t* now = calloc(nv ? nv : 1, 1);
    uint32_t *first = NULL, *faces = NULL;
    if (!bad || !touched || !now) {
        free(bad), free(touched), free(now);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "repair: out of memory");
    }
    if (meso_vertex_faces(m, &first, &faces, "repair", err) != MESO_OK) {
        free(bad), free(touched), free(now);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    uint32_t nbad = 0, round = 0;
    meso_shell_checker* ck = shared;
    meso_result r = ck ? MESO_OK : meso_shell_checker_create(m, sign, threads, &ck, err);
    if (r == MESO_OK && redo && !shared)
        r = meso_shell_checker_prime(ck, d, redo, err);
    while (r == MESO_OK) {
        r = meso_shell_checker_bad_faces(ck, d, bad, &nbad, err);
        if (r != MESO_OK || nbad == 0 || round == max_rounds)
            break;
        memset(now, 0, nv);
        for (uint32_t f = 0; f < nt; ++f)
            if (bad[f])
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = m->indices[3 * (size_t)f + k];
                    now[v] = !redo || redo[v];
                }
        /* A director that does not leave every adjacent face on the shell's
         * side keeps its prisms inverted at any length: turn it into a
         * feasible direction (same length). Others are shortened by 0.8.
         * (Turning every director towards the normal was tried and gave up
         * more thickness on the bunny: mean ratio 0.81 vs 0.965 at 10 %.) */
        for (uint32_t v = 0; v < nv; ++v) {
            if (!now[v])
                continue;
            touched[v] = 1;
            float* dv = d + 3 * (size_t)v;
            const double len = sqrt((double)dv[0] * dv[0] + (double)dv[1] * dv[1] + (double)dv[2] * dv[2]);
            double worst = 1.0;
            for (uint32_t i = first[v]; i < first[v + 1] && len > 0; ++i) {
                double n[3];
                if (meso_mesh_face_normal(m, faces[i], n) > 0.0)
                    worst = fmin(worst, sign * (dv[0] * n[0] + dv[1] * n[1] + dv[2] * n[2]) / len);
            }
            double dir[3];
            if (worst < 0.1 && len > 0 && feasible_direction(m, first, faces, v, sign, dir)) {
                for (int k = 0; k < 3; ++k)
                    dv[k] = (float)(len * dir[k]);
            } else {
                for (int k = 0; k < 3; ++k)
                    dv[k] *= 0.8f;
            }
        }
        ++round;
    }
    uint32_t n = 0;
    for (uint32_t v = 0; v < nv; ++v)
        n += touched[v];
    *shortened = n;
    *rounds = round;
    *bad_left = nbad;
    if (!shared)
        meso_shell_checker_destroy(ck);
    free(bad), free(touched), free(now), free(first), free(faces);
    return r;
}
