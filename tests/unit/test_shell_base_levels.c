/*
 * test_shell_base_levels.c — a shell's coarser base meshes
 * (bake/shell_base_levels.c, issue 14), on torus_uv.obj with a thick brick
 * shell, where one beats the mid-surface stand-in:
 *
 * - the bake writes at least one native level with a MESH of its own, whose
 *   SDIR and STHK match its vertex count, between level 0 and the stand-in;
 *   the file validates (full tier); 1 and 2 threads give the same bytes;
 * - its stated error, minus the texture level's it shares, bounds the
 *   largest |Φ_level − Φ_0| found by brute force (points in texture space:
 *   every level-0 vertex, points along every edge and inside every
 *   triangle, located in the coarse mesh's uv triangles by a search over
 *   all of them, w = 0 and 1), and is within 10 % of it (the bound is a
 *   maximum over the overlay's vertices, not a guess);
 * - every kept vertex keeps its position, uv and directors bit for bit;
 * - spot_uv.obj with a thin shell gets none (a collapse slides the texture
 *   farther than the mid-surface stand-in is off), and says why not or
 *   that the chain ended.
 */
#include "test_util.h"
#include "bake_bytes.h"

#include <math.h>
#include <string.h>

#include "meso_bake.h"
#include "meso_file.h"

static uint8_t* bake(const char* name, double thickness_rel, int threads, size_t* size)
{
    meso_bake_shell_options o = meso_bake_shell_defaults();
    char path[512];
    snprintf(path, sizeof path, "%s/%s", MESO_TEST_DATA, name);
    o.input = path;
    o.texture = "bricks:64";
    o.thickness_rel = thickness_rel;
    o.common.threads = threads;
    meso_bake_output* out = NULL;
    meso_error err = {0};
    const meso_result r = meso_bake_shell(&o, &out, NULL, &err);
    if (r != MESO_OK)
        fprintf(stderr, "    bake: %s\n", err.message);
    assert(r == MESO_OK);
    return bake_bytes(out, size);
}

static int count_issue(void* user, const meso_error* issue)
{
    fprintf(stderr, "    issue %u: %s\n", issue->code, issue->message);
    ++*(int*)user;
    return 0;
}

static void* read_chunk(meso_file* f, int32_t i, size_t* size)
{
    assert(i >= 0);
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)i);
    void* p = malloc(c->decoded_size ? c->decoded_size : 1);
    meso_error err;
    assert(p && meso_file_read_chunk(f, (uint32_t)i, p, c->decoded_size, &err) == MESO_OK);
    *size = c->decoded_size;
    return p;
}

/* A level's shell as the runtime builds it (rt_shell.c fill_vertex_texels). */
typedef struct shell {
    void *mesh_data, *sdir_data;
    meso_mesh_view v;
    const float* sdir;
    uint32_t layers;
} shell;

static shell shell_at(meso_file* f, uint16_t lod)
{
    shell s;
    size_t size;
    meso_error err;
    s.mesh_data = read_chunk(f, meso_file_find_level(f, MESO_CHUNK_MESH, 1, lod), &size);
    assert(meso_mesh_parse(s.mesh_data, size, &s.v, &err) == MESO_OK && s.v.uvs);
    const int32_t di = meso_file_find_level(f, MESO_CHUNK_SDIR, 1, lod);
    s.sdir_data = read_chunk(f, di, &size);
    s.sdir = s.sdir_data;
    s.layers = meso_file_chunk(f, (uint32_t)di)->dims[1];
    assert(meso_file_chunk(f, (uint32_t)di)->dims[0] == s.v.layout.vertex_count);
    const int32_t ti = meso_file_find_level(f, MESO_CHUNK_STHK, 1, lod);
    assert(ti >= 0 && meso_file_chunk(f, (uint32_t)ti)->dims[0] == s.v.layout.vertex_count);
    return s;
}

static void shell_free(shell* s)
{
    free(s->mesh_data);
    free(s->sdir_data);
}

/* Φ(u, v, w) over triangle t at barycentrics b. */
static void phi(const shell* s, uint32_t t, const double b[3], double w, double out[3])
{
    const uint32_t nv = s->v.layout.vertex_count;
    out[0] = out[1] = out[2] = 0.0;
    for (int c = 0; c < 3; ++c) {
        const uint32_t v = s->v.indices[3 * t + (uint32_t)c];
        for (int k = 0; k < 3; ++k) {
            const double p = s->v.positions[3 * v + (uint32_t)k];
            const double bottom = s->layers == 2 ? p + s->sdir[3 * (nv + v) + (uint32_t)k] : p;
            const double top = p + s->sdir[3 * v + (uint32_t)k];
            out[k] += b[c] * (bottom + w * (top - bottom));
        }
    }
}

