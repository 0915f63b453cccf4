/* Draco adapter: a mesh round-trips within its quantisation error, keeps its
 * vertex order and connectivity (sequential encoding), and garbage input is
 * an error, not a crash. */
#include "test_util.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "adapters.h"

/* Draco quantises each attribute over its bounding cube: the largest
 * per-component error is half a step, extent / (2^bits - 1) / 2. */
static double max_abs_err(const float* a, const float* b, size_t n)
{
    double e = 0;
    for (size_t i = 0; i < n; ++i)
        e = fmax(e, fabs((double)a[i] - (double)b[i]));
    return e;
}

static double extent(const float* a, size_t n, int comps)
{
    double e = 0;
    for (int k = 0; k < comps; ++k) {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < n; ++i) {
            lo = fmin(lo, a[i * (size_t)comps + (size_t)k]);
            hi = fmax(hi, a[i * (size_t)comps + (size_t)k]);
        }
        e = fmax(e, hi - lo);
    }
    return e;
}

static void roundtrip(const char* file, int bits)
{
    meso_mesh m, d;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(file), &m, NULL, &err) == MESO_OK);
    meso_draco_options o = {bits, 12, 12, 5};
    void* buf = NULL;
    size_t size = 0;
    assert(meso_draco_encode(&m, &o, &buf, &size, &err) == MESO_OK);
    assert(size > 0 && size < (size_t)m.vertex_count * 24 + (size_t)m.triangle_count * 12);
    assert(meso_draco_decode(buf, size, &d, &err) == MESO_OK);
    assert(d.vertex_count == m.vertex_count && d.triangle_count == m.triangle_count);
    assert(memcmp(d.indices, m.indices, (size_t)m.triangle_count * 12) == 0);
    const double step = extent(m.positions, m.vertex_count, 3) / (double)((1 << bits) - 1);
    const double e = max_abs_err(m.positions, d.positions, (size_t)m.vertex_count * 3);
    /* Half a step, plus the float rounding of Draco's dequantisation
     * (min + q * step in float: two roundings, each at most half an ulp of
     * the largest coordinate). At 24 bits the step is already below that
     * ulp: the rounding is most of the error (MESO_DRACO_MAX_BITS). */
    double big = 0;
    for (size_t i = 0; i < (size_t)m.vertex_count * 3; ++i)
        big = fmax(big, fabs((double)m.positions[i]));
    assert(e <= 0.5 * step * 1.0001 + 2.0 * FLT_EPSILON * big);
    assert(d.normals != NULL);
    /* Normals are quantised on the octahedron: 12 bits keep them within ~0.2 degrees. */
    for (uint32_t i = 0; i < m.vertex_count; ++i) {
        double dot = 0;
        for (int k = 0; k < 3; ++k)
            dot += (double)m.normals[3 * i + k] * d.normals[3 * i + k];
        assert(dot > cos(0.5 * M_PI / 180.0));
    }
    free(buf);
    meso_mesh_free(&m);
    meso_mesh_free(&d);
}

static void roundtrip_within_quantisation(void)
{
    roundtrip("sphere.obj", 14);
    roundtrip("spot_low_resolution.obj", 11);
    roundtrip("torus.obj", 8);
    roundtrip("spot_low_resolution.obj", MESO_DRACO_MAX_BITS); /* the most meso asks (meso_bake.h) */
}

/* Bits above MESO_DRACO_MAX_BITS (or below the least) for any attribute
 * are refused before Draco runs (at 30 one attribute of the sphere cost
 * Draco 4.2 GB), with a message that names the range. */
static void bits_outside_the_range_are_refused(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data("sphere.obj"), &m, NULL, &err) == MESO_OK);
    const int most = MESO_DRACO_MAX_BITS;
    char range[16];
    snprintf(range, sizeof range, "1..%d", most);
    const meso_draco_options bad[] = {{most + 1, 10, 12, 7}, {14, most + 1, 12, 7}, {14, 10, most + 1, 7},
                                      {14, 1, 12, 7}, {30, 30, 30, 7}}; /* (0: the default) */
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        void* buf = NULL;
        size_t size = 0;
        memset(&err, 0, sizeof err);
        const meso_draco_options o = bad[i];
        assert(meso_draco_encode(&m, &o, &buf, &size, &err) == MESO_ERR_INVALID_ARG);
        assert(buf == NULL && strstr(err.message, range) != NULL);
    }
    meso_mesh_free(&m);
}

static void garbage_is_an_error(void)
{
    meso_mesh d;
    meso_error err = {0};
    uint8_t junk[256];
    uint64_t rng = 42;
    for (size_t i = 0; i < sizeof(junk); ++i)
        junk[i] = (uint8_t)test_rng_next(&rng);
    assert(meso_draco_decode(junk, sizeof(junk), &d, &err) != MESO_OK);
    assert(d.positions == NULL);
    memcpy(junk, "DRACO", 5);
    assert(meso_draco_decode(junk, sizeof(junk), &d, &err) != MESO_OK);
    assert(meso_draco_decode(junk, 0, &d, &err) != MESO_OK);
}

int main(void)
{
    TEST_RUN(roundtrip_within_quantisation);
    TEST_RUN(garbage_is_an_error);
    TEST_RUN(bits_outside_the_range_are_refused);
    return 0;
}
