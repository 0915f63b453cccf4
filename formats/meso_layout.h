/*
 * meso_layout.h — byte offsets and sizes of every on-disk structure of the
 * .meso container (format 1.0). FORMAT.md is the normative description.
 *
 * #define-only on purpose: this file is prepended to GLSL sources, so it must
 * not contain typedefs, includes or C-only syntax. All values little-endian.
 * Naming: MESO_<STRUCT>_OFF_<FIELD> is a byte offset inside the structure,
 * MESO_<STRUCT>_SIZE_<FIELD> is a field's size in bytes.
 */
#ifndef MESO_LAYOUT_H
#define MESO_LAYOUT_H

/* Alignment of every payload and of the file size. */
#define MESO_ALIGN 64

/* File header: 64 bytes at offset 0. */
#define MESO_HDR_SIZE 64
#define MESO_HDR_OFF_MAGIC 0
#define MESO_HDR_SIZE_MAGIC 8
#define MESO_HDR_OFF_MAJOR 8
#define MESO_HDR_OFF_MINOR 10
#define MESO_HDR_OFF_FLAGS 12
#define MESO_HDR_OFF_FILE_SIZE 16
#define MESO_HDR_OFF_TOC_OFFSET 24
#define MESO_HDR_OFF_CHUNK_COUNT 32
#define MESO_HDR_OFF_TOC_ENTRY_SIZE 36
#define MESO_HDR_OFF_TOC_CRC 40
#define MESO_HDR_OFF_HEADER_CRC 44
#define MESO_HDR_OFF_RESERVED 48
#define MESO_HDR_SIZE_RESERVED 16

/* Table of contents entry: 64 bytes in format 1.0 (larger in newer minors;
 * the first 64 bytes keep this layout). */
#define MESO_TOC_ENTRY_SIZE 64
#define MESO_TOC_OFF_TYPE 0
#define MESO_TOC_OFF_FLAGS 4
#define MESO_TOC_OFF_OBJECT 8
#define MESO_TOC_OFF_LOD 12
#define MESO_TOC_OFF_ENCODING 14
#define MESO_TOC_OFF_OFFSET 16
#define MESO_TOC_OFF_STORED_SIZE 24
#define MESO_TOC_OFF_DECODED_SIZE 32
#define MESO_TOC_OFF_CRC 40
#define MESO_TOC_OFF_DTYPE 44
#define MESO_TOC_OFF_COMPONENTS 46
#define MESO_TOC_OFF_DIMS 48
#define MESO_TOC_SIZE_DIMS 12
#define MESO_TOC_OFF_RESERVED 60

/* MESH chunk (decoded layout): a 64-byte header, then the arrays. Offsets
 * of the arrays are relative to the start of the chunk. */
#define MESO_MESH_HDR_SIZE 64
#define MESO_MESH_OFF_VERTEX_COUNT 0
#define MESO_MESH_OFF_INDEX_COUNT 4
#define MESO_MESH_OFF_ATTRIBUTES 8
#define MESO_MESH_OFF_QUANT_POSITION 12
#define MESO_MESH_OFF_QUANT_NORMAL 13
#define MESO_MESH_OFF_QUANT_UV 14
#define MESO_MESH_OFF_RESERVED0 15
#define MESO_MESH_OFF_POSITIONS 16
#define MESO_MESH_OFF_NORMALS 24
#define MESO_MESH_OFF_UVS 32
#define MESO_MESH_OFF_INDICES 40
#define MESO_MESH_OFF_RESERVED1 48
#define MESO_MESH_SIZE_RESERVED1 16
#define MESO_MESH_ARRAY_ALIGN 16
#define MESO_MESH_POSITION_STRIDE 12
#define MESO_MESH_NORMAL_STRIDE 12
#define MESO_MESH_UV_STRIDE 8
#define MESO_MESH_INDEX_STRIDE 4

