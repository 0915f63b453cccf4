// cgal_adapter.cpp — CGAL behind extern "C": exact point-in-mesh queries.
// Kernel: exact predicates, inexact constructions (the side test only needs predicates).
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <exception>
#include <memory>
#include <new>
#include <vector>

#include "adapters.h"

namespace {
typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
typedef CGAL::Side_of_triangle_mesh<Mesh, K> Side;
} // namespace

struct meso_cgal_inside {
    Mesh mesh;
    std::unique_ptr<Side> side;
};

extern "C" meso_result meso_cgal_inside_create(const meso_mesh* m, meso_cgal_inside** out, meso_error* err)
{
    *out = nullptr;
    try {
        std::unique_ptr<meso_cgal_inside> t(new meso_cgal_inside());
        std::vector<Mesh::Vertex_index> vs;
        vs.reserve(m->vertex_count);
        for (uint32_t i = 0; i < m->vertex_count; ++i)
            vs.push_back(t->mesh.add_vertex(Point(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2])));
        for (uint32_t f = 0; f < m->triangle_count; ++f) {
            const uint32_t* ix = m->indices + 3 * f;
            if (ix[0] >= m->vertex_count || ix[1] >= m->vertex_count || ix[2] >= m->vertex_count)
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "triangle %u: index out of range", f);
            if (t->mesh.add_face(vs[ix[0]], vs[ix[1]], vs[ix[2]]) == Mesh::null_face())
                return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "triangle %u: non-manifold, CGAL cannot add it", f);
        }
        if (!CGAL::is_closed(t->mesh))
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "mesh is not closed: point-in-mesh is undefined");
        t->side.reset(new Side(t->mesh));
        *out = t.release();
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}

extern "C" meso_result meso_cgal_inside_query(const meso_cgal_inside* t, const double* xyz, size_t count,
                                              int8_t* side, meso_error* err)
{
    try {
        for (size_t i = 0; i < count; ++i) {
            CGAL::Bounded_side s = (*t->side)(Point(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
            side[i] = s == CGAL::ON_BOUNDED_SIDE ? 1 : s == CGAL::ON_UNBOUNDED_SIDE ? -1 : 0;
        }
        return MESO_OK;
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}

extern "C" void meso_cgal_inside_destroy(meso_cgal_inside* t)
{
    delete t;
}
