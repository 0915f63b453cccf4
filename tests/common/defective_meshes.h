/* defective_meshes.h — bad meshes made by the tests themselves, so no test
 * needs the unlicensed defective meshes it read before from outside
 * the repository. Each one carries
 * the defect its namesake there was used for (none is a copy of one):
 *
 *   doubled_faces      an octahedron whose 8 faces are each stored twice, in
 *                      both orientations (16 faces, 12 edges with 4 faces:
 *                      non-manifold, zero volume)          ~ degenerated.obj
 *   two_boxes          two overlapping boxes, each of their 12 faces an
 *                      unwelded grid of its own (11 of 4x4, one of 3x3:
 *                      welded by position it still has T-junction cracks),
 *                      the boxes' surfaces cross each other
 *                                                 ~ two-boxes-bad-self-union
 *   folded_cube        a closed, welded genus-0 cube (3x3 grid per face)
 *                      with one vertex of the top face pushed past its
 *                      neighbour: topologically clean, geometrically folded
 *                                                          ~ cube_with_fold
 *   soup               an open multi-component soup: a box without its lid,
 *                      a fin (three faces on one edge), a strip whose quads
 *                      alternate in orientation, a sheet shredded into 360
 *                      loose triangles cutting through the box, a needle
 *                      triangle and two copies of one tetrahedron
 *                                                            ~ truck.obj
 *   open_parts         four intersecting open parts: a cup with an unwelded
 *                      seam, a lid through its rim, a spout tube through its
 *                      wall, a handle whose ends go into it   ~ teapot.obj
 *
 * dm_write_obj / dm_write_ply (binary little-endian) write them; the
 * make_defective program (tests/common/make_defective.c) writes them all
 * into a directory for the command-line tests. */
#ifndef MESO_DEFECTIVE_MESHES_H
#define MESO_DEFECTIVE_MESHES_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct dm_mesh {
    double* v; /* 3 per vertex */
    uint32_t* f; /* 3 per triangle, 0-based */
    uint32_t nv, nf, cv, cf;
} dm_mesh;

static inline uint32_t dm_vertex(dm_mesh* m, double x, double y, double z)
{
    if (m->nv == m->cv) {
        m->cv = m->cv ? 2 * m->cv : 64;
        m->v = realloc(m->v, sizeof(double) * 3 * m->cv);
        if (!m->v)
            abort();
    }
    m->v[3 * m->nv] = x, m->v[3 * m->nv + 1] = y, m->v[3 * m->nv + 2] = z;
    return m->nv++;
}

static inline void dm_tri(dm_mesh* m, uint32_t a, uint32_t b, uint32_t c)
{
    if (m->nf == m->cf) {
        m->cf = m->cf ? 2 * m->cf : 64;
        m->f = realloc(m->f, sizeof(uint32_t) * 3 * m->cf);
        if (!m->f)
            abort();
    }
    m->f[3 * m->nf] = a, m->f[3 * m->nf + 1] = b, m->f[3 * m->nf + 2] = c;
    m->nf++;
}

static inline void dm_free(dm_mesh* m)
{
    free(m->v);
    free(m->f);
    memset(m, 0, sizeof(*m));
}

/* An n x n grid of quads over the parallelogram o + s·u + t·w (s, t in
 * [0, 1]), its own vertices, two triangles per quad, normal u × w. */
static inline void dm_grid(dm_mesh* m, const double o[3], const double u[3], const double w[3], int n)
{
    const uint32_t base = m->nv;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double s = (double)i / n, t = (double)j / n;
            dm_vertex(m, o[0] + s * u[0] + t * w[0], o[1] + s * u[1] + t * w[1], o[2] + s * u[2] + t * w[2]);
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = base + (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
            dm_tri(m, a, b, d);
            dm_tri(m, a, d, c);
        }
}

/* The six faces of the box [lo, hi], outward, as separate n x n grids
 * (unwelded: vertices on the box's edges exist once per face). face_mask
 * bit k leaves face k out (0 -x, 1 +x, 2 -y, 3 +y, 4 -z, 5 +z). */
