/*
 * file_validate.c — every rule a .meso file must satisfy, in one place.
 *
 * The reader (open = cheap tier), the validator (full tier) and the writer
 * (meso_writer_add) all call these functions, so the writer cannot emit a
 * file the reader rejects. Rules and issue codes: FORMAT.md §Validation.
 * Nothing here allocates; bad bytes are reported, never asserted.
 */
#include "file_internal.h"

#include <math.h>

/* >>entry checks (cheap tier) --------------------------------------------- */

uint32_t meso_dtype_size(meso_dtype t)
{
    switch (t) {
    case MESO_DTYPE_BYTES:
    case MESO_DTYPE_U8:
    case MESO_DTYPE_I8: return 1;
    case MESO_DTYPE_U16:
    case MESO_DTYPE_I16:
    case MESO_DTYPE_F16: return 2;
    case MESO_DTYPE_U32:
    case MESO_DTYPE_I32:
    case MESO_DTYPE_F32: return 4;
    default: return 0;
    }
}

int mesoi_known_type(uint32_t type)
{
    switch (type) {
    case MESO_CHUNK_META:
    case MESO_CHUNK_RPRT:
    case MESO_CHUNK_OBJT:
    case MESO_CHUNK_MESH:
    case MESO_CHUNK_SDIR:
    case MESO_CHUNK_STHK:
    case MESO_CHUNK_TX2D:
    case MESO_CHUNK_TX3D:
    case MESO_CHUNK_DIST:
    case MESO_CHUNK_TILE:
    case MESO_CHUNK_SPLT:
    case MESO_CHUNK_MEMB:
    case MESO_CHUNK_NRMM:
    case MESO_CHUNK_COLR:
    case MESO_CHUNK_SKEL:
    case MESO_CHUNK_FRUS:
    case MESO_CHUNK_FSEG:
    case MESO_CHUNK_BALL:
    case MESO_CHUNK_CELL:
    case MESO_CHUNK_ANIM:
    case MESO_CHUNK_CMAP:
    case MESO_CHUNK_LODS:
    case MESO_CHUNK_TXFR:
    case MESO_CHUNK_DSFR:
    case MESO_CHUNK_RELF:
    case MESO_CHUNK_VCOL:
    case MESO_CHUNK_PRTS:
    case MESO_CHUNK_PMSH:
    case MESO_CHUNK_PVCL:
    case MESO_CHUNK_PTRI: return 1;
    default: return 0;
    }
}

meso_result mesoi_check_entry(const meso_chunk_info* c, uint32_t reserved, uint16_t minor, int32_t chunk, uint64_t eo,
                              meso_error* err)
{
    char cc[5];
    mesoi_fourcc_str(c->type, cc);
    for (int i = 0; i < 4; i++) {
        uint8_t b = (uint8_t)(c->type >> (8 * i));
        if (b < 0x20 || b > 0x7E)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_TYPE, eo + MESO_TOC_OFF_TYPE, chunk,
                                    "chunk %d: type 0x%08X is not four printable ASCII characters", (int)chunk,
                                    c->type);
    }
    if (c->flags & ~MESO_CHUNK_FLAG_REQUIRED)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_FLAGS, eo + MESO_TOC_OFF_FLAGS, chunk,
                                "chunk %d (%s): unknown flag bits 0x%X", (int)chunk, cc, c->flags);
    if (reserved != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_RESERVED, eo + MESO_TOC_OFF_RESERVED, chunk,
                                "chunk %d (%s): reserved field is 0x%X, must be 0", (int)chunk, cc, reserved);
    if (!mesoi_known_type(c->type) && (c->flags & MESO_CHUNK_FLAG_REQUIRED))
        return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_CHUNK_UNKNOWN_REQUIRED, eo + MESO_TOC_OFF_TYPE,
                                chunk,
                                "chunk %d: required chunk type '%s' is not supported by this reader (format %d.%d)",
                                (int)chunk, cc, MESO_FORMAT_MAJOR, MESO_FORMAT_MINOR);
    if (c->stored_size == 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_EMPTY, eo + MESO_TOC_OFF_STORED_SIZE, chunk,
                                "chunk %d (%s): stored_size is 0", (int)chunk, cc);
    /* Newer minors may add encodings and dtypes: only a 1.0 file is wrong to
     * use one; for newer files the chunk is refused when it is read. */
    int newer = minor > MESO_FORMAT_MINOR;
    if (c->encoding >= MESO_ENCODING_COUNT && !newer)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_ENCODING, eo + MESO_TOC_OFF_ENCODING, chunk,
                                "chunk %d (%s): unknown encoding %u", (int)chunk, cc, c->encoding);
    if (c->dtype >= MESO_DTYPE_COUNT && !newer)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_DTYPE, eo + MESO_TOC_OFF_DTYPE, chunk,
                                "chunk %d (%s): unknown dtype %u", (int)chunk, cc, c->dtype);
    if (c->components < 1 || c->components > 16)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_COMPONENTS, eo + MESO_TOC_OFF_COMPONENTS, chunk,
                                "chunk %d (%s): components %u outside 1..16", (int)chunk, cc, c->components);
    for (int i = 0; i < 3; i++) {
        if (c->dims[i] == 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_DIMS,
                                    eo + MESO_TOC_OFF_DIMS + 4u * (unsigned)i, chunk,
                                    "chunk %d (%s): dims[%d] is 0 (unused axes are 1)", (int)chunk, cc, i);
    }
    if (c->encoding == MESO_ENCODING_RAW && c->stored_size != c->decoded_size)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_RAW_SIZE, eo + MESO_TOC_OFF_DECODED_SIZE, chunk,
                                "chunk %d (%s): raw chunk has stored_size %llu != decoded_size %llu", (int)chunk, cc,
                                (unsigned long long)c->stored_size, (unsigned long long)c->decoded_size);
    /* A Draco chunk cannot expand without bound (FORMAT.md §6): otherwise a
     * few hundred bytes could make every reader allocate gigabytes. */
    if (c->encoding == MESO_ENCODING_DRACO &&
        c->stored_size <= (UINT64_MAX - MESO_DRACO_EXPANSION_SLACK) / MESO_DRACO_MAX_EXPANSION &&
        c->decoded_size > c->stored_size * MESO_DRACO_MAX_EXPANSION + MESO_DRACO_EXPANSION_SLACK)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_EXPANSION, eo + MESO_TOC_OFF_DECODED_SIZE,
                                chunk,
                                "chunk %d (%s): Draco decoded_size %llu exceeds %u x stored_size %llu + %u bytes",
                                (int)chunk, cc, (unsigned long long)c->decoded_size, MESO_DRACO_MAX_EXPANSION,
                                (unsigned long long)c->stored_size, MESO_DRACO_EXPANSION_SLACK);
    if (c->dtype != MESO_DTYPE_BYTES && c->dtype < MESO_DTYPE_COUNT) {
        uint64_t n = meso_dtype_size((meso_dtype)c->dtype);
        int ok = mesoi_mul_u64(n, c->components, &n) && mesoi_mul_u64(n, c->dims[0], &n) && mesoi_mul_u64(n, c->dims[1], &n) &&
                 mesoi_mul_u64(n, c->dims[2], &n);
        if (!ok || n != c->decoded_size)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_TYPED_SIZE, eo + MESO_TOC_OFF_DECODED_SIZE,
                                    chunk,
                                    "chunk %d (%s): decoded_size %llu != dtype size x %u components x %ux%ux%u%s",
                                    (int)chunk, cc, (unsigned long long)c->decoded_size, c->components, c->dims[0],
                                    c->dims[1], c->dims[2], ok ? "" : " (overflows)");
    }
    return MESO_OK;
}

