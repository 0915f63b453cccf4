/* A cells object's levels (FORMAT.md §7.10; issue 14), each with the error
 * mesobake states.
 *
 * Native coarser levels (the tile map halved, bake/cells_levels.h):
 * every point the reference hits on level L lies within the stated error
 * of level 0's drawn faces, and every point it hits on level 0 within the
 * stated error of level L's (brute force over the faces), from the same
 * views as below; and the bound is not loose.
 *
 * Mesh stand-ins (form MESH): the base mesh, then its simplifications.
 * Checked against the exact CPU reference, both ways, from several views:
 *  - every surface point the reference ray caster hits (the voxel faces the
 *    object draws, carved by the empty cells) lies within the stated error
 *    of the level's mesh (brute force over its triangles);
 *  - every point the same pixel rays hit on the level's mesh (brute force
 *    ray-triangle) lies within the stated error of the drawn surface: the
 *    faces between SOLID and non-SOLID voxels of meso_ref_cells_solid,
 *    listed by brute force over the grid;
 * and the bound is not loose (the farthest point reaches a fair part of
 * it). Level 1 and the coarsest level are checked (the levels between are
 * made the same way). The file validates in full, the report has "levels", errors do not
 * decrease, and `--levels 1` writes one level and no LODS.
 * usage: test_cells_standin MESOBAKE */
#include "test_util.h"

#include <string.h>

#include "camera.h"
#include "cell_reference.h"
#include "meso_file.h"
#include "meso_layout.h"
#include "point_cloud.h"
#include "point_triangle.h"
#include "ref_common.h"

/* The drawn surface: one axis-aligned unit square per SOLID voxel face
 * whose neighbour is not SOLID (lo corner and axis). */
typedef struct faces {
    double* lo; /* 3 per face: the face's min corner */
    int* axis;  /* the normal's axis */
    size_t n, cap;
} faces;

static void list_faces(const meso_ref_cells* c, faces* fs)
{
    memset(fs, 0, sizeof *fs);
    const int64_t N[3] = {(int64_t)c->tiles[0] * c->res, (int64_t)c->tiles[1] * c->res,
                          (int64_t)c->tiles[2] * c->res};
    for (int64_t k = 0; k < N[2]; ++k)
        for (int64_t j = 0; j < N[1]; ++j)
            for (int64_t i = 0; i < N[0]; ++i) {
                if (!meso_ref_cells_solid(c, i, j, k))
                    continue;
                for (int dir = 0; dir < 6; ++dir) {
                    const int a = dir / 2;
                    const int64_t s = dir & 1 ? 1 : -1;
                    int64_t q[3] = {i, j, k};
                    q[a] += s;
                    if (meso_ref_cells_solid(c, q[0], q[1], q[2]))
                        continue;
                    if (fs->n == fs->cap) {
                        fs->cap = fs->cap ? 2 * fs->cap : 1024;
                        fs->lo = realloc(fs->lo, sizeof(double) * 3 * fs->cap);
                        fs->axis = realloc(fs->axis, sizeof(int) * fs->cap);
                        assert(fs->lo && fs->axis);
                    }
                    const int64_t v[3] = {i, j, k};
                    for (int d = 0; d < 3; ++d)
                        fs->lo[3 * fs->n + (size_t)d] = c->origin[d] + (double)(v[d] + (d == a && s > 0)) * c->voxel;
                    fs->axis[fs->n++] = a;
                }
            }
}

/* Distance from p to the nearest listed face (a square of edge h). */
static double face_distance(const faces* fs, double h, const double p[3])
{
    double best = INFINITY;
    for (size_t f = 0; f < fs->n; ++f) {
        double s = 0;
        for (int d = 0; d < 3; ++d) {
            const double lo = fs->lo[3 * f + (size_t)d], hi = d == fs->axis[f] ? lo : lo + h;
            const double e = p[d] < lo ? lo - p[d] : p[d] > hi ? p[d] - hi : 0;
            s += e * e;
        }
        best = fmin(best, s);
    }
    return sqrt(best);
}

/* Nearest t in [0, 1] where o + t d meets triangle abc (Möller-Trumbore);
 * INFINITY for none. */
