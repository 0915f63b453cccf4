// openvdb_adapter.cpp — OpenVDB behind extern "C": sparse level sets of meshes.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>

#include <exception>
#include <mutex>
#include <new>
#include <vector>

#include "adapters.h"

struct meso_vdb_grid {
    openvdb::FloatGrid::Ptr grid;
};

namespace {
void init_once()
{
    static std::once_flag flag;
    std::call_once(flag, [] { openvdb::initialize(); });
}
} // namespace

extern "C" meso_result meso_vdb_level_set(const meso_mesh* m, double voxel_size, float half_width,
                                          meso_vdb_grid** out, meso_error* err)
{
    *out = nullptr;
    if (!(voxel_size > 0.0) || !(half_width >= 1.0f))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "voxel size must be > 0 and half width >= 1 voxel");
    try {
        init_once();
        auto xform = openvdb::math::Transform::createLinearTransform(voxel_size);
        std::vector<openvdb::Vec3s> pts(m->vertex_count);
        // meshToLevelSet takes world-space points and applies xform itself.
        for (uint32_t i = 0; i < m->vertex_count; ++i)
            pts[i] = openvdb::Vec3s(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]);
        std::vector<openvdb::Vec3I> tris(m->triangle_count);
        for (uint32_t f = 0; f < m->triangle_count; ++f)
            tris[f] = openvdb::Vec3I(m->indices[3 * f], m->indices[3 * f + 1], m->indices[3 * f + 2]);
        std::vector<openvdb::Vec4I> quads;
        auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, pts, tris, quads, half_width);
        *out = new meso_vdb_grid{grid};
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "OpenVDB: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "OpenVDB: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "OpenVDB: unknown exception");
    }
}

extern "C" meso_result meso_vdb_sample(const meso_vdb_grid* g, const double* xyz, size_t count, float* dist,
                                       meso_error* err)
{
    try {
        openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> s(*g->grid);
        for (size_t i = 0; i < count; ++i)
            dist[i] = s.wsSample(openvdb::Vec3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
        return MESO_OK;
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "OpenVDB: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "OpenVDB: unknown exception");
    }
}

extern "C" uint64_t meso_vdb_active_voxels(const meso_vdb_grid* g)
{
    return g ? g->grid->activeVoxelCount() : 0;
}

extern "C" void meso_vdb_destroy(meso_vdb_grid* g)
{
    delete g;
}
