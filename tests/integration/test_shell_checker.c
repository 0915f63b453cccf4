/* test_shell_checker.c — the incremental shell checks (bake/shell_checker.c:
 * only the faces around moved directors re-tested, with the box grid of
 * bake/box_grid.c as the broad phase) against a fresh full check
 * (meso_shell_bad_faces: CGAL's box intersection over every triangle) after
 * every round of random director moves: a few percent of the directors
 * scaled and tilted per round, sometimes most of them (the full path), on
 * thick exterior and interior shells of the bundled meshes where many faces
 * fail. The verdicts must be the same face for face, every round. */
#include "test_util.h"

#include <math.h>
#include <string.h>

#include "adapters.h"
#include "shell_checker.h"
#include "shell_hybrid.h"

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static double uniform(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static void run(const char* name, double rel, int sign)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(name), &m, NULL, &err) == MESO_OK);
    const uint32_t nv = m.vertex_count, nt = m.triangle_count;
    float* n = malloc(sizeof(float) * 3 * nv);
    float* d = malloc(sizeof(float) * 3 * nv);
    uint8_t* inc = malloc(nt);
    uint8_t* ref = malloc(nt);
    assert(meso_vertex_normals(&m, n, &err) == MESO_OK);
    double lo[3], hi[3];
    const double h = rel * meso_mesh_bounds(&m, lo, hi);
    for (size_t i = 0; i < 3 * (size_t)nv; ++i)
        d[i] = (float)(sign * h * n[i]);
    meso_shell_checker* c = NULL;
    assert(meso_shell_checker_create(&m, sign, 2, &c, &err) == MESO_OK);
    uint32_t total_bad = 0, rounds = 40;
    for (uint32_t round = 0; round < rounds; ++round) {
        /* every 10th round moves most directors: the checker's full path */
        const double p = round % 10 == 9 ? 0.7 : 0.03;
        for (uint32_t v = 0; round && v < nv; ++v) {
            if (uniform() > p)
                continue;
            const double s = 0.3 + 1.2 * uniform();
            for (int k = 0; k < 3; ++k)
                d[3 * v + k] = (float)(s * d[3 * v + k] + 0.2 * h * (uniform() - 0.5));
        }
        uint32_t ci = 0, cr = 0;
        assert(meso_shell_checker_bad_faces(c, d, inc, &ci, &err) == MESO_OK);
        assert(meso_shell_bad_faces(&m, d, sign, ref, &cr, &err) == MESO_OK);
        if (ci != cr || memcmp(inc, ref, nt) != 0) {
            fprintf(stderr, "%s round %u: incremental %u bad faces, full check %u\n", name, round, ci, cr);
            exit(1);
        }
        total_bad += cr;
    }
    printf("%s %s %.2f: %u rounds, %u bad faces in all, incremental == full every round\n", name,
           sign > 0 ? "exterior" : "interior", rel, rounds, total_bad);
    assert(total_bad > rounds); /* the shells did fail: the verdicts were tested */
    meso_shell_checker_destroy(c);
    free(n), free(d), free(inc), free(ref);
    meso_mesh_free(&m);
}

int main(void)
{
    run("spot_low_resolution.obj", 0.15, 1);
    run("saddle.obj", 0.3, 1);
    run("torus.obj", 0.2, -1);
    puts("shell_checker: ok");
    return 0;
}
