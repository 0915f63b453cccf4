/* test_mesh_guard.c — the mesh guard (bake/mesh_guard.c): one case per
 * malformed input the guard must refuse, with the code it must give; valid
 * tetrahedra in every format and the bundled meshes accepted, with the
 * counts the OpenMesh adapter reads from the same files; every prefix of a
 * valid file refused or accepted, read from an allocation of exactly its
 * size (ASan sees any overread). */
#include "test_util.h"

#include <string.h>

#include "adapters.h"
#include "mesh_guard.h"

/* >>helpers ---------------------------------------------------------------- */

/* Check `text` (or `size` bytes of it) as `fmt` from an exact-size copy. */
static meso_result check_bytes(meso_mesh_format fmt, const void* bytes, size_t size, uint64_t max_bytes,
                               meso_mesh_guard_stats* st, meso_error* err)
{
    uint8_t* copy = malloc(size ? size : 1);
    assert(copy);
    memcpy(copy, bytes, size);
    memset(err, 0, sizeof(*err));
    meso_result r = meso_mesh_guard_check(fmt, copy, size, max_bytes, st, err);
    free(copy);
    return r;
}

/* The guard refuses `text` with `code`, and its message names `place`. */
static void refuse(meso_mesh_format fmt, const void* bytes, size_t size, uint32_t code, const char* place)
{
    meso_error err;
    meso_result r = check_bytes(fmt, bytes, size, 0, NULL, &err);
    if (r != MESO_ERR_CORRUPT || err.code != code || (place && !strstr(err.message, place))) {
        fprintf(stderr, "    expected E%u (%s), got result %d E%u: %s\n", code, place ? place : "-", (int)r, err.code,
                err.message);
        assert(0);
    }
}

static void refuse_text(meso_mesh_format fmt, const char* text, uint32_t code, const char* place)
{
    refuse(fmt, text, strlen(text), code, place);
}

static void accept(meso_mesh_format fmt, const void* bytes, size_t size, uint64_t vertices, uint64_t triangles)
{
    meso_error err;
    meso_mesh_guard_stats st;
    meso_result r = check_bytes(fmt, bytes, size, 0, &st, &err);
    if (r != MESO_OK) {
        fprintf(stderr, "    refused a valid file: E%u %s\n", err.code, err.message);
        assert(0);
    }
    assert(st.vertices == vertices);
    assert(st.triangles == triangles);
}

/* The regular tetrahedron corner set, faces CCW from outside. */
static const float tet_v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
static const int tet_f[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};

#define TET_OBJ "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
#define TET_OFF_HEAD "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
#define TET_PLY_HEAD                                                                                              \
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"         \
    "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
#define TET_PLY_BODY_V "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"

static const char tet_obj[] = TET_OBJ "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
static const char tet_off[] = TET_OFF_HEAD "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
static const char tet_ply[] = TET_PLY_HEAD TET_PLY_BODY_V "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";

static void put(uint8_t** p, const void* v, size_t n, int big)
{
    for (size_t i = 0; i < n; ++i)
        (*p)[i] = ((const uint8_t*)v)[big ? n - 1 - i : i];
    *p += n;
}

/* Binary PLY of the tetrahedron; returns its size. */
static size_t tet_ply_binary(uint8_t* buf, int big)
{
    int n = snprintf((char*)buf, 512,
                     "ply\nformat %s 1.0\ncomment made by test_mesh_guard\nelement vertex 4\nproperty float x\n"
                     "property float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                     "end_header\n",
                     big ? "binary_big_endian" : "binary_little_endian");
    uint8_t* p = buf + n;
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k)
            put(&p, &tet_v[i][k], 4, big);
    for (int f = 0; f < 4; ++f) {
        *p++ = 3;
        for (int k = 0; k < 3; ++k) {
            int32_t x = tet_f[f][k];
            put(&p, &x, 4, big);
        }
    }
    return (size_t)(p - buf);
}