static inline void dm_box_faces(dm_mesh* m, const double lo[3], const double hi[3], int n, unsigned face_mask)
{
    const double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    const double X[3] = {dx, 0, 0}, Y[3] = {0, dy, 0}, Z[3] = {0, 0, dz};
    const double o_mx[3] = {lo[0], lo[1], lo[2]}, o_px[3] = {hi[0], lo[1], lo[2]};
    const double o_my[3] = {lo[0], lo[1], lo[2]}, o_py[3] = {lo[0], hi[1], lo[2]};
    const double o_mz[3] = {lo[0], lo[1], lo[2]}, o_pz[3] = {lo[0], lo[1], hi[2]};
    if (!(face_mask & 1u)) dm_grid(m, o_mx, Z, Y, n); /* Z × Y = -x */
    if (!(face_mask & 2u)) dm_grid(m, o_px, Y, Z, n); /* Y × Z = +x */
    if (!(face_mask & 4u)) dm_grid(m, o_my, X, Z, n); /* X × Z = -y */
    if (!(face_mask & 8u)) dm_grid(m, o_py, Z, X, n); /* Z × X = +y */
    if (!(face_mask & 16u)) dm_grid(m, o_mz, Y, X, n); /* Y × X = -z */
    if (!(face_mask & 32u)) dm_grid(m, o_pz, X, Y, n); /* X × Y = +z */
}

/* Merge vertices at identical positions (exact compare), keeping the first. */
static inline void dm_weld(dm_mesh* m)
{
    uint32_t* map = malloc(sizeof(uint32_t) * (m->nv ? m->nv : 1));
    if (!map)
        abort();
    uint32_t kept = 0;
    for (uint32_t i = 0; i < m->nv; ++i) {
        uint32_t j = 0;
        for (; j < kept; ++j)
            if (!memcmp(m->v + 3 * j, m->v + 3 * i, 3 * sizeof(double)))
                break;
        if (j == kept) {
            memmove(m->v + 3 * kept, m->v + 3 * i, 3 * sizeof(double));
            ++kept;
        }
        map[i] = j;
    }
    for (uint32_t k = 0; k < 3 * m->nf; ++k)
        m->f[k] = map[m->f[k]];
    m->nv = kept;
    free(map);
}

static inline dm_mesh dm_doubled_faces(void)
{
    dm_mesh m = {0};
    const double p[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int i = 0; i < 6; ++i)
        dm_vertex(&m, p[i][0], p[i][1], p[i][2]);
    const uint32_t f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int i = 0; i < 8; ++i) {
        dm_tri(&m, f[i][0], f[i][1], f[i][2]);
        dm_tri(&m, f[i][0], f[i][2], f[i][1]);
    }
    return m;
}

static inline dm_mesh dm_two_boxes(void)
{
    dm_mesh m = {0};
    const double lo1[3] = {0, 0, 0}, hi1[3] = {2, 2, 2};
    const double lo2[3] = {1.25, 0.5, 0.75}, hi2[3] = {3.5, 1.5, 1.25};
    dm_box_faces(&m, lo1, hi1, 4, 0);
    /* The second box's +x face is a 3x3 grid: its border vertices do not
     * meet the 4x4 neighbours', so even welded by position the pieces
     * leave T-junction cracks (boundary edges), as a bad union does. */
    dm_box_faces(&m, lo2, hi2, 4, 2u);
    const double o[3] = {hi2[0], lo2[1], lo2[2]}, Y[3] = {0, hi2[1] - lo2[1], 0}, Z[3] = {0, 0, hi2[2] - lo2[2]};
    dm_grid(&m, o, Y, Z, 3);
    return m;
}

static inline dm_mesh dm_folded_cube(void)
{
    dm_mesh m = {0};
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    dm_box_faces(&m, lo, hi, 3, 0);
    dm_weld(&m); /* closed: 6·9 + 12·2 + 8 = 56 vertices, 108 triangles */
    /* The top face's grid vertex (1/3, 1, 1/3) goes past (-1/3, 1, -1/3):
     * the triangles around it flip over their neighbours in the plane. */
    for (uint32_t i = 0; i < m.nv; ++i) {
        double* q = m.v + 3 * i;
        if (q[1] == 1.0 && fabs(q[0] - 1.0 / 3) < 1e-12 && fabs(q[2] - 1.0 / 3) < 1e-12) {
            q[0] = -0.6;
            q[2] = -0.55;
        }
    }
    return m;
}

