/*
 * adapters.h — the C interface of the five C++ adapters.
 *
 * One adapter per library (openmesh_adapter.cpp, cgal_adapter.cpp,
 * openvdb_adapter.cpp, draco_adapter.cpp, gltf_adapter.cpp). Each is a thin translation layer:
 * C arrays in, C arrays out, every exception caught at the extern "C"
 * boundary and returned as a meso_result with a message. No project logic
 * lives in them. An adapter whose library is missing is not compiled, and
 * MESO_HAVE_<LIB> is 0; callers then report MESO_ERR_UNSUPPORTED (exit 5).
 */
#ifndef MESO_ADAPTERS_H
#define MESO_ADAPTERS_H

#include "gltf_model.h"
#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* >>openmesh ------------------------------------------------------------- */

/* Read OBJ, OFF, PLY, STL or OM (by extension) into `out`, triangulated, with
 * vertex normals computed by OpenMesh (the normalised mean of the unit face
 * normals around the vertex: not area- or angle-weighted). Texture coordinates are
 * kept when the file has per-vertex ones. Faces OpenMesh refuses (complex
 * edges of non-manifold input) are counted in *dropped_faces (may be NULL). */
meso_result meso_openmesh_read(const char* path, meso_mesh* out, uint32_t* dropped_faces, meso_error* err);

/* >>cgal ---------------------------------------------------------------- */

typedef struct meso_cgal_inside meso_cgal_inside;

/* Build an AABB tree over a closed triangle mesh for exact point-in-mesh
 * queries (CGAL::Side_of_triangle_mesh, exact predicates). */
meso_result meso_cgal_inside_create(const meso_mesh* m, meso_cgal_inside** out, meso_error* err);
/* side[i] = 1 inside, -1 outside, 0 on the surface, for points xyz[3*i]. */
meso_result meso_cgal_inside_query(const meso_cgal_inside* t, const double* xyz, size_t count, int8_t* side,
                                   meso_error* err);
void meso_cgal_inside_destroy(meso_cgal_inside* t);

/* Exact triangle-triangle intersection counts (exact predicates on the given
 * double coordinates, sequential and deterministic). Zero-area triangles —
 * repeated index or collinear corners — are skipped and counted. */
typedef struct meso_cgal_intersection_count {
    uint64_t pairs;        /* intersecting triangle pairs */
    uint32_t degenerate_a; /* zero-area triangles of the (first) embedding */
    uint32_t degenerate_b; /* same for the second embedding (cross counts only) */
} meso_cgal_intersection_count;

/* Self-intersecting triangle pairs of the mesh (xyz[3*vertex_count], indices
 * [3*triangle_count]), by CGAL::Polygon_mesh_processing::self_intersections:
 * triangles sharing an edge count only when they overlap coplanarly, sharing
 * a vertex only when they meet beyond it. Non-manifold connectivity (which
 * CGAL::Surface_mesh refuses) is handled by the same rules on the triangle
 * soup, adjacency taken from the indices; duplicate triangles count. */
meso_result meso_cgal_self_intersections(const double* xyz, uint32_t vertex_count, const uint32_t* indices,
                                         uint32_t triangle_count, meso_cgal_intersection_count* out, meso_error* err);
/* Intersecting pairs (triangle s of embedding a, triangle t of embedding b) of
 * two embeddings xyz_a, xyz_b of the same connectivity. Vertex i is a shared
 * corner of the pair when it is a corner of both and xyz_a[i] == xyz_b[i]
 * exactly; shared corners are handled as for adjacent triangles above, and
 * a pair sharing all three corners (the same triangle) never counts. */
meso_result meso_cgal_cross_intersections(const double* xyz_a, const double* xyz_b, uint32_t vertex_count,
                                          const uint32_t* indices, uint32_t triangle_count,
                                          meso_cgal_intersection_count* out, meso_error* err);
/* The same counts, also setting flags[t] = 1 (flags_a / flags_b for the two
 * embeddings) for every triangle of a counted pair; other entries are left
 * as they are, and a NULL array is allowed. Zero-area triangles are counted
 * in degenerate_*, not flagged. */
meso_result meso_cgal_self_intersections_mark(const double* xyz, uint32_t vertex_count, const uint32_t* indices,
                                              uint32_t triangle_count, uint8_t* flags,
                                              meso_cgal_intersection_count* out, meso_error* err);
