/* test_shell_bend.c — directors that bend before they shrink
 * (bake/shell_bend.c), on the bundled sphere, both sides:
 *  - known answer: normal displacement of the allowed thickness is a valid
 *    shell there, so a director shortened to 5 % and tilted 30 degrees off
 *    its normal gets back the whole allowed length and nothing else moves
 *  - one that must turn: a neighbour cut short makes its own direction at
 *    full length invert a prism, the normal's does not (setup checked): it
 *    gets the whole length, nearer the normal;
 *  - invariants on many shortened, tilted directors at once: the result
 *    passes the whole-shell validation (meso_shell_validate, not the
 *    incremental checker the bend uses), no director gets shorter or longer
 *    than allowed, only the vertices asked may change, and 1 and 2 threads
 *    and a checker the caller has already used give the same bits. */
#include "test_util.h"

#include <string.h>

#include "shell_allowed.h"
#include "test_mesh.h"
#include "shell_bend.h"
#include "shell_checker.h"
#include "shell_directors.h"
#include "shell_validate.h"

static double len3f(const float* v)
{
    return sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
}

/* Whole-shell validation: no inverted prism and no intersection. */
static int valid(const meso_mesh* m, const float* d, double h, int sign)
{
    meso_shell_report rep;
    meso_error err;
    memset(&err, 0, sizeof(err));
    assert(meso_shell_validate(m, d, NULL, h, sign, NULL, &rep, &err) == MESO_OK);
    return rep.inverted_prisms == 0 && rep.offset_self_intersections == 0 && rep.offset_base_intersections == 0;
}

/* Director of v: length l, turned by `deg` degrees from sign·n_v towards
 * a tangent (the direction to v's first neighbour, projected). */
static void tilted(const meso_mesh* m, const float* normals, uint32_t v, int sign, double deg, double l, float* out)
{
    uint32_t u = v;
    for (uint32_t f = 0; f < m->triangle_count && u == v; ++f)
        for (int k = 0; k < 3; ++k)
            if (m->indices[3 * f + k] == v)
                u = m->indices[3 * f + (k + 1) % 3];
    const float* n = normals + 3 * (size_t)v;
    double t[3], tn = 0, tl = 0;
    for (int k = 0; k < 3; ++k)
        t[k] = m->positions[3 * (size_t)u + k] - m->positions[3 * (size_t)v + k];
    for (int k = 0; k < 3; ++k)
        tn += t[k] * n[k];
    for (int k = 0; k < 3; ++k)
        t[k] -= tn * n[k], tl += t[k] * t[k];
    tl = sqrt(tl);
    const double a = deg * M_PI / 180.0;
    for (int k = 0; k < 3; ++k)
        out[k] = (float)(l * (cos(a) * sign * n[k] + sin(a) * t[k] / tl));
}

typedef struct sphere_case {
    meso_mesh m;
    float* normals;
    double* allowed;
    float* d; /* sign · allowed · n: valid */
    double h;
} sphere_case;

static void sphere_case_make(sphere_case* c, int sign, double rel)
{
    memset(c, 0, sizeof(*c));
    const int loaded = test_load_mesh(test_data("sphere.obj"), &c->m);
    assert(loaded);
    const uint32_t nv = c->m.vertex_count;
    double lo[3], hi[3];
    meso_mesh_bounds(&c->m, lo, hi);
    c->h = rel * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                      (hi[2] - lo[2]) * (hi[2] - lo[2]));
    c->normals = malloc(sizeof(float) * 3 * nv);
    c->allowed = malloc(sizeof(double) * nv);
    c->d = malloc(sizeof(float) * 3 * nv);
    meso_error err;
    memset(&err, 0, sizeof(err));
    assert(c->normals && c->allowed && c->d && meso_vertex_normals(&c->m, c->normals, &err) == MESO_OK);
    assert(meso_shell_allowed(&c->m, c->normals, sign, c->h, 2, c->allowed, &err) == MESO_OK);
    for (uint32_t v = 0; v < nv; ++v)
        for (int k = 0; k < 3; ++k)
            c->d[3 * v + k] = (float)(sign * c->allowed[v] * c->normals[3 * v + k]);
    assert(valid(&c->m, c->d, c->h, sign));
}

static void sphere_case_free(sphere_case* c)
{
    free(c->normals), free(c->allowed), free(c->d);
    meso_mesh_free(&c->m);
}

/* Bends only v (everything else of d asked to stay): bend must change
 * exactly one director. Returns v's angle off its normal in degrees; *ratio
 * gets |d_v| / allowed_v. */