/* OBJT chunk: one 64-byte record per object. */
#define MESO_OBJT_RECORD_SIZE 64
#define MESO_OBJT_OFF_ID 0
#define MESO_OBJT_OFF_KIND 4
#define MESO_OBJT_OFF_BBOX_MIN 8
#define MESO_OBJT_OFF_BBOX_MAX 20
#define MESO_OBJT_OFF_NAME 32
#define MESO_OBJT_SIZE_NAME 32

/* ANIM chunk: one 32-byte record (FORMAT.md §7.2 "Animated texture functions"). */
#define MESO_ANIM_RECORD_SIZE 32
#define MESO_ANIM_OFF_FRAME_COUNT 0
#define MESO_ANIM_OFF_FLAGS 4
#define MESO_ANIM_OFF_FPS 8
#define MESO_ANIM_OFF_TIME0 12
#define MESO_ANIM_OFF_RESERVED 16
#define MESO_ANIM_SIZE_RESERVED 16

/* CMAP chunk: one 32-byte record (FORMAT.md §7.2 "Shell colour"). */
#define MESO_CMAP_RECORD_SIZE 32
#define MESO_CMAP_OFF_MAPPING 0
#define MESO_CMAP_OFF_FLAGS 4
#define MESO_CMAP_OFF_SCALE 8
#define MESO_CMAP_OFF_RESERVED 16
#define MESO_CMAP_SIZE_RESERVED 16

/* LODS chunk: one 48-byte record per level of an object (FORMAT.md §7.10). */
#define MESO_LODS_RECORD_SIZE 48
#define MESO_LODS_OFF_OBJECT 0
#define MESO_LODS_OFF_LOD 4
#define MESO_LODS_OFF_FORM 6
#define MESO_LODS_OFF_ERROR 8
#define MESO_LODS_OFF_RESERVED0 12
#define MESO_LODS_OFF_BBOX_MIN 16
#define MESO_LODS_OFF_BBOX_MAX 28
#define MESO_LODS_OFF_RESERVED1 40
#define MESO_LODS_SIZE_RESERVED1 8

/* PRTS chunk (FORMAT.md §7.11): a 16-byte header, then LODS-layout records
 * (48 bytes; `object` holds the part number), then neighbour pairs. */
#define MESO_PRTS_HDR_SIZE 16
#define MESO_PRTS_OFF_PARTS 0
#define MESO_PRTS_OFF_RECORDS 4
#define MESO_PRTS_OFF_EDGES 8
#define MESO_PRTS_OFF_RESERVED 12
#define MESO_PRTS_EDGE_SIZE 8
/* A shell part's lod-0 record: its prisms, a range of the PTRI chunk's
 * triangle list, in the LODS layout's reserved bytes 40..47. */
#define MESO_PRTS_OFF_FIRST_TRIANGLE 40
#define MESO_PRTS_OFF_TRIANGLE_COUNT 44

/* SKEL chunk: one 32-byte record per skeleton node. */
#define MESO_SKEL_RECORD_SIZE 32
#define MESO_SKEL_OFF_POSITION 0
#define MESO_SKEL_OFF_RADIUS 12
#define MESO_SKEL_OFF_PARENT 16
#define MESO_SKEL_OFF_NODE_TYPE 20
#define MESO_SKEL_OFF_RESERVED 24
#define MESO_SKEL_SIZE_RESERVED 8

/* FRUS chunk: one 64-byte record per conical frustum. */
#define MESO_FRUS_RECORD_SIZE 64
#define MESO_FRUS_OFF_CENTER0 0
#define MESO_FRUS_OFF_RADIUS0 12
#define MESO_FRUS_OFF_CENTER1 16
#define MESO_FRUS_OFF_RADIUS1 28
#define MESO_FRUS_OFF_PLANE0 32
#define MESO_FRUS_OFF_PLANE1 44
#define MESO_FRUS_OFF_SKEL_NODE 56
#define MESO_FRUS_OFF_RESERVED 60

/* FSEG chunk: one 80-byte record per frustum (same order as FRUS): its
 * skeleton nodes, joint neighbours, end kinds and §2.3 parametrisation. */