meso_result meso_cgal_cross_intersections_mark(const double* xyz_a, const double* xyz_b, uint32_t vertex_count,
                                               const uint32_t* indices, uint32_t triangle_count, uint8_t* flags_a,
                                               uint8_t* flags_b, meso_cgal_intersection_count* out, meso_error* err);

/* The intersecting pairs of a shell's offset surface `top` (self, by the
 * soup rules above: adjacency from the indices) and of `top` against the
 * base surface `base` (cross, as meso_cgal_cross_intersections), limited to
 * pairs with a triangle in `changed` (per triangle, 1 = its top moved; NULL
 * = every triangle): self pairs with at least one changed triangle, cross
 * pairs whose top triangle changed. What the incremental checks of
 * shell_checker.c need. Pairs are returned as malloc'd arrays of (a, b)
 * index pairs (self: a < b; cross: a on top, b on the base), sorted, so the
 * result does not depend on `threads` (1..; the work is split over that
 * many threads, over two when every triangle is searched). Zero-area triangles are skipped. Free with free(). */
typedef struct meso_cgal_pairs {
    uint32_t* pairs; /* 2 * count indices */
    size_t count;
} meso_cgal_pairs;
meso_result meso_cgal_shell_pairs(const double* top, const double* base, uint32_t vertex_count,
                                  const uint32_t* indices, uint32_t triangle_count, const uint8_t* changed,
                                  int threads, meso_cgal_pairs* self, meso_cgal_pairs* cross, meso_error* err);

/* The exact test of meso_cgal_shell_pairs for given candidate pairs (the
 * caller found them by box overlap; shell_checker.c): hit[i] = 1 when pair
 * i intersects — self pairs (`cross` 0): top triangle pairs[2i] against top
 * triangle pairs[2i+1]; cross pairs (`cross` 1): top pairs[2i] against base
 * pairs[2i+1] — with the same shared-corner rules, and 0 when either
 * triangle has zero area (meso_cgal_shell_pairs skips those). Split over
 * `threads`; hit does not depend on it. */
meso_result meso_cgal_test_pairs(const double* top, const double* base, uint32_t vertex_count, const uint32_t* indices,
                                 uint32_t triangle_count, const uint32_t* pairs, size_t count, int cross, int threads,
                                 uint8_t* hit, meso_error* err);

/* Curve skeleton of a closed triangle mesh by mean curvature flow
 * (CGAL::Mean_curvature_flow_skeletonization: medially centred, 500
 * iterations at most, min edge length 0.002 x bbox diagonal, and the two
 * weights below). The graph may have cycles (one per handle of the
 * surface). Every array is malloc'd (free each with free()); on failure all
 * are NULL and counts 0. */
typedef struct meso_cgal_skeleton {
    uint32_t vertex_count;
    uint32_t edge_count;
    double* xyz;           /* 3 * vertex_count skeleton vertex positions */
    uint32_t* edges;       /* 2 * edge_count skeleton vertex pairs */
    uint32_t* corr_offset; /* vertex_count + 1: mesh vertices of skeleton vertex i are corr[corr_offset[i] .. [i+1]) */
    uint32_t* corr;        /* mesh vertex indices (CGAL's correspondence), corr_offset[vertex_count] of them */
} meso_cgal_skeleton;

/* CGAL's weights (Tagliasacchi et al. 2012); <= 0 keeps CGAL's default. */
typedef struct meso_cgal_skeleton_params {
    double quality_speed_tradeoff;           /* w_H, CGAL default 0.1 */
    double medially_centered_speed_tradeoff; /* w_M, CGAL default 0.2 */
} meso_cgal_skeleton_params;

/* Skeletonize the mesh (xyz[3*vertex_count], indices[3*triangle_count], CCW
 * from outside; params may be NULL). CGAL requires a closed, manifold,
 * one-component surface and does not check it (open or multi-component
 * input crashes it): the caller checks that first, and passes no unused
 * vertex and no degenerate face (bake/skeleton_from_mesh.c). The adapter
 * itself refuses faces Surface_mesh cannot add and open meshes
 * (MESO_ERR_CORRUPT). Deterministic: the flow runs on an arena (see the
 * adapter). */
meso_result meso_cgal_skeletonize(const double* xyz, uint32_t vertex_count, const uint32_t* indices,
                                  uint32_t triangle_count, const meso_cgal_skeleton_params* params,
                                  meso_cgal_skeleton* out, meso_error* err);

/* >>openvdb ------------------------------------------------------------- */

