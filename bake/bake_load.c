/*
 * bake_load.c — the bake's inputs, checked before any stage sees them:
 * meshes by extension (bytes through the mesh guard, then OpenMesh or
 * Draco; or a glTF scene through gltf_scene.c; then the checks every stage
 * relies on and orientation outward),
 * whole files (provenance checksums, .drc), texture SPECs.
 */
#include "bake_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "adapters.h"
#include "gltf_model.h"
#include "mesh_check.h"
#include "mesh_guard.h"
#include "mesh_orient.h"
#include "texture_function.h"

const char* mesoi_base_name(const char* path)
{
    if (!path)
        return "(memory)"; /* a host's mesh in memory (the options' `mesh`), as META names it */
    const char* s = strrchr(path, '/');
    return s ? s + 1 : path;
}

int mesoi_has_suffix(const char* s, const char* suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    if (n < m)
        return 0;
    for (size_t i = 0; i < m; ++i) {
        char c = s[n - m + i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != suffix[i])
            return 0;
    }
    return 1;
}

meso_result mesoi_slurp(const char* path, uint8_t** data, size_t* size, meso_error* err)
{
    *data = NULL;
    *size = 0;
    FILE* f = fopen(path, "rb");
    if (!f)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", path, strerror(errno));
    if (fseek(f, 0, SEEK_END) != 0) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot seek: %s", path, strerror(errno));
    }
    long n = ftell(f);
    rewind(f);
    if (n < 0) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: not a regular file", path);
    }
    uint8_t* buf = malloc((size_t)n + 1);
    if (!buf) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", path);
    }
    if (fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: read failed", path);
    }
    fclose(f);
    *data = buf;
    *size = (size_t)n;
    return MESO_OK;
}

/* Check what every stage relies on: finite coordinates, indices in range,
 * no degenerate index triples. Problems are errors naming the element. */
static meso_result check_mesh(const char* path, const meso_mesh* m, meso_error* err)
{
    for (uint32_t i = 0; i < 3u * m->vertex_count; ++i)
        if (!(m->positions[i] == m->positions[i]) || m->positions[i] > 3.0e38f || m->positions[i] < -3.0e38f)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3101, "%s: vertex %u has a non-finite coordinate", path,
                                  i / 3u);
    for (uint32_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t* ix = m->indices + 3u * t;
        if (ix[0] >= m->vertex_count || ix[1] >= m->vertex_count || ix[2] >= m->vertex_count)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3102, "%s: triangle %u refers to a missing vertex", path, t);
    }
    return MESO_OK;
}

/* What a reader refuses that the element checks do not see: faces on
 * non-manifold edges (OpenMesh drops them) or on misoriented ones. For
 * meshes that no reader built (in memory, glTF). */
static meso_result check_structure(const char* what, meso_mesh* m, meso_error* err)
{
    meso_mesh_topology topo;
    memset(&topo, 0, sizeof(topo));
    meso_result r = meso_mesh_topology_compute(m, 0.0, &topo, err);
    free(topo.boundary);
    if (r == MESO_OK && topo.nonmanifold_edges)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3110, "%s: %u non-manifold edges (face %u is on one)", what,
                           topo.nonmanifold_edges, topo.first_bad_face);
    else if (r == MESO_OK && topo.misoriented_edges)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3111,
                           "%s: %u edges are traversed the same way by both faces (face %u is on one)", what,
                           topo.misoriented_edges, topo.first_bad_face);
    return r;
}

/* Inside-out closed components are flipped with a warning (mesh_orient.h
 * says which, and why per component). */
