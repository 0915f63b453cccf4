/*
 * export.c — `mesoinspect export FILE.meso -o OUT.glb`: every object's
 * base geometry as a standard glTF 2.0 binary, the fallback an engine
 * without libmeso can draw (issue 16, "glTF out").
 *
 * One glTF node, mesh, primitive and material per object, in object order,
 * each named after the object:
 *  - mesh: its MESH (positions, normals, uvs, indices; a point set stays
 *    points), the default albedo;
 *  - shell: the base mesh (w = 0) with one texture tile's baked normal and
 *    base-colour maps, uvs (s, t') on a REPEAT sampler, and tangents
 *    (export_shell_maps.c says what is baked and in which conventions).
 *    Triangles whose (s, t') have no area take the barycentric texture
 *    coordinates FORMAT.md §7.2 gives them, on their own three vertices,
 *    and vertices where the uv layout mirrors are split by orientation
 *    (split_uv_vertices);
 *  - cells: the base mesh, coloured by the mean of its COLR over the
 *    non-empty voxels (alpha > 0), averaged in linear RGB;
 *  - frusta: a triangle tessellation of the surface with its relief
 *    (runtime/reference/frusta_tessellate.h), --frusta-grid points around
 *    each frustum, the default albedo; with a COLR, per-vertex COLOR_0
 *    (linear RGB, baseColorFactor 1) = meso_ref_frusta_albedo at each
 *    vertex on the frustum or ball that made it (the COLR bilinear at the
 *    vertex's relief coordinates; balls their mean colour), so colour is
 *    interpolated across triangles rather than textured (a frustum's
 *    relief coordinates are not one chart an engine could texture with).
 *    Shells' COLR follow their CMAP (export_shell_maps.c): TILED on
 *    TEXCOORD_0, BASE on TEXCOORD_1.
 * Every exported uv is glTF's (u, v) = (s, 1 − t'): meso's texture rows run
 * from t' = 0 at the bottom (OpenGL's way), glTF's from v = 0 at the top.
 * Normals are written unit length: a MESH normal that is not finite and
 * non-zero is replaced by the area-weighted normal of its triangles.
 * Materials are metallic 0, roughness 1 (libmeso's Lambertian look); the
 * default albedo is libmeso's (meso_rt_draw_desc.albedo).
 *
 * The input is checked first as `validate --full` checks it (exit 3 and
 * nothing written on any issue); the output is staged and renamed into
 * place whole (cli_output.h). The GLB container is glb_write.c's.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_output.h"
#include "export.h"
#include "frusta_pose.h"
#include "frusta_tessellate.h"
#include "frustum_reference.h"
#include "inspect.h"
#include "meso_layout.h"
#include "shell_reference.h"

#define EXPORT_DEFAULT_GRID 48u

static const char* const usage_export =
    "Usage: mesoinspect export FILE -o OUT.glb [options]\n"
    "\n"
    "Write every object of FILE as a glTF 2.0 binary (.glb): one node, mesh and\n"
    "material per object, named after it, in object order. Meshes as they are;\n"
    "shells as their base mesh with one texture tile's baked tangent-space normal\n"
    "map and base-colour map (the shell's COLR colours, or the default albedo times\n"
    "the height-dependent occlusion 0.25 + 0.75 w), uvs repeating; a colour baked\n"
    "with --color from-mesh (CMAP BASE) is the base mesh's own texture on TEXCOORD_1\n"
    "(uv = texture coordinates / tiling); cells as their base mesh in the mean colour\n"
    "of their cells; frusta as a triangle tessellation of their surface and relief,\n"
    "coloured per vertex (COLOR_0) by their COLR when they have one. FILE is first\n"
    "checked as 'mesoinspect validate --full' does; a file with issues is not\n"
    "exported (exit 3).\n"
    "\n"
    "  -o, --output FILE     the .glb to write (atomically; a symbolic link is written\n"
    "                        through, a device, FIFO or directory refused)\n"
    "      --object ID       export only this object (its id, or its name as\n"
    "                        'mesoinspect info' lists it)\n"
    "      --frusta-grid N   frusta: grid points around each frustum (2..1024, default 48;\n"
    "                        along it as densely)\n"
    "  -h, --help            this help\n";

/* >>reading ----------------------------------------------------------------- */