/* Binary STL of the tetrahedron (84 + 4 * 50 bytes). */
static size_t tet_stl_binary(uint8_t* buf)
{
    memset(buf, 0, 84);
    memcpy(buf, "binary tetrahedron", 18);
    uint32_t n = 4;
    uint8_t* p = buf + 80;
    put(&p, &n, 4, 0);
    for (int f = 0; f < 4; ++f) {
        float zero[3] = {0, 0, 0};
        put(&p, zero, 12, 0);
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c)
                put(&p, &tet_v[tet_f[f][k]][c], 4, 0);
        *p++ = 0;
        *p++ = 0;
    }
    return (size_t)(p - buf);
}

static size_t tet_stl_ascii(char* buf, size_t cap)
{
    size_t n = (size_t)snprintf(buf, cap, "solid tet\n");
    for (int f = 0; f < 4; ++f) {
        n += (size_t)snprintf(buf + n, cap - n, "  facet normal 0 0 0\n    outer loop\n");
        for (int k = 0; k < 3; ++k)
            n += (size_t)snprintf(buf + n, cap - n, "      vertex %g %g %g\n", tet_v[tet_f[f][k]][0],
                                  tet_v[tet_f[f][k]][1], tet_v[tet_f[f][k]][2]);
        n += (size_t)snprintf(buf + n, cap - n, "    endloop\n  endfacet\n");
    }
    n += (size_t)snprintf(buf + n, cap - n, "endsolid tet\n");
    return n;
}

/* >>valid ------------------------------------------------------------------ */

static void valid_tetrahedra_accepted(void)
{
    accept(MESO_MESH_FORMAT_OBJ, tet_obj, strlen(tet_obj), 4, 4);
    accept(MESO_MESH_FORMAT_OFF, tet_off, strlen(tet_off), 4, 4);
    accept(MESO_MESH_FORMAT_PLY, tet_ply, strlen(tet_ply), 4, 4);
    uint8_t bin[1024];
    accept(MESO_MESH_FORMAT_PLY, bin, tet_ply_binary(bin, 0), 4, 4);
    accept(MESO_MESH_FORMAT_PLY, bin, tet_ply_binary(bin, 1), 4, 4);
    accept(MESO_MESH_FORMAT_STL, bin, tet_stl_binary(bin), 12, 4);
    char text[2048];
    accept(MESO_MESH_FORMAT_STL, text, tet_stl_ascii(text, sizeof(text)), 12, 4);
    /* OBJ: a quad (2 triangles), relative indices, forward references,
     * v/vt/vn corners, comments and other statements. */
    const char* obj = "# cube side\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\n"
                      "vn 0 0 1\ns off\nf 1/1/1 2/2/1 3//1 4\nf 5 -4 -2 # ahead\nv 0 0 1\n";
    accept(MESO_MESH_FORMAT_OBJ, obj, strlen(obj), 5, 3);
    /* OFF: comments, counts on the header line, a colour after the face. */
    const char* off = "OFF 4 4 6\n# c\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1 255 0 0\n3 0 1 3\n3 1 2 3\n3 0 3 2\n\n";
    accept(MESO_MESH_FORMAT_OFF, off, strlen(off), 4, 4);
}

/* The bundled meshes pass, and the guard counts what OpenMesh reads. */
static void bundled_meshes_accepted(void)
{
    const char* names[] = {"blub_fish_low_resolution.obj", "cube_no_bottom.obj", "saddle.obj", "sphere.obj",
                           "spot_low_resolution.obj", "spot_uv.obj", "torus.obj", "wingnut.obj"};
    for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); ++i) {
        meso_error err = {0};
        meso_mesh_guard_stats st;
        meso_result r = meso_mesh_guard_check_file(test_data(names[i]), 0, &st, &err);
        if (r != MESO_OK)
            fprintf(stderr, "    %s: E%u %s\n", names[i], err.code, err.message);
        assert(r == MESO_OK);
        meso_mesh m;
        assert(meso_openmesh_read(test_data(names[i]), &m, NULL, &err) == MESO_OK);
        assert(st.vertices == m.vertex_count);
        assert(st.triangles == m.triangle_count);
        meso_mesh_free(&m);
    }
}