/* >>type rules (full tier) ------------------------------------------------ */

static meso_result elem_error(const meso_chunk_info* c, int32_t chunk, meso_error* err, const char* want)
{
    char cc[5];
    mesoi_fourcc_str(c->type, cc);
    return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_TYPE_ELEMENT, UINT64_MAX, chunk,
                            "chunk %d (%s): dtype %u x %u components, dims %ux%ux%u; %s must be %s", (int)chunk, cc,
                            c->dtype, c->components, c->dims[0], c->dims[1], c->dims[2], cc, want);
}

#define DT(t) MESOI_DT(t)
#define DT_TYPED (DT(U8) | DT(U16) | DT(U32) | DT(I8) | DT(I16) | DT(I32) | DT(F16) | DT(F32))

meso_result mesoi_check_type_rules(const meso_chunk_info* c, int32_t chunk, meso_error* err)
{
    char cc[5];
    mesoi_fourcc_str(c->type, cc);
    /* Unknown types, and dtypes/encodings of a newer minor, have no rules here. */
    if (!mesoi_known_type(c->type) || c->dtype >= MESO_DTYPE_COUNT || c->encoding >= MESO_ENCODING_COUNT)
        return MESO_OK;
    if (c->encoding != MESO_ENCODING_RAW && !(mesoi_mesh_layout(c->type) && c->encoding == MESO_ENCODING_DRACO))
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_TYPE_ENCODING, UINT64_MAX, chunk,
                                "chunk %d (%s): encoding %u is not allowed for %s", (int)chunk, cc, c->encoding, cc);
    int flat = c->dims[1] == 1 && c->dims[2] == 1;
    switch (c->type) {
    case MESO_CHUNK_META:
    case MESO_CHUNK_RPRT:
    case MESO_CHUNK_OBJT:
    case MESO_CHUNK_LODS:
        if (c->object != 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_TYPE_OBJECT, UINT64_MAX, chunk,
                                    "chunk %d (%s): file-wide chunk has object %u, must be 0", (int)chunk, cc,
                                    c->object);
        /* fallthrough */
    case MESO_CHUNK_MESH:
    case MESO_CHUNK_SKEL:
    case MESO_CHUNK_FRUS:
    case MESO_CHUNK_FSEG:
    case MESO_CHUNK_BALL:
    case MESO_CHUNK_CELL:
    case MESO_CHUNK_ANIM:
    case MESO_CHUNK_CMAP:
        if (c->dtype != MESO_DTYPE_BYTES || c->components != 1)
            return elem_error(c, chunk, err, "BYTES x 1");
        return MESO_OK;
    case MESO_CHUNK_SDIR:
        /* Layer 0: top offsets; layer 1 (envelope shells): bottom offsets. */
        if (c->dtype != MESO_DTYPE_F32 || c->components != 3 || c->dims[2] != 1 || c->dims[1] < 1 || c->dims[1] > 2)
            return elem_error(c, chunk, err, "F32 x 3, dims N x (1 or 2) x 1");
        return MESO_OK;
    case MESO_CHUNK_STHK:
        if (c->dtype != MESO_DTYPE_F32 || c->components != 1 || !flat)
            return elem_error(c, chunk, err, "F32 x 1, dims N x 1 x 1");
        return MESO_OK;
    case MESO_CHUNK_TX2D:
    case MESO_CHUNK_RELF:
        if (!mesoi_is_dtype(c, DT_TYPED) || c->components > 4 || c->dims[2] != 1)
            return elem_error(c, chunk, err, "a numeric dtype x 1..4, dims W x H x 1");
        return MESO_OK;
    case MESO_CHUNK_TX3D:
    case MESO_CHUNK_TXFR:
        if (!mesoi_is_dtype(c, DT_TYPED) || c->components > 4)
            return elem_error(c, chunk, err, "a numeric dtype x 1..4");
        return MESO_OK;
    case MESO_CHUNK_DIST:
    case MESO_CHUNK_DSFR:
        if (!mesoi_is_dtype(c, DT(U8) | DT(U16) | DT(F16) | DT(F32)) || c->components != 1)
            return elem_error(c, chunk, err, "U8, U16, F16 or F32 x 1");
        return MESO_OK;
    case MESO_CHUNK_TILE:
        if (!mesoi_is_dtype(c, DT(U16) | DT(U32)) || c->components != 1)
            return elem_error(c, chunk, err, "U16 or U32 x 1");
        return MESO_OK;
    case MESO_CHUNK_SPLT:
        if (!mesoi_is_dtype(c, DT(U8) | DT(U16) | DT(U32)) || !flat)
            return elem_error(c, chunk, err, "U8, U16 or U32 x faces, dims N x 1 x 1");
        return MESO_OK;
    case MESO_CHUNK_MEMB:
        if (!mesoi_is_dtype(c, DT(U8) | DT(U32)) || c->components != 1 || c->dims[2] != 1)
            return elem_error(c, chunk, err, "U8 or U32 x 1, dims words x tiles x 1");
        return MESO_OK;
    case MESO_CHUNK_NRMM:
        if (c->dtype != MESO_DTYPE_U16 || c->components != 2)
            return elem_error(c, chunk, err, "U16 x 2");
        return MESO_OK;
    case MESO_CHUNK_COLR:
        if (c->dtype != MESO_DTYPE_U8 || c->components != 4)
            return elem_error(c, chunk, err, "U8 x 4");
        return MESO_OK;
    case MESO_CHUNK_PRTS:
        if (c->object == 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_TYPE_OBJECT, UINT64_MAX, chunk,
                                    "chunk %d (PRTS): object 0; parts belong to an OBJT object", (int)chunk);
        if (c->dtype != MESO_DTYPE_BYTES || c->components != 1)
            return elem_error(c, chunk, err, "BYTES x 1");
        return MESO_OK;
    case MESO_CHUNK_PMSH: /* dims[0] names the part (1..), so it is not free as for other BYTES chunks */
        if (c->dtype != MESO_DTYPE_BYTES || c->components != 1 || !flat || c->object == 0)
            return elem_error(c, chunk, err, "BYTES x 1, dims part x 1 x 1, an OBJT object");
        return MESO_OK;
    case MESO_CHUNK_VCOL:
        if (c->dtype != MESO_DTYPE_U8 || (c->components != 4 && c->components != 1) || !flat)
            return elem_error(c, chunk, err, "U8 x 4 or U8 x 1, dims N x 1 x 1");
        return MESO_OK;
    case MESO_CHUNK_PTRI:
        if (c->dtype != MESO_DTYPE_U32 || c->components != 1 || !flat || c->object == 0 || c->lod != 0)
            return elem_error(c, chunk, err, "U32 x 1, dims T x 1 x 1, an OBJT object, lod 0");
        return MESO_OK;
    case MESO_CHUNK_PVCL: /* as PMSH: dims[0] names the part; components bytes per vertex */
        if (c->dtype != MESO_DTYPE_BYTES || (c->components != 4 && c->components != 1) || !flat || c->object == 0)
            return elem_error(c, chunk, err, "BYTES x 4 or BYTES x 1, dims part x 1 x 1, an OBJT object");
        return MESO_OK;
    default: return MESO_OK;
    }
}