#define MESO_FSEG_RECORD_SIZE 80
#define MESO_FSEG_OFF_NODE0 0
#define MESO_FSEG_OFF_NODE1 4
#define MESO_FSEG_OFF_NODE_RADIUS0 8
#define MESO_FSEG_OFF_NODE_RADIUS1 12
#define MESO_FSEG_OFF_OTHER0 16
#define MESO_FSEG_OFF_OTHER1 20
#define MESO_FSEG_OFF_FLAGS 24
#define MESO_FSEG_OFF_ALIGN_FROM 28
#define MESO_FSEG_OFF_FRAME_X 32
#define MESO_FSEG_OFF_U_OFFSET 44
#define MESO_FSEG_OFF_TWIST 48
#define MESO_FSEG_OFF_U_SCALE 52
#define MESO_FSEG_OFF_V_OFFSET 56
#define MESO_FSEG_OFF_V_SCALE 60
#define MESO_FSEG_OFF_RELIEF_DEPTH 64
#define MESO_FSEG_OFF_RESERVED 68
#define MESO_FSEG_SIZE_RESERVED 12
/* FSEG flags: end kinds (2 bits each), caps, which ends the u frame is
 * carried across (bits 6, 7). */
#define MESO_FSEG_END_TIP 0u
#define MESO_FSEG_END_JOINT 1u
#define MESO_FSEG_END_BALL 2u
#define MESO_FSEG_KIND0_SHIFT 0
#define MESO_FSEG_KIND1_SHIFT 2
#define MESO_FSEG_CAP0 (1u << 4)
#define MESO_FSEG_CAP1 (1u << 5)
#define MESO_FSEG_ALIGN_END (1u << 6)      /* end of this segment at the shared node (0: c0, 1: c1) */
#define MESO_FSEG_ALIGN_FROM_END (1u << 7) /* end of the align_from segment at the shared node */
#define MESO_FSEG_FLAGS_KNOWN 0xFFu

/* BALL chunk: one 32-byte record per ball closing a branch point or ball joint. */
#define MESO_BALL_RECORD_SIZE 32
#define MESO_BALL_OFF_CENTER 0
#define MESO_BALL_OFF_RADIUS 12
#define MESO_BALL_OFF_NODE 16
#define MESO_BALL_OFF_RESERVED 20
#define MESO_BALL_SIZE_RESERVED 12

/* CELL chunk: one 64-byte record, the grid of a cells object (FORMAT.md §7.8). */
#define MESO_CELL_RECORD_SIZE 64
#define MESO_CELL_OFF_TILES 0          /* u32 x 3: T0, T1, T2 */
#define MESO_CELL_OFF_TILE_RES 12      /* u32: R, tile-map voxels per tile edge */
#define MESO_CELL_OFF_SPLIT_COUNT 16   /* u32: S */
#define MESO_CELL_OFF_CELL_COUNT 20    /* u32: C */
#define MESO_CELL_OFF_ORIGIN 24        /* f32 x 3: min corner of tile (0, 0, 0) */
#define MESO_CELL_OFF_VOXEL_SIZE 36    /* f32: h; a tile edge is R h */
#define MESO_CELL_OFF_MIXED_TILES 40   /* u64: M, MIXED tiles = MEMB records */
#define MESO_CELL_OFF_RESERVED 48
#define MESO_CELL_SIZE_RESERVED 16
#define MESO_CELL_MAX_TILES 16384     /* per axis */
#define MESO_CELL_MAX_TILE_RES 1024
/* SPLT of a cells object: U32 x 6 per split cell. */
#define MESO_SPLT_COMPONENTS 6
#define MESO_SPLT_CELL 0
#define MESO_SPLT_FACE_CODE 1
#define MESO_SPLT_TILE_INDEX 2
#define MESO_SPLT_OFFSET 3             /* i32 x 3 (two's complement) */

#endif /* MESO_LAYOUT_H */