static meso_result orient_mesh(mesoi_bake_run* run, const char* path, meso_mesh* m, meso_bake_mesh_fixes* fixes,
                               meso_error* err)
{
    meso_mesh_orientation o;
    memset(&o, 0, sizeof(o));
    meso_result r = meso_mesh_orient_outward(m, &o, err);
    if (r != MESO_OK)
        return r;
    fixes->reoriented_components = o.reoriented_components;
    fixes->closed_components = o.closed_components;
    fixes->reoriented_faces = o.reoriented_faces;
    fixes->orientation_unchecked = o.unchecked != 0;
    if (o.reoriented_components)
        mesoi_run_warning(run, MESO_BAKE_ISSUE_REORIENTED,
                          "%s: %u of %u closed components were inside-out (negative volume); flipped their %u faces",
                          path, o.reoriented_components, o.closed_components, o.reoriented_faces);
    if (o.unchecked)
        mesoi_run_warning(run, 0,
                          "%s: too many nested closed components to check their orientation; left as they are",
                          path);
    return MESO_OK;
}

/* A glTF scene (gltf_model.h) welded into one mesh, then what a mesh from
 * memory gets: the element and structure checks, orientation. */
static meso_result load_gltf(mesoi_bake_run* run, const char* path, meso_mesh* m, meso_mesh_materials* mats,
                             meso_bake_mesh_fixes* fixes, meso_error* err)
{
    uint32_t dropped = 0;
    meso_result r = meso_gltf_load(path, run->common.gltf_node, run->common.max_memory, m, mats, &dropped, err);
    if (r != MESO_OK)
        return r;
    if (dropped)
        mesoi_run_warning(run, 0, "%s: %u triangles with two corners at one position were dropped", path, dropped);
    r = check_mesh(path, m, err);
    if (r == MESO_OK)
        r = check_structure(path, m, err);
    if (r == MESO_OK)
        r = orient_mesh(run, path, m, fixes, err);
    return r;
}

static meso_result load_unchecked(mesoi_bake_run* run, const char* path, meso_mesh* m, meso_mesh_materials* mats,
                                  meso_bake_mesh_fixes* fixes, meso_error* err)
{
    FILE* probe = fopen(path, "rb");
    if (!probe)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", path, strerror(errno));
    fclose(probe);
    meso_result r;
    /* No third-party reader sees a file the guard refuses (bake/mesh_guard.h). */
    if (meso_mesh_format_from_path(path) != MESO_MESH_FORMAT_UNKNOWN &&
        (r = meso_mesh_guard_check_file(path, run->common.max_memory, NULL, err)) != MESO_OK)
        return r;
    if (mesoi_has_suffix(path, ".gltf") || mesoi_has_suffix(path, ".glb"))
        return load_gltf(run, path, m, mats, fixes, err);
    if (mesoi_has_suffix(path, ".drc")) {
#if MESO_HAVE_DRACO
        uint8_t* data;
        size_t size;
        if ((r = mesoi_slurp(path, &data, &size, err)) != MESO_OK)
            return r;
        r = meso_draco_decode(data, size, m, err);
        free(data);
        if (r != MESO_OK) {
            char msg[sizeof(err->message)];
            snprintf(msg, sizeof(msg), "%s", err->message);
            return meso_bake_fail(err, r, err->code, "%s: %s", path, msg);
        }
#else
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "%s: .drc input needs the Draco adapter", path);
#endif
    } else {
#if MESO_HAVE_OPENMESH
        uint32_t dropped = 0;
        if (!(mesoi_has_suffix(path, ".obj") || mesoi_has_suffix(path, ".off") || mesoi_has_suffix(path, ".ply") ||
              mesoi_has_suffix(path, ".stl") || mesoi_has_suffix(path, ".om")))
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3251,
                                  "%s: not a mesh file we can read: unknown extension (expected .obj .off .ply "
                                  ".stl .om .drc .gltf .glb)",
                                  path);
        r = meso_openmesh_read(path, m, &dropped, err);
        if (r != MESO_OK)
            return r == MESO_ERR_IO ? meso_bake_fail(err, MESO_ERR_CORRUPT, 3100, "%s", err->message) : r;
        if (dropped) {
            meso_mesh_free(m);
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3110,
                                  "%s: %u faces are non-manifold (complex edges or vertices) and could not be "
                                  "imported; repair the mesh (split non-manifold edges and vertices) and bake again",
                                  path, dropped);
        }