static uint64_t at(uint64_t base, uint64_t off) { return base == UINT64_MAX ? UINT64_MAX : base + off; }

static meso_result check_json(const uint8_t* d, size_t n, int32_t chunk, const char* cc, uint64_t base, meso_error* err)
{
    size_t bad = mesoi_utf8_invalid(d, n);
    if (bad != SIZE_MAX)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_JSON_UTF8, at(base, bad), chunk,
                                "chunk %d (%s): invalid UTF-8 at byte %zu", (int)chunk, cc, bad);
    uint32_t code = 0;
    const char* what = NULL;
    size_t pos = 0;
    if (mesoi_json_check(d, n, &code, &what, &pos))
        return MESO_OK;
    return mesoi_file_error(err, MESO_ERR_CORRUPT, code, at(base, pos), chunk,
                            "chunk %d (%s): invalid JSON at byte %zu: %s", (int)chunk, cc, pos, what);
}

/* >>structured chunks ----------------------------------------------------- */

static int finite3(const uint8_t* p)
{
    return isfinite(mesoi_ldf32(p)) && isfinite(mesoi_ldf32(p + 4)) && isfinite(mesoi_ldf32(p + 8));
}

static meso_result check_objt(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n % MESO_OBJT_RECORD_SIZE != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_OBJT_SIZE, at(base, 0), chunk,
                                "chunk %d (OBJT): size %zu is not a multiple of 64", (int)chunk, n);
    uint32_t prev_id = 0;
    for (size_t r = 0; r < n / MESO_OBJT_RECORD_SIZE; r++) {
        const uint8_t* p = d + r * MESO_OBJT_RECORD_SIZE;
        uint64_t ro = r * MESO_OBJT_RECORD_SIZE;
        uint32_t id = mesoi_ld32(p + MESO_OBJT_OFF_ID);
        uint32_t kind = mesoi_ld32(p + MESO_OBJT_OFF_KIND);
        if (id == 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_OBJT_ID, at(base, ro), chunk,
                                    "chunk %d (OBJT): record %zu has id 0 (reserved for file-wide chunks)", (int)chunk,
                                    r);
        if (r > 0 && id <= prev_id)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_OBJT_DUPLICATE, at(base, ro), chunk,
                                    "chunk %d (OBJT): record %zu id %u is not above the previous id %u (duplicate or "
                                    "unsorted)",
                                    (int)chunk, r, id, prev_id);
        prev_id = id;
        if (kind == MESO_OBJECT_INVALID || kind >= MESO_OBJECT_KIND_COUNT)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_OBJT_KIND, at(base, ro + MESO_OBJT_OFF_KIND),
                                    chunk, "chunk %d (OBJT): object %u has unknown kind %u", (int)chunk, id, kind);
        const uint8_t* bmin = p + MESO_OBJT_OFF_BBOX_MIN;
        const uint8_t* bmax = p + MESO_OBJT_OFF_BBOX_MAX;
        int bbox_ok = finite3(bmin) && finite3(bmax);
        for (int k = 0; k < 3 && bbox_ok; k++)
            bbox_ok = mesoi_ldf32(bmin + 4 * k) <= mesoi_ldf32(bmax + 4 * k);
        if (!bbox_ok)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_OBJT_BBOX, at(base, ro + MESO_OBJT_OFF_BBOX_MIN),
                                    chunk, "chunk %d (OBJT): object %u has a non-finite or inverted bounding box",
                                    (int)chunk, id);
        const uint8_t* name = p + MESO_OBJT_OFF_NAME;
        size_t len = 0;
        while (len < MESO_OBJT_SIZE_NAME && name[len] != 0)
            len++;
        int name_ok = len < MESO_OBJT_SIZE_NAME;
        for (size_t k = len; k < MESO_OBJT_SIZE_NAME && name_ok; k++)
            name_ok = name[k] == 0;
        if (name_ok && mesoi_utf8_invalid(name, len) != SIZE_MAX)
            name_ok = 0;
        if (!name_ok)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_OBJT_NAME, at(base, ro + MESO_OBJT_OFF_NAME),
                                    chunk, "chunk %d (OBJT): object %u name is not NUL-terminated, NUL-padded UTF-8",
                                    (int)chunk, id);
    }
    return MESO_OK;
}

