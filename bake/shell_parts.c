/*
 * shell_parts.c — a shell in parts (FORMAT.md §7.11; issue 14, Deliver 3:
 * "each object (and each part, where a kind has parts, e.g. shell
 * patches, so a long object near the camera is fine near and coarse far)
 * draws the coarsest level whose projected error is ≤ τ; neighbouring
 * parts may differ by at most one level and never crack").
 *
 * A shell's native levels all draw the same prisms (they differ in the
 * texture function only, FORMAT.md §7.10), and its coarser levels are mesh
 * stand-ins: the mid-surface (or base mesh) and its simplifications. The
 * paper's shells have no levels at all; what is decided here:
 *
 *  - The parts are the shell's first stand-in cut as `mesobake mesh` cuts
 *    a mesh (mesh_parts.c: median splits of the triangles' centroids into
 *    parts of 512-1024 triangles, each simplified alone with its border
 *    locked). The stand-in has the base mesh's triangles in its order, so
 *    a part is also a set of prisms: the base triangles it holds.
 *  - Part lod 0 is those prisms, drawn by whatever native level the whole
 *    shell draws. The PTRI chunk lists the base triangles part after
 *    part (the base MESH keeps its order, which `mesobake shell --update`
 *    compares), at lod 0: what a stream needs for a first image stays
 *    small. Its bounds hold the prisms'
 *    corners: every base vertex and its offsets along each director layer
 *    (the OBJT bounds' rule).
 *  - Part lod 1 is the stand-in's patch (its error the stand-in's), lods
 *    2.. its simplifications (the stand-in's error plus their own distance
 *    to the patch, the triangle inequality, as the whole stand-in chain's).
 *    Each has a PMSH and, when the stand-ins have vertex colours, a PVCL,
 *    so a part drawn as a mesh shades as the whole stand-in would: lod 1
 *    the stand-in's own colours, lods 2.. what the stand-in shows near
 *    each vertex, sampled as the whole chain's are (patch_colours). The
 *    patches have the stand-in's baked normals (standin_levels.h): lod 1
 *    its own, lods 2.. averaged from them as their colours are.
 *  - Where a part drawn as prisms meets one drawn as its stand-in patch,
 *    the two surfaces meet along the patch border within the stand-in's
 *    error (the prisms' side faces are closed, and the patch ends on
 *    them); the runtime only puts them side by side where that error is
 *    within the pixel error. Stand-in patches meet each other edge to edge
 *    (the locked borders).
 */
#include "shell_parts.h"

#include "meso_layout.h"
#include "standin_appearance.h"
#include "standin_levels.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void st32(uint8_t* p, uint32_t v)
{
    for (int k = 0; k < 4; ++k)
        p[k] = (uint8_t)(v >> (8 * k));
}

void mesoi_shell_parts_free(mesoi_shell_parts* sp)
{
    const uint32_t n = sp->records > sp->count ? sp->records - sp->count : 0;
    for (uint32_t i = 0; sp->pmsh && i < n; ++i)
        free(sp->pmsh[i].data);
    for (uint32_t i = 0; sp->pvcl && i < n; ++i)
        free(sp->pvcl[i]);
    free(sp->pmsh);
    free(sp->pvcl);
    free(sp->prts);
    free(sp->list);
    free(sp->chunks);
    memset(sp, 0, sizeof(*sp));
}

/* The bounds of the prisms over base triangles list[0..n). */
static void prism_bounds(const mesoi_shell_parts_input* in, const uint32_t* list, uint32_t n, float lo[3],
                         float hi[3])
{
    const meso_mesh* b = in->base;
    for (int k = 0; k < 3; ++k) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (uint32_t t = 0; t < n; ++t)
        for (int c = 0; c < 3; ++c) {
            const size_t v = b->indices[3 * (size_t)list[t] + (size_t)c];
            for (int l = -1; l < in->layers; ++l)
                for (int k = 0; k < 3; ++k) {
                    const float x = b->positions[3 * v + (size_t)k] +
                                    (l < 0 ? 0.0f : in->sdir[3 * ((size_t)l * b->vertex_count + v) + (size_t)k]);
                    lo[k] = fminf(lo[k], x);
                    hi[k] = fmaxf(hi[k], x);
                }
        }
}