/* The object's chunk of `type` at its finest lod (the smallest), or -1. */
static int32_t finest_chunk(const meso_file* f, uint32_t type, uint32_t id)
{
    int32_t best = -1;
    uint16_t lod = UINT16_MAX;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == type && c->object == id && (best < 0 || c->lod < lod)) {
            best = (int32_t)i;
            lod = c->lod;
        }
    }
    return best;
}

static int report(const meso_error* e, meso_result r)
{
    char line[400];
    mi_format_issue(e, line, sizeof(line));
    mi_error("%s", line);
    return meso_exit_for(r);
}

static int out_of_memory(void)
{
    mi_error("out of memory");
    return MESO_EXIT_INTERNAL;
}

/* A chunk read whole and decoded; exit code. */
static int read_chunk(meso_file* f, const meso_object_record* rec, uint32_t type, uint8_t** data, size_t* size)
{
    *data = NULL;
    *size = 0;
    const int32_t ci = finest_chunk(f, type, rec->id);
    if (ci < 0) {
        char cc[5];
        mi_fourcc(type, cc);
        mi_error("object %u (%s) has no %s chunk", rec->id, rec->name, cc);
        return MESO_EXIT_INVALID;
    }
    meso_error err;
    memset(&err, 0, sizeof(err));
    const meso_result r = mi_read_decoded(f, (uint32_t)ci, data, size, &err);
    return r == MESO_OK ? MESO_EXIT_OK : report(&err, r);
}

/* The object's MESH, parsed (the view points into *buf; free it). */
static int read_mesh(meso_file* f, const meso_object_record* rec, uint8_t** buf, meso_mesh_view* v)
{
    size_t size = 0;
    int code = read_chunk(f, rec, MESO_CHUNK_MESH, buf, &size);
    if (code != MESO_EXIT_OK)
        return code;
    meso_error err;
    memset(&err, 0, sizeof(err));
    const meso_result r = meso_mesh_parse(*buf, size, v, &err);
    if (r != MESO_OK) {
        free(*buf);
        *buf = NULL;
        return report(&err, r);
    }
    return MESO_EXIT_OK;
}

/* >>geometry ---------------------------------------------------------------- */

static float* dup_floats(const float* src, size_t n)
{
    float* d = malloc(sizeof(float) * (n ? n : 1));
    if (d && n)
        memcpy(d, src, sizeof(float) * n);
    return d;
}

/* Unit normals for the vertices: `in` (may be NULL) where it is finite and
 * non-zero, else the area-weighted normal of the vertex's triangles, else
 * +z (a vertex on no triangle with area). NULL on out of memory. */
static float* unit_normals(const float* pos, const float* in, uint32_t nv, const uint32_t* idx, uint32_t ni)
{
    float* out = malloc(sizeof(float) * 3 * (nv ? nv : 1));
    double* acc = NULL;
    if (!out)
        return NULL;
    int need_faces = !in;
    for (uint32_t v = 0; v < nv && !need_faces; ++v) {
        const double x = in[3 * (size_t)v], y = in[3 * (size_t)v + 1], z = in[3 * (size_t)v + 2];
        const double l = sqrt(x * x + y * y + z * z);
        need_faces = !(l > 1e-20 && isfinite(l));
    }
    if (need_faces) {
        acc = calloc(3 * (size_t)(nv ? nv : 1), sizeof(double));
        if (!acc) {
            free(out);
            return NULL;
        }
        for (uint32_t t = 0; t + 2 < ni; t += 3) {
            const float* a = pos + 3 * (size_t)idx[t];
            const float* b = pos + 3 * (size_t)idx[t + 1];
            const float* c = pos + 3 * (size_t)idx[t + 2];
            const double e1[3] = {(double)b[0] - a[0], (double)b[1] - a[1], (double)b[2] - a[2]};
            const double e2[3] = {(double)c[0] - a[0], (double)c[1] - a[1], (double)c[2] - a[2]};
            const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                 e1[0] * e2[1] - e1[1] * e2[0]};
            for (int k = 0; k < 3; ++k)
                for (int j = 0; j < 3; ++j)
                    acc[3 * (size_t)idx[t + (uint32_t)k] + (size_t)j] += n[j];
        }
    }
    for (uint32_t v = 0; v < nv; ++v) {
        double n[3] = {0, 0, 0}, l = 0;
        if (in) {
            for (int k = 0; k < 3; ++k)
                n[k] = in[3 * (size_t)v + (size_t)k];
            l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        }
        if (!(l > 1e-20 && isfinite(l))) {
            for (int k = 0; k < 3; ++k)
                n[k] = acc[3 * (size_t)v + (size_t)k];
            l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        }
        if (!(l > 1e-300 && isfinite(l))) {
            n[0] = n[1] = 0;
            n[2] = l = 1;
        }
        for (int k = 0; k < 3; ++k)
            out[3 * (size_t)v + (size_t)k] = (float)(n[k] / l);
    }
    free(acc);
    return out;
}

