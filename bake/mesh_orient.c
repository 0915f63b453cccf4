/*
 * mesh_orient.c — flip inside-out closed components (mesh_orient.h).
 *
 * Components: union-find over the vertices of each face. Volumes: the sum
 * of a . (b x c) / 6 over a component's faces, relative to one of its
 * vertices (less cancellation far from the origin). Closedness: the same
 * sorted directed-edge pass as mesh_check.c, per component. Nesting: the
 * generalized winding number (van Oosterom–Strackee solid angles) of one
 * vertex of a component with respect to each other closed component whose
 * bounding box contains it. Nothing here depends on thread count or memory
 * layout, so the result is deterministic.
 */
#include "mesh_orient.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec3d.h"

typedef struct orient_edge {
    uint64_t key;  /* min << 32 | max */
    uint32_t from; /* the face traverses from -> to */
    uint32_t comp;
} orient_edge;

static int cmp_edge(const void* a, const void* b)
{
    const orient_edge *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->from < y->from ? -1 : x->from > y->from;
}

static uint32_t find_root(uint32_t* parent, uint32_t v)
{
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

typedef struct comp_info {
    double volume6; /* six times the signed volume */
    double lo[3], hi[3];
    uint32_t first_face, face_count; /* into the face order */
    uint32_t probe;                  /* a vertex of the component */
    int closed;                      /* closed and consistently oriented */
    int depth, container;            /* nesting among the judged components; container: -1 or a component */
    int flip;
} comp_info;

/* Winding number of the faces `faces[0..n)` of `m` around point p. */
static double winding(const meso_mesh* m, const uint32_t* faces, uint32_t n, const double p[3])
{
    double sum = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t* ix = m->indices + 3 * (size_t)faces[i];
        double v[3][3], l[3];
        for (int c = 0; c < 3; ++c) {
            for (int k = 0; k < 3; ++k)
                v[c][k] = (double)m->positions[3 * (size_t)ix[c] + (size_t)k] - p[k];
            l[c] = len3(v[c]);
        }
        const double det = v[0][0] * (v[1][1] * v[2][2] - v[1][2] * v[2][1]) -
                           v[0][1] * (v[1][0] * v[2][2] - v[1][2] * v[2][0]) +
                           v[0][2] * (v[1][0] * v[2][1] - v[1][1] * v[2][0]);
        const double d01 = dot3(v[0], v[1]), d02 = dot3(v[0], v[2]), d12 = dot3(v[1], v[2]);
        sum += 2.0 * atan2(det, l[0] * l[1] * l[2] + d01 * l[2] + d02 * l[1] + d12 * l[0]);
    }
    return sum / (4.0 * M_PI);
}

static int bbox_contains(const comp_info* c, const double p[3])
{
    for (int k = 0; k < 3; ++k)
        if (p[k] < c->lo[k] || p[k] > c->hi[k])
            return 0;
    return 1;
}

/* Nesting of component i (its probe point p) among the other judged
 * components: how many enclose it, and the innermost (smallest volume) of
 * them. `work` counts box tests and triangles visited. */
static void nest(const meso_mesh* m, const uint32_t* order, comp_info* comps, uint32_t count, uint32_t i,
                 const double p[3], uint64_t* work)
{
    comp_info* a = &comps[i];
    *work += count;
    for (uint32_t j = 0; j < count; ++j) {
        const comp_info* b = &comps[j];
        if (j == i || !b->closed || !bbox_contains(b, p))
            continue;
        *work += b->face_count;
        if (fabs(winding(m, order + b->first_face, b->face_count, p)) > 0.5) {
            a->depth++;
            if (a->container < 0 || fabs(b->volume6) < fabs(comps[a->container].volume6))
                a->container = (int)j;
        }
    }
}

/* Components, their volumes and bounds (*comps, malloc'd; NULL when out of
 * memory); `face_comp` gets each face's component, `order` the faces
 * grouped by component. Returns the count. */
