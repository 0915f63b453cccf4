/*
 * gltf_model.h — a glTF 2.0 document as plain C arrays, and its issue codes.
 *
 * The glTF adapter (adapters/gltf_adapter.cpp, tinygltf) parses the JSON,
 * reads the buffers (external files, data: URIs, the .glb BIN chunk) and
 * decodes the images (PNG, JPEG: stb_image inside Debian's libtinygltf), and
 * copies what carries geometry or base colour into these structs, unchecked:
 * every index is the file's own (-1 when absent) and may point anywhere.
 * gltf_scene.c checks them (references, bounds, types, the node graph) and
 * builds the mesh; see meso_gltf_load there.
 *
 * Issue codes (meso_error.code; mesobake exits 3 for each). Every message
 * names the file and the place, e.g.
 * "box.gltf: meshes[0].primitives[1].indices: index 9 out of range (8 vertices)".
 *   3500 the glTF reader refused the document: not JSON / not a .glb, a
 *        schema violation (a required property missing or of the wrong JSON
 *        type, an unknown enum value)
 *   3501 a buffer or image that cannot be read: a missing file, a URI that is
 *        not a relative path or a data: URI, fewer bytes than byteLength
 *   3502 a reference to an element that does not exist (an accessor,
 *        bufferView, buffer, mesh, node, material, texture, image or scene
 *        index out of range)
 *   3503 an accessor or bufferView outside its bufferView / buffer, or a
 *        byteStride that is too small or misaligned
 *   3504 a wrong type or componentType for its use (POSITION not VEC3 float,
 *        indices not SCALAR unsigned, TEXCOORD_0 not VEC2 float or
 *        normalized unsigned byte/short), or counts that disagree
 *   3505 an index out of range of the primitive's vertices
 *   3506 a non-finite position or texture coordinate
 *   3507 a node graph that is not a forest: a cycle, or a node with two
 *        parents
 *   3508 a primitive mode that is not triangles (points, lines)
 *   3509 a feature not read here: sparse accessors, a required extension
 *        other than KHR_draco_mesh_compression
 *   3510 --node NAME|INDEX names no node of the document
 *   3511 a KHR_draco_mesh_compression primitive that does not decode, or
 *        disagrees with its accessors
 *   3512 a base-colour texture whose image does not decode (PNG and JPEG are
 *        read) or has no pixels
 *   3513 the scene (or the chosen node) holds no triangles
 * Size limits are the mesh guard's (mesh_guard.h): 3201 when a file, the
 * buffers or the triangles would need more than the memory budget.
 */
#ifndef MESO_GLTF_MODEL_H
#define MESO_GLTF_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

enum {
    MESO_GLTF_ISSUE_SCHEMA = 3500,
    MESO_GLTF_ISSUE_BUFFER = 3501,
    MESO_GLTF_ISSUE_REFERENCE = 3502,
    MESO_GLTF_ISSUE_BOUNDS = 3503,
    MESO_GLTF_ISSUE_TYPE = 3504,
    MESO_GLTF_ISSUE_INDEX = 3505,
    MESO_GLTF_ISSUE_NONFINITE = 3506,
    MESO_GLTF_ISSUE_GRAPH = 3507,
    MESO_GLTF_ISSUE_MODE = 3508,
    MESO_GLTF_ISSUE_UNSUPPORTED = 3509,
    MESO_GLTF_ISSUE_NODE = 3510,
    MESO_GLTF_ISSUE_DRACO = 3511,
    MESO_GLTF_ISSUE_IMAGE = 3512,
    MESO_GLTF_ISSUE_EMPTY = 3513,
    MESO_GLTF_ISSUE_COUNT
};

/* glTF enum values (the specification's numbers). */
#define MESO_GLTF_BYTE 5120
#define MESO_GLTF_UNSIGNED_BYTE 5121
#define MESO_GLTF_SHORT 5122
#define MESO_GLTF_UNSIGNED_SHORT 5123
#define MESO_GLTF_UNSIGNED_INT 5125
#define MESO_GLTF_FLOAT 5126
#define MESO_GLTF_MODE_TRIANGLES 4
#define MESO_GLTF_MODE_TRIANGLE_STRIP 5
#define MESO_GLTF_MODE_TRIANGLE_FAN 6

typedef struct meso_gltf_buffer {
    const uint8_t* data; /* the bytes read (NULL when none) */
    size_t size;         /* bytes read */
    size_t byte_length;  /* what the document declares */
} meso_gltf_buffer;

typedef struct meso_gltf_view {
    int buffer;
    size_t offset, length;
    size_t stride; /* 0: tightly packed */
} meso_gltf_view;