static double ray_triangle(const double o[3], const double d[3], const float* a, const float* b, const float* c)
{
    double e1[3], e2[3], pv[3], tv[3], qv[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
        tv[k] = o[k] - a[k];
    }
    pv[0] = d[1] * e2[2] - d[2] * e2[1];
    pv[1] = d[2] * e2[0] - d[0] * e2[2];
    pv[2] = d[0] * e2[1] - d[1] * e2[0];
    const double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
    if (fabs(det) < 1e-300)
        return INFINITY;
    const double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
    qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
    qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
    qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
    const double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
    const double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
    return u < 0 || v < 0 || u + v > 1 || t < 0 || t > 1 ? INFINITY : t;
}

typedef struct mesh {
    uint8_t* bytes;
    meso_mesh_view v;
    uint32_t tris;
} mesh;

static void read_mesh(meso_file* f, int32_t ci, mesh* m)
{
    assert(ci >= 0);
    const meso_chunk_info* mc = meso_file_chunk(f, (uint32_t)ci);
    m->bytes = malloc((size_t)mc->decoded_size);
    assert(m->bytes && meso_file_read_chunk(f, (uint32_t)ci, m->bytes, (size_t)mc->decoded_size, NULL) == MESO_OK);
    assert(meso_mesh_parse(m->bytes, (size_t)mc->decoded_size, &m->v, NULL) == MESO_OK);
    m->tris = m->v.layout.index_count / 3;
}

static const float* corner(const mesh* m, uint32_t t, int k)
{
    return m->v.positions + 3 * (size_t)m->v.indices[3 * (size_t)t + (size_t)k];
}

/* 1 inside the mesh, 0 outside, -1 undecided (a crossing within 1e-9 of
 * a triangle's edge): parity of the ray p + t (1, 0, 0), t > 0. */
static int inside_mesh(const mesh* m, const double p[3])
{
    int n = 0;
    for (uint32_t t = 0; t < m->tris; ++t) {
        const float *a = corner(m, t, 0), *b = corner(m, t, 1), *c = corner(m, t, 2);
        if (fmax(a[0], fmax(b[0], c[0])) < p[0] || fmin(a[1], fmin(b[1], c[1])) > p[1] ||
            fmax(a[1], fmax(b[1], c[1])) < p[1] || fmin(a[2], fmin(b[2], c[2])) > p[2] ||
            fmax(a[2], fmax(b[2], c[2])) < p[2])
            continue;
        /* Barycentrics of (p1, p2) in the triangle's projection on yz. */
        const double y0 = a[1], z0 = a[2], y1 = b[1] - y0, z1 = b[2] - z0, y2 = c[1] - y0, z2 = c[2] - z0;
        const double det = y1 * z2 - y2 * z1;
        if (fabs(det) < 1e-300)
            continue; /* edge-on: parallel to the ray */
        const double u = ((p[1] - y0) * z2 - y2 * (p[2] - z0)) / det, v = (y1 * (p[2] - z0) - (p[1] - y0) * z1) / det;
        if (u < -1e-9 || v < -1e-9 || u + v > 1 + 1e-9)
            continue;
        if (u < 1e-9 || v < 1e-9 || u + v > 1 - 1e-9)
            return -1;
        const double x = a[0] + u * ((double)b[0] - a[0]) + v * ((double)c[0] - a[0]);
        if (fabs(x - p[0]) < 1e-9)
            return -1;
        n += x > p[0];
    }
    return n & 1;
}

/* >>clipped. What libmeso draws of a level: each pixel ray starts where it
 * first enters the base mesh and takes the first SOLID point from there
 * (cells_frag.glsl), the reference traced from that entry. Its surface is
 * C = (F ∩ M_in) ∪ (∂M ∩ S) (bake/cells_standin.c): here a subset of it,
 * found without the bake's machinery: points spaced h0 / 2 on the base
 * mesh that lie in a SOLID voxel, and on every face of F whose parity
 * along +x says inside the mesh (a crossing too near an edge: the point is
 * left out). Distances to a subset are no smaller than to C, so a hit
 * within the stated error of them is within it of C. */