static inline dm_mesh dm_soup(void)
{
    dm_mesh m = {0};
    /* a box without its +y face: 16 boundary edges */
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    dm_box_faces(&m, lo, hi, 4, 8u);
    dm_weld(&m);
    /* a fin: three triangles on the edge (2,0,0)-(3,0,0) */
    const uint32_t a = dm_vertex(&m, 2, 0, 0), b = dm_vertex(&m, 3, 0, 0);
    dm_tri(&m, a, b, dm_vertex(&m, 2.5, 1, 0));
    dm_tri(&m, b, a, dm_vertex(&m, 2.5, -1, 0));
    dm_tri(&m, a, b, dm_vertex(&m, 2.5, 0, 1));
    /* a strip of 6 quads whose orientation alternates */
    const uint32_t s0 = m.nv;
    for (int i = 0; i <= 6; ++i) {
        dm_vertex(&m, 4 + 0.5 * i, 0, 0.2 * sin(i));
        dm_vertex(&m, 4 + 0.5 * i, 1, 0.2 * cos(i));
    }
    for (uint32_t i = 0; i < 6; ++i) {
        const uint32_t p = s0 + 2 * i, q = p + 1, r = p + 2, s = p + 3;
        if (i % 2) {
            dm_tri(&m, p, s, r);
            dm_tri(&m, p, q, s);
        } else {
            dm_tri(&m, p, r, s);
            dm_tri(&m, p, s, q);
        }
    }
    /* a shredded sheet: 2·15·12 triangles with vertices of their own over
     * a bumpy patch, 1080 boundary edges (more than the voxelizer sums
     * directly, like a CAD export's soup) */
    for (int j = 0; j < 12; ++j)
        for (int i = 0; i < 15; ++i) {
            static const int corner[2][3] = {{0, 1, 3}, {0, 3, 2}};
            for (int t = 0; t < 2; ++t) {
                double p[3][2], c[2] = {0, 0};
                for (int k = 0; k < 3; ++k) {
                    p[k][0] = 0.2 * (i + (corner[t][k] & 1));
                    p[k][1] = 0.2 * (j + (corner[t][k] >> 1));
                    c[0] += p[k][0] / 3, c[1] += p[k][1] / 3;
                }
                uint32_t v[3];
                for (int k = 0; k < 3; ++k) { /* shrunk by 10 %: no shared corners */
                    const double x = c[0] + 0.9 * (p[k][0] - c[0]), y = c[1] + 0.9 * (p[k][1] - c[1]);
                    v[k] = dm_vertex(&m, x - 0.5, y - 0.8, 0.6 + 0.3 * sin(3 * x) * cos(2 * y));
                }
                dm_tri(&m, v[0], v[1], v[2]);
            }
        }
    /* a needle */
    dm_tri(&m, dm_vertex(&m, 0, 2, 0), dm_vertex(&m, 3, 2, 0), dm_vertex(&m, 1.5, 2.01, 0.002));
    /* two copies of one tetrahedron, sharing its vertices */
    const uint32_t t0 = dm_vertex(&m, 0, -2, 0), t1 = dm_vertex(&m, 1, -2, 0), t2 = dm_vertex(&m, 0, -1, 0),
                   t3 = dm_vertex(&m, 0, -2, 1);
    for (int k = 0; k < 2; ++k) {
        dm_tri(&m, t0, t2, t1);
        dm_tri(&m, t0, t1, t3);
        dm_tri(&m, t0, t3, t2);
        dm_tri(&m, t1, t2, t3);
    }
    return m;
}

/* A straight open tube from p to q of radius r: k sides, `rings` rows. */
static inline void dm_tube(dm_mesh* m, const double p[3], const double q[3], double r, int k, int rings)
{
    double ax[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const double len = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    for (int i = 0; i < 3; ++i)
        ax[i] /= len;
    const double e[3] = {fabs(ax[0]) < 0.6 ? 1 : 0, fabs(ax[0]) < 0.6 ? 0 : 1, 0};
    double u[3] = {ax[1] * e[2] - ax[2] * e[1], ax[2] * e[0] - ax[0] * e[2], ax[0] * e[1] - ax[1] * e[0]};
    const double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int i = 0; i < 3; ++i)
        u[i] /= ul;
    const double w[3] = {ax[1] * u[2] - ax[2] * u[1], ax[2] * u[0] - ax[0] * u[2], ax[0] * u[1] - ax[1] * u[0]};
    const uint32_t base = m->nv;
    for (int j = 0; j <= rings; ++j)
        for (int i = 0; i < k; ++i) {
            const double t = (double)j / rings, a = 2 * 3.14159265358979323846 * i / k;
            double x[3];
            for (int c = 0; c < 3; ++c)
                x[c] = p[c] + t * (q[c] - p[c]) + r * (cos(a) * u[c] + sin(a) * w[c]);
            dm_vertex(m, x[0], x[1], x[2]);
        }
    for (int j = 0; j < rings; ++j)
        for (int i = 0; i < k; ++i) {
            const uint32_t a = base + (uint32_t)(j * k + i), b = base + (uint32_t)(j * k + (i + 1) % k);
            const uint32_t c = a + (uint32_t)k, d = b + (uint32_t)k;
            dm_tri(m, a, b, d);
            dm_tri(m, a, d, c);
        }
}