meso_result mesoi_check_mesh_header(const uint8_t* h, uint64_t size, meso_mesh_layout* out, int32_t chunk,
                                    uint64_t base, meso_error* err)
{
    meso_mesh_layout l;
    memset(&l, 0, sizeof l);
    if (size < MESO_MESH_HDR_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_SIZE, at(base, 0), chunk,
                                "chunk %d (MESH): decoded size %llu is smaller than the 64-byte mesh header",
                                (int)chunk, (unsigned long long)size);
    l.vertex_count = mesoi_ld32(h + MESO_MESH_OFF_VERTEX_COUNT);
    l.index_count = mesoi_ld32(h + MESO_MESH_OFF_INDEX_COUNT);
    l.attributes = mesoi_ld32(h + MESO_MESH_OFF_ATTRIBUTES);
    l.quant_bits_position = h[MESO_MESH_OFF_QUANT_POSITION];
    l.quant_bits_normal = h[MESO_MESH_OFF_QUANT_NORMAL];
    l.quant_bits_uv = h[MESO_MESH_OFF_QUANT_UV];
    l.positions_offset = mesoi_ld64(h + MESO_MESH_OFF_POSITIONS);
    l.normals_offset = mesoi_ld64(h + MESO_MESH_OFF_NORMALS);
    l.uvs_offset = mesoi_ld64(h + MESO_MESH_OFF_UVS);
    l.indices_offset = mesoi_ld64(h + MESO_MESH_OFF_INDICES);
    l.size = size;
    int reserved_zero = h[MESO_MESH_OFF_RESERVED0] == 0;
    for (int k = 0; k < MESO_MESH_SIZE_RESERVED1; k++)
        reserved_zero = reserved_zero && h[MESO_MESH_OFF_RESERVED1 + k] == 0;
    if (!reserved_zero)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_RESERVED, at(base, MESO_MESH_OFF_RESERVED1),
                                chunk, "chunk %d (MESH): reserved header bytes are not zero", (int)chunk);
    const uint32_t known = MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS | MESO_MESH_ATTR_UVS;
    if (!(l.attributes & MESO_MESH_ATTR_POSITIONS) || (l.attributes & ~known))
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_ATTRIBUTES, at(base, MESO_MESH_OFF_ATTRIBUTES),
                                chunk,
                                "chunk %d (MESH): attributes 0x%X (positions are required, only bits 0-2 defined)",
                                (int)chunk, l.attributes);
    if (l.vertex_count == 0 || l.index_count % 3 != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_COUNTS, at(base, 0), chunk,
                                "chunk %d (MESH): vertex_count %u, index_count %u (need >= 1 vertex, whole triangles)",
                                (int)chunk, l.vertex_count, l.index_count);
    int has_n = (l.attributes & MESO_MESH_ATTR_NORMALS) != 0, has_uv = (l.attributes & MESO_MESH_ATTR_UVS) != 0;
    if (l.quant_bits_position > 30 || l.quant_bits_normal > 30 || l.quant_bits_uv > 30 ||
        (!has_n && l.quant_bits_normal) || (!has_uv && l.quant_bits_uv))
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_QUANT, at(base, MESO_MESH_OFF_QUANT_POSITION),
                                chunk,
                                "chunk %d (MESH): quantisation bits %u/%u/%u invalid (0..30, 0 for absent attributes)",
                                (int)chunk, l.quant_bits_position, l.quant_bits_normal, l.quant_bits_uv);
    struct {
        const char* name;
        uint64_t off;
        uint64_t bytes;
        int present;
        unsigned field;
    } arr[4] = {
        {"positions", l.positions_offset, (uint64_t)l.vertex_count * MESO_MESH_POSITION_STRIDE, 1,
         MESO_MESH_OFF_POSITIONS},
        {"normals", l.normals_offset, (uint64_t)l.vertex_count * MESO_MESH_NORMAL_STRIDE, has_n, MESO_MESH_OFF_NORMALS},
        {"uvs", l.uvs_offset, (uint64_t)l.vertex_count * MESO_MESH_UV_STRIDE, has_uv, MESO_MESH_OFF_UVS},
        {"indices", l.indices_offset, (uint64_t)l.index_count * MESO_MESH_INDEX_STRIDE, l.index_count > 0,
         MESO_MESH_OFF_INDICES},
    };
    uint64_t end = MESO_MESH_HDR_SIZE;
    for (int k = 0; k < 4; k++) {
        if (arr[k].present != (arr[k].off != 0))
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_PRESENCE, at(base, arr[k].field), chunk,
                                    "chunk %d (MESH): %s offset %llu but the array is %s", (int)chunk, arr[k].name,
                                    (unsigned long long)arr[k].off, arr[k].present ? "present" : "absent");
        if (!arr[k].present)
            continue;
        if (arr[k].off % MESO_MESH_ARRAY_ALIGN != 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_ALIGN, at(base, arr[k].field), chunk,
                                    "chunk %d (MESH): %s offset %llu is not 16-byte aligned", (int)chunk, arr[k].name,
                                    (unsigned long long)arr[k].off);
        if (arr[k].off < end)
            return mesoi_file_error(
                err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_OVERLAP, at(base, arr[k].field), chunk,
                "chunk %d (MESH): %s at %llu overlaps the header or the previous array (ends at %llu)", (int)chunk,
                arr[k].name, (unsigned long long)arr[k].off, (unsigned long long)end);
        if (arr[k].off > size || arr[k].bytes > size - arr[k].off)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_BOUNDS, at(base, arr[k].field), chunk,
                                    "chunk %d (MESH): %s [%llu, +%llu) exceeds the decoded size %llu", (int)chunk,
                                    arr[k].name, (unsigned long long)arr[k].off, (unsigned long long)arr[k].bytes,
                                    (unsigned long long)size);
        end = arr[k].off + arr[k].bytes;
    }
    if (end != size)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_TRAILING, at(base, end), chunk,
                                "chunk %d (MESH): the last array ends at %llu but the decoded size is %llu", (int)chunk,
                                (unsigned long long)end, (unsigned long long)size);
    if (out)
        *out = l;
    return MESO_OK;
}

static meso_result check_mesh(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    meso_mesh_layout l;
    meso_result r = mesoi_check_mesh_header(d, n, &l, chunk, base, err);
    if (r != MESO_OK)
        return r;
    for (uint32_t i = 0; i < l.index_count; i++) {
        uint64_t o = l.indices_offset + (uint64_t)i * 4u;
        uint32_t v = mesoi_ld32(d + o);
        if (v >= l.vertex_count)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_INDEX, at(base, o), chunk,
                                    "chunk %d (MESH): index %u is %u, vertex_count is %u", (int)chunk, i, v,
                                    l.vertex_count);
    }
    /* Every vertex value finite (4312): a NaN position or normal would be
     * drawn as garbage or poison a ray caster's bounds. */
    const struct {
        const char* name;
        uint64_t off;
        uint32_t stride;
    } attr[3] = {{"position", l.positions_offset, MESO_MESH_POSITION_STRIDE},
                 {"normal", l.normals_offset, MESO_MESH_NORMAL_STRIDE},
                 {"uv", l.uvs_offset, MESO_MESH_UV_STRIDE}};
    for (int a = 0; a < 3; a++) {
        if (attr[a].off == 0)
            continue;
        const uint64_t floats = (uint64_t)l.vertex_count * (attr[a].stride / 4u);
        for (uint64_t k = 0; k < floats; k++) {
            uint64_t o = attr[a].off + 4u * k;
            if (!isfinite(mesoi_ldf32(d + o)))
                return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_VALUE, at(base, o), chunk,
                                        "chunk %d (MESH): vertex %llu has a non-finite %s", (int)chunk,
                                        (unsigned long long)(k / (attr[a].stride / 4u)), attr[a].name);
        }
    }
    return MESO_OK;
}