typedef struct meso_vdb_grid meso_vdb_grid;

/* Narrow-band signed distance level set of a closed mesh (OpenVDB
 * meshToLevelSet): negative inside. half_width is in voxels. */
meso_result meso_vdb_level_set(const meso_mesh* m, double voxel_size, float half_width, meso_vdb_grid** out,
                               meso_error* err);
/* Trilinearly sampled signed distance at world points. */
meso_result meso_vdb_sample(const meso_vdb_grid* g, const double* xyz, size_t count, float* dist, meso_error* err);
/* Active voxel count (sparse storage actually used). */
uint64_t meso_vdb_active_voxels(const meso_vdb_grid* g);
void meso_vdb_destroy(meso_vdb_grid* g);

/* A float grid of a .vdb file, sampled densely. */
typedef struct meso_vdb_dense {
    float* values;     /* dims[0]*dims[1]*dims[2] samples, x fastest (malloc'd: free()) */
    uint32_t dims[3];  /* samples along index-space x, y, z */
    int is_level_set;  /* the grid's class is GRID_LEVEL_SET (else fog volume or unknown) */
    double voxel_size; /* world units per voxel along x (uniform grids) */
} meso_vdb_dense;

/* Open `path`, take the float grid named `grid_name` (NULL: the first float
 * grid), and sample it (trilinearly, in index space) at the centres of a
 * dims[0] x dims[1] x dims[2] lattice over its active voxels' bounding box
 * (voxel cells included whole), where dims is the box's size in voxels
 * scaled uniformly so that no side exceeds max_res. Values are the grid's
 * own (background outside the active region). MESO_ERR_IO when the file can
 * not be read, MESO_ERR_CORRUPT (code `issue`) for a missing/non-float/empty
 * grid. */
meso_result meso_vdb_read_dense(const char* path, const char* grid_name, uint32_t max_res, uint32_t issue,
                                meso_vdb_dense* out, meso_error* err);

/* Tests only: write a .vdb holding one float grid named `grid_name`: a
 * sphere of `radius` at `center` (world units) with `voxel_size`, as a
 * narrow-band level set (fog = 0) or as a fog volume (fog = 1, OpenVDB's
 * sdfToFogVolume: 1 inside, 0 outside, a linear ramp across the band). */
meso_result meso_vdb_write_sphere(const char* path, const char* grid_name, const double center[3], double radius,
                                  double voxel_size, int fog, meso_error* err);

/* >>draco --------------------------------------------------------------- */

typedef struct meso_draco_options {
    int position_bits; /* quantisation bits 1..MESO_DRACO_MAX_BITS (meso_bake.h: why), default 14 */
    int normal_bits;   /* 2..MESO_DRACO_MAX_BITS (Draco's octahedral normals need 2), default 10 */
    int uv_bits;       /* 1..MESO_DRACO_MAX_BITS, default 12 */
    int speed;         /* 0 (best) .. 10 (fastest), default 7 */
} meso_draco_options;

/* Encode a mesh. *out is malloc'd; free it with free(). Vertex order is kept
 * (sequential connectivity) so per-vertex chunks stay aligned with it. */
meso_result meso_draco_encode(const meso_mesh* m, const meso_draco_options* opt, void** out, size_t* out_size,
                              meso_error* err);
/* Decode a Draco mesh bitstream (also .drc files). */
meso_result meso_draco_decode(const void* data, size_t size, meso_mesh* out, meso_error* err);

/* >>gltf ---------------------------------------------------------------- */

/* Parse the glTF 2.0 document at `path` (.gltf with external or data: URI
 * buffers, or .glb, told apart by the magic) with tinygltf, reading its
 * buffers and decoding its images (PNG, JPEG), into *out (gltf_model.h),
 * unchecked. No file is larger than max_bytes, nor all of them together
 * (0: MESO_MESH_GUARD_DEFAULT_MAX_BYTES; else code 3201). MESO_ERR_IO (5001)
 * when `path` cannot be read, MESO_ERR_CORRUPT with code 3500 (JSON or
 * schema) or 3501 (a buffer that cannot be read). Free *out with
 * meso_gltf_model_free. */
meso_result meso_gltf_read(const char* path, uint64_t max_bytes, meso_gltf_model* out, meso_error* err);
void meso_gltf_model_free(meso_gltf_model* m);

#ifdef __cplusplus
}
#endif
#endif /* MESO_ADAPTERS_H */