static inline dm_mesh dm_open_parts(void)
{
    dm_mesh m = {0};
    const double PI = 3.14159265358979323846;
    /* The cup: radius 1, height 1.2, bottom closed, top open; the seam at
     * angle 0 has its vertices twice (the last column repeats the first). */
    const int k = 16, h = 6;
    const uint32_t body = m.nv;
    for (int j = 0; j <= h; ++j)
        for (int i = 0; i <= k; ++i) {
            const double a = 2 * PI * (i % k) / k;
            dm_vertex(&m, cos(a), 1.2 * j / h, sin(a));
        }
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < k; ++i) {
            const uint32_t a = body + (uint32_t)(j * (k + 1) + i), b = a + 1, c = a + (uint32_t)(k + 1), d = c + 1;
            dm_tri(&m, a, d, b);
            dm_tri(&m, a, c, d);
        }
    const uint32_t centre = dm_vertex(&m, 0, 0, 0);
    for (int i = 0; i < k; ++i)
        dm_tri(&m, centre, body + (uint32_t)i, body + (uint32_t)i + 1);
    /* The lid: a cone of radius 1.1 whose rim dips below the cup's rim. */
    const uint32_t lid = m.nv;
    for (int i = 0; i < k; ++i) {
        const double a = 2 * PI * (i + 0.5) / k;
        dm_vertex(&m, 1.1 * cos(a), 1.1, 1.1 * sin(a));
    }
    const uint32_t apex = dm_vertex(&m, 0, 1.6, 0);
    for (int i = 0; i < k; ++i)
        dm_tri(&m, apex, lid + (uint32_t)((i + 1) % k), lid + (uint32_t)i);
    /* The spout: an open tube from inside the cup out through its wall. */
    const double s0[3] = {0.6, 0.4, 0.1}, s1[3] = {1.9, 1.1, 0.1};
    dm_tube(&m, s0, s1, 0.15, 10, 4);
    /* The handle: three tube pieces whose ends enter the wall. */
    const double h0[3] = {-0.8, 0.3, 0}, h1[3] = {-1.6, 0.3, 0}, h2[3] = {-1.6, 0.9, 0}, h3[3] = {-0.8, 0.9, 0};
    dm_tube(&m, h0, h1, 0.08, 8, 2);
    dm_tube(&m, h1, h2, 0.08, 8, 2);
    dm_tube(&m, h2, h3, 0.08, 8, 2);
    return m;
}

static inline int dm_write_obj(const char* path, const dm_mesh* m)
{
    FILE* f = fopen(path, "w");
    if (!f)
        return 0;
    fprintf(f, "# generated by tests/common/defective_meshes.h (meso tests)\n");
    for (uint32_t i = 0; i < m->nv; ++i)
        fprintf(f, "v %.17g %.17g %.17g\n", m->v[3 * i], m->v[3 * i + 1], m->v[3 * i + 2]);
    for (uint32_t i = 0; i < m->nf; ++i)
        fprintf(f, "f %u %u %u\n", m->f[3 * i] + 1, m->f[3 * i + 1] + 1, m->f[3 * i + 2] + 1);
    return fclose(f) == 0;
}

static inline void dm_put_le32(FILE* f, uint32_t x)
{
    const unsigned char b[4] = {(unsigned char)x, (unsigned char)(x >> 8), (unsigned char)(x >> 16),
                                (unsigned char)(x >> 24)};
    fwrite(b, 1, 4, f);
}

/* Binary little-endian PLY, float coordinates, uchar/int face lists. */
static inline int dm_write_ply(const char* path, const dm_mesh* m)
{
    FILE* f = fopen(path, "wb");
    if (!f)
        return 0;
    fprintf(f,
            "ply\nformat binary_little_endian 1.0\ncomment generated by tests/common/defective_meshes.h\n"
            "element vertex %u\nproperty float x\nproperty float y\nproperty float z\n"
            "element face %u\nproperty list uchar int vertex_indices\nend_header\n",
            m->nv, m->nf);
    for (uint32_t i = 0; i < 3 * m->nv; ++i) {
        const float x = (float)m->v[i];
        uint32_t u;
        memcpy(&u, &x, 4);
        dm_put_le32(f, u);
    }
    for (uint32_t i = 0; i < m->nf; ++i) {
        fputc(3, f);
        for (int c = 0; c < 3; ++c)
            dm_put_le32(f, m->f[3 * i + c]);
    }
    return fclose(f) == 0;
}

typedef struct dm_case {
    const char* name; /* file stem */
    dm_mesh (*make)(void);
} dm_case;

static const dm_case dm_cases[] = {
    {"doubled_faces", dm_doubled_faces}, {"two_boxes", dm_two_boxes}, {"folded_cube", dm_folded_cube},
    {"soup", dm_soup},                   {"open_parts", dm_open_parts},
};
#define DM_CASE_COUNT (sizeof(dm_cases) / sizeof(dm_cases[0]))

#endif