static meso_result check_skel(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n % MESO_SKEL_RECORD_SIZE != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_SKEL_SIZE, at(base, 0), chunk,
                                "chunk %d (SKEL): size %zu is not a multiple of 32", (int)chunk, n);
    for (size_t i = 0; i < n / MESO_SKEL_RECORD_SIZE; i++) {
        const uint8_t* p = d + i * MESO_SKEL_RECORD_SIZE;
        uint64_t ro = i * MESO_SKEL_RECORD_SIZE;
        int32_t parent = (int32_t)mesoi_ld32(p + MESO_SKEL_OFF_PARENT);
        if (parent < -1 || (parent >= 0 && (size_t)parent >= i))
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_SKEL_PARENT, at(base, ro + MESO_SKEL_OFF_PARENT),
                                    chunk, "chunk %d (SKEL): node %zu has parent %d (must be -1 or an earlier node)",
                                    (int)chunk, i, (int)parent);
        float r = mesoi_ldf32(p + MESO_SKEL_OFF_RADIUS);
        if (!finite3(p) || !isfinite(r) || r < 0.0f || mesoi_ld32(p + MESO_SKEL_OFF_NODE_TYPE) > 3 ||
            mesoi_ld64(p + MESO_SKEL_OFF_RESERVED) != 0)
            return mesoi_file_error(
                err, MESO_ERR_CORRUPT, MESO_ISSUE_SKEL_VALUE, at(base, ro), chunk,
                "chunk %d (SKEL): node %zu has a non-finite value, negative radius, unknown type or "
                "non-zero reserved field",
                (int)chunk, i);
    }
    return MESO_OK;
}

static meso_result check_frus(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n % MESO_FRUS_RECORD_SIZE != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_FRUS_SIZE, at(base, 0), chunk,
                                "chunk %d (FRUS): size %zu is not a multiple of 64", (int)chunk, n);
    for (size_t i = 0; i < n / MESO_FRUS_RECORD_SIZE; i++) {
        const uint8_t* p = d + i * MESO_FRUS_RECORD_SIZE;
        float r0 = mesoi_ldf32(p + MESO_FRUS_OFF_RADIUS0), r1 = mesoi_ldf32(p + MESO_FRUS_OFF_RADIUS1);
        if (!finite3(p + MESO_FRUS_OFF_CENTER0) || !finite3(p + MESO_FRUS_OFF_CENTER1) ||
            !finite3(p + MESO_FRUS_OFF_PLANE0) || !finite3(p + MESO_FRUS_OFF_PLANE1) || !isfinite(r0) ||
            !isfinite(r1) || r0 < 0.0f || r1 < 0.0f || mesoi_ld32(p + MESO_FRUS_OFF_RESERVED) != 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_FRUS_VALUE, at(base, i * MESO_FRUS_RECORD_SIZE),
                                    chunk,
                                    "chunk %d (FRUS): frustum %zu has a non-finite value, negative radius or non-zero "
                                    "reserved field",
                                    (int)chunk, i);
    }
    return MESO_OK;
}

static int finite_f32s(const uint8_t* p, int count)
{
    for (int i = 0; i < count; i++)
        if (!isfinite(mesoi_ldf32(p + 4 * i)))
            return 0;
    return 1;
}

static int zero_bytes(const uint8_t* p, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (p[i])
            return 0;
    return 1;
}

static meso_result check_fseg(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n % MESO_FSEG_RECORD_SIZE != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_FSEG_SIZE, at(base, 0), chunk,
                                "chunk %d (FSEG): size %zu is not a multiple of 80", (int)chunk, n);
    size_t count = n / MESO_FSEG_RECORD_SIZE;
    for (size_t i = 0; i < count; i++) {
        const uint8_t* p = d + i * MESO_FSEG_RECORD_SIZE;
        uint32_t flags = mesoi_ld32(p + MESO_FSEG_OFF_FLAGS);
        uint32_t k0 = (flags >> MESO_FSEG_KIND0_SHIFT) & 3u, k1 = (flags >> MESO_FSEG_KIND1_SHIFT) & 3u;
        int32_t align = (int32_t)mesoi_ld32(p + MESO_FSEG_OFF_ALIGN_FROM);
        int32_t other[2] = {(int32_t)mesoi_ld32(p + MESO_FSEG_OFF_OTHER0), (int32_t)mesoi_ld32(p + MESO_FSEG_OFF_OTHER1)};
        const char* why = NULL;
        if ((flags & ~MESO_FSEG_FLAGS_KNOWN) || k0 > MESO_FSEG_END_BALL || k1 > MESO_FSEG_END_BALL)
            why = "unknown flag bits or end kind";
        else if (align < -1 || (align >= 0 && (size_t)align >= i))
            why = "align_from is not -1 or an earlier frustum";
        else if ((k0 == MESO_FSEG_END_JOINT) != (other[0] >= 0) || (k1 == MESO_FSEG_END_JOINT) != (other[1] >= 0) ||
                 other[0] < -1 || other[1] < -1 || (other[0] >= 0 && (size_t)other[0] >= count) ||
                 (other[1] >= 0 && (size_t)other[1] >= count) || (size_t)other[0] == i || (size_t)other[1] == i)
            why = "a joint end without a valid other frustum (or a neighbour at a non-joint end)";
        else if (!finite_f32s(p + MESO_FSEG_OFF_NODE_RADIUS0, 2) || !finite_f32s(p + MESO_FSEG_OFF_FRAME_X, 9) ||
                 mesoi_ldf32(p + MESO_FSEG_OFF_NODE_RADIUS0) < 0.0f ||
                 mesoi_ldf32(p + MESO_FSEG_OFF_NODE_RADIUS1) < 0.0f ||
                 mesoi_ldf32(p + MESO_FSEG_OFF_RELIEF_DEPTH) < 0.0f)
            why = "a non-finite value, or a negative radius or relief depth";
        else if (!zero_bytes(p + MESO_FSEG_OFF_RESERVED, MESO_FSEG_SIZE_RESERVED))
            why = "non-zero reserved bytes";
        if (why)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_FSEG_VALUE, at(base, i * MESO_FSEG_RECORD_SIZE),
                                    chunk, "chunk %d (FSEG): frustum %zu: %s", (int)chunk, i, why);
    }
    return MESO_OK;
}

static meso_result check_ball(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n % MESO_BALL_RECORD_SIZE != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_BALL_SIZE, at(base, 0), chunk,
                                "chunk %d (BALL): size %zu is not a multiple of 32", (int)chunk, n);
    for (size_t i = 0; i < n / MESO_BALL_RECORD_SIZE; i++) {
        const uint8_t* p = d + i * MESO_BALL_RECORD_SIZE;
        if (!finite_f32s(p, 4) || mesoi_ldf32(p + MESO_BALL_OFF_RADIUS) < 0.0f ||
            !zero_bytes(p + MESO_BALL_OFF_RESERVED, MESO_BALL_SIZE_RESERVED))
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_BALL_VALUE, at(base, i * MESO_BALL_RECORD_SIZE),
                                    chunk,
                                    "chunk %d (BALL): ball %zu has a non-finite value, negative radius or non-zero "
                                    "reserved bytes",
                                    (int)chunk, i);
    }
    return MESO_OK;
}