static uint32_t find_components(const meso_mesh* m, uint32_t* parent, uint32_t* face_comp, uint32_t* order,
                                comp_info** comps_out)
{
    const uint32_t nv = m->vertex_count, nf = m->triangle_count;
    for (uint32_t v = 0; v < nv; ++v)
        parent[v] = v;
    for (uint32_t f = 0; f < nf; ++f) {
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        for (int c = 1; c < 3; ++c) {
            const uint32_t a = find_root(parent, ix[0]), b = find_root(parent, ix[c]);
            if (a != b)
                parent[a > b ? a : b] = a < b ? a : b; /* the smaller index wins: deterministic */
        }
    }
    /* Dense ids in order of first face. */
    uint32_t count = 0;
    uint32_t* id = order; /* scratch: a root's component id, reused below */
    for (uint32_t v = 0; v < nv; ++v)
        id[v] = UINT32_MAX;
    for (uint32_t f = 0; f < nf; ++f) {
        const uint32_t r = find_root(parent, m->indices[3 * (size_t)f]);
        face_comp[f] = r;
        if (id[r] == UINT32_MAX)
            id[r] = count++;
    }
    comp_info* comps = *comps_out = malloc(sizeof(comp_info) * count);
    if (!comps)
        return 0;
    count = 0;
    for (uint32_t v = 0; v < nv; ++v)
        id[v] = UINT32_MAX;
    for (uint32_t f = 0; f < nf; ++f) {
        const uint32_t r = face_comp[f];
        if (id[r] == UINT32_MAX) {
            id[r] = count;
            comps[count] = (comp_info){.lo = {INFINITY, INFINITY, INFINITY}, .hi = {-INFINITY, -INFINITY, -INFINITY},
                                       .probe = m->indices[3 * (size_t)f], .container = -1};
            ++count;
        }
        face_comp[f] = id[r];
    }
    for (uint32_t f = 0; f < nf; ++f) {
        comp_info* c = &comps[face_comp[f]];
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        const float* o = m->positions + 3 * (size_t)c->probe;
        double q[3][3];
        for (int k = 0; k < 3; ++k) {
            for (int j = 0; j < 3; ++j)
                q[k][j] = (double)m->positions[3 * (size_t)ix[k] + (size_t)j] - o[j];
            for (int j = 0; j < 3; ++j) {
                const double x = m->positions[3 * (size_t)ix[k] + (size_t)j];
                c->lo[j] = x < c->lo[j] ? x : c->lo[j];
                c->hi[j] = x > c->hi[j] ? x : c->hi[j];
            }
        }
        c->volume6 += q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) -
                      q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
                      q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]);
        c->face_count++;
    }
    uint32_t off = 0;
    for (uint32_t i = 0; i < count; ++i) {
        comps[i].first_face = off;
        off += comps[i].face_count;
        comps[i].face_count = 0;
    }
    for (uint32_t f = 0; f < nf; ++f) {
        comp_info* c = &comps[face_comp[f]];
        order[c->first_face + c->face_count++] = f;
    }
    return count;
}

/* Marks the components that are closed and consistently oriented: every
 * edge used by exactly two faces, in opposite directions. */
static meso_result mark_closed(const meso_mesh* m, const uint32_t* face_comp, comp_info* comps, uint32_t count)
{
    const size_t ne = 3 * (size_t)m->triangle_count;
    orient_edge* e = malloc(sizeof(*e) * (ne ? ne : 1));
    if (!e)
        return MESO_ERR_OUT_OF_MEMORY;
    for (size_t f = 0; f < m->triangle_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m->indices[3 * f + (size_t)k], b = m->indices[3 * f + (size_t)(k + 1) % 3];
            const uint64_t lo = a < b ? a : b, hi = a < b ? b : a;
            e[3 * f + (size_t)k] = (orient_edge){.key = lo << 32 | hi, .from = a, .comp = face_comp[f]};
        }
    qsort(e, ne, sizeof(*e), cmp_edge);
    for (uint32_t i = 0; i < count; ++i)
        comps[i].closed = 1;
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && e[j].key == e[i].key)
            ++j;
        if (j - i != 2 || e[i].from == e[i + 1].from)
            comps[e[i].comp].closed = 0;
        i = j;
    }
    free(e);
    return MESO_OK;
}