/* glTF uvs (s, 1 − t') of n vertices. */
static float* gltf_uvs(const float* st, uint32_t n)
{
    float* uv = malloc(sizeof(float) * 2 * (n ? n : 1));
    if (!uv)
        return NULL;
    for (uint32_t v = 0; v < n; ++v) {
        uv[2 * (size_t)v] = st[2 * (size_t)v];
        uv[2 * (size_t)v + 1] = 1.0f - st[2 * (size_t)v + 1];
    }
    return uv;
}

static void set_albedo(mi_glb_prim* p)
{
    p->base_color[0] = MI_DEFAULT_ALBEDO_R;
    p->base_color[1] = MI_DEFAULT_ALBEDO_G;
    p->base_color[2] = MI_DEFAULT_ALBEDO_B;
    p->base_color[3] = 1.0f;
}

/* The MESH as a primitive: positions, unit normals when the MESH has
 * normals (or always, with `normals`), glTF uvs, indices. */
static int mesh_prim(const meso_mesh_view* v, int normals, mi_glb_prim* p)
{
    const uint32_t nv = v->layout.vertex_count, ni = v->layout.index_count;
    p->vertex_count = nv;
    p->index_count = ni;
    p->positions = dup_floats(v->positions, 3 * (size_t)nv);
    p->indices = malloc(sizeof(uint32_t) * (ni ? ni : 1));
    if (v->normals || normals)
        p->normals = unit_normals(v->positions, v->normals, nv, v->indices, ni);
    if (v->uvs)
        p->uvs = gltf_uvs(v->uvs, nv);
    if (!p->positions || !p->indices || ((v->normals || normals) && !p->normals) || (v->uvs && !p->uvs))
        return out_of_memory();
    if (ni)
        memcpy(p->indices, v->indices, sizeof(uint32_t) * ni);
    set_albedo(p);
    return MESO_EXIT_OK;
}

/* >>kinds ------------------------------------------------------------------- */

static int export_mesh(meso_file* f, const meso_object_record* rec, mi_glb_prim* p)
{
    uint8_t* buf = NULL;
    meso_mesh_view v;
    int code = read_mesh(f, rec, &buf, &v);
    if (code == MESO_EXIT_OK)
        code = mesh_prim(&v, 0, p);
    free(buf);
    return code;
}

static int export_cells(meso_file* f, const meso_object_record* rec, mi_glb_prim* p)
{
    uint8_t *buf = NULL, *colr = NULL;
    size_t colr_size = 0;
    meso_mesh_view v;
    int code = read_mesh(f, rec, &buf, &v);
    if (code == MESO_EXIT_OK)
        code = mesh_prim(&v, 0, p);
    if (code == MESO_EXIT_OK)
        code = read_chunk(f, rec, MESO_CHUNK_COLR, &colr, &colr_size);
    if (code == MESO_EXIT_OK) {
        /* COLR is sRGB (FORMAT.md §7.2 kind 3): average in linear light. */
        double sum[3] = {0, 0, 0};
        size_t n = 0;
        for (size_t i = 0; i + 3 < colr_size; i += 4)
            if (colr[i + 3]) {
                for (int k = 0; k < 3; ++k)
                    sum[k] += mi_srgb_to_linear(colr[i + (size_t)k]);
                ++n;
            }
        if (n)
            for (int k = 0; k < 3; ++k)
                p->base_color[k] = (float)(sum[k] / (double)n);
    }
    free(colr);
    free(buf);
    return code;
}