/* CELL (FORMAT.md §7.8): one record; ranges that keep every size derived
 * from it (R^3, T, MEMB words) far from overflow. */
static meso_result check_cell(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n != MESO_CELL_RECORD_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_SIZE, at(base, 0), chunk,
                                "chunk %d (CELL): size %zu, must be one 64-byte record", (int)chunk, n);
    const char* why = NULL;
    uint64_t tiles = 1;
    for (int a = 0; a < 3; a++) {
        uint32_t t = mesoi_ld32(d + MESO_CELL_OFF_TILES + 4 * a);
        if (t < 1 || t > MESO_CELL_MAX_TILES)
            why = "a tile count outside 1..16384";
        tiles *= t;
    }
    uint32_t res = mesoi_ld32(d + MESO_CELL_OFF_TILE_RES), splits = mesoi_ld32(d + MESO_CELL_OFF_SPLIT_COUNT);
    uint32_t cells = mesoi_ld32(d + MESO_CELL_OFF_CELL_COUNT);
    float h = mesoi_ldf32(d + MESO_CELL_OFF_VOXEL_SIZE);
    if (why) {
    } else if (res < 1 || res > MESO_CELL_MAX_TILE_RES)
        why = "tile_res outside 1..1024";
    else if (splits < 1 || cells < 1 || cells > splits)
        why = "split_count 0, or cell_count outside 1..split_count";
    else if (!finite_f32s(d + MESO_CELL_OFF_ORIGIN, 4) || !(h > 0.0f))
        why = "origin not finite or voxel_size not > 0";
    else if (mesoi_ld64(d + MESO_CELL_OFF_MIXED_TILES) > tiles)
        why = "more MIXED tiles than tiles";
    else if (!zero_bytes(d + MESO_CELL_OFF_RESERVED, MESO_CELL_SIZE_RESERVED))
        why = "reserved bytes not zero";
    if (why)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_VALUE, at(base, 0), chunk,
                                "chunk %d (CELL): %s", (int)chunk, why);
    return MESO_OK;
}

meso_result mesoi_check_contents(const meso_chunk_info* c, const uint8_t* data, size_t size, int32_t chunk,
                                 uint64_t base, meso_error* err)
{
    switch (c->type) {
    case MESO_CHUNK_META: return check_json(data, size, chunk, "META", base, err);
    case MESO_CHUNK_RPRT: return check_json(data, size, chunk, "RPRT", base, err);
    case MESO_CHUNK_OBJT: return check_objt(data, size, chunk, base, err);
    case MESO_CHUNK_MESH:
    case MESO_CHUNK_PMSH: return check_mesh(data, size, chunk, base, err);
    case MESO_CHUNK_PRTS: return mesoi_check_prts(data, size, chunk, base, err);
    case MESO_CHUNK_SKEL: return check_skel(data, size, chunk, base, err);
    case MESO_CHUNK_FRUS: return check_frus(data, size, chunk, base, err);
    case MESO_CHUNK_FSEG: return check_fseg(data, size, chunk, base, err);
    case MESO_CHUNK_BALL: return check_ball(data, size, chunk, base, err);
    case MESO_CHUNK_CELL: return check_cell(data, size, chunk, base, err);
    case MESO_CHUNK_ANIM: return mesoi_check_anim(data, size, chunk, base, err);
    case MESO_CHUNK_CMAP: return mesoi_check_cmap(data, size, chunk, base, err);
    case MESO_CHUNK_LODS: return mesoi_check_lods(data, size, chunk, base, err);
    default: return MESO_OK;
    }
}

/* >>mesh & object helpers ------------------------------------------------- */

static uint64_t align16(uint64_t v) { return (v + 15u) & ~(uint64_t)15u; }

meso_result meso_mesh_compute_layout(uint32_t vertex_count, uint32_t index_count, uint32_t attributes,
                                     meso_mesh_layout* out)
{
    const uint32_t known = MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS | MESO_MESH_ATTR_UVS;
    if (out == NULL || vertex_count == 0 || index_count % 3 != 0 || !(attributes & MESO_MESH_ATTR_POSITIONS) ||
        (attributes & ~known))
        return MESO_ERR_INVALID_ARG;
    meso_mesh_layout l;
    memset(&l, 0, sizeof l);
    l.vertex_count = vertex_count;
    l.index_count = index_count;
    l.attributes = attributes;
    /* u32 counts times strides <= 16 cannot overflow u64. */
    uint64_t end = MESO_MESH_HDR_SIZE;
    l.positions_offset = end;
    end += (uint64_t)vertex_count * MESO_MESH_POSITION_STRIDE;
    if (attributes & MESO_MESH_ATTR_NORMALS) {
        l.normals_offset = align16(end);
        end = l.normals_offset + (uint64_t)vertex_count * MESO_MESH_NORMAL_STRIDE;
    }
    if (attributes & MESO_MESH_ATTR_UVS) {
        l.uvs_offset = align16(end);
        end = l.uvs_offset + (uint64_t)vertex_count * MESO_MESH_UV_STRIDE;
    }
    if (index_count > 0) {
        l.indices_offset = align16(end);
        end = l.indices_offset + (uint64_t)index_count * MESO_MESH_INDEX_STRIDE;
    }
    l.size = end;
    if (end > SIZE_MAX)
        return MESO_ERR_INVALID_ARG;
    *out = l;
    return MESO_OK;
}

void meso_mesh_write_header(const meso_mesh_layout* l, void* dst)
{
    uint8_t* h = (uint8_t*)dst;
    memset(h, 0, MESO_MESH_HDR_SIZE);
    mesoi_st32(h + MESO_MESH_OFF_VERTEX_COUNT, l->vertex_count);
    mesoi_st32(h + MESO_MESH_OFF_INDEX_COUNT, l->index_count);
    mesoi_st32(h + MESO_MESH_OFF_ATTRIBUTES, l->attributes);
    h[MESO_MESH_OFF_QUANT_POSITION] = l->quant_bits_position;
    h[MESO_MESH_OFF_QUANT_NORMAL] = l->quant_bits_normal;
    h[MESO_MESH_OFF_QUANT_UV] = l->quant_bits_uv;
    mesoi_st64(h + MESO_MESH_OFF_POSITIONS, l->positions_offset);
    mesoi_st64(h + MESO_MESH_OFF_NORMALS, l->normals_offset);
    mesoi_st64(h + MESO_MESH_OFF_UVS, l->uvs_offset);
    mesoi_st64(h + MESO_MESH_OFF_INDICES, l->indices_offset);
}