/* >>malformed: OBJ ------------------------------------------------------------ */

static void obj_defects_refused(void)
{
    refuse_text(MESO_MESH_FORMAT_OBJ, "v 0 0 0\nv nan 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n",
                MESO_MESH_GUARD_NONFINITE, "line 2");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 -inf\n", MESO_MESH_GUARD_NUMBER,
                "line 8");
    refuse_text(MESO_MESH_FORMAT_OBJ, "v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n", MESO_MESH_GUARD_NONFINITE, "line 3");
    refuse_text(MESO_MESH_FORMAT_OBJ, "v 0 0 0\nv 1 0 0\nv 0 1 1e39\nf 1 2 3\n", MESO_MESH_GUARD_NONFINITE, "line 3");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 3 2\nf 1 2 4\nf 2 3 5\nf 1 4 3\n", MESO_MESH_GUARD_INDEX_RANGE,
                "line 7");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 3 2\nf -5 2 4\n", MESO_MESH_GUARD_INDEX_RANGE, "line 6");
    /* relative indices count the vertices before the face, not the file's */
    refuse_text(MESO_MESH_FORMAT_OBJ, "v 0 0 0\nv 1 0 0\nf -3 -2 -1\nv 0 1 0\n", MESO_MESH_GUARD_INDEX_RANGE,
                "line 3");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 2 99999999999999999999999\n", MESO_MESH_GUARD_INDEX_RANGE,
                "line 5");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 0 3 2\n", MESO_MESH_GUARD_INDEX_ZERO, "line 5");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 3\nf 1 2 4\n", MESO_MESH_GUARD_FACE_SIZE, "line 5");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "vt 0 0\nf 1/1 2/2 3/1\n", MESO_MESH_GUARD_ATTR_INDEX, "line 6");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "vn 0 0 1\nf 1//1 2//0 3//1\n", MESO_MESH_GUARD_ATTR_INDEX, "line 6");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 2 2\n", MESO_MESH_GUARD_REPEATED_CORNER, "line 5");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 3 2\nf 1 3 2\n", MESO_MESH_GUARD_DUPLICATE_EDGE, "line 6");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 2 3\nf 1 2 4\n", MESO_MESH_GUARD_DUPLICATE_EDGE, "line 5");
    refuse_text(MESO_MESH_FORMAT_OBJ, "v 0 0\nf 1 1 1\n", MESO_MESH_GUARD_NUMBER, "line 1");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1/2/3/4 2 3\n", MESO_MESH_GUARD_NUMBER, "line 5");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ "f 1 2 x\n", MESO_MESH_GUARD_NUMBER, "line 5");
    refuse_text(MESO_MESH_FORMAT_OBJ, TET_OBJ, MESO_MESH_GUARD_EMPTY, NULL);
    refuse_text(MESO_MESH_FORMAT_OBJ, "f 1 2 3\n", MESO_MESH_GUARD_EMPTY, NULL);
    refuse(MESO_MESH_FORMAT_OBJ, "", 0, MESO_MESH_GUARD_EMPTY, NULL);
}

/* >>malformed: OFF ------------------------------------------------------------ */

