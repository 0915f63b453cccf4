/* A shell's stand-ins carry baked normals (issue 14: "the plain base mesh
 * with baked normal/colour"; bake/standin_appearance.h): each stand-in
 * vertex's normal is the hat-weighted mean of the unit normals of the
 * surface level 0 draws over that vertex's part of the mesh, normalised.
 *
 * The case: a flat G x G grid of the unit square (open; normals +z,
 * uv = xy) under a 16-bit height field h(s, t) = 1/2 + 2/5 sin 2πs, as an
 * exterior shell 0.2 thick (mesobake shell --texture height:FILE
 * --thickness 0.2). Level 0 is a wave whose slope reaches 0.2 · 0.8π ≈ 0.5
 * (27°) where the stand-in itself is flat: its own normals are all +z.
 *
 * The expectation is brute force, independent of the bake's sampling,
 * texture and derivation (the bake: the implicit gradient of w − h by
 * central differences on the texels, carried by Φ's inverse transpose
 * Jacobian; here: the parametric surface x(b) = Σ b_k (bottom_k + h
 * span_k) with the analytic h and its analytic derivative, and the cross
 * product of ∂x/∂b1 and ∂x/∂b2), Φ built from the file's SDIR: for each
 * vertex, over 32 x 32 sub-triangles of every triangle around it.
 * Asserted:
 *  - level 1 (the first mesh stand-in): every vertex within 0.5° of it,
 *    and the wave is there (the largest expected tilt is over 20°, which
 *    the mesh's own normals would miss by as much);
 *  - the simplified levels: every vertex within 2° of the same mean over
 *    its own, larger, triangles (they average level 1's normals, which
 *    are already a mean over a smaller part);
 *  - the parts' stand-in patches (PMSH at part lod 1) carry level 1's
 *    normals, vertex for vertex;
 *  - level 0's MESH keeps the input's normals (FORMAT.md §7.2: the normals
 *    the directors started from).
 * usage: test_shell_standin_normals MESOBAKE */
#include "test_util.h"

#include <math.h>
#include <string.h>

#include "meso_file.h"
#include "meso_layout.h"
#include "png_io.h"
#include "standin_check.h"

enum { G = 32, TEX = 256, SUB = 32 };

static double h_of(double s) { return 0.5 + 0.4 * sin(2 * M_PI * s); }
static double dh_ds(double s) { return 0.4 * 2 * M_PI * cos(2 * M_PI * s); }

/* The unit-square grid as OBJ, and the height field as a 16-bit PNG. */
static void write_inputs(const char* dir)
{
    char path[512];
    snprintf(path, sizeof path, "%s/plane.obj", dir);
    FILE* f = fopen(path, "w");
    assert(f);
    for (int j = 0; j <= G; ++j)
        for (int i = 0; i <= G; ++i)
            fprintf(f, "v %.9g %.9g 0\nvt %.9g %.9g\nvn 0 0 1\n", (double)i / G, (double)j / G, (double)i / G,
                    (double)j / G);
    for (int j = 0; j < G; ++j)
        for (int i = 0; i < G; ++i) {
            const int a = j * (G + 1) + i + 1, b = a + 1, c = a + G + 1, d = c + 1;
            fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d\nf %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, b, b, b, d, d, d, a,
                    a, a, d, d, d, c, c, c);
        }
    fclose(f);
    uint16_t* v = malloc(sizeof(uint16_t) * TEX * TEX);
    assert(v);
    for (int y = 0; y < TEX; ++y)
        for (int x = 0; x < TEX; ++x) /* texel centres at (x + 1/2) / TEX */
            v[y * TEX + x] = (uint16_t)lrint(65535.0 * h_of((x + 0.5) / TEX));
    snprintf(path, sizeof path, "%s/wave.png", dir);
    char why[256];
    assert(meso_png_write_gray(path, v, TEX, TEX, 16, why, sizeof why) == 0);
    free(v);
}

/* Φ over the unit square from the file: grid vertex v's bottom is its
 * position, its span SDIR's top offset (an exterior shell). */
typedef struct wave {
    float* sdir; /* 3 per grid vertex */
} wave;

/* x(s, t) on the level 0 surface and its unit normal, for a point (s, t)
 * of the plane: in the grid triangle holding it, Φ's barycentric
 * interpolation with the analytic h. */