meso_result meso_mesh_parse(const void* data, size_t size, meso_mesh_view* out, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (data == NULL || out == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_mesh_parse: NULL argument");
    if (((uintptr_t)data & 3u) != 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_mesh_parse: data must be 4-byte aligned");
    const uint8_t* d = (const uint8_t*)data;
    static const meso_chunk_info mesh_info = {MESO_CHUNK_MESH, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, {1, 1, 1}};
    meso_result r = mesoi_check_contents(&mesh_info, d, size, -1, UINT64_MAX, err);
    if (r != MESO_OK)
        return r;
    memset(out, 0, sizeof *out);
    mesoi_check_mesh_header(d, size, &out->layout, -1, UINT64_MAX, NULL);
    /* Offsets are 16-aligned relative to a 4-aligned base: casts are aligned. */
    out->positions = (const float*)(const void*)(d + out->layout.positions_offset);
    out->normals = out->layout.normals_offset ? (const float*)(const void*)(d + out->layout.normals_offset) : NULL;
    out->uvs = out->layout.uvs_offset ? (const float*)(const void*)(d + out->layout.uvs_offset) : NULL;
    out->indices = out->layout.indices_offset ? (const uint32_t*)(const void*)(d + out->layout.indices_offset) : NULL;
    return MESO_OK;
}

void meso_object_record_encode(const meso_object_record* rec, void* dst)
{
    uint8_t* p = (uint8_t*)dst;
    memset(p, 0, MESO_OBJT_RECORD_SIZE);
    mesoi_st32(p + MESO_OBJT_OFF_ID, rec->id);
    mesoi_st32(p + MESO_OBJT_OFF_KIND, rec->kind);
    for (int k = 0; k < 3; k++) {
        mesoi_stf32(p + MESO_OBJT_OFF_BBOX_MIN + 4 * k, rec->bbox_min[k]);
        mesoi_stf32(p + MESO_OBJT_OFF_BBOX_MAX + 4 * k, rec->bbox_max[k]);
    }
    for (int k = 0; k < MESO_OBJT_SIZE_NAME - 1 && rec->name[k] != 0; k++)
        p[MESO_OBJT_OFF_NAME + k] = (uint8_t)rec->name[k];
}

void meso_object_record_decode(const void* src, meso_object_record* rec)
{
    const uint8_t* p = (const uint8_t*)src;
    rec->id = mesoi_ld32(p + MESO_OBJT_OFF_ID);
    rec->kind = mesoi_ld32(p + MESO_OBJT_OFF_KIND);
    for (int k = 0; k < 3; k++) {
        rec->bbox_min[k] = mesoi_ldf32(p + MESO_OBJT_OFF_BBOX_MIN + 4 * k);
        rec->bbox_max[k] = mesoi_ldf32(p + MESO_OBJT_OFF_BBOX_MAX + 4 * k);
    }
    memcpy(rec->name, p + MESO_OBJT_OFF_NAME, MESO_OBJT_SIZE_NAME);
    rec->name[MESO_OBJT_SIZE_NAME - 1] = 0;
}

/* >>full validation ------------------------------------------------------- */

typedef struct validate_state {
    meso_issue_fn fn;
    void* user;
    meso_result first;
    int stop;
} validate_state;

/* Record an issue; returns non-zero when the caller asked to stop. */
static int report(validate_state* s, const meso_error* e)
{
    if (s->first == MESO_OK)
        s->first = e->result;
    if (s->fn && s->fn(s->user, e))
        s->stop = 1;
    return s->stop;
}

/* All bytes of [from, to) must be zero. */
static void check_zero(meso_file* f, uint64_t from, uint64_t to, int32_t chunk, uint8_t* buf, size_t buf_size,
                       validate_state* s)
{
    meso_error e;
    while (from < to && !s->stop) {
        size_t n = (size_t)(to - from < buf_size ? to - from : buf_size);
        const uint8_t* p;
        if (f->data) {
            p = f->data + from;
        } else {
            if (mesoi_read_at(f, from, buf, n, &e) != MESO_OK) {
                report(s, &e);
                return;
            }
            p = buf;
        }
        for (size_t i = 0; i < n; i++) {
            if (p[i] != 0) {
                mesoi_file_error(&e, MESO_ERR_CORRUPT, MESO_ISSUE_PAYLOAD_PADDING, from + i, chunk,
                                 "non-zero padding byte 0x%02X at offset %llu", p[i], (unsigned long long)(from + i));
                report(s, &e);
                return;
            }
        }
        from += n;
    }
}

static void validate_chunk(meso_file* f, uint32_t i, uint8_t* buf, size_t buf_size, validate_state* s)
{
    const meso_chunk_info* c = &f->chunks[i];
    int32_t ci = (int32_t)i;
    char cc[5];
    meso_error e;
    mesoi_fourcc_str(c->type, cc);
    int rules_ok = mesoi_check_type_rules(c, ci, &e) == MESO_OK;
    if (!rules_ok && report(s, &e))
        return;
    int known = mesoi_known_type(c->type);
    int structured = known && (c->type == MESO_CHUNK_META || c->type == MESO_CHUNK_RPRT || c->type == MESO_CHUNK_OBJT ||
                               c->type == MESO_CHUNK_MESH || c->type == MESO_CHUNK_SKEL || c->type == MESO_CHUNK_FRUS ||
                               c->type == MESO_CHUNK_FSEG || c->type == MESO_CHUNK_BALL ||
                               c->type == MESO_CHUNK_CELL || c->type == MESO_CHUNK_ANIM ||
                               c->type == MESO_CHUNK_CMAP || c->type == MESO_CHUNK_LODS ||
                               c->type == MESO_CHUNK_PMSH || c->type == MESO_CHUNK_PRTS);
    const uint8_t* whole = NULL;
    uint8_t* owned = NULL;
    if (f->data) {
        whole = f->data + c->offset;
    } else if (structured || c->encoding != MESO_ENCODING_RAW) {
        if (c->stored_size > SIZE_MAX) {
            mesoi_file_error(&e, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_TOO_LARGE, c->offset, ci,
                             "chunk %u (%s): %llu bytes do not fit in memory on this platform", i, cc,
                             (unsigned long long)c->stored_size);
            report(s, &e);
            return;
        }
        owned = (uint8_t*)mesoi_file_alloc(&f->alloc, (size_t)c->stored_size);
        if (!owned) {
            mesoi_file_error(&e, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, c->offset, ci,
                             "chunk %u (%s): out of memory for %llu bytes", i, cc, (unsigned long long)c->stored_size);
            report(s, &e);
            return;
        }
    }
    /* One pass over the stored bytes: each block is checksummed right after
     * it is read (into `owned`, or streamed through `buf` when the contents
     * are not needed). */
    uint32_t crc = 0;
    if (f->data) {
        crc = meso_crc32c(0, whole, (size_t)c->stored_size);
    } else if (owned) {
        if (mesoi_read_crc(f, c->offset, owned, (size_t)c->stored_size, &crc, &e) != MESO_OK) {
            report(s, &e);
            mesoi_file_free(&f->alloc, owned);
            return;
        }
        whole = owned;
    } else {
        for (uint64_t o = 0; o < c->stored_size;) {
            size_t n = (size_t)(c->stored_size - o < buf_size ? c->stored_size - o : buf_size);
            if (mesoi_read_crc(f, c->offset + o, buf, n, &crc, &e) != MESO_OK) {
                report(s, &e);
                return;
            }
            o += n;
        }
    }
    if (crc != c->crc32c) {
        mesoi_file_error(&e, MESO_ERR_CORRUPT, MESO_ISSUE_PAYLOAD_CRC, c->offset, ci,
                         "chunk %u (%s, object %u): payload CRC32C 0x%08X != 0x%08X in the TOC", i, cc, c->object, crc,
                         c->crc32c);
        report(s, &e);
    } else if (known && c->encoding == MESO_ENCODING_RAW) {
        if (mesoi_check_contents(c, whole, (size_t)c->stored_size, ci, c->offset, &e) != MESO_OK)
            report(s, &e);
    } else if (mesoi_mesh_layout(c->type) && c->encoding == MESO_ENCODING_DRACO) {
        meso_result r = c->stored_size < MESO_MESH_HDR_SIZE
                            ? mesoi_file_error(&e, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_SIZE, c->offset, ci,
                                               "chunk %u (%s): Draco payload smaller than the 64-byte mesh header", i,
                                               cc)
                            : mesoi_check_mesh_header(whole, c->decoded_size, NULL, ci, c->offset, &e);
        if (r != MESO_OK) {
            report(s, &e);
        } else if (rules_ok && mesoi_find_decoder(f, c->encoding) && c->decoded_size <= SIZE_MAX) {
            /* With a decoder, check the decoded mesh too (read_chunk does
             * the decode, CRC and content checks). Open bounded
             * decoded_size (max_decoded_size, expansion rule). */
            uint8_t* dec = (uint8_t*)mesoi_file_alloc(&f->alloc, (size_t)c->decoded_size);
            if (!dec) {
                mesoi_file_error(&e, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, c->offset, ci,
                                 "chunk %u (MESH): out of memory for %llu decoded bytes", i,
                                 (unsigned long long)c->decoded_size);
                report(s, &e);
            } else {
                if (meso_file_read_chunk(f, i, dec, (size_t)c->decoded_size, &e) != MESO_OK)
                    report(s, &e);
                mesoi_file_free(&f->alloc, dec);
            }
        }
    }
    mesoi_file_free(&f->alloc, owned);
}

/* Objects against their kinds (file_validate_objects.c). Only the object
 * issues (6xxx) are new here: a chunk an object check reads again reports
 * the issue of its own check, already listed. */
static int object_issue(void* user, const meso_error* e)
{
    validate_state* s = (validate_state*)user;
    if ((e->code < MESO_ISSUE_OBJ_CHUNKS || e->code >= 7000u) && e->result != MESO_ERR_OUT_OF_MEMORY)
        return 0;
    return report(s, e);
}

static void validate_objects(meso_file* f, validate_state* s)
{
    uint32_t count = 0;
    meso_error e;
    if (meso_file_objects(f, NULL, 0, &count, &e) != MESO_OK || count == 0) {
        if (count == 0 && e.result == MESO_ERR_OUT_OF_MEMORY)
            report(s, &e); /* other failures: a bad OBJT, reported with its chunk */
        return;
    }
    meso_object_record* recs = (meso_object_record*)mesoi_file_alloc(&f->alloc, (size_t)count * sizeof *recs);
    if (!recs) {
        mesoi_file_error(&e, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1,
                         "out of memory for %u object records", count);
        report(s, &e);
        return;
    }
    if (meso_file_objects(f, recs, count, &count, &e) != MESO_OK)
        object_issue(s, &e);
    else
    {
        for (uint32_t i = 0; i < count && !s->stop; i++)
            mesoi_check_object(f, &recs[i], object_issue, s);
        if (!s->stop)
            mesoi_check_levels(f, recs, count, object_issue, s);
        if (!s->stop)
            mesoi_check_parts(f, recs, count, object_issue, s);
    }
    mesoi_file_free(&f->alloc, recs);
}

meso_result meso_file_validate(meso_file* f, meso_check level, meso_issue_fn fn, void* user)
{
    if (f == NULL || (unsigned)level >= MESO_CHECK_COUNT)
        return MESO_ERR_INVALID_ARG;
    if (level == MESO_CHECK_CHEAP)
        return MESO_OK; /* open refuses any file that fails the cheap tier */
    validate_state s = {fn, user, MESO_OK, 0};
    size_t buf_size = MESOI_READ_BLOCK;
    uint8_t* buf = NULL;
    if (f->data == NULL) {
        buf = (uint8_t*)mesoi_file_alloc(&f->alloc, buf_size);
        if (!buf) {
            meso_error e;
            mesoi_file_error(&e, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1,
                             "out of memory for the validation buffer");
            report(&s, &e);
            return s.first;
        }
    }
    uint64_t end = (uint64_t)MESO_HDR_SIZE + (uint64_t)f->chunk_count * f->toc_entry_size;
    for (uint32_t i = 0; i < f->chunk_count && !s.stop; i++) {
        const meso_chunk_info* c = &f->chunks[i];
        check_zero(f, end, c->offset, (int32_t)i - 1, buf, buf_size, &s);
        if (s.stop)
            break;
        validate_chunk(f, i, buf, buf_size, &s);
        end = c->offset + c->stored_size;
    }
    if (!s.stop)
        check_zero(f, end, f->file_size, f->chunk_count ? (int32_t)f->chunk_count - 1 : -1, buf, buf_size, &s);
    /* Cells objects: their chunks against their CELL record, at every lod
     * that has one (a native coarser level's own chunks). Only the
     * cross-chunk issues (4803..4806) are new here: CRC, type-rule and
     * content issues of the chunks read were reported above. */
    for (uint32_t i = 0; i < f->chunk_count && !s.stop; i++) {
        meso_error e;
        const meso_chunk_info* c = &f->chunks[i];
        if (c->type == MESO_CHUNK_CELL && meso_file_find(f, MESO_CHUNK_CELL, c->object, c->lod) == (int32_t)i &&
            mesoi_check_type_rules(c, (int32_t)i, &e) == MESO_OK &&
            meso_file_check_cells_level(f, c->object, c->lod, &e) != MESO_OK &&
            e.code >= MESO_ISSUE_CELL_CHUNKS && e.code <= MESO_ISSUE_CELL_MEMB)
            report(&s, &e);
    }
    if (!s.stop)
        validate_objects(f, &s);
    mesoi_file_free(&f->alloc, buf);
    return s.first;
}
