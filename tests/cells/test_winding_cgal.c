/* The hierarchical winding-number classifier (bake/winding_number.c) against
 * CGAL's exact point-in-mesh (Side_of_triangle_mesh, bake/adapters) on the
 * bundled closed meshes: points spread over the grown bounding box, and
 * points just off the surface (each vertex moved along its normal by
 * +-1e-4 and +-1e-2 of the diagonal, where sign errors would show first).
 * On a closed, consistently oriented mesh the winding number is exactly 0 or
 * 1 off the surface, so the classifications must agree everywhere CGAL does
 * not report "on the surface": zero disagreements. */
#include "test_util.h"

#include <math.h>
#include <stdlib.h>

#include "adapters.h"
#include "winding_number.h"

#if MESO_HAVE_CGAL

static uint64_t rng = 0x9E3779B97F4A7C15ull;

static double rnd(void) /* splitmix64 -> [0, 1) */
{
    uint64_t z = (rng += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

static void check_mesh(const char* name)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(name), &m, NULL, &err) == MESO_OK);
    assert(m.normals != NULL);
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(&m, lo, hi);
    const size_t n_box = 20000, n_near = 4 * (size_t)m.vertex_count, n = n_box + n_near;
    double* p = malloc(sizeof(double) * 3 * n);
    assert(p);
    for (size_t i = 0; i < n_box; ++i)
        for (int k = 0; k < 3; ++k) {
            const double g = 0.1 * (hi[k] - lo[k]);
            p[3 * i + k] = lo[k] - g + (hi[k] - lo[k] + 2 * g) * rnd();
        }
    static const double offsets[4] = {1e-4, -1e-4, 1e-2, -1e-2};
    for (size_t v = 0; v < m.vertex_count; ++v)
        for (int o = 0; o < 4; ++o)
            for (int k = 0; k < 3; ++k)
                p[3 * (n_box + 4 * v + (size_t)o) + k] =
                    m.positions[3 * v + (size_t)k] + offsets[o] * diag * m.normals[3 * v + (size_t)k];

    meso_cgal_inside* exact = NULL;
    assert(meso_cgal_inside_create(&m, &exact, &err) == MESO_OK);
    int8_t* side = malloc(n);
    assert(side && meso_cgal_inside_query(exact, p, n, side, &err) == MESO_OK);
    meso_winding* wn = NULL;
    assert(meso_winding_build(&m, 0, &wn, &err) == MESO_OK);
    double* w = malloc(sizeof(double) * n);
    assert(w);
    meso_winding_query_many(wn, p, n, w, 0);

    size_t on = 0, inside = 0, disagree = 0;
    double margin = INFINITY; /* smallest |w - 0.5| over the compared points */
    for (size_t i = 0; i < n; ++i) {
        if (side[i] == 0) {
            ++on;
            continue;
        }
        inside += side[i] > 0;
        disagree += meso_winding_inside(w[i]) != (side[i] > 0);
        margin = fmin(margin, fabs(w[i] - 0.5));
    }
    fprintf(stderr,
            "    %-28s %6zu points (%zu inside, %zu on the surface): %zu disagree with CGAL; "
            "smallest |w - 1/2| %.3f\n",
            name, n, inside, on, disagree, margin);
    assert(disagree == 0);
    assert(inside > n / 20); /* both sides are exercised */

    free(w);
    free(side);
    free(p);
    meso_winding_free(wn);
    meso_cgal_inside_destroy(exact);
    meso_mesh_free(&m);
}

int main(void)
{
    check_mesh("sphere.obj");
    check_mesh("torus.obj");
    check_mesh("spot_low_resolution.obj");
    check_mesh("spot_uv.obj");
    check_mesh("blub_fish_low_resolution.obj");
    fprintf(stderr, "winding numbers agree with CGAL's exact point-in-mesh\n");
    return 0;
}

#else
int main(void)
{
    fprintf(stderr, "built without CGAL: skipped\n");
    return 77; /* meson: skipped */
}
#endif
