/* OpenMesh adapter: reads OBJ, OFF and PLY (ASCII and binary), computes
 * vertex normals and keeps per-corner uvs at seams. Expectations are analytic: an octahedron written here in
 * each format (vertex normals = normalised positions by symmetry) and the
 * bundled unit sphere (normals ~ positions). */
#include "test_util.h"

#include <string.h>
#include <unistd.h>

#include "adapters.h"

static const float octa_v[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
/* Counter-clockwise seen from outside. */
static const uint32_t octa_f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                      {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};

static char tmpdir[256];

static const char* tmp_path(const char* name)
{
    static char buf[512];
    snprintf(buf, sizeof(buf), "%s/%s", tmpdir, name);
    return buf;
}

static void write_octa(const char* name, int format)
{
    FILE* f = fopen(tmp_path(name), "wb");
    assert(f);
    if (format == 0) { /* OBJ */
        for (int i = 0; i < 6; ++i)
            fprintf(f, "v %g %g %g\n", octa_v[i][0], octa_v[i][1], octa_v[i][2]);
        for (int i = 0; i < 8; ++i)
            fprintf(f, "f %u %u %u\n", octa_f[i][0] + 1, octa_f[i][1] + 1, octa_f[i][2] + 1);
    } else if (format == 1) { /* OFF */
        fprintf(f, "OFF\n6 8 0\n");
        for (int i = 0; i < 6; ++i)
            fprintf(f, "%g %g %g\n", octa_v[i][0], octa_v[i][1], octa_v[i][2]);
        for (int i = 0; i < 8; ++i)
            fprintf(f, "3 %u %u %u\n", octa_f[i][0], octa_f[i][1], octa_f[i][2]);
    } else if (format == 2) { /* ASCII PLY */
        fprintf(f, "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 8\nproperty list uchar int vertex_indices\nend_header\n");
        for (int i = 0; i < 6; ++i)
            fprintf(f, "%g %g %g\n", octa_v[i][0], octa_v[i][1], octa_v[i][2]);
        for (int i = 0; i < 8; ++i)
            fprintf(f, "3 %u %u %u\n", octa_f[i][0], octa_f[i][1], octa_f[i][2]);
    } else { /* binary little-endian PLY */
        fprintf(f, "ply\nformat binary_little_endian 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 8\nproperty list uchar int vertex_indices\nend_header\n");
        fwrite(octa_v, sizeof(float), 18, f);
        for (int i = 0; i < 8; ++i) {
            unsigned char n = 3;
            int32_t ix[3] = {(int32_t)octa_f[i][0], (int32_t)octa_f[i][1], (int32_t)octa_f[i][2]};
            fwrite(&n, 1, 1, f);
            fwrite(ix, 4, 3, f);
        }
    }
    fclose(f);
}

/* Each output vertex must match one input vertex; its normal must be the
 * normalised position (pointing outwards), and every face must keep its
 * orientation (face normal · centroid > 0). */
static void check_octa(const meso_mesh* m)
{
    assert(m->vertex_count == 6 && m->triangle_count == 8);
    assert(m->normals);
    for (uint32_t i = 0; i < 6; ++i) {
        const float* p = m->positions + 3 * i;
        const float* n = m->normals + 3 * i;
        double len = sqrt((double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2]);
        assert(fabs(len - 1.0) < 1e-6);
        for (int k = 0; k < 3; ++k)
            assert(fabs(n[k] - p[k]) < 1e-5);
    }
    for (uint32_t t = 0; t < 8; ++t) {
        const float* a = m->positions + 3 * m->indices[3 * t];
        const float* b = m->positions + 3 * m->indices[3 * t + 1];
        const float* c = m->positions + 3 * m->indices[3 * t + 2];
        double e1[3], e2[3], cen[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = b[k] - a[k];
            e2[k] = c[k] - a[k];
            cen[k] = (a[k] + b[k] + c[k]) / 3.0;
        }
        double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2],
               nz = e1[0] * e2[1] - e1[1] * e2[0];
        assert(nx * cen[0] + ny * cen[1] + nz * cen[2] > 0.0);
    }
}

static void reads_obj_off_ply_with_normals(void)
{
    const char* names[4] = {"octa.obj", "octa.off", "octa_ascii.ply", "octa_binary.ply"};
    for (int fmt = 0; fmt < 4; ++fmt) {
        write_octa(names[fmt], fmt);
        meso_mesh m;
        meso_error err = {0};
        uint32_t dropped = 99;
        meso_result r = meso_openmesh_read(tmp_path(names[fmt]), &m, &dropped, &err);
        if (r != MESO_OK)
            fprintf(stderr, "%s: %s\n", names[fmt], err.message);
        assert(r == MESO_OK);
        assert(dropped == 0);
        check_octa(&m);
        meso_mesh_free(&m);
        unlink(tmp_path(names[fmt]));
    }
}