/* FRUS + FSEG (+ BALL) records of a frusta object; exit code. */
static int frusta_records(meso_file* f, const meso_object_record* rec, meso_frustum_rec** recs, uint32_t* count,
                          meso_frustum_ball_rec** balls, uint32_t* ball_count)
{
    uint8_t *frus = NULL, *fseg = NULL, *ball = NULL;
    size_t nf = 0, ns = 0, nb = 0;
    *recs = NULL;
    *balls = NULL;
    *count = *ball_count = 0;
    int code = read_chunk(f, rec, MESO_CHUNK_FRUS, &frus, &nf);
    if (code == MESO_EXIT_OK)
        code = read_chunk(f, rec, MESO_CHUNK_FSEG, &fseg, &ns);
    if (code == MESO_EXIT_OK && finest_chunk(f, MESO_CHUNK_BALL, rec->id) >= 0)
        code = read_chunk(f, rec, MESO_CHUNK_BALL, &ball, &nb);
    if (code == MESO_EXIT_OK && nf / MESO_FRUS_RECORD_SIZE != ns / MESO_FSEG_RECORD_SIZE) {
        mi_error("object %u (%s): FRUS and FSEG hold different numbers of records", rec->id, rec->name);
        code = MESO_EXIT_INVALID;
    }
    if (code == MESO_EXIT_OK) {
        *count = (uint32_t)(nf / MESO_FRUS_RECORD_SIZE);
        *ball_count = (uint32_t)(nb / MESO_BALL_RECORD_SIZE);
        *recs = calloc(*count ? *count : 1, sizeof(**recs));
        *balls = calloc(*ball_count ? *ball_count : 1, sizeof(**balls));
        if (!*recs || !*balls) {
            code = out_of_memory();
        } else {
            for (uint32_t i = 0; i < *count; ++i)
                meso_frustum_rec_decode(frus + (size_t)i * MESO_FRUS_RECORD_SIZE,
                                        fseg + (size_t)i * MESO_FSEG_RECORD_SIZE, &(*recs)[i]);
            for (uint32_t i = 0; i < *ball_count; ++i)
                meso_frustum_ball_decode(ball + (size_t)i * MESO_BALL_RECORD_SIZE, &(*balls)[i]);
        }
    }
    free(frus);
    free(fseg);
    free(ball);
    return code;
}

static int export_frusta(meso_file* f, const meso_object_record* rec, uint32_t grid, mi_glb_prim* p)
{
    meso_frustum_rec* recs = NULL;
    meso_frustum_ball_rec* balls = NULL;
    uint32_t count = 0, ball_count = 0;
    meso_ref_frusta ref;
    memset(&ref, 0, sizeof(ref));
    meso_error err;
    memset(&err, 0, sizeof(err));
    int code = frusta_records(f, rec, &recs, &count, &balls, &ball_count);
    if (code == MESO_EXIT_OK) {
        /* The relief height field as the reference samples it. */
        const meso_result r = meso_ref_frusta_load(f, rec->id, &ref, &err);
        if (r != MESO_OK)
            code = report(&err, r);
    }
    meso_ref_tess_mesh m;
    memset(&m, 0, sizeof(m));
    if (code == MESO_EXIT_OK && !meso_ref_frusta_tessellate(recs, count, balls, ball_count, &ref.relief.height, grid, &m)) {
        mi_error("object %u (%s): cannot tessellate %u frusta at --frusta-grid %u (out of memory, or more than "
                 "2^32 vertices: try a smaller grid)",
                 rec->id, rec->name, count, grid);
        code = MESO_EXIT_INTERNAL;
    }
    if (code == MESO_EXIT_OK) {
        p->vertex_count = m.vertex_count;
        p->index_count = m.index_count;
        p->positions = m.positions;
        p->indices = m.indices;
        m.positions = NULL;
        m.indices = NULL;
        /* Grid normals vanish where a grid row collapses (cap centres, ball
         * poles): those take their triangles' normal. */
        p->normals = unit_normals(p->positions, m.normals, p->vertex_count, p->indices, p->index_count);
        if (!p->normals)
            code = out_of_memory();
        set_albedo(p);
    }
    if (code == MESO_EXIT_OK && ref.color) {
        /* COLR (FORMAT.md §7.2 kind 4): per vertex, the reference's albedo
         * of a hit there on the part that made the vertex. */
        p->colors = malloc(sizeof(float) * 3 * (p->vertex_count ? p->vertex_count : 1));
        if (!p->colors)
            code = out_of_memory();
        for (uint32_t v = 0; p->colors && v < p->vertex_count; ++v) {
            meso_ref_frustum_hit hit;
            memset(&hit, 0, sizeof(hit));
            for (int k = 0; k < 3; ++k)
                hit.p[k] = p->positions[3 * (size_t)v + (size_t)k];
            const uint32_t o = m.owner[v];
            hit.part = o < count ? MESO_REF_PART_LATERAL : MESO_REF_PART_BALL;
            hit.index = (int32_t)(o < count ? o : o - count);
            double a[3] = {MI_DEFAULT_ALBEDO_R, MI_DEFAULT_ALBEDO_G, MI_DEFAULT_ALBEDO_B};
            meso_ref_frusta_albedo(&ref, &hit, a);
            for (int k = 0; k < 3; ++k)
                p->colors[3 * (size_t)v + (size_t)k] = (float)fmin(1.0, fmax(0.0, a[k]));
        }
        for (int k = 0; k < 3; ++k)
            p->base_color[k] = 1.0f;
    }
    meso_ref_tess_free(&m);
    meso_ref_frusta_free(&ref);
    free(recs);
    free(balls);
    return code;
}