/* Part p's patch levels from l on, joined into one mesh (positions,
 * normals where every patch has them, indices): the vertices of part p's
 * level come at voff[p] (UINT32_MAX: no such level). */
static meso_result joined_level(const meso_mesh_parts* P, uint32_t l, meso_mesh* out, uint32_t* voff)
{
    memset(out, 0, sizeof(*out));
    size_t nv = 0, nt = 0;
    int normals = 1;
    for (uint32_t p = 0; p < P->count; ++p) {
        voff[p] = UINT32_MAX;
        if (l >= P->part[p].level_count)
            continue;
        const meso_mesh* m = &P->part[p].level[l].mesh;
        voff[p] = (uint32_t)nv;
        nv += m->vertex_count;
        nt += m->triangle_count;
        normals &= m->normals != NULL;
    }
    if (nv > UINT32_MAX || nt > UINT32_MAX / 3)
        return MESO_ERR_OUT_OF_MEMORY;
    out->vertex_count = (uint32_t)nv;
    out->triangle_count = (uint32_t)nt;
    out->positions = malloc(sizeof(float) * 3 * (nv ? nv : 1));
    out->normals = normals ? malloc(sizeof(float) * 3 * (nv ? nv : 1)) : NULL;
    out->indices = malloc(sizeof(uint32_t) * 3 * (nt ? nt : 1));
    if (!out->positions || (normals && !out->normals) || !out->indices) {
        meso_mesh_free(out);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    size_t t0 = 0;
    for (uint32_t p = 0; p < P->count; ++p) {
        if (voff[p] == UINT32_MAX)
            continue;
        const meso_mesh* m = &P->part[p].level[l].mesh;
        memcpy(out->positions + 3 * (size_t)voff[p], m->positions, sizeof(float) * 3 * m->vertex_count);
        if (normals)
            memcpy(out->normals + 3 * (size_t)voff[p], m->normals, sizeof(float) * 3 * m->vertex_count);
        for (size_t i = 0; i < 3 * (size_t)m->triangle_count; ++i)
            out->indices[3 * t0 + i] = m->indices[i] + voff[p];
        t0 += m->triangle_count;
    }
    return MESO_OK;
}

/* The patches' vertex colours, pvcl[k] for part p's level l at k = the
 * levels of parts before p, plus l. A level-0 patch is the stand-in's own
 * triangles, so its vertices take the stand-in's colours as they are
 * (corner by corner: patch triangle i is list[first[p] + i]). A simplified
 * level is sampled from the stand-in as the whole chain's are, all parts'
 * patches of that level as one mesh: the sample budget is the level's, as
 * for the whole stand-in (not each patch's, 8x the samples), and a border
 * vertex pools both sides' samples, so neighbouring patches agree on its
 * colour. */
static meso_result patch_colours(const mesoi_shell_parts_input* in, meso_mesh_parts* P, const uint32_t* list,
                                 const uint32_t* first, uint8_t** pvcl, meso_error* err)
{
    const int nc = in->vcol_components;
    uint32_t* kbase = malloc(sizeof(uint32_t) * (P->count + 1));
    uint32_t* voff = malloc(sizeof(uint32_t) * (P->count + 1));
    uint32_t levels = 0, most_v = 1;
    if (kbase)
        for (uint32_t p = 0, k = 0; p < P->count; k += P->part[p].level_count, ++p) {
            kbase[p] = k;
            levels = P->part[p].level_count > levels ? P->part[p].level_count : levels;
            most_v = P->part[p].level[0].mesh.vertex_count > most_v ? P->part[p].level[0].mesh.vertex_count : most_v;
        }
    float* shows = malloc(sizeof(float) * 4 * (size_t)most_v);
    meso_result r = kbase && voff && shows ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    for (uint32_t p = 0; r == MESO_OK && p < P->count; ++p) {
        const meso_mesh* m = &P->part[p].level[0].mesh;
        for (uint32_t i = 0; i < m->triangle_count; ++i)
            for (int c = 0; c < 3; ++c)
                memcpy(shows + 4 * (size_t)m->indices[3 * (size_t)i + (size_t)c],
                       in->shows + 4 * (size_t)in->standin->indices[3 * (size_t)list[first[p] + i] + (size_t)c],
                       4 * sizeof(float));
        if (!(pvcl[kbase[p]] = malloc((size_t)nc * (m->vertex_count ? m->vertex_count : 1))))
            r = MESO_ERR_OUT_OF_MEMORY;
        else
            mesoi_appearance_encode(shows, m->vertex_count, nc, pvcl[kbase[p]]);
    }
    for (uint32_t l = 1; r == MESO_OK && l < levels; ++l) {
        meso_mesh joined;
        if ((r = joined_level(P, l, &joined, voff)) != MESO_OK)
            break;
        const meso_mesh* one = &joined;
        uint8_t* vcol = NULL;
        float* nrm = NULL;
        r = mesoi_standin_colours(in->standin, in->shows, in->baked_normals ? in->standin->normals : NULL, &one, 1,
                                  in->colour_spacing, nc, in->threads, &vcol, &nrm, err);
        for (uint32_t p = 0; r == MESO_OK && p < P->count; ++p) {
            if (voff[p] == UINT32_MAX)
                continue;
            meso_mesh* pm = &P->part[p].level[l].mesh;
            const size_t bytes = (size_t)nc * pm->vertex_count;
            if (!(pvcl[kbase[p] + l] = malloc(bytes ? bytes : 1)))
                r = MESO_ERR_OUT_OF_MEMORY;
            else
                memcpy(pvcl[kbase[p] + l], vcol + (size_t)nc * voff[p], bytes);
            if (nrm && pm->normals)
                memcpy(pm->normals, nrm + 3 * (size_t)voff[p], sizeof(float) * 3 * pm->vertex_count);
        }
        free(vcol);
        free(nrm);
        meso_mesh_free(&joined);
    }
    free(shows);
    free(voff);
    free(kbase);
    if (r == MESO_ERR_OUT_OF_MEMORY)
        return meso_bake_fail(err, r, 0, "shell parts: out of memory");
    return r;
}

meso_result mesoi_shell_parts_build(const mesoi_shell_parts_input* in, mesoi_shell_parts* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    meso_mesh_parts P;
    const meso_mesh_parts_options po = {.part_triangles = in->part_triangles, .threads = in->threads};
    meso_result r = meso_mesh_parts_build(in->standin, &po, &P, err);
    if (r != MESO_OK || P.count == 0) {
        meso_mesh_parts_free(&P);
        return r;
    }
    const uint32_t nt = in->standin->triangle_count, np = P.count;
    uint32_t records = 0;
    for (uint32_t p = 0; p < np; ++p)
        records += 1 + P.part[p].level_count; /* the prisms, then the stand-in patch's levels */
    const uint32_t nm = records - np;
    const size_t prts_size = MESO_PRTS_HDR_SIZE + (size_t)records * MESO_LODS_RECORD_SIZE +
                             (size_t)P.edge_count * MESO_PRTS_EDGE_SIZE;
    out->count = np;
    out->records = records;
    out->edges = P.edge_count;
    out->prts = calloc(1, prts_size);
    out->pmsh = calloc(nm, sizeof(meso_mesh_chunk));
    out->pvcl = calloc(nm, sizeof(uint8_t*));
    out->chunks = calloc(2 + 2 * (size_t)nm, sizeof(mesoi_chunk));
    uint32_t* first = calloc(np + 1, sizeof(uint32_t));
    uint32_t* list = out->list = malloc(sizeof(uint32_t) * (nt ? nt : 1));
    if (!out->prts || !out->pmsh || !out->pvcl || !out->chunks || !first || !list)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell parts: out of memory");
    /* The triangle list: part after part, each in the base mesh's order. */
    if (r == MESO_OK) {
        for (uint32_t t = 0; t < nt; ++t)
            first[P.part_of[t] + 1]++;
        for (uint32_t p = 0; p < np; ++p)
            first[p + 1] += first[p];
        uint32_t* at = malloc(sizeof(uint32_t) * np);
        if (!at)
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell parts: out of memory");
        for (uint32_t p = 0; at && p < np; ++p)
            at[p] = first[p];
        for (uint32_t t = 0; at && t < nt; ++t)
            list[at[P.part_of[t]]++] = t;
        free(at);
    }
    if (r == MESO_OK && in->shows)
        r = patch_colours(in, &P, list, first, out->pvcl, err);
    /* Records, PMSH and PVCL chunks. */
    uint8_t* rec = out->prts + MESO_PRTS_HDR_SIZE;
    size_t n = 0;
    for (uint32_t p = 0, k = 0; r == MESO_OK && p < np; ++p) {
        meso_level_record lr = {.object = p + 1, .lod = 0, .form = MESO_LEVEL_NATIVE};
        prism_bounds(in, list + first[p], first[p + 1] - first[p], lr.bbox_min, lr.bbox_max);
        meso_level_record_encode(&lr, rec);
        st32(rec + MESO_PRTS_OFF_FIRST_TRIANGLE, first[p]);
        st32(rec + MESO_PRTS_OFF_TRIANGLE_COUNT, first[p + 1] - first[p]);
        rec += MESO_LODS_RECORD_SIZE;
        for (uint32_t l = 0; r == MESO_OK && l < P.part[p].level_count; ++l, ++k) {
            const meso_mesh_part_level* L = &P.part[p].level[l];
            if ((r = meso_bake_mesh_chunk(&L->mesh, NULL, &out->pmsh[k], err)) != MESO_OK)
                break;
            const uint16_t lod = (uint16_t)(l + 1);
            out->chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_PMSH, .object = in->object, .lod = lod,
                                                      .encoding = out->pmsh[k].encoding,
                                                      .decoded_size = out->pmsh[k].decoded_size,
                                                      .dims = {p + 1, 1, 1}},
                                             .data = out->pmsh[k].data,
                                             .size = out->pmsh[k].size};
            out->bytes += out->pmsh[k].size;
            if (out->pvcl[k]) {
                const uint16_t nc = (uint16_t)in->vcol_components;
                out->chunks[n++] = (mesoi_chunk){
                    .desc = {.type = MESO_CHUNK_PVCL, .object = in->object, .lod = lod, .dtype = MESO_DTYPE_BYTES,
                             .components = nc, .dims = {p + 1, 1, 1}},
                    .data = out->pvcl[k],
                    .size = nc * (size_t)L->mesh.vertex_count};
                out->bytes += out->chunks[n - 1].size;
            }
            meso_level_record ml = {.object = p + 1, .lod = lod, .form = MESO_LEVEL_MESH,
                                    .error = mesoi_f32_up(in->standin_error + L->error)};
            for (int a = 0; a < 3; ++a) {
                ml.bbox_min[a] = (float)L->bbox_min[a];
                ml.bbox_max[a] = (float)L->bbox_max[a];
            }
            meso_level_record_encode(&ml, rec);
            rec += MESO_LODS_RECORD_SIZE;
        }
    }
    if (r == MESO_OK) {
        st32(out->prts + MESO_PRTS_OFF_PARTS, np);
        st32(out->prts + MESO_PRTS_OFF_RECORDS, records);
        st32(out->prts + MESO_PRTS_OFF_EDGES, P.edge_count);
        for (uint32_t i = 0; i < 2 * P.edge_count; ++i)
            st32(rec + 4 * (size_t)i, P.edges[i] + 1); /* part numbers */
        out->chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_PRTS, .object = in->object,
                                                  .dtype = MESO_DTYPE_BYTES, .components = 1, .dims = {1, 1, 1}},
                                         .data = out->prts,
                                         .size = prts_size};
        out->chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_PTRI, .object = in->object,
                                                  .dtype = MESO_DTYPE_U32, .components = 1, .dims = {nt, 1, 1}},
                                         .data = list,
                                         .size = sizeof(uint32_t) * (size_t)nt};
        out->bytes += prts_size + sizeof(uint32_t) * (size_t)nt;
        out->chunk_count = n;
    }
    free(first);
    meso_mesh_parts_free(&P);
    if (r != MESO_OK)
        mesoi_shell_parts_free(out);
    return r;
}