static void off_defects_refused(void)
{
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF\n2147483648 1 0\n0 0 0\n", MESO_MESH_GUARD_SIZE, "line 2");
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF\n4 4000000000 0\n0 0 0\n", MESO_MESH_GUARD_SIZE, "line 2");
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF\n99999999999999999999999 1 0\n0 0 0\n", MESO_MESH_GUARD_SIZE, "line 2");
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF\n-4 4 0\n0 0 0\n", MESO_MESH_GUARD_HEADER, "line 2");
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF\n4 -1 0\n0 0 0\n", MESO_MESH_GUARD_HEADER, "line 2");
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF\n", MESO_MESH_GUARD_HEADER, NULL);
    refuse_text(MESO_MESH_FORMAT_OFF, "OFX\n4 4 0\n", MESO_MESH_GUARD_HEADER, "line 1");
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF BINARY\n", MESO_MESH_GUARD_VARIANT, "line 1");
    refuse_text(MESO_MESH_FORMAT_OFF, "4OFF\n4 4 0\n", MESO_MESH_GUARD_VARIANT, "line 1");
    refuse_text(MESO_MESH_FORMAT_OFF, TET_OFF_HEAD "3 0 2 1\n3 0 1 3\n3 1 2 -1\n3 0 3 2\n", MESO_MESH_GUARD_INDEX_RANGE,
                "line 9");
    refuse_text(MESO_MESH_FORMAT_OFF, TET_OFF_HEAD "3 0 2 1\n3 0 1 3\n3 1 2 4\n3 0 3 2\n", MESO_MESH_GUARD_INDEX_RANGE,
                "line 9");
    refuse_text(MESO_MESH_FORMAT_OFF, TET_OFF_HEAD "2 0 2\n3 0 1 3\n3 1 2 3\n3 0 3 2\n", MESO_MESH_GUARD_FACE_SIZE,
                "line 7");
    refuse_text(MESO_MESH_FORMAT_OFF, TET_OFF_HEAD "3 0 2\n3 0 1 3\n3 1 2 3\n3 0 3 2\n", MESO_MESH_GUARD_NUMBER,
                "line 7");
    refuse_text(MESO_MESH_FORMAT_OFF, "OFF\n4 4 0\n0 0 0\n1 nan 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n",
                MESO_MESH_GUARD_NONFINITE, "line 4");
    refuse_text(MESO_MESH_FORMAT_OFF, TET_OFF_HEAD "3 0 2 1\n3 0 1 3\n", MESO_MESH_GUARD_SIZE, NULL);
    refuse_text(MESO_MESH_FORMAT_OFF, TET_OFF_HEAD "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n3 0 1 2\n",
                MESO_MESH_GUARD_TRAILING, "line 11");
    refuse_text(MESO_MESH_FORMAT_OFF, TET_OFF_HEAD "3 0 2 2\n3 0 1 3\n3 1 2 3\n3 0 3 2\n",
                MESO_MESH_GUARD_REPEATED_CORNER, "line 7");
}

/* >>malformed: PLY ------------------------------------------------------------ */