/* Twice the signed (s, t') area of triangle i (0 without uvs). */
static double uv_det(const meso_mesh_view* v, const uint32_t i[3])
{
    if (!v->uvs)
        return 0;
    const float *a = v->uvs + 2 * (size_t)i[0], *b = v->uvs + 2 * (size_t)i[1], *c = v->uvs + 2 * (size_t)i[2];
    return ((double)b[0] - a[0]) * ((double)c[1] - a[1]) - ((double)c[0] - a[0]) * ((double)b[1] - a[1]);
}

/* The shell's vertices as a normal map needs them:
 *  - triangles whose (s, t') have no area (|det| < 1e-12, FORMAT.md §7.2)
 *    take barycentric texture coordinates (0, 0), (1, 0), (0, 1), on three
 *    vertices of their own;
 *  - a vertex shared by triangles of both uv orientations (a layout that
 *    mirrors without a seam, e.g. the planar projection mesobake gives a
 *    closed mesh without uvs) gets a copy for its mirrored triangles (those
 *    with det < 0), so each copy has one tangent frame that fits all its
 *    triangles — the handedness split MikkTSpace makes too.
 * New vertices come after the MESH's, which keep their numbers; every
 * triangle keeps its place and its corners' positions. Exit code. */
static int split_uv_vertices(const meso_mesh_view* v, const float* heights, mi_glb_prim* p, float** prism_h)
{
    const uint32_t nv = v->layout.vertex_count, ni = v->layout.index_count;
    uint8_t* seen = calloc(nv ? nv : 1, 1); /* bit 0: det > 0, bit 1: det < 0 */
    uint32_t* copy = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    if (!seen || !copy) {
        free(seen);
        free(copy);
        return out_of_memory();
    }
    uint64_t extra = 0;
    for (uint32_t t = 0; t + 2 < ni; t += 3) {
        const double det = uv_det(v, v->indices + t);
        if (fabs(det) < 1e-12)
            extra += 3;
        else
            for (int k = 0; k < 3; ++k)
                seen[v->indices[t + (uint32_t)k]] |= det > 0 ? 1 : 2;
    }
    for (uint32_t i = 0; i < nv; ++i)
        extra += seen[i] == 3;
    if (nv + extra > UINT32_MAX) {
        free(seen);
        free(copy);
        mi_error("%s: too many vertices once uv seams are split", p->name);
        return MESO_EXIT_UNSUPPORTED;
    }
    const uint32_t n = nv + (uint32_t)extra;
    float* pos = malloc(sizeof(float) * 3 * n);
    float* st = calloc(2 * (size_t)n, sizeof(float));
    float* hh = malloc(sizeof(float) * n);
    float* nrm = v->normals ? malloc(sizeof(float) * 3 * n) : NULL;
    uint32_t* idx = malloc(sizeof(uint32_t) * (ni ? ni : 1));
    if (!pos || !st || !hh || (v->normals && !nrm) || !idx) {
        free(seen);
        free(copy);
        free(pos);
        free(st);
        free(hh);
        free(nrm);
        free(idx);
        return out_of_memory();
    }
    memcpy(pos, v->positions, sizeof(float) * 3 * nv);
    if (v->uvs)
        memcpy(st, v->uvs, sizeof(float) * 2 * nv);
    memcpy(hh, heights, sizeof(float) * nv);
    if (nrm)
        memcpy(nrm, v->normals, sizeof(float) * 3 * nv);
    memcpy(idx, v->indices, sizeof(uint32_t) * ni);
    uint32_t next = nv;
    /* New vertex `next` as a copy of MESH vertex m with (s, t') = uv. */
#define NEW_VERTEX(m, s0, t0)                                                             \
    do {                                                                                 \
        memcpy(pos + 3 * (size_t)next, v->positions + 3 * (size_t)(m), sizeof(float) * 3); \
        if (nrm)                                                                         \
            memcpy(nrm + 3 * (size_t)next, v->normals + 3 * (size_t)(m), sizeof(float) * 3); \
        st[2 * (size_t)next] = (s0);                                                     \
        st[2 * (size_t)next + 1] = (t0);                                                 \
        hh[next] = heights[m];                                                           \
    } while (0)
    for (uint32_t i = 0; i < nv; ++i)
        if (seen[i] == 3) {
            NEW_VERTEX(i, st[2 * (size_t)i], st[2 * (size_t)i + 1]);
            copy[i] = next++;
        }
    static const float bary[3][2] = {{0, 0}, {1, 0}, {0, 1}};
    for (uint32_t t = 0; t + 2 < ni; t += 3) {
        const uint32_t* i = v->indices + t;
        const double det = uv_det(v, i);
        for (int k = 0; k < 3; ++k) {
            if (fabs(det) < 1e-12) {
                NEW_VERTEX(i[k], bary[k][0], bary[k][1]);
                idx[t + (uint32_t)k] = next++;
            } else if (det < 0 && seen[i[k]] == 3) {
                idx[t + (uint32_t)k] = copy[i[k]];
            }
        }
    }
#undef NEW_VERTEX
    free(seen);
    free(copy);
    p->vertex_count = n;
    p->index_count = ni;
    p->positions = pos;
    p->indices = idx;
    p->uvs = gltf_uvs(st, n);
    p->normals = unit_normals(pos, nrm, n, idx, ni);
    *prism_h = hh;
    free(st);
    free(nrm);
    return p->uvs && p->normals ? MESO_EXIT_OK : out_of_memory();
}