typedef struct meso_gltf_accessor {
    int view; /* -1: all zeros (glTF allows it) */
    size_t offset;
    int component_type; /* MESO_GLTF_* */
    int components;     /* 1 SCALAR, 2..4 VECn, 4/9/16 MATn */
    int is_matrix;
    size_t count;
    int normalized;
    int sparse; /* the accessor has a sparse part */
} meso_gltf_accessor;

typedef struct meso_gltf_primitive {
    int mode; /* default 4 */
    int indices, position, texcoord, material; /* -1 when absent */
    /* KHR_draco_mesh_compression (draco_view -1 when the primitive has none) */
    int draco_view;
    int draco_position, draco_texcoord; /* attribute ids, -1 when absent */
} meso_gltf_primitive;

typedef struct meso_gltf_mesh {
    const char* name;
    uint32_t first_primitive, primitive_count; /* into meso_gltf_model.primitives */
} meso_gltf_mesh;

typedef struct meso_gltf_node {
    const char* name;
    int mesh;
    int has_matrix;
    double matrix[16]; /* column-major, when has_matrix */
    double translation[3], rotation[4], scale[3]; /* defaults 0, (0,0,0,1), 1 */
    uint32_t first_child, child_count; /* into meso_gltf_model.children */
} meso_gltf_node;

typedef struct meso_gltf_scene {
    uint32_t first_node, node_count; /* into meso_gltf_model.scene_nodes */
} meso_gltf_scene;

typedef struct meso_gltf_material {
    double base_color_factor[4];
    int base_color_texture; /* texture index, -1 when none */
    int base_color_texcoord;
} meso_gltf_material;

typedef struct meso_gltf_image {
    int width, height, components, bits; /* as decoded; 0 when not decoded */
    const uint8_t* pixels;               /* width*height*components*(bits/8) bytes, or NULL */
    size_t size;
} meso_gltf_image;

/* The whole document. Strings and arrays belong to the adapter's handle
 * (free with meso_gltf_model_free). */
typedef struct meso_gltf_model {
    meso_gltf_buffer* buffers;
    meso_gltf_view* views;
    meso_gltf_accessor* accessors;
    meso_gltf_primitive* primitives;
    meso_gltf_mesh* meshes;
    meso_gltf_node* nodes;
    int* children;
    meso_gltf_scene* scenes;
    int* scene_nodes;
    meso_gltf_material* materials;
    int* texture_sources; /* image of each texture, -1 when none */
    meso_gltf_image* images;
    uint32_t buffer_count, view_count, accessor_count, primitive_count, mesh_count, node_count, child_count,
        scene_count, scene_node_count, material_count, texture_count, image_count;
    int default_scene; /* -1 when the document names none */
    const char* unsupported_extension; /* the first required extension not read here, or NULL */
    void* handle;                      /* the adapter's */
} meso_gltf_model;

/* >>accessors (gltf_accessor.c) ------------------------------------------ */

/* The `accessor`'s elements as floats, `components` per element: float, or
 * (allow_normalized) normalized unsigned byte/short scaled to [0, 1]. Every
 * byte read is checked to lie in its bufferView and buffer (3502, 3503,
 * 3504, 3509 as listed above); messages start "path: place (accessors[i])".
 * *out is malloc'd (free()), *count its elements. */
meso_result meso_gltf_read_floats(const char* path, const meso_gltf_model* g, int accessor, const char* place,
                                  int components, int allow_normalized, float** out, size_t* count, meso_error* err);
/* The `accessor` as vertex indices (SCALAR unsigned byte/short/int), each
 * below vertex_count (else 3505 naming the first one out of range). */
meso_result meso_gltf_read_indices(const char* path, const meso_gltf_model* g, int accessor, const char* place,
                                   size_t vertex_count, uint32_t** out, size_t* count, meso_error* err);

/* >>scene (gltf_scene.c) -------------------------------------------------- */

/* Load the glTF document at `path` into *out: every triangle primitive of
 * every mesh of the scene (the default scene, else the first, else every root
 * node), or of the subtree of the node `node` names (a name, else a decimal
 * index; NULL: the scene), positions transformed by their node's world
 * matrix and welded (mesh_weld.h), TEXCOORD_0 per corner (v flipped to the
 * OBJ convention: 1 - v); the materials' base colour (every texture in
 * use decoded and checked) into *materials (may be NULL: checked only).
 * max_bytes bounds the files and the triangles (mesh guard estimate, code
 * 3201). *dropped counts triangles that welding made degenerate (dropped).
 * Codes as listed above; *out is zeroed on failure. */
meso_result meso_gltf_load(const char* path, const char* node, uint64_t max_bytes, meso_mesh* out,
                           meso_mesh_materials* materials, uint32_t* dropped, meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_GLTF_MODEL_H */