/* Barycentrics of q in triangle t's uvs; 1 when inside (with slack). */
static int locate(const shell* s, uint32_t t, const double q[2], double b[3])
{
    const uint32_t* ix = s->v.indices + 3 * t;
    const float* uv = s->v.uvs;
    const double ax = uv[2 * ix[0]], ay = uv[2 * ix[0] + 1];
    const double e1x = uv[2 * ix[1]] - ax, e1y = uv[2 * ix[1] + 1] - ay;
    const double e2x = uv[2 * ix[2]] - ax, e2y = uv[2 * ix[2] + 1] - ay;
    const double d = e1x * e2y - e2x * e1y;
    if (d == 0.0)
        return 0;
    const double qx = q[0] - ax, qy = q[1] - ay;
    b[1] = (qx * e2y - e2x * qy) / d;
    b[2] = (e1x * qy - qx * e1y) / d;
    b[0] = 1.0 - b[1] - b[2];
    const double eps = 1e-9;
    return b[0] >= -eps && b[1] >= -eps && b[2] >= -eps;
}

/* The largest |Φ_c − Φ_0| at sample points of level 0's texture space: each
 * point's nearest coarse answer among the coarse triangles over it (a point
 * on a shared edge lies in two). */
static double brute(const shell* f, const shell* c)
{
    const uint32_t nf = f->v.layout.index_count / 3, nc = c->v.layout.index_count / 3;
    float(*box)[4] = malloc(sizeof(*box) * nc);
    assert(box);
    for (uint32_t t = 0; t < nc; ++t) {
        box[t][0] = box[t][1] = INFINITY;
        box[t][2] = box[t][3] = -INFINITY;
        for (int k = 0; k < 3; ++k) {
            const float* uv = c->v.uvs + 2 * c->v.indices[3 * t + (uint32_t)k];
            box[t][0] = fminf(box[t][0], uv[0]);
            box[t][1] = fminf(box[t][1], uv[1]);
            box[t][2] = fmaxf(box[t][2], uv[0]);
            box[t][3] = fmaxf(box[t][3], uv[1]);
        }
    }
    enum { EDGE = 8, INSIDE = 4 };
    double worst = 0.0;
    uint32_t seed = 12345;
    for (uint32_t t = 0; t < nf; ++t)
        for (int i = 0; i < 3 + 3 * EDGE + INSIDE; ++i) {
            double b[3] = {0, 0, 0};
            if (i < 3) {
                b[i] = 1.0;
            } else if (i < 3 + 3 * EDGE) {
                const int e = (i - 3) / EDGE;
                const double s = ((i - 3) % EDGE + 1.0) / (EDGE + 1.0);
                b[e] = 1.0 - s;
                b[(e + 1) % 3] = s;
            } else {
                seed = seed * 1664525u + 1013904223u;
                double x = (seed >> 8) / 16777216.0;
                seed = seed * 1664525u + 1013904223u;
                double y = (seed >> 8) / 16777216.0;
                if (x + y > 1.0)
                    x = 1.0 - x, y = 1.0 - y;
                b[0] = 1.0 - x - y, b[1] = x, b[2] = y;
            }
            double q[2] = {0, 0};
            for (int k = 0; k < 3; ++k)
                for (int a = 0; a < 2; ++a)
                    q[a] += b[k] * f->v.uvs[2 * f->v.indices[3 * t + (uint32_t)k] + (uint32_t)a];
            double p0[2][3];
            phi(f, t, b, 0.0, p0[0]);
            phi(f, t, b, 1.0, p0[1]);
            double best = INFINITY;
            for (uint32_t u = 0; u < nc; ++u) {
                double bc[3];
                if (q[0] < box[u][0] - 1e-6 || q[0] > box[u][2] + 1e-6 || q[1] < box[u][1] - 1e-6 ||
                    q[1] > box[u][3] + 1e-6 || !locate(c, u, q, bc))
                    continue;
                double d = 0.0;
                for (int w = 0; w < 2; ++w) {
                    double pc[3];
                    phi(c, u, bc, w, pc);
                    d = fmax(d, sqrt((pc[0] - p0[w][0]) * (pc[0] - p0[w][0]) +
                                     (pc[1] - p0[w][1]) * (pc[1] - p0[w][1]) +
                                     (pc[2] - p0[w][2]) * (pc[2] - p0[w][2])));
                }
                best = fmin(best, d);
            }
            assert(best < INFINITY); /* the coarse charts cover level 0's */
            worst = fmax(worst, best);
        }
    free(box);
    return worst;
}