static void sphere_normals_point_outwards(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data("sphere.obj"), &m, NULL, &err) == MESO_OK);
    assert(m.vertex_count == 642 && m.triangle_count == 1280);
    double worst = 1.0;
    for (uint32_t i = 0; i < m.vertex_count; ++i) {
        const float* p = m.positions + 3 * i;
        const float* n = m.normals + 3 * i;
        double d = (double)p[0] * n[0] + (double)p[1] * n[1] + (double)p[2] * n[2];
        worst = d < worst ? d : worst;
    }
    /* The icosphere's vertex normals deviate from the radial direction by well under a degree. */
    assert(worst > cos(1.0 * M_PI / 180.0));
    meso_mesh_free(&m);
}

/* A cube of quads, each mapped onto the unit square in listing order: every
 * vertex gets two or three uvs. Each triangle of a quad's fan must carry the
 * quad's uv at each of its corners (OpenMesh alone mislabels them). */
static void reads_corner_uvs_of_quads(void)
{
    static const float uvsq[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    static const uint32_t quads[6][4] = {{1, 4, 3, 2}, {5, 6, 7, 8}, {1, 2, 6, 5},
                                         {2, 3, 7, 6}, {3, 4, 8, 7}, {4, 1, 5, 8}};
    FILE* f = fopen(tmp_path("quads.obj"), "wb");
    assert(f);
    for (int i = 0; i < 8; ++i)
        fprintf(f, "v %d %d %d\n", i == 1 || i == 2 || i == 5 || i == 6 ? 1 : -1, i % 4 >= 2 ? 1 : -1, i >= 4 ? 1 : -1);
    for (int i = 0; i < 4; ++i)
        fprintf(f, "vt %g %g\n", uvsq[i][0], uvsq[i][1]);
    for (int q = 0; q < 6; ++q)
        fprintf(f, "f %u/1 %u/2 %u/3 %u/4\n", quads[q][0], quads[q][1], quads[q][2], quads[q][3]);
    fclose(f);
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(tmp_path("quads.obj"), &m, NULL, &err) == MESO_OK);
    assert(m.vertex_count == 8 && m.triangle_count == 12 && m.uvs && m.corner_uvs);
    for (uint32_t t = 0; t < 12; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t* q = quads[t / 2];
            const uint32_t v = m.indices[3 * t + (uint32_t)k];
            int i = 0;
            while (i < 4 && q[i] - 1 != v)
                ++i;
            assert(i < 4);
            assert(m.corner_uvs[6 * t + 2 * (uint32_t)k] == uvsq[i][0]);
            assert(m.corner_uvs[6 * t + 2 * (uint32_t)k + 1] == uvsq[i][1]);
        }
    meso_mesh_free(&m);
    unlink(tmp_path("quads.obj"));
}

/* One uv per vertex (saddle.obj: vt k with vertex k' throughout): no seam, so
 * no corner uvs; no uvs at all (sphere.obj): neither. */
static void corner_uvs_only_at_seams(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data("saddle.obj"), &m, NULL, &err) == MESO_OK);
    assert(m.uvs && !m.corner_uvs);
    meso_mesh_free(&m);
    assert(meso_openmesh_read(test_data("sphere.obj"), &m, NULL, &err) == MESO_OK);
    assert(!m.uvs && !m.corner_uvs);
    meso_mesh_free(&m);
    assert(meso_openmesh_read(test_data("cube_no_bottom.obj"), &m, NULL, &err) == MESO_OK);
    assert(m.uvs && m.corner_uvs);
    meso_mesh_free(&m);
}

static void missing_and_malformed_files_fail_cleanly(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(tmp_path("does_not_exist.obj"), &m, NULL, &err) != MESO_OK);
    assert(err.message[0] != '\0');
    assert(m.positions == NULL);
    FILE* f = fopen(tmp_path("empty.off"), "wb");
    assert(f);
    fclose(f);
    assert(meso_openmesh_read(tmp_path("empty.off"), &m, NULL, &err) != MESO_OK);
    assert(m.positions == NULL);
    unlink(tmp_path("empty.off"));
}

int main(void)
{
    snprintf(tmpdir, sizeof(tmpdir), "/tmp/meso_test_openmesh_XXXXXX");
    assert(mkdtemp(tmpdir));
    TEST_RUN(reads_obj_off_ply_with_normals);
    TEST_RUN(sphere_normals_point_outwards);
    TEST_RUN(reads_corner_uvs_of_quads);
    TEST_RUN(corner_uvs_only_at_seams);
    TEST_RUN(missing_and_malformed_files_fail_cleanly);
    rmdir(tmpdir);
    return 0;
}