static void clipped_cloud(const meso_ref_cells* c, const faces* fs, const mesh* m, double h0, cloud* out)
{
    memset(out, 0, sizeof *out);
    /* Faces: n x n points a face, n = its edge / (h0 / 2), inside the mesh. */
    const int n = (int)lround(2.0 * c->voxel / h0);
    for (size_t f = 0; f < fs->n; ++f) {
        const int a = fs->axis[f], b = (a + 1) % 3, d = (a + 2) % 3;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                double p[3];
                memcpy(p, fs->lo + 3 * f, sizeof p);
                p[b] += (i + 0.5) / n * c->voxel;
                p[d] += (j + 0.5) / n * c->voxel;
                if (inside_mesh(m, p) == 1)
                    cloud_add(out, p);
            }
    }
    /* The mesh: each triangle's barycentric lattice at h0 / 2, in S. */
    for (uint32_t t = 0; t < m->tris; ++t) {
        const float *a = corner(m, t, 0), *b = corner(m, t, 1), *cc = corner(m, t, 2);
        double l = 0;
        for (int e = 0; e < 3; ++e) {
            const float *p = corner(m, t, e), *q = corner(m, t, (e + 1) % 3);
            l = fmax(l, sqrt(((double)p[0] - q[0]) * (p[0] - q[0]) + ((double)p[1] - q[1]) * (p[1] - q[1]) +
                             ((double)p[2] - q[2]) * (p[2] - q[2])));
        }
        const int k = (int)ceil(l / (0.5 * h0));
        for (int i = 0; i <= k; ++i)
            for (int j = 0; i + j <= k; ++j) {
                double p[3];
                int64_t v[3];
                for (int d = 0; d < 3; ++d) {
                    p[d] = a[d] + (double)i / k * ((double)b[d] - a[d]) + (double)j / k * ((double)cc[d] - a[d]);
                    v[d] = (int64_t)floor((p[d] - c->origin[d]) / c->voxel);
                }
                if (meso_ref_cells_solid(c, v[0], v[1], v[2]))
                    cloud_add(out, p);
            }
    }
    cloud_grid(out, h0);
}

/* The clipped hits of level `c` from the views: what libmeso draws. */
static void clipped_hits(const meso_ref_cells* c, const mesh* m, const meso_ref_view* views, int nviews, int size,
                         cloud* out)
{
    memset(out, 0, sizeof *out);
    static const double light[3] = {0, 0, 1};
    for (int e = 0; e < nviews; ++e) {
        mesoi_ref_camera cam;
        assert(mesoi_ref_camera_init(&views[e], &cam));
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                double o[3], dv[3], best = INFINITY;
                mesoi_ref_pixel_ray(&cam, x, y, size, size, o, dv);
                for (uint32_t t = 0; t < m->tris; ++t)
                    best = fmin(best, ray_triangle(o, dv, corner(m, t, 0), corner(m, t, 1), corner(m, t, 2)));
                if (best == INFINITY)
                    continue;
                const double len = sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]);
                const double entry[3] = {o[0] + best * dv[0], o[1] + best * dv[1], o[2] + best * dv[2]};
                const double u[3] = {dv[0] / len, dv[1] / len, dv[2] / len};
                meso_ref_cells_path path;
                meso_ref_cells_trace(c, entry, u, 100.0, light, NULL, &path);
                if (path.hit)
                    cloud_add(out, path.p[0]);
            }
    }
}

/* Level L against level 0, the clipped way, both ways: the farthest. */
static double clipped_worst(const cloud* hits, const cloud* other)
{
    double worst = 0;
    for (size_t i = 0; i < hits->n; ++i)
        worst = fmax(worst, cloud_nearest(other, hits->p + 3 * i));
    return worst;
}