static int export_shell(meso_file* f, const meso_object_record* rec, mi_glb_prim* p)
{
    uint8_t *buf = NULL, *colr = NULL;
    size_t colr_size = 0;
    float *heights = NULL, *prism_h = NULL;
    meso_mesh_view v;
    meso_ref_shell rs;
    memset(&rs, 0, sizeof(rs));
    meso_error err;
    memset(&err, 0, sizeof(err));
    int code = read_mesh(f, rec, &buf, &v);
    if (code != MESO_EXIT_OK)
        return code;
    /* Directors and the texture function as the reference reads them. */
    meso_result r = meso_ref_shell_load(f, rec->id, &rs, &err);
    if (r != MESO_OK) {
        code = report(&err, r);
        goto done;
    }
    if (rs.vertex_count != v.layout.vertex_count || v.layout.index_count == 0) {
        mi_error("object %u (%s): the shell's MESH and SDIR disagree", rec->id, rec->name);
        code = MESO_EXIT_INVALID;
        goto done;
    }
    heights = malloc(sizeof(float) * rs.vertex_count);
    if (!heights) {
        code = out_of_memory();
        goto done;
    }
    for (uint32_t i = 0; i < rs.vertex_count; ++i) {
        /* |top − bottom|: layer 0 is the top offset, layer 1 (L = 2) the bottom's. */
        double d[3];
        for (int k = 0; k < 3; ++k) {
            d[k] = rs.directors[3 * (size_t)i + (size_t)k];
            if (rs.layers == 2)
                d[k] -= rs.directors[3 * ((size_t)rs.vertex_count + i) + (size_t)k];
        }
        heights[i] = (float)sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    code = split_uv_vertices(&v, heights, p, &prism_h);
    if (code != MESO_EXIT_OK)
        goto done;
    mi_shell_src src = {.positions = p->positions, .normals = p->normals, .uvs = p->uvs, .heights = prism_h,
                        .indices = p->indices, .vertex_count = p->vertex_count, .triangle_count = p->index_count / 3,
                        .tex = &rs.tex};
    const int32_t ci = finest_chunk(f, MESO_CHUNK_COLR, rec->id);
    if (ci >= 0) {
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
        if (c->dtype == MESO_DTYPE_U8 && c->components == 4) {
            code = read_chunk(f, rec, MESO_CHUNK_COLR, &colr, &colr_size);
            if (code != MESO_EXIT_OK)
                goto done;
            if (colr_size == 4ull * c->dims[0] * c->dims[1] * c->dims[2]) {
                src.colr = colr;
                memcpy(src.colr_dims, c->dims, sizeof(src.colr_dims));
            }
        }
        if (!src.colr)
            mi_warning("object %u (%s): its COLR chunk is not RGBA8 (u8 x 4, W x H x D); the default colour is "
                       "exported",
                       rec->id, rec->name);
    }
    meso_cmap_record cmap = {.mapping = MESO_CMAP_TILED, .scale = {1.0f, 1.0f}};
    if (src.colr) {
        /* How the COLR maps (validated: 4911, 4912, 6106). */
        uint8_t* rec_bytes = NULL;
        size_t rec_size = 0;
        code = read_chunk(f, rec, MESO_CHUNK_CMAP, &rec_bytes, &rec_size);
        if (code == MESO_EXIT_OK && rec_size == MESO_CMAP_RECORD_SIZE)
            meso_cmap_record_decode(rec_bytes, &cmap);
        free(rec_bytes);
        if (code != MESO_EXIT_OK)
            goto done;
        src.colr_mapping = cmap.mapping;
    }
    if (src.colr && cmap.mapping == MESO_CMAP_BASE) {
        /* TEXCOORD_1 = (s · scale0, 1 − t' · scale1), t' = 1 − v. */
        p->uvs1 = malloc(sizeof(float) * 2 * (p->vertex_count ? p->vertex_count : 1));
        if (!p->uvs1) {
            code = out_of_memory();
            goto done;
        }
        for (size_t i = 0; i < p->vertex_count; ++i) {
            const double s0 = p->uvs[2 * i], t0 = 1.0 - (double)p->uvs[2 * i + 1];
            p->uvs1[2 * i] = (float)(s0 * cmap.scale[0]);
            p->uvs1[2 * i + 1] = (float)(1.0 - t0 * cmap.scale[1]);
        }
        p->color_texcoord = 1;
    }
    const double k = mi_shell_slope_scale(&src);
    if (mi_shell_tangents(&src, &p->tangents) != MESO_OK) {
        code = out_of_memory();
        goto done;
    }
    char why[256];
    if (mi_shell_maps(&src, k, &p->normal_png, &p->normal_png_size, &p->color_png, &p->color_png_size, why,
                      sizeof(why)) != 0) {
        mi_error("object %u (%s): %s", rec->id, rec->name, why);
        code = MESO_EXIT_INTERNAL;
        goto done;
    }
    if (p->color_png) {
        for (int c = 0; c < 4; ++c)
            p->base_color[c] = 1.0f;
    } else {
        set_albedo(p);
    }
done:
    meso_ref_shell_free(&rs);
    free(heights);
    free(prism_h);
    free(colr);
    free(buf);
    return code;
}

/* >>command ----------------------------------------------------------------- */

int mesoinspect_export(int argc, char** argv)
{
    const char *file = NULL, *out = NULL, *only_name = NULL;
    unsigned long only = 0, grid = EXPORT_DEFAULT_GRID;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        const int val = i + 1 < argc;
        if (mi_is_help(a)) {
            fputs(usage_export, stdout);
            return mi_finish_stdout(MESO_EXIT_OK);
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && val) {
            out = argv[++i];
        } else if (!strcmp(a, "--object") && val) {
            const int code = mi_object_option(argv[++i], &only, &only_name);
            if (code != MESO_EXIT_OK)
                return code;
        } else if (!strcmp(a, "--frusta-grid") && val) {
            char* end = NULL;
            const char* s = argv[++i];
            errno = 0;
            grid = strtoul(s, &end, 10);
            if (s[0] < '0' || s[0] > '9' || !end || *end || errno || grid < 2 || grid > 1024)
                return mi_usage_error("--frusta-grid expects 2..1024, got '%s'", s);
        } else if (a[0] == '-' && a[1]) {
            const int valued = !strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--object") ||
                               !strcmp(a, "--frusta-grid");
            return mi_usage_error("%s '%s'", valued ? "missing value for option" : "unrecognized option", a);
        } else if (!file) {
            file = a;
        } else {
            return mi_usage_error("unexpected argument '%s'", a);
        }
    }
    if (!file || !out) {
        fputs(usage_export, stderr);
        return MESO_EXIT_USAGE;
    }
    int code = mi_check_output(out);
    if (code != MESO_EXIT_OK)
        return code;
    code = mi_validate_full(file, "exported");
    if (code != MESO_EXIT_OK)
        return code;
    if (only_name && (code = mi_object_by_name(file, only_name, &only)) != MESO_EXIT_OK)
        return code;

    meso_file* f = NULL;
    if ((code = mi_open_or_report(file, &f)) != MESO_EXIT_OK)
        return code;
    meso_result r = MESO_OK;
    uint32_t count = 0;
    meso_object_record* recs = mi_all_records(f, &count, &r);
    mi_glb_prim* prims = recs ? calloc(count ? count : 1, sizeof(*prims)) : NULL;
    uint32_t n = 0;
    uint8_t* glb = NULL;
    size_t glb_size = 0;
    if (!recs) {
        code = meso_exit_for(r);
        goto done;
    }
    if (!prims) {
        code = out_of_memory();
        goto done;
    }
    for (uint32_t i = 0; i < count && code == MESO_EXIT_OK; ++i) {
        const meso_object_record* rec = &recs[i];
        if (only && rec->id != only)
            continue;
        mi_glb_prim* p = &prims[n++];
        snprintf(p->name, sizeof(p->name), "%s", rec->name);
        switch (rec->kind) {
        case MESO_OBJECT_MESH: code = export_mesh(f, rec, p); break;
        case MESO_OBJECT_SHELL: code = export_shell(f, rec, p); break;
        case MESO_OBJECT_CELLS: code = export_cells(f, rec, p); break;
        case MESO_OBJECT_FRUSTA: code = export_frusta(f, rec, (uint32_t)grid, p); break;
        default:
            mi_warning("object %u (%s) is of an unknown kind (%u); exported as an empty node", rec->id, rec->name,
                       rec->kind);
            break;
        }
    }
    if (code != MESO_EXIT_OK)
        goto done;
    if (n == 0) {
        mi_error("%s: no object%s to export", file, only ? " with that id" : "s");
        code = only ? MESO_EXIT_USAGE : MESO_EXIT_UNSUPPORTED;
        goto done;
    }
    meso_error err;
    memset(&err, 0, sizeof(err));
    r = mi_glb_write(prims, n, "mesoinspect " MESO_VERSION_STRING, &glb, &glb_size, &err);
    if (r != MESO_OK) {
        code = report(&err, r);
        goto done;
    }
    meso_output* o = NULL;
    if ((code = mi_stage_output(out, &o)) != MESO_EXIT_OK)
        goto done;
    r = meso_output_write(o, glb, glb_size, &err);
    code = r == MESO_OK ? mi_publish_outputs() : mi_output_failed(&err, r);
done:
    for (uint32_t i = 0; i < n; ++i)
        mi_glb_prim_free(&prims[i]);
    free(prims);
    free(recs);
    free(glb);
    meso_file_close(f);
    return code;
}