#else
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "%s: mesh import needs the OpenMesh adapter", path);
#endif
    }
    if (r == MESO_OK && m->triangle_count == 0) /* empty, or not a mesh at all */
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3252, "%s: no triangles (an empty file, or not a mesh)", path);
    if (r == MESO_OK)
        r = check_mesh(path, m, err);
    if (r == MESO_OK)
        r = orient_mesh(run, path, m, fixes, err);
    return r;
}

static meso_result load_mesh(mesoi_bake_run* run, const char* path, meso_mesh* m, meso_mesh_materials* mats,
                             meso_bake_mesh_fixes* fixes, meso_error* err)
{
    meso_bake_mesh_fixes ignored;
    if (!fixes)
        fixes = &ignored;
    memset(fixes, 0, sizeof(*fixes));
    memset(m, 0, sizeof(*m));
    if (!path)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "no input mesh given");
    if (mats)
        memset(mats, 0, sizeof(*mats));
    meso_result r = load_unchecked(run, path, m, mats, fixes, err);
    /* Every failure carries a code: 3100 for an input the readers reject. */
    if (r != MESO_OK && err && err->code == 0)
        err->code = r == MESO_ERR_IO ? 5004 : 3100;
    if (r != MESO_OK) {
        meso_mesh_free(m);
        meso_mesh_materials_free(mats);
    }
    return r;
}

meso_result mesoi_load_mesh(mesoi_bake_run* run, const char* path, meso_mesh* m, meso_bake_mesh_fixes* fixes,
                            meso_error* err)
{
    return load_mesh(run, path, m, NULL, fixes, err);
}

meso_result mesoi_load_mesh_materials(mesoi_bake_run* run, const char* path, meso_mesh* m,
                                      meso_mesh_materials* materials, meso_bake_mesh_fixes* fixes, meso_error* err)
{
    return load_mesh(run, path, m, materials, fixes, err);
}

/* A copy of `src`'s arrays into *m (zeroed first); 0 when out of memory. */
static int copy_mesh(const meso_mesh* src, meso_mesh* m)
{
    const size_t nv = src->vertex_count, nt = src->triangle_count;
    memset(m, 0, sizeof(*m));
    m->vertex_count = src->vertex_count;
    m->triangle_count = src->triangle_count;
    m->positions = malloc(sizeof(float) * 3 * (nv ? nv : 1));
    m->indices = malloc(sizeof(uint32_t) * 3 * (nt ? nt : 1));
    m->normals = src->normals ? malloc(sizeof(float) * 3 * (nv ? nv : 1)) : NULL;
    m->uvs = src->uvs ? malloc(sizeof(float) * 2 * (nv ? nv : 1)) : NULL;
    m->corner_uvs = src->corner_uvs ? malloc(sizeof(float) * 6 * (nt ? nt : 1)) : NULL;
    if (!m->positions || !m->indices || (src->normals && !m->normals) || (src->uvs && !m->uvs) ||
        (src->corner_uvs && !m->corner_uvs)) {
        meso_mesh_free(m);
        return 0;
    }
    memcpy(m->positions, src->positions, sizeof(float) * 3 * nv);
    memcpy(m->indices, src->indices, sizeof(uint32_t) * 3 * nt);
    if (src->normals)
        memcpy(m->normals, src->normals, sizeof(float) * 3 * nv);
    if (src->uvs)
        memcpy(m->uvs, src->uvs, sizeof(float) * 2 * nv);
    if (src->corner_uvs)
        memcpy(m->corner_uvs, src->corner_uvs, sizeof(float) * 6 * nt);
    return 1;
}

