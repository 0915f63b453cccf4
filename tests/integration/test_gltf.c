/*
 * test_gltf.c — glTF 2.0 input (issue 16, deliver 1) through the public
 * loader (meso_bake_load_mesh_materials), on tests/data/gltf/ (made by
 * make_gltf.py there): the textured box welded from 24 split vertices to one
 * closed 8-vertex manifold with its uv seams and base colour (PNG), the same
 * box from an embedded data: URI buffer, a .glb with a JPEG texture, a Draco
 * primitive, a multi-node scene against its transforms applied by hand,
 * --node by name and index, the bundled sphere as .glb against the OBJ, and
 * every malformed file refused with its code (gltf_model.h) and its place.
 */
#include <string.h>

#include "gltf_model.h"
#include "meso_bake.h"
#include "test_util.h"

static meso_result load(const char* name, const char* node, meso_mesh* m, meso_mesh_materials* mats,
                        meso_bake_mesh_fixes* fixes, meso_error* err)
{
    meso_bake_common c;
    memset(&c, 0, sizeof(c));
    c.gltf_node = node;
    memset(err, 0, sizeof(*err));
    return meso_bake_load_mesh_materials(test_data(name), &c, m, mats, fixes, err);
}

/* Every undirected edge is on exactly two triangles, used once each way. */
static int closed_manifold(const meso_mesh* m)
{
    for (uint32_t t = 0; t < m->triangle_count; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m->indices[3 * t + k], b = m->indices[3 * t + (k + 1) % 3];
            int same = 0, opposite = 0;
            for (uint32_t u = 0; u < m->triangle_count; ++u)
                for (int j = 0; j < 3; ++j) {
                    const uint32_t c = m->indices[3 * u + j], d = m->indices[3 * u + (j + 1) % 3];
                    same += c == a && d == b;
                    opposite += c == b && d == a;
                }
            if (same != 1 || opposite != 1)
                return 0;
        }
    return 1;
}

static int has_point(const meso_mesh* m, double x, double y, double z)
{
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        const float* p = m->positions + 3 * v;
        if (fabs(p[0] - x) < 1e-5 && fabs(p[1] - y) < 1e-5 && fabs(p[2] - z) < 1e-5)
            return 1;
    }
    return 0;
}

static void check_box(const char* name, int jpeg)
{
    meso_mesh m;
    meso_mesh_materials mats;
    meso_bake_mesh_fixes fixes;
    meso_error err;
    assert(load(name, NULL, &m, &mats, &fixes, &err) == MESO_OK);
    assert(m.vertex_count == 8 && m.triangle_count == 12); /* 24 split vertices welded */
    assert(closed_manifold(&m));
    assert(fixes.reoriented_components == 0); /* outward as written: nothing flipped */
    for (int c = 0; c < 8; ++c)
        assert(has_point(&m, c & 1 ? 0.5 : -0.5, c & 2 ? 0.5 : -0.5, c & 4 ? 0.5 : -0.5));
    /* uvs kept per corner: every corner uv is a corner of the unit square, and
     * the vertices sit on seams (each has several) */
    assert(m.uvs && m.corner_uvs && m.normals);
    for (uint32_t i = 0; i < 6 * m.triangle_count; ++i)
        assert(m.corner_uvs[i] == 0.0f || m.corner_uvs[i] == 1.0f);
    /* base colour: factor and the 4 x 4 texture, every triangle on material 0 */
    assert(mats.material_count == 1 && mats.triangle_materials);
    for (uint32_t t = 0; t < m.triangle_count; ++t)
        assert(mats.triangle_materials[t] == 0);
    const meso_mesh_material* mat = &mats.materials[0];
    assert(mat->width == 4 && mat->height == 4 && mat->rgba);
    const int tol = jpeg ? 12 : 0; /* JPEG at quality 100 is close, not exact */
    static const uint8_t expect[4][3] = {{200, 40, 40}, {40, 200, 40}, {40, 40, 200}, {220, 220, 40}};
    for (int q = 0; q < 4; ++q) {
        const int x = q & 1 ? 3 : 0, y = q & 2 ? 3 : 0;
        const uint8_t* px = mat->rgba + 4 * (4 * y + x);
        for (int c = 0; c < 3; ++c)
            assert(abs(px[c] - expect[q][c]) <= tol);
        assert(px[3] == 255);
    }
    if (!jpeg)
        assert(mat->base_color_factor[1] == 0.8f && mat->base_color_factor[2] == 0.6f);
    meso_mesh_free(&m);
    meso_mesh_materials_free(&mats);
}