static void ply_defects_refused(void)
{
    refuse_text(MESO_MESH_FORMAT_PLY, "ply\nformat ascii 1.0\nelem", MESO_MESH_GUARD_HEADER, "truncated");
    refuse_text(MESO_MESH_FORMAT_PLY, "ply\nformat ascii 1.0\nelem\n#$%^&*\x01\x02", MESO_MESH_GUARD_HEADER, "line 3");
    refuse_text(MESO_MESH_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nbogus\nend_header\n",
                MESO_MESH_GUARD_HEADER, "line 5");
    refuse_text(MESO_MESH_FORMAT_PLY, "plx\nformat ascii 1.0\nend_header\n", MESO_MESH_GUARD_HEADER, "line 1");
    refuse_text(MESO_MESH_FORMAT_PLY, "ply\nformat ascii 2.0\nend_header\n", MESO_MESH_GUARD_VARIANT, "line 2");
    refuse_text(MESO_MESH_FORMAT_PLY, "ply\nformat text 1.0\nend_header\n", MESO_MESH_GUARD_HEADER, "line 2");
    refuse_text(MESO_MESH_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
                MESO_MESH_GUARD_HEADER, "line 4");
    refuse_text(MESO_MESH_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", MESO_MESH_GUARD_HEADER,
                "line 3");
    {
        /* a header longer than the bound */
        size_t n = MESO_MESH_GUARD_PLY_HEADER_MAX + 100;
        char* big = malloc(n);
        assert(big);
        memcpy(big, "ply\n", 4);
        for (size_t i = 4; i < n; ++i)
            big[i] = (i % 64 == 3) ? '\n' : 'c';
        for (size_t i = 4; i + 8 < n; i += 64)
            memcpy(big + i, "comment ", 8);
        refuse(MESO_MESH_FORMAT_PLY, big, n, MESO_MESH_GUARD_HEADER, "first 65536 bytes");
        free(big);
    }
    /* counts that would allocate gigabytes */
    const char* counts[] = {"2147483648", "4000000000", "1073741823"};
    for (int i = 0; i < 3; ++i) {
        char text[512];
        snprintf(text, sizeof(text),
                 "ply\nformat binary_little_endian 1.0\nelement vertex %s\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
                 counts[i]);
        refuse_text(MESO_MESH_FORMAT_PLY, text, MESO_MESH_GUARD_SIZE, "element 'vertex'");
        uint8_t bin[1024];
        size_t n = tet_ply_binary(bin, 0);
        memcpy(strstr((char*)bin, "element face 4") + 13, "9", 1); /* 4 -> 9 faces */
        refuse(MESO_MESH_FORMAT_PLY, bin, n, MESO_MESH_GUARD_SIZE, "element 'face'");
    }
    refuse_text(MESO_MESH_FORMAT_PLY, TET_PLY_HEAD TET_PLY_BODY_V "3 0 2 1\n3 0 1 3\n3 1 2 -1\n3 0 3 2\n",
                MESO_MESH_GUARD_INDEX_RANGE, "face 2");
    refuse_text(MESO_MESH_FORMAT_PLY, TET_PLY_HEAD TET_PLY_BODY_V "3 0 2 1\n3 0 1 3\n3 1 2 4\n3 0 3 2\n",
                MESO_MESH_GUARD_INDEX_RANGE, "face 2");
    refuse_text(MESO_MESH_FORMAT_PLY, TET_PLY_HEAD TET_PLY_BODY_V "2 0 2\n3 0 1 3\n3 1 2 3\n3 0 3 2\n",
                MESO_MESH_GUARD_FACE_SIZE, "face 0");
    refuse_text(MESO_MESH_FORMAT_PLY, TET_PLY_HEAD "0 0 0\n1 0 0\n0 1 0\n0 0 nan\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n",
                MESO_MESH_GUARD_NONFINITE, "vertex 3");
    refuse_text(MESO_MESH_FORMAT_PLY, TET_PLY_HEAD TET_PLY_BODY_V "3 0 2 1\n3 0 1 3\ngarbage\x01\x02 3 0 3 2\n",
                MESO_MESH_GUARD_NUMBER, "line 16");
    refuse_text(MESO_MESH_FORMAT_PLY, TET_PLY_HEAD TET_PLY_BODY_V "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n7\n",
                MESO_MESH_GUARD_TRAILING, NULL);
    refuse_text(MESO_MESH_FORMAT_PLY, TET_PLY_HEAD TET_PLY_BODY_V "3 0 2 1\n3 0 2 1\n3 1 2 3\n3 0 3 2\n",
                MESO_MESH_GUARD_DUPLICATE_EDGE, "face 1");
    refuse_text(MESO_MESH_FORMAT_PLY,
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nelement face 1\n"
                "property list uchar int vertex_indices\nend_header\n0 0\n3 0 0 0\n",
                MESO_MESH_GUARD_VARIANT, "line 3");
    uint8_t bin[1024];
    size_t n = tet_ply_binary(bin, 1);
    /* big-endian list count 200 in the last face: more than the bytes left */
    bin[n - 13] = 200;
    refuse(MESO_MESH_FORMAT_PLY, bin, n, MESO_MESH_GUARD_SIZE, "face' 3");
    n = tet_ply_binary(bin, 0);
    float nan_x = NAN;
    memcpy(strstr((char*)bin, "end_header\n") + 11 + 12, &nan_x, 4); /* vertex 1 x */
    refuse(MESO_MESH_FORMAT_PLY, bin, n, MESO_MESH_GUARD_NONFINITE, "vertex 1");
    n = tet_ply_binary(bin, 0);
    bin[n++] = 'x';
    refuse(MESO_MESH_FORMAT_PLY, bin, n, MESO_MESH_GUARD_TRAILING, NULL);
}

/* >>malformed: STL, OM, DRC ----------------------------------------------------- */