static double bend_one(const sphere_case* c, float* d, uint32_t v, int sign, double* ratio)
{
    const uint32_t nv = c->m.vertex_count;
    uint8_t* redo = calloc(nv, 1);
    assert(redo);
    redo[v] = 1;
    meso_error err;
    memset(&err, 0, sizeof(err));
    uint32_t bent = 0;
    assert(meso_shell_bend(&c->m, d, c->normals, c->allowed, sign, 2, redo, NULL, &bent, &err) == MESO_OK);
    assert(bent == 1);
    free(redo);
    const float* dv = d + 3 * v;
    const double l = len3f(dv);
    double cosn = 0;
    for (int k = 0; k < 3; ++k)
        cosn += sign * dv[k] * c->normals[3 * v + k] / l;
    *ratio = l / c->allowed[v];
    return acos(fmin(1.0, cosn)) * 180 / M_PI;
}

/* One director shortened and tilted: it gets the whole allowed length back. */
static void one_vertex(int sign)
{
    sphere_case c;
    sphere_case_make(&c, sign, sign > 0 ? 0.10 : 0.05);
    const uint32_t nv = c.m.vertex_count, v = 17;
    float* d = malloc(sizeof(float) * 3 * nv);
    assert(d);
    /* Tilted 30 degrees: valid at every length (45, 60 and 75 degrees are
     * valid at none here: the neighbours' prisms invert, checked by hand). */
    const double deg = 30.0, sh = 0.05;
    memcpy(d, c.d, sizeof(float) * 3 * nv);
    tilted(&c.m, c.normals, v, sign, deg, sh * c.allowed[v], d + 3 * v);
    assert(valid(&c.m, d, c.h, sign));
    double ratio = 0;
    const double off = bend_one(&c, d, v, sign, &ratio);
    printf("    %s: %.0f degrees off the normal at %.2f of allowed -> %.6f of allowed, %.1f degrees off\n",
           sign > 0 ? "exterior" : "interior", deg, sh, ratio, off);
    assert(fabs(ratio - 1.0) < 1e-5);
    assert(off < 60.0);
    assert(valid(&c.m, d, c.h, sign));
    for (uint32_t u = 0; u < nv; ++u)
        assert(u == v || memcmp(d + 3 * u, c.d + 3 * u, 3 * sizeof(float)) == 0);
    free(d);
    sphere_case_free(&c);
}

/* A director that must turn: v's neighbour u is cut short, so v's own
 * (tilted) direction at the whole allowed length inverts a prism they share,
 * while the normal at that length does not (setup, searched over the tilt
 * and u's length and checked by the whole-shell validation). Bend must give
 * v the whole allowed length in a direction nearer the normal than its
 * own. */
static void must_turn(int sign)
{
    sphere_case c;
    sphere_case_make(&c, sign, sign > 0 ? 0.10 : 0.05);
    const uint32_t nv = c.m.vertex_count, v = 17;
    uint32_t u = v;
    for (uint32_t f = 0; f < c.m.triangle_count && u == v; ++f)
        for (int k = 0; k < 3; ++k)
            if (c.m.indices[3 * f + k] == v)
                u = c.m.indices[3 * f + (k + 1) % 3];
    float* d = malloc(sizeof(float) * 3 * nv);
    assert(d);
    static const double tilts[] = {42.0, 44.0, 46.0, 48.0, 50.0, 52.0, 55.0, 60.0}, shorts[] = {0.02, 0.1, 0.3, 0.6};
    double deg = 0, su = 0;
    for (int i = 0; i < 8 && !deg; ++i)
        for (int j = 0; j < 4 && !deg; ++j) {
            memcpy(d, c.d, sizeof(float) * 3 * nv);
            for (int k = 0; k < 3; ++k)
                d[3 * u + k] *= (float)shorts[j];
            tilted(&c.m, c.normals, v, sign, tilts[i], c.allowed[v], d + 3 * v);
            const int own_full = valid(&c.m, d, c.h, sign);
            tilted(&c.m, c.normals, v, sign, 0.0, c.allowed[v], d + 3 * v);
            const int normal_full = valid(&c.m, d, c.h, sign);
            tilted(&c.m, c.normals, v, sign, tilts[i], 0.05 * c.allowed[v], d + 3 * v);
            if (!own_full && normal_full && valid(&c.m, d, c.h, sign))
                deg = tilts[i], su = shorts[j];
        }
    assert(deg > 0); /* the setup exists */
    float* before = malloc(sizeof(float) * 3 * nv);
    assert(before);
    memcpy(before, d, sizeof(float) * 3 * nv);
    double ratio = 0;
    const double off = bend_one(&c, d, v, sign, &ratio);
    printf("    %s: u at %.2f, v %.0f degrees off the normal at 0.05 -> %.6f of allowed, %.1f degrees off\n",
           sign > 0 ? "exterior" : "interior", su, deg, ratio, off);
    assert(fabs(ratio - 1.0) < 1e-5);
    assert(off < deg - 1.0);
    assert(valid(&c.m, d, c.h, sign));
    for (uint32_t w = 0; w < nv; ++w)
        assert(w == v || memcmp(d + 3 * w, before + 3 * w, 3 * sizeof(float)) == 0);
    free(d), free(before);
    sphere_case_free(&c);
}

