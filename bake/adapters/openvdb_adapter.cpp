// openvdb_adapter.cpp — OpenVDB behind extern "C": sparse level sets of
// meshes, dense sampling of .vdb grids (texture functions), and a sphere
// writer for the tests.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
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

extern "C" meso_result meso_vdb_read_dense(const char* path, const char* grid_name, uint32_t max_res, uint32_t issue,
                                           meso_vdb_dense* out, meso_error* err)
{
    *out = meso_vdb_dense{nullptr, {0, 0, 0}, 0, 0.0};
    if (max_res == 0)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, issue, "max_res must be >= 1");
    try {
        init_once();
        openvdb::io::File file(path);
        try {
            file.open();
        } catch (const std::exception& e) {
            return meso_bake_fail(err, MESO_ERR_IO, issue, "%s: %s", path, e.what());
        }
        openvdb::GridPtrVecPtr grids = file.getGrids();
        file.close();
        openvdb::FloatGrid::Ptr grid;
        for (const auto& g : *grids)
            if (g && g->isType<openvdb::FloatGrid>() && (!grid_name || g->getName() == grid_name)) {
                grid = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
                break;
            }
        if (!grid)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, issue, "%s: no float grid%s%s%s", path,
                                  grid_name ? " named '" : "", grid_name ? grid_name : "", grid_name ? "'" : "");
        const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
        if (box.empty())
            return meso_bake_fail(err, MESO_ERR_CORRUPT, issue, "%s: grid '%s' has no active voxels", path,
                                  grid->getName().c_str());
        const openvdb::Coord ext = box.dim();
        const double longest = std::max({ext.x(), ext.y(), ext.z()});
        const double scale = longest > max_res ? max_res / longest : 1.0;
        uint32_t n[3];
        for (int a = 0; a < 3; ++a)
            n[a] = static_cast<uint32_t>(std::max(1.0, std::min<double>(max_res, std::round(ext[a] * scale))));
        const size_t count = static_cast<size_t>(n[0]) * n[1] * n[2];
        float* v = static_cast<float*>(std::malloc(sizeof(float) * count));
        if (!v)
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, issue, "%s: out of memory", path);
        openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> s(*grid);
        size_t i = 0;
        for (uint32_t z = 0; z < n[2]; ++z)
            for (uint32_t y = 0; y < n[1]; ++y)
                for (uint32_t x = 0; x < n[0]; ++x) {
                    // Voxel c covers [c - 1/2, c + 1/2] in index space.
                    const openvdb::Vec3d p(box.min().x() - 0.5 + (x + 0.5) * ext.x() / n[0],
                                           box.min().y() - 0.5 + (y + 0.5) * ext.y() / n[1],
                                           box.min().z() - 0.5 + (z + 0.5) * ext.z() / n[2]);
                    v[i++] = s.isSample(p);
                }
        *out = meso_vdb_dense{v, {n[0], n[1], n[2]}, grid->getGridClass() == openvdb::GRID_LEVEL_SET ? 1 : 0,
                              grid->voxelSize()[0]};
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, issue, "OpenVDB: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, issue, "%s: OpenVDB: %s", path, e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, issue, "%s: OpenVDB: unknown exception", path);
    }
}

extern "C" meso_result meso_vdb_write_sphere(const char* path, const char* grid_name, const double center[3],
                                             double radius, double voxel_size, int fog, meso_error* err)
{
    try {
        init_once();
        auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
            static_cast<float>(radius), openvdb::Vec3f(center[0], center[1], center[2]),
            static_cast<float>(voxel_size));
        if (fog)
            openvdb::tools::sdfToFogVolume(*grid);
        grid->setName(grid_name);
        openvdb::io::File file(path);
        file.write(openvdb::GridCPtrVec{grid});
        file.close();
        return MESO_OK;
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: OpenVDB: %s", path, e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: OpenVDB: unknown exception", path);
    }
}