static void stl_om_drc_defects_refused(void)
{
    uint8_t bin[1024];
    size_t n = tet_stl_binary(bin);
    refuse(MESO_MESH_FORMAT_STL, bin, n - 1, MESO_MESH_GUARD_SIZE, "84 + 50 x 4");
    uint32_t many = 100000000;
    uint8_t* p = bin + 80;
    put(&p, &many, 4, 0);
    refuse(MESO_MESH_FORMAT_STL, bin, n, MESO_MESH_GUARD_SIZE, "84 + 50 x 100000000");
    n = tet_stl_binary(bin);
    float inf = INFINITY;
    memcpy(bin + 84 + 2 * 50 + 12 + 4, &inf, 4); /* triangle 2, corner 1, y */
    refuse(MESO_MESH_FORMAT_STL, bin, n, MESO_MESH_GUARD_NONFINITE, "triangle 2 at byte 184");
    n = tet_stl_binary(bin);
    memcpy(bin + 84 + 50 + 24, bin + 84 + 50 + 12, 12); /* triangle 1: corner 2 = corner 1 */
    refuse(MESO_MESH_FORMAT_STL, bin, n, MESO_MESH_GUARD_REPEATED_CORNER, "triangle 1");
    refuse_text(MESO_MESH_FORMAT_STL, "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n",
                MESO_MESH_GUARD_STL_STRUCTURE, "line 6");
    refuse_text(MESO_MESH_FORMAT_STL,
                "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n",
                MESO_MESH_GUARD_STL_STRUCTURE, "before 'endsolid'");
    refuse_text(MESO_MESH_FORMAT_STL,
                "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 nan\nvertex 0 1 0\nendloop\n"
                "endfacet\nendsolid x\n",
                MESO_MESH_GUARD_NONFINITE, "line 2");
    refuse_text(MESO_MESH_FORMAT_STL, "solid x\nendsolid x\n", MESO_MESH_GUARD_EMPTY, NULL);
    refuse_text(MESO_MESH_FORMAT_STL, "not an stl", MESO_MESH_GUARD_SIZE, NULL);

    uint8_t om[64] = {'O', 'M', 'T', 2};
    p = om + 4;
    uint32_t c[3] = {2000000000u, 1, 1};
    for (int i = 0; i < 3; ++i)
        put(&p, &c[i], 4, 0);
    refuse(MESO_MESH_FORMAT_OM, om, sizeof(om), MESO_MESH_GUARD_SIZE, "2000000000 vertices");
    refuse(MESO_MESH_FORMAT_OM, "MO\0\0", 4, MESO_MESH_GUARD_HEADER, NULL);
    refuse(MESO_MESH_FORMAT_DRC, "DRACX\2\2", 7, MESO_MESH_GUARD_HEADER, NULL);
    meso_error err;
    uint8_t drc[64] = "DRACO";
    assert(check_bytes(MESO_MESH_FORMAT_DRC, drc, sizeof(drc), 16 * 63, NULL, &err) == MESO_ERR_CORRUPT &&
           err.code == MESO_MESH_GUARD_BUDGET);
    assert(check_bytes(MESO_MESH_FORMAT_DRC, drc, sizeof(drc), 16 * 64, NULL, &err) == MESO_OK);
}

/* The byte budget: the tetrahedron needs 4 * 128 + 4 * 256 bytes plus its own size. */
static void budget_refuses_before_reading(void)
{
    meso_error err;
    uint64_t need = 4 * MESO_MESH_GUARD_BYTES_PER_VERTEX + 4 * MESO_MESH_GUARD_BYTES_PER_TRIANGLE + strlen(tet_off);
    assert(check_bytes(MESO_MESH_FORMAT_OFF, tet_off, strlen(tet_off), need, NULL, &err) == MESO_OK);
    assert(check_bytes(MESO_MESH_FORMAT_OFF, tet_off, strlen(tet_off), need - 1, NULL, &err) == MESO_ERR_CORRUPT);
    assert(err.code == MESO_MESH_GUARD_BUDGET);
    assert(check_bytes(MESO_MESH_FORMAT_OBJ, tet_obj, strlen(tet_obj), 10, NULL, &err) == MESO_ERR_CORRUPT);
    assert(err.code == MESO_MESH_GUARD_BUDGET);
}