/* A mesh the host holds in memory gets what a file gets after its reader:
 * the same element checks, and the structure a reader would have refused
 * (faces on non-manifold or misoriented edges: OpenMesh drops them, the
 * guard refuses the directed edge used twice), then orientation. */
static meso_result load_memory(mesoi_bake_run* run, const meso_mesh* src, meso_mesh* m, meso_bake_mesh_fixes* fixes,
                               meso_error* err)
{
    const char* what = MESOI_MEMORY_INPUT;
    if ((src->vertex_count && !src->positions) || (src->triangle_count && !src->indices))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "%s: NULL positions or indices", what);
    if (src->triangle_count == 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 3252, "%s: no triangles", what);
    if (src->vertex_count > UINT32_MAX / 3 || src->triangle_count > UINT32_MAX / 6)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "%s: %u vertices, %u triangles: too many", what,
                              src->vertex_count, src->triangle_count);
    meso_result r = check_mesh(what, src, err);
    if (r != MESO_OK)
        return r;
    if (!copy_mesh(src, m))
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", what);
    r = check_structure(what, m, err);
    if (r == MESO_OK)
        r = orient_mesh(run, what, m, fixes, err);
    return r;
}

meso_result mesoi_load_input(mesoi_bake_run* run, const char* path, const meso_mesh* mem, meso_mesh* m,
                             meso_bake_mesh_fixes* fixes, meso_error* err)
{
    if (!mem)
        return mesoi_load_mesh(run, path, m, fixes, err);
    meso_bake_mesh_fixes ignored;
    if (!fixes)
        fixes = &ignored;
    memset(fixes, 0, sizeof(*fixes));
    memset(m, 0, sizeof(*m));
    if (path)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "both an input path and an in-memory mesh given");
    const meso_result r = load_memory(run, mem, m, fixes, err);
    if (r != MESO_OK)
        meso_mesh_free(m);
    return r;
}

meso_result mesoi_load_input_materials(mesoi_bake_run* run, const char* path, const meso_mesh* mem, meso_mesh* m,
                                       meso_mesh_materials* mats, meso_bake_mesh_fixes* fixes, meso_error* err)
{
    if (!mem)
        return load_mesh(run, path, m, mats, fixes, err);
    memset(mats, 0, sizeof(*mats));
    return mesoi_load_input(run, path, mem, m, fixes, err);
}

const char* mesoi_input_label(const char* path)
{
    return path ? mesoi_base_name(path) : "mesh";
}

meso_result meso_bake_load_mesh(const char* path, const meso_bake_common* c, meso_mesh* m,
                                meso_bake_mesh_fixes* fixes, meso_error* err)
{
    mesoi_bake_run run;
    mesoi_run_begin(&run, c);
    return mesoi_load_mesh(&run, path, m, fixes, err);
}

meso_result meso_bake_load_mesh_materials(const char* path, const meso_bake_common* c, meso_mesh* m,
                                          meso_mesh_materials* materials, meso_bake_mesh_fixes* fixes,
                                          meso_error* err)
{
    mesoi_bake_run run;
    mesoi_run_begin(&run, c);
    return load_mesh(&run, path, m, materials, fixes, err);
}

meso_result meso_bake_texture_probe(const char* spec, const meso_bake_common* c, meso_bake_texture_info* info,
                                    meso_error* err)
{
    mesoi_bake_run run;
    mesoi_run_begin(&run, c);
    meso_texfn fn;
    memset(&fn, 0, sizeof(fn));
    if (!spec)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC, "no texture SPEC given");
    const meso_result r = meso_texfn_from_spec_max(spec, run.common.max_memory, &fn, err);
    if (r == MESO_OK && info) {
        info->density = fn.kind == MESO_TEXFN_DENSITY;
        memcpy(info->dims, fn.dims, sizeof(info->dims));
        info->dtype = fn.dtype;
    }
    meso_texfn_free(&fn);
    return r;
}
