/* CGAL adapter: exact point-in-mesh on the unit sphere and the torus against
 * the analytic shapes, on fixed and on random points. */
#include "test_util.h"

#include "adapters.h"
#include "shapes.h"

typedef int (*class_fn)(const double p[3]);

static void check_mesh(const char* file, class_fn cls, const double fixed_in[][3], int n_in,
                       const double fixed_out[][3], int n_out)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(file), &m, NULL, &err) == MESO_OK);
    meso_cgal_inside* t = NULL;
    meso_result r = meso_cgal_inside_create(&m, &t, &err);
    if (r != MESO_OK)
        fprintf(stderr, "%s\n", err.message);
    assert(r == MESO_OK);
    int8_t side;
    for (int i = 0; i < n_in; ++i) {
        assert(meso_cgal_inside_query(t, fixed_in[i], 1, &side, &err) == MESO_OK);
        assert(side == 1);
    }
    for (int i = 0; i < n_out; ++i) {
        assert(meso_cgal_inside_query(t, fixed_out[i], 1, &side, &err) == MESO_OK);
        assert(side == -1);
    }
    /* Random points in the bounding cube, classified analytically. */
    enum { N = 20000 };
    static double pts[3 * N];
    static int8_t sides[N];
    uint64_t rng = 0x9E3779B97F4A7C15ULL;
    for (int i = 0; i < 3 * N; ++i)
        pts[i] = test_rng_uniform(&rng, -1.4, 1.4);
    assert(meso_cgal_inside_query(t, pts, N, sides, &err) == MESO_OK);
    int checked = 0;
    for (int i = 0; i < N; ++i) {
        int c = cls(pts + 3 * i);
        if (c == 0)
            continue;
        assert(sides[i] == c);
        ++checked;
    }
    assert(checked > N / 2);
    meso_cgal_inside_destroy(t);
    meso_mesh_free(&m);
}

static void sphere_inside_outside(void)
{
    const double in[][3] = {{0, 0, 0}, {0.5, 0.5, 0.5}, {0, -0.96, 0}};
    const double out[][3] = {{2, 0, 0}, {0.6, 0.6, 0.6}, {0, 0, -1.02}};
    check_mesh("sphere.obj", sphere_class, in, 3, out, 3);
}

static void torus_inside_outside(void)
{
    const double in[][3] = {{1, 0, 0}, {0, 0.1, -1}, {-0.8, 0, 0}};
    const double out[][3] = {{0, 0, 0}, {1, 0.3, 0}, {0, 0, 1.3}};
    check_mesh("torus.obj", torus_class, in, 3, out, 3);
}

static void open_mesh_is_refused(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data("cube_no_bottom.obj"), &m, NULL, &err) == MESO_OK);
    meso_cgal_inside* t = NULL;
    assert(meso_cgal_inside_create(&m, &t, &err) == MESO_ERR_CORRUPT);
    assert(t == NULL);
    assert(err.message[0] != '\0');
    meso_mesh_free(&m);
}

int main(void)
{
    TEST_RUN(sphere_inside_outside);
    TEST_RUN(torus_inside_outside);
    TEST_RUN(open_mesh_is_refused);
    return 0;
}