/* Every 7th director shortened to 5-40 % and tilted 0-30 degrees, the
 * vertices asked every 7th from 0 and every 14th from 3 (some shortened ones
 * are not asked and must stay). */
static void many_vertices(int sign)
{
    sphere_case c;
    sphere_case_make(&c, sign, sign > 0 ? 0.10 : 0.05);
    const uint32_t nv = c.m.vertex_count;
    float* d0 = malloc(sizeof(float) * 3 * nv);
    float* d1 = malloc(sizeof(float) * 3 * nv);
    float* d2 = malloc(sizeof(float) * 3 * nv);
    uint8_t* redo = calloc(nv, 1);
    assert(d0 && d1 && d2 && redo);
    memcpy(d0, c.d, sizeof(float) * 3 * nv);
    uint32_t asked = 0;
    for (uint32_t v = 0; v < nv; v += 7) {
        tilted(&c.m, c.normals, v, sign, (double)(v * 37 % 31), (0.05 + 0.35 * (v % 5) / 4.0) * c.allowed[v],
               d0 + 3 * v);
        redo[v] = v % 14 == 0;
        asked += redo[v];
    }
    for (uint32_t v = 3; v < nv; v += 14)
        redo[v] = 1, ++asked; /* at full length already: nothing to do */
    assert(valid(&c.m, d0, c.h, sign));
    meso_error err;
    memset(&err, 0, sizeof(err));
    uint32_t bent1 = 0, bent2 = 0;
    memcpy(d1, d0, sizeof(float) * 3 * nv);
    memcpy(d2, d0, sizeof(float) * 3 * nv);
    assert(meso_shell_bend(&c.m, d1, c.normals, c.allowed, sign, 1, redo, NULL, &bent1, &err) == MESO_OK);
    assert(meso_shell_bend(&c.m, d2, c.normals, c.allowed, sign, 2, redo, NULL, &bent2, &err) == MESO_OK);
    assert(bent1 == bent2 && memcmp(d1, d2, sizeof(float) * 3 * nv) == 0);
    /* With the caller's checker, as a bake passes the one repair and
     * regrow used (its verdicts for d0 kept): the same bits. */
    float* d3 = malloc(sizeof(float) * 3 * nv);
    uint8_t* bad = malloc(c.m.triangle_count);
    meso_shell_checker* ck = NULL;
    uint32_t nbad = 0, bent3 = 0;
    assert(d3 && bad && meso_shell_checker_create(&c.m, sign, 2, &ck, &err) == MESO_OK);
    assert(meso_shell_checker_bad_faces(ck, d0, bad, &nbad, &err) == MESO_OK && nbad == 0);
    memcpy(d3, d0, sizeof(float) * 3 * nv);
    assert(meso_shell_bend(&c.m, d3, c.normals, c.allowed, sign, 2, redo, ck, &bent3, &err) == MESO_OK);
    assert(bent3 == bent1 && memcmp(d1, d3, sizeof(float) * 3 * nv) == 0);
    meso_shell_checker_destroy(ck);
    free(d3), free(bad);
    assert(valid(&c.m, d1, c.h, sign));
    uint32_t changed = 0, full = 0;
    double before = 0, after = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        const double l0 = len3f(d0 + 3 * v), l1 = len3f(d1 + 3 * v);
        const int moved = memcmp(d0 + 3 * v, d1 + 3 * v, 3 * sizeof(float)) != 0;
        assert(!moved || redo[v]);
        assert(l1 >= l0);
        assert(l1 <= c.allowed[v] * (1.0 + 1e-6));
        changed += moved;
        full += moved && l1 > c.allowed[v] * (1.0 - 1e-5);
        before += fmin(1.0, l0 / c.allowed[v]) / nv;
        after += fmin(1.0, l1 / c.allowed[v]) / nv;
    }
    printf("    %s: %u asked, %u bent (%u to the whole allowed length); mean achieved/allowed %.4f -> %.4f\n",
           sign > 0 ? "exterior" : "interior", asked, changed, full, before, after);
    assert(changed == bent1 && changed > 0 && after > before);
    free(d0), free(d1), free(d2), free(redo);
    sphere_case_free(&c);
}

static void exterior_one(void)
{
    one_vertex(1);
}
static void interior_one(void)
{
    one_vertex(-1);
}
static void exterior_turn(void)
{
    must_turn(1);
}
static void interior_turn(void)
{
    must_turn(-1);
}
static void exterior_many(void)
{
    many_vertices(1);
}
static void interior_many(void)
{
    many_vertices(-1);
}

int main(void)
{
    TEST_RUN(exterior_one);
    TEST_RUN(interior_one);
    TEST_RUN(exterior_turn);
    TEST_RUN(interior_turn);
    TEST_RUN(exterior_many);
    TEST_RUN(interior_many);
    return 0;
}