static void surface_normal(const wave* w, double s, double t, double n[3])
{
    int i = (int)floor(s * G), j = (int)floor(t * G);
    i = i < 0 ? 0 : i >= G ? G - 1 : i;
    j = j < 0 ? 0 : j >= G ? G - 1 : j;
    const double fx = s * G - i, fy = t * G - j;
    /* the two triangles (a, b, d) below the diagonal, (a, d, c) above */
    const int a = j * (G + 1) + i, b = a + 1, c = a + G + 1, d = c + 1;
    const int upper = fy > fx;
    const int v[3] = {a, upper ? d : b, upper ? c : d};
    double P[3][3], S[3][3], st[3][2];
    for (int k = 0; k < 3; ++k) {
        st[k][0] = (double)(v[k] % (G + 1)) / G;
        st[k][1] = (double)(v[k] / (G + 1)) / G;
        for (int q = 0; q < 3; ++q)
            S[k][q] = w->sdir[3 * v[k] + q];
        P[k][0] = st[k][0];
        P[k][1] = st[k][1];
        P[k][2] = 0;
    }
    /* barycentrics of (s, t) */
    const double e1[2] = {st[1][0] - st[0][0], st[1][1] - st[0][1]}, e2[2] = {st[2][0] - st[0][0], st[2][1] - st[0][1]};
    const double det = e1[0] * e2[1] - e1[1] * e2[0];
    const double b1 = ((s - st[0][0]) * e2[1] - (t - st[0][1]) * e2[0]) / det;
    const double b2 = (e1[0] * (t - st[0][1]) - e1[1] * (s - st[0][0])) / det;
    const double bb[3] = {1 - b1 - b2, b1, b2};
    const double h = h_of(s), hs = dh_ds(s);
    double xb[2][3], span[3] = {0, 0, 0};
    for (int q = 0; q < 3; ++q)
        for (int k = 0; k < 3; ++k)
            span[q] += bb[k] * S[k][q];
    for (int k = 1; k < 3; ++k) {
        const double dh = hs * (st[k][0] - st[0][0]); /* h depends on s alone */
        for (int q = 0; q < 3; ++q)
            xb[k - 1][q] = (P[k][q] + h * S[k][q]) - (P[0][q] + h * S[0][q]) + dh * span[q];
    }
    n[0] = xb[0][1] * xb[1][2] - xb[0][2] * xb[1][1];
    n[1] = xb[0][2] * xb[1][0] - xb[0][0] * xb[1][2];
    n[2] = xb[0][0] * xb[1][1] - xb[0][1] * xb[1][0];
    const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double o = n[0] * span[0] + n[1] * span[1] + n[2] * span[2] < 0 ? -1 : 1; /* towards w = 1 */
    for (int q = 0; q < 3; ++q)
        n[q] *= o / len;
}

/* Per vertex of the mesh `mv` (on the plane z = 0 up to rounding), the
 * hat-weighted mean unit normal of level 0 over its triangles,
 * normalised, into exp (3 per vertex). */
static void expected_normals(const wave* w, const meso_mesh_view* mv, double* exp)
{
    const uint32_t nv = mv->layout.vertex_count, nt = mv->layout.index_count / 3;
    memset(exp, 0, sizeof(double) * 3 * nv);
    for (uint32_t t = 0; t < nt; ++t) {
        const uint32_t* ix = mv->indices + 3 * t;
        const float* p[3] = {mv->positions + 3 * ix[0], mv->positions + 3 * ix[1], mv->positions + 3 * ix[2]};
        const double area = 0.5 * fabs(((double)p[1][0] - p[0][0]) * ((double)p[2][1] - p[0][1]) -
                                       ((double)p[1][1] - p[0][1]) * ((double)p[2][0] - p[0][0]));
        for (int j = 0; j < SUB; ++j)
            for (int i = 0; i + j < SUB; ++i)
                for (int inv = 0; inv < 2; ++inv) {
                    if (inv && i + j >= SUB - 1)
                        continue;
                    const double off = inv ? 2.0 / 3.0 : 1.0 / 3.0;
                    const double b1 = (i + off) / SUB, b2 = (j + off) / SUB, b[3] = {1 - b1 - b2, b1, b2};
                    const double s = b[0] * p[0][0] + b[1] * p[1][0] + b[2] * p[2][0];
                    const double tt = b[0] * p[0][1] + b[1] * p[1][1] + b[2] * p[2][1];
                    double n[3];
                    surface_normal(w, s, tt, n);
                    for (int c = 0; c < 3; ++c)
                        for (int q = 0; q < 3; ++q)
                            exp[3 * ix[c] + q] += b[c] * area * n[q];
                }
    }
    for (uint32_t v = 0; v < nv; ++v) {
        double* e = exp + 3 * v;
        const double len = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        for (int q = 0; q < 3; ++q)
            e[q] = len > 0 ? e[q] / len : 0;
    }
}

static double angle_deg(const double* e, const float* n)
{
    const double ln = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
    const double c = (e[0] * n[0] + e[1] * n[1] + e[2] * n[2]) / ln;
    return acos(c > 1 ? 1 : c < -1 ? -1 : c) * 180 / M_PI;
}