/* Every prefix of a valid file, from an exact-size allocation: refused with a
 * guard code or accepted; never read beyond (ASan). Prefixes shorter than
 * `refused_below` bytes must be refused: of the binary files they lose part
 * of their last element, of ASCII STL the endsolid. */
static void truncation_loop(meso_mesh_format fmt, const uint8_t* data, size_t size, size_t refused_below)
{
    for (size_t i = 0; i < size; ++i) {
        meso_error err;
        meso_result r = check_bytes(fmt, data, i, 0, NULL, &err);
        assert(r == MESO_OK || r == MESO_ERR_CORRUPT);
        if (r == MESO_ERR_CORRUPT)
            assert(err.code >= 3200 && err.code <= 3249);
        if (i < refused_below)
            assert(r == MESO_ERR_CORRUPT);
    }
}

static void every_prefix_safe(void)
{
    truncation_loop(MESO_MESH_FORMAT_OBJ, (const uint8_t*)tet_obj, strlen(tet_obj), 0);
    truncation_loop(MESO_MESH_FORMAT_OFF, (const uint8_t*)tet_off, strlen(tet_off), strlen(tet_off) - 1);
    truncation_loop(MESO_MESH_FORMAT_PLY, (const uint8_t*)tet_ply, strlen(tet_ply), strlen(tet_ply) - 1);
    uint8_t bin[1024];
    size_t n = tet_ply_binary(bin, 0);
    truncation_loop(MESO_MESH_FORMAT_PLY, bin, n, n);
    n = tet_ply_binary(bin, 1);
    truncation_loop(MESO_MESH_FORMAT_PLY, bin, n, n);
    n = tet_stl_binary(bin);
    truncation_loop(MESO_MESH_FORMAT_STL, bin, n, n);
    char text[2048];
    n = tet_stl_ascii(text, sizeof(text));
    truncation_loop(MESO_MESH_FORMAT_STL, (const uint8_t*)text, n, (size_t)(strstr(text, "endsolid") - text) + 8);
    uint8_t om[28] = {'O', 'M', 'T', 2, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    truncation_loop(MESO_MESH_FORMAT_OM, om, sizeof(om), 16 + 12);
}

/* The path wrapper: the path leads the message, unknown extensions refused. */
static void path_wrapper(void)
{
    meso_error err = {0};
    assert(meso_mesh_guard_check_file("no/such/file.obj", 0, NULL, &err) == MESO_ERR_IO);
    assert(meso_mesh_guard_check_file(test_data("sphere.obj"), 1000, NULL, &err) == MESO_ERR_CORRUPT);
    assert(err.code == MESO_MESH_GUARD_BUDGET && strstr(err.message, "sphere.obj: "));
    assert(meso_mesh_guard_check_file("x.glb", 0, NULL, &err) == MESO_ERR_CORRUPT);
    assert(err.code == MESO_MESH_GUARD_EXTENSION);
    assert(meso_mesh_format_from_path("A.PLY") == MESO_MESH_FORMAT_PLY);
    assert(meso_mesh_format_from_path("a.om") == MESO_MESH_FORMAT_OM);
    assert(meso_mesh_format_from_path("a.stlx") == MESO_MESH_FORMAT_UNKNOWN);
}

int main(void)
{
    TEST_RUN(valid_tetrahedra_accepted);
    TEST_RUN(bundled_meshes_accepted);
    TEST_RUN(obj_defects_refused);
    TEST_RUN(off_defects_refused);
    TEST_RUN(ply_defects_refused);
    TEST_RUN(stl_om_drc_defects_refused);
    TEST_RUN(budget_refuses_before_reading);
    TEST_RUN(every_prefix_safe);
    TEST_RUN(path_wrapper);
    return 0;
}