int main(int argc, char** argv)
{
    assert(argc == 2);
    char dir[256], path[512], report[512], cmd[10240];
    test_temp_dir(dir, sizeof dir, "cells_standin");
    snprintf(path, sizeof path, "%s/cells.meso", dir);
    snprintf(report, sizeof report, "%s/report.json", dir);
    snprintf(cmd, sizeof cmd, "'%s' cells -i '%s' --tiles 4 --tile-res 16 -j 2 --report '%s' -o '%s' >/dev/null",
             argv[1], test_data("sphere.obj"), report, path);
    assert(system(cmd) == 0);
    FILE* rf = fopen(report, "rb");
    assert(rf);
    char text[65536];
    const size_t got = fread(text, 1, sizeof text - 1, rf);
    text[got] = 0;
    fclose(rf);
    assert(strstr(text, "\"levels\""));

    meso_file* f = NULL;
    assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_level_info li[16];
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, li, 16, &n, NULL) == MESO_OK && n >= 4); /* native, base mesh, simplified */
    meso_ref_cells rc;
    assert(meso_ref_cells_load(f, 1, &rc, NULL) == MESO_OK);
    faces fs;
    list_faces(&rc, &fs);
    assert(fs.n > 1000);

    /* The views, and the reference's hits once. */
    enum { VIEWS = 3, S = 40 };
    static const double eyes[VIEWS][3] = {{0, 0.3, 3.2}, {2.6, 1.4, -1.2}, {-1.8, -2.2, 1.5}};
    meso_ref_view views[VIEWS];
    meso_ref_image imgs[VIEWS];
    for (int e = 0; e < VIEWS; ++e) {
        views[e] = (meso_ref_view){.width = S, .height = S, .threads = 2};
        static const double at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
        meso_camera_look_at_d(views[e].view, eyes[e], at, up);
        meso_camera_perspective_d(views[e].proj, 40.0 * M_PI / 180.0, 1.0, 0.1, 20.0);
        assert(meso_ref_cells_render(&rc, &views[e], NULL, &imgs[e]) == MESO_OK);
    }
    uint32_t natives = 0;
    for (uint32_t L = 1; L < n && li[L].rec.form == MESO_LEVEL_NATIVE; ++L) {
        ++natives;
        const double err = li[L].rec.error;
        assert(err > 0 && err >= li[L - 1].rec.error);
        meso_ref_cells rl;
        assert(meso_ref_cells_load_level(f, 1, (uint16_t)L, &rl, NULL) == MESO_OK);
        assert(rl.res * (1u << L) == rc.res && fabs(rl.voxel - rc.voxel * (1 << L)) <= 1e-6 * rl.voxel);
        faces fl;
        list_faces(&rl, &fl);
        double worst_l = 0, worst_0 = 0; /* level L's hits -> level 0's faces, and back */
        size_t hits_l = 0, hits_0 = 0;
        for (int e = 0; e < VIEWS; ++e) {
            meso_ref_image il;
            assert(meso_ref_cells_render(&rl, &views[e], NULL, &il) == MESO_OK);
            for (size_t p = 0; p < (size_t)S * S; ++p) {
                if (il.coverage[p]) {
                    const double q[3] = {il.hit[3 * p], il.hit[3 * p + 1], il.hit[3 * p + 2]};
                    worst_l = fmax(worst_l, face_distance(&fs, rc.voxel, q));
                    ++hits_l;
                }
                if (imgs[e].coverage[p]) {
                    const double q[3] = {imgs[e].hit[3 * p], imgs[e].hit[3 * p + 1], imgs[e].hit[3 * p + 2]};
                    worst_0 = fmax(worst_0, face_distance(&fl, rl.voxel, q));
                    ++hits_0;
                }
            }
            meso_ref_image_free(&il);
        }
        printf("  native level %u: %u voxels a tile, stated error %.6g (%.2f voxels of level 0); farthest of %zu "
               "level-%u hits %.6g (%.0f %%), of %zu level-0 hits %.6g (%.0f %%)\n",
               L, rl.res, err, err / rc.voxel, hits_l, L, worst_l, 100.0 * worst_l / err, hits_0, worst_0,
               100.0 * worst_0 / err);
        fflush(stdout);
        assert(hits_l > 1000 && hits_0 > 1000);
        assert(worst_l <= err * (1 + 1e-5) + 1e-7 && worst_0 <= err * (1 + 1e-5) + 1e-7);
        /* The clipped surfaces, as libmeso draws them (>>clipped above). */
        mesh base;
        read_mesh(f, meso_file_find_level(f, MESO_CHUNK_MESH, 1, 0), &base);
        cloud c0, cl, h0s, hls;
        clipped_cloud(&rc, &fs, &base, rc.voxel, &c0);
        clipped_cloud(&rl, &fl, &base, rc.voxel, &cl);
        clipped_hits(&rc, &base, views, VIEWS, 2 * S, &h0s);
        clipped_hits(&rl, &base, views, VIEWS, 2 * S, &hls);
        const double cw_l = clipped_worst(&hls, &c0), cw_0 = clipped_worst(&h0s, &cl);
        printf("  native level %u, clipped to the mesh: farthest of %zu level-%u hits from level 0's surface %.6g "
               "(%.0f %%), of %zu level-0 hits from level %u's %.6g (%.0f %%)\n",
               L, hls.n, L, cw_l, 100.0 * cw_l / err, h0s.n, L, cw_0, 100.0 * cw_0 / err);
        assert(hls.n > 4000 && h0s.n > 4000);
        assert(cw_l <= err * (1 + 1e-5) + 1e-7 && cw_0 <= err * (1 + 1e-5) + 1e-7);
        if (L == 1) /* not a loose guess */
            assert(fmax(fmax(worst_l, worst_0), fmax(cw_l, cw_0)) >= 0.4 * err);
        cloud_free(&c0);
        cloud_free(&cl);
        cloud_free(&h0s);
        cloud_free(&hls);
        free(base.bytes);
        free(fl.lo);
        free(fl.axis);
        meso_ref_cells_free(&rl);
    }
    assert(natives >= 1);
    for (uint32_t L = natives + 1; L < n; ++L) {
        assert(li[L].rec.form == MESO_LEVEL_MESH && li[L].rec.error > 0);
        assert(li[L].rec.error >= li[L - 1].rec.error);
        if (L != natives + 1 && L != n - 1) /* the levels between follow the same rule: time */
            continue;
        const double err = li[L].rec.error;
        mesh m;
        read_mesh(f, meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)L), &m);
        double worst_native = 0, worst_standin = 0;
        size_t native_hits = 0, standin_hits = 0;
        for (int e = 0; e < VIEWS; ++e) {
            mesoi_ref_camera cam;
            assert(mesoi_ref_camera_init(&views[e], &cam));
            for (int y = 0; y < S; ++y)
                for (int x = 0; x < S; ++x) {
                    const size_t p = (size_t)y * S + (size_t)x;
                    if (imgs[e].coverage[p]) { /* native -> stand-in */
                        const double q[3] = {imgs[e].hit[3 * p], imgs[e].hit[3 * p + 1], imgs[e].hit[3 * p + 2]};
                        double d = INFINITY;
                        for (uint32_t t = 0; t < m.tris; ++t)
                            d = fmin(d, point_triangle(q, corner(&m, t, 0), corner(&m, t, 1), corner(&m, t, 2)));
                        worst_native = fmax(worst_native, d);
                        ++native_hits;
                    }
                    double o[3], dv[3], best = INFINITY; /* stand-in -> native */
                    mesoi_ref_pixel_ray(&cam, x, y, S, S, o, dv);
                    for (uint32_t t = 0; t < m.tris; ++t)
                        best = fmin(best, ray_triangle(o, dv, corner(&m, t, 0), corner(&m, t, 1), corner(&m, t, 2)));
                    if (best == INFINITY)
                        continue;
                    const double q[3] = {o[0] + best * dv[0], o[1] + best * dv[1], o[2] + best * dv[2]};
                    worst_standin = fmax(worst_standin, face_distance(&fs, rc.voxel, q));
                    ++standin_hits;
                }
        }
        printf("  level %u: %u triangles, stated error %.6g (%.2f voxels); farthest of %zu reference hits %.6g "
               "(%.0f %%), of %zu stand-in hits %.6g (%.0f %%)\n",
               L, m.tris, err, err / rc.voxel, native_hits, worst_native, 100.0 * worst_native / err, standin_hits,
               worst_standin, 100.0 * worst_standin / err);
        fflush(stdout);
        assert(native_hits > 1000 && standin_hits > 1000);
        assert(worst_native <= err * (1 + 1e-5) + 1e-7); /* the stated error holds both ways */
        assert(worst_standin <= err * (1 + 1e-5) + 1e-7);
        if (L == natives + 1) /* and is not a loose guess */
            assert(fmax(worst_native, worst_standin) >= 0.4 * err);
        free(m.bytes);
    }
    for (int e = 0; e < VIEWS; ++e)
        meso_ref_image_free(&imgs[e]);
    free(fs.lo);
    free(fs.axis);
    meso_ref_cells_free(&rc);
    meso_file_close(f);

    /* --levels 1: the file of earlier bakes, one level; --levels 2: the base
     * mesh only; --levels 3: one native level and the base mesh. */
    for (int want = 1; want <= 3; ++want) {
        snprintf(cmd, sizeof cmd, "'%s' cells -i '%s' --tiles 4 --tile-res 8 -j 2 --levels %d -o '%s' >/dev/null",
                 argv[1], test_data("sphere.obj"), want, path);
        assert(system(cmd) == 0);
        assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
        assert(meso_file_levels(f, 1, NULL, 0, &n, NULL) == MESO_OK && n == (uint32_t)want);
        assert((meso_file_find(f, MESO_CHUNK_LODS, UINT32_MAX, UINT16_MAX) < 0) == (want == 1));
        if (want == 3) {
            assert(meso_file_levels(f, 1, li, 16, &n, NULL) == MESO_OK);
            assert(li[1].rec.form == MESO_LEVEL_NATIVE && li[2].rec.form == MESO_LEVEL_MESH);
            assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
        }
        meso_file_close(f);
    }
    test_temp_dir_remove(dir);
    puts("test_cells_standin: ok");
    return 0;
}