static void test_box(void)
{
    check_box("gltf/box.gltf", 0);
    check_box("gltf/box_embedded.gltf", 0);
    check_box("gltf/box.glb", 1);
}

static void test_draco(void)
{
    meso_mesh m;
    meso_error err;
    assert(load("gltf/box_draco.glb", NULL, &m, NULL, NULL, &err) == MESO_OK);
    assert(m.vertex_count == 8 && m.triangle_count == 12 && m.uvs);
    assert(closed_manifold(&m));
    for (int c = 0; c < 8; ++c)
        assert(has_point(&m, c & 1 ? 0.5 : -0.5, c & 2 ? 0.5 : -0.5, c & 4 ? 0.5 : -0.5));
    meso_mesh_free(&m);
}

/* make_gltf.py's scene: root T(10,0,0); A = matrix (scale 2, T(0,5,0)); B =
 * R_z(90) then T(0,-5,0); C = scale(-1,1,1) then T(0,0,5); "outside" =
 * T(0,0,-20), not in the scene. */
static void world_corner(char node, int c, double p[3])
{
    const double x = c & 1 ? 0.5 : -0.5, y = c & 2 ? 0.5 : -0.5, z = c & 4 ? 0.5 : -0.5;
    switch (node) {
    case 'A': p[0] = 10 + 2 * x, p[1] = 5 + 2 * y, p[2] = 2 * z; break;
    case 'B': p[0] = 10 - y, p[1] = -5 + x, p[2] = z; break;
    case 'C': p[0] = 10 - x, p[1] = y, p[2] = 5 + z; break;
    default: p[0] = x, p[1] = y, p[2] = z - 20; break;
    }
}

static void check_nodes(const char* node, const char* which)
{
    meso_mesh m;
    meso_bake_mesh_fixes fixes;
    meso_error err;
    assert(load("gltf/scene.gltf", node, &m, NULL, &fixes, &err) == MESO_OK);
    const uint32_t n = (uint32_t)strlen(which);
    assert(m.vertex_count == 8 * n && m.triangle_count == 12 * n);
    assert(closed_manifold(&m));
    /* the mirrored box's winding was reversed with it: nothing inside-out */
    assert(fixes.reoriented_components == 0);
    for (uint32_t k = 0; k < n; ++k)
        for (int c = 0; c < 8; ++c) {
            double p[3];
            world_corner(which[k], c, p);
            assert(has_point(&m, p[0], p[1], p[2]));
        }
    meso_mesh_free(&m);
}

static void test_scene(void)
{
    check_nodes(NULL, "ABC");
    check_nodes("B", "B");
    check_nodes("1", "A");
    check_nodes("root", "ABC");
    check_nodes("outside", "O");
}

/* The bundled sphere as .glb bakes the OBJ's positions and triangles. */
static void test_same_as_obj(void)
{
    meso_mesh a, b;
    meso_error err;
    memset(&err, 0, sizeof(err));
    assert(meso_bake_load_mesh(test_data("sphere.obj"), NULL, &a, NULL, &err) == MESO_OK);
    assert(load("gltf/sphere.glb", NULL, &b, NULL, NULL, &err) == MESO_OK);
    assert(a.vertex_count == b.vertex_count && a.triangle_count == b.triangle_count);
    assert(memcmp(a.positions, b.positions, sizeof(float) * 3 * a.vertex_count) == 0);
    assert(memcmp(a.indices, b.indices, sizeof(uint32_t) * 3 * a.triangle_count) == 0);
    for (uint32_t i = 0; i < 3 * a.vertex_count; ++i) /* OpenMesh's float normals vs ours in double */
        assert(fabs(a.normals[i] - b.normals[i]) < 1e-6);
    meso_mesh_free(&a);
    meso_mesh_free(&b);
}