/* The largest angle between a stand-in level's normals and the expected
 * ones; *tilt the largest expected tilt from +z. */
static double level_worst(const wave* w, const meso_mesh_view* mv, double* tilt)
{
    const uint32_t nv = mv->layout.vertex_count;
    double* exp = malloc(sizeof(double) * 3 * nv);
    assert(exp && mv->normals);
    expected_normals(w, mv, exp);
    double worst = 0;
    *tilt = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        if (exp[3 * v] == 0 && exp[3 * v + 1] == 0 && exp[3 * v + 2] == 0)
            continue; /* on no triangle with area */
        worst = fmax(worst, angle_deg(exp + 3 * v, mv->normals + 3 * v));
        *tilt = fmax(*tilt, acos(fmin(1, fabs(exp[3 * v + 2]))) * 180 / M_PI);
    }
    free(exp);
    return worst;
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    setvbuf(stdout, NULL, _IONBF, 0);
    char dir[256], in[512], tex[600];
    test_temp_dir(dir, sizeof dir, "standin_normals");
    write_inputs(dir);
    snprintf(in, sizeof in, "%s/plane.obj", dir);
    snprintf(tex, sizeof tex, "--texture height:%s/wave.png --thickness 0.2", dir);
    meso_file* f = test_bake_open(argv[1], "shell", in, tex, dir, "wave", NULL);

    wave w = {0};
    const int32_t si = meso_file_find(f, MESO_CHUNK_SDIR, 1, UINT16_MAX);
    assert(si >= 0);
    const meso_chunk_info* sc = meso_file_chunk(f, (uint32_t)si);
    assert(sc->dims[0] == (G + 1) * (G + 1) && sc->dims[1] == 1); /* exterior: one layer */
    w.sdir = malloc((size_t)sc->decoded_size);
    assert(w.sdir && meso_file_read_chunk(f, (uint32_t)si, w.sdir, (size_t)sc->decoded_size, NULL) == MESO_OK);

    meso_level_info li[16];
    uint32_t first = 0;
    const uint32_t n = test_standin_chain(f, li, 3, &first);
    printf("plane under a wave: %u levels, stand-ins from level %u\n", n, first);
    for (uint32_t L = first; L < n; ++L) {
        meso_mesh_view mv;
        uint8_t* mb = test_read_level_mesh(f, (uint16_t)L, &mv);
        double tilt = 0;
        const double worst = level_worst(&w, &mv, &tilt);
        printf("  level %u: %u vertices, normals within %.3f deg of the mean surface normal (largest tilt %.1f deg)\n",
               L, mv.layout.vertex_count, worst, tilt);
        if (L == first) {
            assert(worst <= 0.5);
            assert(tilt > 20); /* what the mesh's own normals (+z) would miss */
            /* The parts' patches at part lod 1: level 1's normals, vertex by vertex (by position). */
            uint32_t patches = 0;
            for (uint32_t c = 0; c < meso_file_chunk_count(f); ++c) {
                const meso_chunk_info* ci = meso_file_chunk(f, c);
                if (ci->type != MESO_CHUNK_PMSH || ci->lod != 1)
                    continue;
                uint8_t* pb = malloc((size_t)ci->decoded_size);
                meso_mesh_view pv;
                assert(pb && meso_file_read_chunk(f, c, pb, (size_t)ci->decoded_size, NULL) == MESO_OK);
                assert(meso_mesh_parse(pb, (size_t)ci->decoded_size, &pv, NULL) == MESO_OK && pv.normals);
                for (uint32_t v = 0; v < pv.layout.vertex_count; ++v) {
                    uint32_t u = 0;
                    while (u < mv.layout.vertex_count && memcmp(mv.positions + 3 * u, pv.positions + 3 * v, 12))
                        ++u;
                    assert(u < mv.layout.vertex_count && !memcmp(mv.normals + 3 * u, pv.normals + 3 * v, 12));
                }
                ++patches;
                free(pb);
            }
            printf("  %u part patches carry level %u's normals\n", patches, L);
            assert(patches >= 2);
        } else {
            assert(worst <= 2.0);
        }
        free(mb);
    }
    /* Level 0's MESH: the input's normals. */
    meso_mesh_view m0;
    uint8_t* b0 = test_read_level_mesh(f, (uint16_t)(first - 1), &m0);
    for (uint32_t v = 0; v < m0.layout.vertex_count; ++v)
        assert(m0.normals[3 * v] == 0 && m0.normals[3 * v + 1] == 0 && m0.normals[3 * v + 2] == 1);
    free(b0);
    free(w.sdir);
    meso_file_close(f);
    test_temp_dir_remove(dir);
    puts("test_shell_standin_normals: ok");
    return 0;
}