static void thick_torus(void)
{
    printf("  torus_uv.obj, bricks:64, thickness 0.1 of the diagonal\n");
    size_t size = 0, size2 = 0;
    uint8_t* a = bake("torus_uv.obj", 0.1, 1, &size);
    uint8_t* b = bake("torus_uv.obj", 0.1, 2, &size2);
    assert(size == size2 && memcmp(a, b, size) == 0);
    meso_file* f = NULL;
    meso_error err = {0};
    assert(meso_file_open_memory(a, size, NULL, &f, &err) == MESO_OK);
    int issues = 0;
    assert(meso_file_validate(f, MESO_CHECK_FULL, count_issue, &issues) == MESO_OK && issues == 0);
    meso_level_info lv[16];
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, lv, 16, &n, &err) == MESO_OK && n <= 16);
    const int32_t mesh0 = meso_file_find_level(f, MESO_CHUNK_MESH, 1, 0);
    shell s0 = shell_at(f, 0);
    int own = 0;
    for (uint32_t l = 1; l < n; ++l) {
        if (lv[l].rec.form != MESO_LEVEL_NATIVE || meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)l) == mesh0)
            continue;
        ++own;
        /* The texture level it shares: the last native level with level 0's mesh. */
        uint32_t T = l;
        while (T > 0 && meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)T) != mesh0)
            --T;
        shell sc = shell_at(f, (uint16_t)l);
        const uint32_t nc = sc.v.layout.vertex_count, n0 = s0.v.layout.vertex_count;
        assert(sc.v.layout.index_count < s0.v.layout.index_count && sc.layers == s0.layers);
        /* Kept vertices: bit for bit (a subset in level 0's order). */
        uint32_t at = 0;
        for (uint32_t v = 0; v < nc; ++v) {
            while (at < n0 && (memcmp(s0.v.positions + 3 * at, sc.v.positions + 3 * v, 12) ||
                               memcmp(s0.v.uvs + 2 * at, sc.v.uvs + 2 * v, 8)))
                ++at;
            assert(at < n0);
            for (uint32_t k = 0; k < sc.layers; ++k)
                assert(!memcmp(s0.sdir + 3 * (k * n0 + at), sc.sdir + 3 * (k * nc + v), 12));
            ++at;
        }
        const double stated = (double)lv[l].rec.error - (double)lv[T].rec.error, found = brute(&s0, &sc);
        printf("    level %u: %u of %u triangles, stated %.6g over level %u's, brute force %.6g\n", l,
               sc.v.layout.index_count / 3, s0.v.layout.index_count / 3, stated, T, found);
        assert(found <= stated + 1e-6);
        assert(stated <= 1.1 * found + 1e-5);
        assert(lv[l].rec.error < lv[l + 1 < n ? l + 1 : l].rec.error || l + 1 == n);
        shell_free(&sc);
    }
    assert(own >= 1);
    shell_free(&s0);
    meso_file_close(f);
    free(a);
    free(b);
}

static void thin_spot(void)
{
    printf("  spot_uv.obj, bricks:64, thickness 0.02: no coarser base\n");
    size_t size = 0;
    uint8_t* a = bake("spot_uv.obj", 0.02, 2, &size);
    meso_file* f = NULL;
    meso_error err = {0};
    assert(meso_file_open_memory(a, size, NULL, &f, &err) == MESO_OK);
    meso_level_info lv[16];
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, lv, 16, &n, &err) == MESO_OK && n <= 16);
    const int32_t mesh0 = meso_file_find_level(f, MESO_CHUNK_MESH, 1, 0);
    for (uint32_t l = 1; l < n; ++l)
        assert(lv[l].rec.form != MESO_LEVEL_NATIVE || meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)l) == mesh0);
    meso_file_close(f);
    free(a);
}

int main(void)
{
    printf("shell base levels\n");
    thick_torus();
    thin_spot();
    printf("ok\n");
    return 0;
}
