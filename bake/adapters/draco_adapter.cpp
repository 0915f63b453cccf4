// draco_adapter.cpp — Draco behind extern "C": mesh compression for MESH chunks and .drc input.
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <new>

#include "adapters.h"

namespace {

int add_attribute(draco::Mesh& dm, draco::GeometryAttribute::Type type, int comps, const float* data, uint32_t n)
{
    draco::GeometryAttribute ga;
    ga.Init(type, nullptr, static_cast<uint8_t>(comps), draco::DT_FLOAT32, false, sizeof(float) * comps, 0);
    const int id = dm.AddAttribute(ga, true, n);
    draco::PointAttribute* pa = dm.attribute(id);
    for (uint32_t i = 0; i < n; ++i)
        pa->SetAttributeValue(draco::AttributeValueIndex(i), data + static_cast<size_t>(comps) * i);
    return id;
}

template <int N> bool read_attribute(const draco::Mesh& dm, draco::GeometryAttribute::Type type, float** out, uint32_t n)
{
    const draco::PointAttribute* pa = dm.GetNamedAttribute(type);
    if (!pa)
        return true;
    *out = static_cast<float*>(std::malloc(sizeof(float) * N * (n ? n : 1)));
    if (!*out)
        throw std::bad_alloc();
    for (uint32_t i = 0; i < n; ++i)
        if (!pa->ConvertValue<float, N>(pa->mapped_index(draco::PointIndex(i)), *out + static_cast<size_t>(N) * i))
            return false;
    return true;
}

} // namespace

extern "C" meso_result meso_draco_encode(const meso_mesh* m, const meso_draco_options* opt, void** out,
                                         size_t* out_size, meso_error* err)
{
    *out = nullptr;
    *out_size = 0;
    const int pbits = opt && opt->position_bits ? opt->position_bits : 14;
    const int nbits = opt && opt->normal_bits ? opt->normal_bits : 10;
    const int tbits = opt && opt->uv_bits ? opt->uv_bits : 12;
    const int speed = opt && opt->speed ? opt->speed : 7;
    const int most = MESO_DRACO_MAX_BITS;
    if (pbits < 1 || pbits > most || nbits < 2 || nbits > most || tbits < 1 || tbits > most || speed < 0 || speed > 10)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                              "Draco: quantisation bits must be 1..%d (normals 2..%d) and speed 0..10", most, most);
    try {
        draco::Mesh dm;
        dm.set_num_points(m->vertex_count);
        add_attribute(dm, draco::GeometryAttribute::POSITION, 3, m->positions, m->vertex_count);
        if (m->normals)
            add_attribute(dm, draco::GeometryAttribute::NORMAL, 3, m->normals, m->vertex_count);
        if (m->uvs)
            add_attribute(dm, draco::GeometryAttribute::TEX_COORD, 2, m->uvs, m->vertex_count);
        for (uint32_t f = 0; f < m->triangle_count; ++f) {
            draco::Mesh::Face face;
            for (int k = 0; k < 3; ++k)
                face[k] = draco::PointIndex(m->indices[3 * f + k]);
            dm.AddFace(face);
        }
        draco::Encoder enc;
        enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, pbits);
        enc.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, nbits);
        enc.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, tbits);
        enc.SetSpeedOptions(speed, speed);
        // Sequential connectivity keeps the point order, so SDIR/STHK chunks stay aligned.
        enc.SetEncodingMethod(draco::MESH_SEQUENTIAL_ENCODING);
        draco::EncoderBuffer buf;
        const draco::Status st = enc.EncodeMeshToBuffer(dm, &buf);
        if (!st.ok())
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "Draco encode: %s", st.error_msg());
        *out = std::malloc(buf.size() ? buf.size() : 1);
        if (!*out)
            throw std::bad_alloc();
        std::memcpy(*out, buf.data(), buf.size());
        *out_size = buf.size();
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "Draco encode: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "Draco encode: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "Draco encode: unknown exception");
    }
}

extern "C" meso_result meso_draco_decode(const void* data, size_t size, meso_mesh* out, meso_error* err)
{
    std::memset(out, 0, sizeof(*out));
    try {
        draco::DecoderBuffer db;
        db.Init(static_cast<const char*>(data), size);
        draco::Decoder dec;
        auto so = dec.DecodeMeshFromBuffer(&db);
        if (!so.ok())
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "Draco decode: %s", so.status().error_msg());
        std::unique_ptr<draco::Mesh> dm = std::move(so).value();
        if (!dm || dm->num_points() == 0 || dm->num_faces() == 0)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "Draco decode: empty mesh");
        if (!dm->GetNamedAttribute(draco::GeometryAttribute::POSITION))
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "Draco decode: mesh has no positions");
        const uint32_t nv = dm->num_points(), nf = dm->num_faces();
        out->vertex_count = nv;
        out->triangle_count = nf;
        bool ok = read_attribute<3>(*dm, draco::GeometryAttribute::POSITION, &out->positions, nv) &&
                  read_attribute<3>(*dm, draco::GeometryAttribute::NORMAL, &out->normals, nv) &&
                  read_attribute<2>(*dm, draco::GeometryAttribute::TEX_COORD, &out->uvs, nv);
        if (!ok) {
            meso_mesh_free(out);
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "Draco decode: attribute has the wrong component count");
        }
        out->indices = static_cast<uint32_t*>(std::malloc(sizeof(uint32_t) * 3 * nf));
        if (!out->indices)
            throw std::bad_alloc();
        for (uint32_t f = 0; f < nf; ++f) {
            const draco::Mesh::Face& face = dm->face(draco::FaceIndex(f));
            for (int k = 0; k < 3; ++k)
                out->indices[3 * f + k] = face[k].value();
        }
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "Draco decode: out of memory");
    } catch (const std::exception& e) {
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "Draco decode: %s", e.what());
    } catch (...) {
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "Draco decode: unknown exception");
    }
}