meso_result meso_mesh_orient_outward(meso_mesh* m, meso_mesh_orientation* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    const uint32_t nv = m->vertex_count, nf = m->triangle_count;
    if (nf == 0)
        return MESO_OK;
    uint32_t* parent = malloc(sizeof(uint32_t) * nv);
    uint32_t* face_comp = malloc(sizeof(uint32_t) * nf);
    uint32_t* order = malloc(sizeof(uint32_t) * (nf > nv ? nf : nv));
    comp_info* comps = NULL;
    meso_result r = parent && face_comp && order ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    uint32_t count = 0;
    int any_negative = 0;
    if (r == MESO_OK) {
        count = find_components(m, parent, face_comp, order, &comps);
        r = comps ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r == MESO_OK) {
        for (uint32_t i = 0; i < count; ++i)
            any_negative |= comps[i].volume6 < 0;
        out->components = count;
    }
    /* Every volume positive (the usual case): nothing can be inside-out. */
    if (r == MESO_OK && any_negative)
        r = mark_closed(m, face_comp, comps, count);
    if (r == MESO_OK && any_negative) {
        /* Judged: closed, with a volume clearly away from zero. */
        for (uint32_t i = 0; i < count; ++i) {
            comp_info* c = &comps[i];
            const double d = dist3(c->hi, c->lo);
            c->closed = c->closed && fabs(c->volume6) > 1e-9 * d * d * d;
            out->closed_components += (uint32_t)c->closed;
        }
        /* Negative volumes first: flipped at even depth. Then the positive
         * components inside a flipped one's box: flipped at odd depth when
         * their direct container was. Nothing else needs its depth. */
        uint64_t work = 0;
        for (int pass = 0; pass < 2 && work <= MESO_ORIENT_MAX_WORK; ++pass)
            for (uint32_t i = 0; i < count && work <= MESO_ORIENT_MAX_WORK; ++i) {
                comp_info* c = &comps[i];
                if (!c->closed || (pass == 0) != (c->volume6 < 0))
                    continue;
                const double p[3] = {m->positions[3 * (size_t)c->probe], m->positions[3 * (size_t)c->probe + 1],
                                     m->positions[3 * (size_t)c->probe + 2]};
                int near_flipped = 0;
                for (uint32_t j = 0; pass == 1 && j < count && !near_flipped; ++j)
                    near_flipped = comps[j].flip && bbox_contains(&comps[j], p);
                work += pass == 1 ? count : 0;
                if (pass == 1 && !near_flipped)
                    continue;
                nest(m, order, comps, count, i, p, &work);
                c->flip = pass == 0 ? c->depth % 2 == 0
                                    : c->depth % 2 == 1 && c->container >= 0 && comps[c->container].flip;
            }
        if (work > MESO_ORIENT_MAX_WORK) {
            out->unchecked = 1; /* too many nested components to judge in bounded time: leave the mesh as it is */
            for (uint32_t i = 0; i < count; ++i)
                comps[i].flip = 0;
        }
        for (uint32_t i = 0; i < count; ++i)
            if (comps[i].flip) {
                out->reoriented_components++;
                out->reoriented_faces += comps[i].face_count;
            }
    }
    if (r == MESO_OK && out->reoriented_components) {
        for (uint32_t f = 0; f < nf; ++f) {
            if (!comps[face_comp[f]].flip)
                continue;
            uint32_t* ix = m->indices + 3 * (size_t)f;
            const uint32_t t = ix[1];
            ix[1] = ix[2];
            ix[2] = t;
            if (m->corner_uvs)
                for (int k = 0; k < 2; ++k) {
                    float* uv = m->corner_uvs + 6 * (size_t)f;
                    const float s = uv[2 + k];
                    uv[2 + k] = uv[4 + k];
                    uv[4 + k] = s;
                }
        }
        /* A vertex belongs to the component of any face using it. */
        for (uint32_t f = 0; m->normals && f < nf; ++f)
            if (comps[face_comp[f]].flip)
                for (int k = 0; k < 3; ++k)
                    parent[m->indices[3 * (size_t)f + (size_t)k]] = UINT32_MAX;
        for (uint32_t v = 0; m->normals && v < nv; ++v)
            if (parent[v] == UINT32_MAX)
                for (int k = 0; k < 3; ++k)
                    m->normals[3 * (size_t)v + (size_t)k] = -m->normals[3 * (size_t)v + (size_t)k];
    }
    free(parent);
    free(face_comp);
    free(order);
    free(comps);
    if (r != MESO_OK)
        return meso_bake_fail(err, r, 0, "orientation: out of memory (%u triangles)", nf);
    return MESO_OK;
}
