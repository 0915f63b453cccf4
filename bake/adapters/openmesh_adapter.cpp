// openmesh_adapter.cpp — OpenMesh behind extern "C": mesh import and vertex normals.
// Thin by design: no project logic here (STYLE.md §1).
#include <OpenMesh/Core/IO/MeshIO.hh> // must come before the mesh kernel header
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <OpenMesh/Core/System/omstream.hh>

#include <iostream>

#include <cstdlib>
#include <cctype>
#include <cstring>
#include <sstream>
#include <string>
#include <algorithm>
#include <exception>
#include <new>
#include <vector>

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

// The stock importer plus per-corner texcoords that survive triangulation.
// OpenMesh's OBJ reader hands a face's corner texcoords to
// add_face_texcoords() with the face handle add_face() returned; for a
// polygon a TriMesh returns only the last triangle of its fan, and the stock
// importer walks that triangle's halfedges with the polygon's list, so a quad
// gets wrong corners on one triangle and none on the other. Here each corner
// of every triangle the polygon became takes the texcoord of its own vertex.
// The texcoords are kept here, per halfedge, rather than in a halfedge
// property, so that meshes without them cost nothing; corners without one
// (faces without `vt`) fall back to the vertex texcoord.
class CornerImporter : public OpenMesh::IO::ImporterT<TriMesh> {
  public:
    typedef OpenMesh::IO::ImporterT<TriMesh> Base;
    using Base::add_face;
    using Base::add_face_texcoords;
    using Base::set_texcoord;

    explicit CornerImporter(TriMesh& mesh) : Base(mesh), mesh_(mesh) {}

    OpenMesh::FaceHandle add_face(const VHandles& indices) override
    {
        first_face_ = mesh_.n_faces();
        polygon_ = indices;
        return Base::add_face(indices);
    }

    void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle,
                            const std::vector<OpenMesh::Vec2f>& texcoords) override
    {
        if (texcoords.size() != polygon_.size()) // the reader dropped repeated vertices
            return;
        for (size_t f = first_face_; f < mesh_.n_faces(); ++f)
            for (auto he : mesh_.fh_range(TriMesh::FaceHandle(static_cast<int>(f))))
                for (size_t i = 0; i < polygon_.size(); ++i)
                    if (polygon_[i] == mesh_.to_vertex_handle(he))
                        set_texcoord(he, texcoords[i]);
    }

    void set_texcoord(OpenMesh::HalfedgeHandle he, const OpenMesh::Vec2f& texcoord) override
    {
        const size_t i = static_cast<size_t>(he.idx());
        if (flagged_.size() <= i) {
            flagged_.resize(std::max(2 * flagged_.size(), i + 1), 0);
            texcoords_.resize(flagged_.size());
        }
        flagged_[i] = 1;
        texcoords_[i] = texcoord;
    }

    // The texcoord the file gave halfedge he, or NULL.
    const OpenMesh::Vec2f* texcoord(OpenMesh::HalfedgeHandle he) const
    {
        const size_t i = static_cast<size_t>(he.idx());
        return i < flagged_.size() && flagged_[i] ? &texcoords_[i] : nullptr;
    }

  private:
    TriMesh& mesh_;
    VHandles polygon_;      // the last face add_face() was given
    size_t first_face_ = 0; // the first triangle it became
    std::vector<char> flagged_;
    std::vector<OpenMesh::Vec2f> texcoords_;
};

// out->corner_uvs (see meso_bake.h): the texcoord of the halfedge of face f
// pointing to the corner's vertex, or the vertex's own where the file gave
// none. Kept only when some vertex has two different ones: without a seam
// out->uvs already says everything. fill_vertex_uvs: the file had no
// per-vertex texcoords, so out->uvs takes each vertex's last corner uv.
void read_corner_uvs(const TriMesh& mesh, const CornerImporter& importer, bool fill_vertex_uvs, meso_mesh* out)
{
    const size_t nf = out->triangle_count;
    float* cuv = alloc_array<float>(6 * nf);
    for (size_t f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = out->indices[3 * f + k];
            float* c = cuv + 6 * f + 2 * k;
            std::memcpy(c, out->uvs + 2 * static_cast<size_t>(v), 2 * sizeof(float));
            for (auto he : mesh.fh_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
                const OpenMesh::Vec2f* t = importer.texcoord(he);
                if (t && static_cast<uint32_t>(mesh.to_vertex_handle(he).idx()) == v) {
                    c[0] = (*t)[0];
                    c[1] = (*t)[1];
                }
            }
            if (fill_vertex_uvs)
                std::memcpy(out->uvs + 2 * static_cast<size_t>(v), c, 2 * sizeof(float));
        }
    // A seam: a corner whose uv differs (bitwise) from its vertex's. The
    // vertex uv is one of its corners' uvs, so this finds every vertex that
    // has two or more.
    bool seam = false;
    for (size_t c = 0; c < 3 * nf && !seam; ++c)
        seam = std::memcmp(cuv + 2 * c, out->uvs + 2 * static_cast<size_t>(out->indices[c]), 2 * sizeof(float)) != 0;
    if (seam)
        out->corner_uvs = cuv;
    else
        std::free(cuv);
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
        // Per-vertex texcoords (one per vertex: the last face to mention it
        // wins) and per-corner ones (CornerImporter), which keep seams.
        mesh.request_vertex_texcoords2D();
        CornerImporter importer(mesh);
        OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexTexCoord;
        opt += OpenMesh::IO::Options::FaceTexCoord;
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
            ok = OpenMesh::IO::IOManager().read(path, importer, opt); // read_mesh() with our importer
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
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3100, "%s: too many elements", path); /* exit 3, not 5 */

        mesh.request_face_normals();
        mesh.request_vertex_normals();
        mesh.update_normals();

        const size_t nv = mesh.n_vertices(), nf = mesh.n_faces();
        out->vertex_count = static_cast<uint32_t>(nv);
        out->triangle_count = static_cast<uint32_t>(nf);
        out->positions = alloc_array<float>(3 * nv);
        out->normals = alloc_array<float>(3 * nv);
        out->indices = alloc_array<uint32_t>(3 * nf);
        // STL has no texture coordinates, but OpenMesh's STL reader leaves the
        // requested texcoord options set, and the vertex texcoords it never
        // wrote are uninitialised memory (bakes differed from run to run).
        const size_t plen = std::strlen(path);
        bool stl = plen >= 4;
        for (size_t k = 0; stl && k < 4; ++k)
            stl = std::tolower(static_cast<unsigned char>(path[plen - 4 + k])) == ".stl"[k];
        const bool has_vertex_uv = !stl && opt.check(OpenMesh::IO::Options::VertexTexCoord);
        const bool has_corner_uv = !stl && opt.check(OpenMesh::IO::Options::FaceTexCoord);
        if (has_vertex_uv || has_corner_uv)
            out->uvs = alloc_array<float>(2 * nv);
        for (auto vh : mesh.vertices()) {
            const size_t i = static_cast<size_t>(vh.idx());
            const auto& p = mesh.point(vh);
            const auto& n = mesh.normal(vh);
            for (int k = 0; k < 3; ++k) {
                out->positions[3 * i + k] = p[k];
                out->normals[3 * i + k] = n[k];
            }
            if (has_vertex_uv) {
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
        if (has_corner_uv) {
            if (!has_vertex_uv)
                std::memset(out->uvs, 0, sizeof(float) * 2 * nv);
            read_corner_uvs(mesh, importer, !has_vertex_uv, out);
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
