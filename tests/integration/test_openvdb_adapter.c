/* OpenVDB adapter: a narrow-band level set of a closed mesh has the right
 * sign inside and outside (analytic sphere and torus) and, near the surface,
 * the right distance. */
#include "test_util.h"

#include "adapters.h"
#include "shapes.h"

typedef int (*class_fn)(const double p[3]);

static void check_sign(const char* file, class_fn cls)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(file), &m, NULL, &err) == MESO_OK);
    const double voxel = 0.02;
    meso_vdb_grid* g = NULL;
    assert(meso_vdb_level_set(&m, voxel, 3.0f, &g, &err) == MESO_OK);
    assert(meso_vdb_active_voxels(g) > 0);
    enum { N = 20000 };
    static double pts[3 * N];
    static float d[N];
    uint64_t rng = 12345;
    for (int i = 0; i < 3 * N; ++i)
        pts[i] = test_rng_uniform(&rng, -1.4, 1.4);
    assert(meso_vdb_sample(g, pts, N, d, &err) == MESO_OK);
    int checked = 0;
    for (int i = 0; i < N; ++i) {
        int c = cls(pts + 3 * i);
        if (c == 0)
            continue;
        assert(c == 1 ? d[i] < 0.0f : d[i] > 0.0f);
        ++checked;
    }
    assert(checked > N / 2);
    meso_vdb_destroy(g);
    meso_mesh_free(&m);
}

static void sphere_sign(void)
{
    check_sign("sphere.obj", sphere_class);
}

static void torus_sign(void)
{
    check_sign("torus.obj", torus_class);
}

/* Inside the narrow band the value is the distance to the unit sphere, up to
 * a voxel (trilinear interpolation of voxel-centre distances) plus the
 * icosphere's 0.002 tessellation gap. */
static void sphere_distance_near_surface(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data("sphere.obj"), &m, NULL, &err) == MESO_OK);
    const double voxel = 0.02;
    meso_vdb_grid* g = NULL;
    assert(meso_vdb_level_set(&m, voxel, 3.0f, &g, &err) == MESO_OK);
    uint64_t rng = 777;
    for (int i = 0; i < 2000; ++i) {
        double dir[3], len = 0;
        for (int k = 0; k < 3; ++k) {
            dir[k] = test_rng_uniform(&rng, -1, 1);
            len += dir[k] * dir[k];
        }
        len = sqrt(len);
        if (len < 1e-3)
            continue;
        double radius = 1.0 + test_rng_uniform(&rng, -0.03, 0.03);
        double p[3] = {dir[0] / len * radius, dir[1] / len * radius, dir[2] / len * radius};
        float dist;
        assert(meso_vdb_sample(g, p, 1, &dist, &err) == MESO_OK);
        assert(fabs(dist - (radius - 1.0)) < voxel + 0.003);
    }
    meso_vdb_destroy(g);
    meso_mesh_free(&m);
}

int main(void)
{
    TEST_RUN(sphere_sign);
    TEST_RUN(torus_sign);
    TEST_RUN(sphere_distance_near_surface);
    return 0;
}
