// openmesh_adapter.cpp — OpenMesh behind extern "C": mesh import and vertex normals.
// Thin by design: no project logic here (STYLE.md §1).
#include <OpenMesh/Core/IO/MeshIO.hh> // must come before the mesh kernel header
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <OpenMesh/Core/System/omstream.hh>

#include <iostream>

#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <exception>
#include <new>

#include "adapters.h"

namespace {

struct Traits : public OpenMesh::DefaultTraits {
    typedef OpenMesh::Vec3f Point;
    typedef OpenMesh::Vec3f Normal;
    typedef OpenMesh::Vec2f TexCoord2D;
};
typedef OpenMesh::TriMesh_ArrayKernelT<Traits> TriMesh;

template <class T> T* alloc_array(size_t n)
{
    T* p = static_cast<T*>(std::malloc(n ? n * sizeof(T) : 1));
    if (!p)
        throw std::bad_alloc();
    return p;
}

} // namespace

extern "C" meso_result meso_openmesh_read(const char* path, meso_mesh* out, uint32_t* dropped_faces,
                                          meso_error* err)
{
    std::memset(out, 0, sizeof(*out));
    if (dropped_faces)
        *dropped_faces = 0;
    try {
        TriMesh mesh;
        mesh.request_vertex_texcoords2D();
        OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexTexCoord;
        // OpenMesh reports every face it refuses (complex edge / vertex of a
        // non-manifold input) on omerr() and drops it. Capture those lines
        // instead of letting them reach stderr, and count them: the caller
        // decides what to tell the user. (omerr is process-global: reads are
        // not meant to run concurrently.)
        // (omerr() writes through std::cerr: swapping std::cerr's buffer for
        // the duration of the read captures it without OpenMesh's connect(),
        // whose target wrapper is never freed.)
        std::ostringstream captured;
        std::streambuf* saved = std::cerr.rdbuf(captured.rdbuf());
        bool ok = false;
        try {
            ok = OpenMesh::IO::read_mesh(mesh, path, opt);
            omerr().flush();
        } catch (...) {
            std::cerr.rdbuf(saved);
            throw;
        }
        std::cerr.rdbuf(saved);
        if (dropped_faces) {
            const std::string log = captured.str();
            uint32_t n = 0;
            // One "complex edge" or "complex vertex" line per refused face.
            for (size_t at = log.find("add_face: complex"); at != std::string::npos;
                 at = log.find("add_face: complex", at + 1))
                ++n;
            *dropped_faces = n;
        }
        if (!ok)
            return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot read mesh (unreadable, unknown extension or malformed)", path);
        if (mesh.n_vertices() == 0 || mesh.n_faces() == 0)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "%s: mesh has no %s", path,
                                  mesh.n_vertices() == 0 ? "vertices" : "faces");
        if (mesh.n_vertices() > UINT32_MAX / 4 || mesh.n_faces() > UINT32_MAX / 4)
            return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "%s: too many elements", path);

        mesh.request_face_normals();
        mesh.request_vertex_normals();
        mesh.update_normals();

        const size_t nv = mesh.n_vertices(), nf = mesh.n_faces();
        out->vertex_count = static_cast<uint32_t>(nv);
        out->triangle_count = static_cast<uint32_t>(nf);
        out->positions = alloc_array<float>(3 * nv);
        out->normals = alloc_array<float>(3 * nv);
        out->indices = alloc_array<uint32_t>(3 * nf);
        const bool has_uv = opt.check(OpenMesh::IO::Options::VertexTexCoord);
        if (has_uv)
            out->uvs = alloc_array<float>(2 * nv);
        for (auto vh : mesh.vertices()) {
            const size_t i = static_cast<size_t>(vh.idx());
            const auto& p = mesh.point(vh);
            const auto& n = mesh.normal(vh);
            for (int k = 0; k < 3; ++k) {
                out->positions[3 * i + k] = p[k];
                out->normals[3 * i + k] = n[k];
            }
            if (has_uv) {
                const auto& t = mesh.texcoord2D(vh);
                out->uvs[2 * i] = t[0];
                out->uvs[2 * i + 1] = t[1];
            }
        }
        size_t f = 0;
        for (auto fh : mesh.faces()) {
            int k = 0;
            for (auto v : mesh.fv_range(fh)) {
                if (k < 3)
                    out->indices[3 * f + k] = static_cast<uint32_t>(v.idx());
                ++k;
            }
            ++f;
        }
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory while reading", path);
    } catch (const std::exception& e) {
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: OpenMesh: %s", path, e.what());
    } catch (...) {
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: OpenMesh: unknown exception", path);
    }
}