static void test_malformed(void)
{
    static const struct {
        const char* file;
        const char* node;
        uint32_t code;
        const char* place;
    } cases[] = {
        {"gltf/bad_index.gltf", NULL, MESO_GLTF_ISSUE_INDEX,
         "meshes[0].primitives[0].indices: index 9 out of range (8 vertices)"},
        {"gltf/bad_missing_buffer.gltf", NULL, MESO_GLTF_ISSUE_BUFFER, "missing.bin"},
        {"gltf/bad_position_type.gltf", NULL, MESO_GLTF_ISSUE_TYPE, "attributes.POSITION (accessors[0])"},
        {"gltf/bad_index_type.gltf", NULL, MESO_GLTF_ISSUE_TYPE, "primitives[0].indices (accessors[1])"},
        {"gltf/bad_accessor_bounds.gltf", NULL, MESO_GLTF_ISSUE_BOUNDS, "overrun bufferViews[0]"},
        {"gltf/bad_view_bounds.gltf", NULL, MESO_GLTF_ISSUE_BOUNDS, "bufferViews[1]"},
        {"gltf/bad_zeros_count.gltf", NULL, MESO_GLTF_ISSUE_BOUNDS, "without a bufferView"},
        {"gltf/bad_nan.gltf", NULL, MESO_GLTF_ISSUE_NONFINITE, "meshes[0].primitives[0]: vertex 0"},
        {"gltf/bad_cycle.gltf", NULL, MESO_GLTF_ISSUE_GRAPH, "cycle"},
        {"gltf/bad_two_parents.gltf", NULL, MESO_GLTF_ISSUE_GRAPH, "two parents"},
        {"gltf/bad_schema.gltf", NULL, MESO_GLTF_ISSUE_SCHEMA, "componentType"},
        {"gltf/bad_not_json.gltf", NULL, MESO_GLTF_ISSUE_SCHEMA, "not valid glTF"},
        {"gltf/bad_lines.gltf", NULL, MESO_GLTF_ISSUE_MODE, "mode: 1 (LINES)"},
        {"gltf/bad_sparse.gltf", NULL, MESO_GLTF_ISSUE_UNSUPPORTED, "sparse"},
        {"gltf/bad_extension.gltf", NULL, MESO_GLTF_ISSUE_UNSUPPORTED, "EXT_meshopt_compression"},
        {"gltf/bad_reference.gltf", NULL, MESO_GLTF_ISSUE_REFERENCE, "nodes[0].mesh: mesh 7"},
        {"gltf/bad_texture.gltf", NULL, MESO_GLTF_ISSUE_IMAGE, "images[0]"},
        {"gltf/bad_empty.gltf", NULL, MESO_GLTF_ISSUE_EMPTY, "no triangles"},
        {"gltf/scene.gltf", "nope", MESO_GLTF_ISSUE_NODE, "--node nope"},
        {"gltf/scene.gltf", "17", MESO_GLTF_ISSUE_NODE, "--node 17"},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); ++i) {
        meso_mesh m;
        meso_mesh_materials mats;
        meso_error err;
        const meso_result r = load(cases[i].file, cases[i].node, &m, &mats, NULL, &err);
        fprintf(stderr, "    %s: E%u %s\n", cases[i].file, err.code, err.message);
        assert(r == MESO_ERR_CORRUPT);
        assert(err.code == cases[i].code);
        assert(strstr(err.message, cases[i].place));
        assert(m.vertex_count == 0 && m.positions == NULL && mats.materials == NULL);
    }
}

int main(void)
{
    TEST_RUN(test_box);
    TEST_RUN(test_draco);
    TEST_RUN(test_scene);
    TEST_RUN(test_same_as_obj);
    TEST_RUN(test_malformed);
    return 0;
}
