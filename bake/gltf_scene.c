/*
 * gltf_scene.c — a glTF 2.0 scene as one mesh (meso_gltf_load, gltf_model.h).
 *
 * glTF 2.0 sections 3.5 (node hierarchy: a forest, no cycles, one parent per
 * node; local matrix = matrix, or T * R * S), 3.7.2 (primitive modes: 4
 * triangles, 5 strip, 6 fan; a negative-determinant world matrix reverses
 * the winding) and 3.9.2 (pbrMetallicRoughness base colour). The document
 * comes from the adapter unchecked; every reference is checked here before
 * it is followed, and accessors by gltf_accessor.c. The triangles of every
 * primitive drawn by the chosen nodes become one soup in world space, welded
 * by mesh_weld.c. KHR_draco_mesh_compression primitives are decoded by the
 * Draco adapter.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "adapters.h"
#include "gltf_model.h"
#include "mesh_guard.h"
#include "mesh_weld.h"

#if MESO_HAVE_GLTF /* else only meso_gltf_load, refusing */

/* The growing soup: world positions, uvs (OBJ convention), triangles. */
typedef struct soup {
    float* xyz;
    float* uv;
    size_t nv, cap_v;
    uint32_t* tri;
    uint32_t* mat;
    size_t nt, cap_t;
    int any_uv;
} soup;

typedef struct loader {
    const char* path;
    const meso_gltf_model* g;
    uint64_t max_bytes;
    double* world;   /* 16 per node, column-major */
    uint8_t* done;   /* world[] computed */
    int* parent;     /* -1: root */
    uint8_t* used_material;
    soup s;
    meso_error* err;
} loader;

static meso_result fail(loader* L, uint32_t code, const char* fmt, const char* place, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 5)))
#endif
    ;
/* "path: place: message", MESO_ERR_CORRUPT with `code`. */
static meso_result fail(loader* L, uint32_t code, const char* fmt, const char* place, ...)
{
    char msg[200];
    va_list ap;
    va_start(ap, place);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    return meso_bake_fail(L->err, MESO_ERR_CORRUPT, code, "%s: %s: %s", L->path, place, msg);
}

static meso_result oom(loader* L)
{
    return meso_bake_fail(L->err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", L->path);
}

/* >>graph ------------------------------------------------------------------ */

/* parent[] from the children lists: refuses a missing child, a node with two
 * parents and a cycle (which a graph of single parents has only without a
 * root above it: found by walking up at most node_count steps). */
static meso_result build_parents(loader* L)
{
    const meso_gltf_model* g = L->g;
    for (uint32_t i = 0; i < g->node_count; ++i)
        L->parent[i] = -1;
    char place[96];
    for (uint32_t i = 0; i < g->node_count; ++i) {
        const meso_gltf_node* n = &g->nodes[i];
        if (n->first_child > g->child_count || n->child_count > g->child_count - n->first_child)
            return oom(L); /* the adapter's arrays disagree: cannot happen */
        for (uint32_t k = 0; k < n->child_count; ++k) {
            const int c = g->children[n->first_child + k];
            snprintf(place, sizeof(place), "nodes[%u].children[%u]", i, k);
            if (c < 0 || (uint32_t)c >= g->node_count)
                return fail(L, MESO_GLTF_ISSUE_REFERENCE, "node %d does not exist (%d nodes)", place, c,
                            (int)g->node_count);
            if ((uint32_t)c == i)
                return fail(L, MESO_GLTF_ISSUE_GRAPH, "node %d is its own child (a cycle)", place, c);
            if (L->parent[c] >= 0)
                return fail(L, MESO_GLTF_ISSUE_GRAPH, "node %d has two parents (nodes[%d] too)", place, c,
                            L->parent[c]);
            L->parent[c] = (int)i;
        }
    }
    for (uint32_t i = 0; i < g->node_count; ++i) {
        int p = (int)i;
        uint32_t steps = 0;
        while (p >= 0 && steps <= g->node_count)
            p = L->parent[p], ++steps;
        if (p >= 0) {
            snprintf(place, sizeof(place), "nodes[%u]", i);
            return fail(L, MESO_GLTF_ISSUE_GRAPH, "the node hierarchy has a cycle through it", place);
        }
    }
    return MESO_OK;
}

static void local_matrix(const meso_gltf_node* n, double m[16])
{
    if (n->has_matrix) {
        memcpy(m, n->matrix, sizeof(double) * 16);
        return;
    }
    const double x = n->rotation[0], y = n->rotation[1], z = n->rotation[2], w = n->rotation[3];
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    memset(m, 0, sizeof(double) * 16);
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
            m[4 * c + k] = r[3 * c + k] * n->scale[c];
    for (int k = 0; k < 3; ++k)
        m[12 + k] = n->translation[k];
    m[15] = 1.0;
}

static void multiply(const double a[16], const double b[16], double out[16])
{
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double s = 0.0;
            for (int k = 0; k < 4; ++k)
                s += a[4 * k + r] * b[4 * c + k];
            out[4 * c + r] = s;
        }
}

/* The world matrix of node i (its ancestors' first, iteratively). */
static const double* world_of(loader* L, int i)
{
    while (!L->done[i]) {
        int top = i; /* the highest ancestor not yet done */
        while (L->parent[top] >= 0 && !L->done[L->parent[top]])
            top = L->parent[top];
        double local[16];
        local_matrix(&L->g->nodes[top], local);
        if (L->parent[top] >= 0)
            multiply(L->world + 16 * (size_t)L->parent[top], local, L->world + 16 * (size_t)top);
        else
            memcpy(L->world + 16 * (size_t)top, local, sizeof(local));
        L->done[top] = 1;
    }
    return L->world + 16 * (size_t)i;
}

/* >>primitives ------------------------------------------------------------ */

/* Grow two parallel arrays (a_size and b_size bytes per element) to hold
 * `need` elements; 0 when out of memory (the arrays stay valid). */
static int grow(void** a, size_t a_size, void** b, size_t b_size, size_t* cap, size_t need)
{
    if (need <= *cap)
        return 1;
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    void* x = realloc(*a, a_size * c);
    if (x)
        *a = x;
    void* y = x ? realloc(*b, b_size * c) : NULL;
    if (y)
        *b = y;
    if (!x || !y)
        return 0;
    *cap = c;
    return 1;
}

static int reserve(soup* s, size_t nv, size_t nt)
{
    void *xyz = s->xyz, *uv = s->uv, *tri = s->tri, *mat = s->mat;
    const int ok = grow(&xyz, 3 * sizeof(float), &uv, 2 * sizeof(float), &s->cap_v, s->nv + nv) &&
                   grow(&tri, 3 * sizeof(uint32_t), &mat, sizeof(uint32_t), &s->cap_t, s->nt + nt);
    s->xyz = xyz, s->uv = uv, s->tri = tri, s->mat = mat;
    return ok;
}

/* The primitive's vertices (positions, uvs) and corner indices: from the
 * Draco bitstream, or from its accessors. */
typedef struct prim_data {
    float* xyz;
    float* uv;
    size_t nv;
    uint32_t* ix;
    size_t ni;
} prim_data;

static meso_result read_draco(loader* L, const meso_gltf_primitive* p, const char* place, prim_data* d)
{
    const meso_gltf_model* g = L->g;
    char where[128];
    snprintf(where, sizeof(where), "%s.extensions.KHR_draco_mesh_compression", place);
    if (p->draco_view < 0 || p->draco_position == -2 || p->draco_texcoord == -2 || p->draco_position < 0)
        return fail(L, MESO_GLTF_ISSUE_SCHEMA, "needs a bufferView and attributes.POSITION (integers)", where);
    if ((uint32_t)p->draco_view >= g->view_count)
        return fail(L, MESO_GLTF_ISSUE_REFERENCE, "bufferView %d does not exist (%d bufferViews)", where,
                    p->draco_view, (int)g->view_count);
    const meso_gltf_view* v = &g->views[p->draco_view];
    if (v->buffer < 0 || (uint32_t)v->buffer >= g->buffer_count)
        return fail(L, MESO_GLTF_ISSUE_REFERENCE, "bufferViews[%d]: buffer %d does not exist", where,
                    p->draco_view, v->buffer);
    const meso_gltf_buffer* b = &g->buffers[v->buffer];
    if (v->offset > b->size || v->length > b->size - v->offset)
        return fail(L, MESO_GLTF_ISSUE_BOUNDS, "bufferViews[%d] lies outside buffers[%d]", where, p->draco_view,
                    v->buffer);
#if MESO_HAVE_DRACO
    meso_mesh dm;
    meso_error derr = {0};
    if (meso_draco_decode(b->data + v->offset, v->length, &dm, &derr) != MESO_OK)
        return meso_bake_fail(L->err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_DRACO, "%s: %s: %s", L->path, where,
                              derr.message);
    const int want_uv = p->texcoord >= 0 && p->draco_texcoord >= 0;
    size_t acc_count = p->position >= 0 && (uint32_t)p->position < g->accessor_count
                           ? g->accessors[p->position].count
                           : dm.vertex_count;
    if (acc_count != dm.vertex_count || (want_uv && !dm.uvs)) {
        const int nv = (int)dm.vertex_count;
        meso_mesh_free(&dm);
        return fail(L, MESO_GLTF_ISSUE_DRACO, "decodes to %d points without the attributes its accessors "
                    "declare (POSITION count %d)", where, nv, (int)acc_count);
    }
    d->xyz = dm.positions;
    d->nv = dm.vertex_count;
    d->ix = dm.indices;
    d->ni = 3 * (size_t)dm.triangle_count;
    if (want_uv) {
        d->uv = dm.uvs;
        dm.uvs = NULL;
    }
    dm.positions = NULL;
    dm.indices = NULL;
    meso_mesh_free(&dm);
    return MESO_OK;
#else
    (void)b;
    (void)d;
    return meso_bake_fail(L->err, MESO_ERR_UNSUPPORTED, 0, "%s: %s: needs the Draco adapter", L->path, where);
#endif
}

static meso_result read_accessors(loader* L, const meso_gltf_primitive* p, const char* place, prim_data* d)
{
    char where[128];
    snprintf(where, sizeof(where), "%s.attributes.POSITION", place);
    if (p->position < 0)
        return fail(L, MESO_GLTF_ISSUE_SCHEMA, "missing", where);
    meso_result r = meso_gltf_read_floats(L->path, L->g, p->position, where, 3, 0, &d->xyz, &d->nv, L->err);
    if (r == MESO_OK && p->texcoord >= 0) {
        size_t n = 0;
        snprintf(where, sizeof(where), "%s.attributes.TEXCOORD_0", place);
        r = meso_gltf_read_floats(L->path, L->g, p->texcoord, where, 2, 1, &d->uv, &n, L->err);
        if (r == MESO_OK && n != d->nv)
            r = fail(L, MESO_GLTF_ISSUE_TYPE, "count %d differs from POSITION's %d", where, (int)n, (int)d->nv);
    }
    if (r != MESO_OK)
        return r;
    if (p->indices >= 0) {
        snprintf(where, sizeof(where), "%s.indices", place);
        return meso_gltf_read_indices(L->path, L->g, p->indices, where, d->nv, &d->ix, &d->ni, L->err);
    }
    d->ix = malloc(sizeof(uint32_t) * (d->nv ? d->nv : 1));
    if (!d->ix)
        return oom(L);
    for (size_t i = 0; i < d->nv; ++i)
        d->ix[i] = (uint32_t)i;
    d->ni = d->nv;
    return MESO_OK;
}

/* Corner k of triangle t of a primitive with `mode` over `ix`. */
static uint32_t corner(int mode, const uint32_t* ix, size_t t, int k)
{
    if (mode == MESO_GLTF_MODE_TRIANGLES)
        return ix[3 * t + (size_t)k];
    if (mode == MESO_GLTF_MODE_TRIANGLE_STRIP) {
        const size_t odd = t % 2;
        return ix[k == 0 ? t : k == 1 ? t + 1 + odd : t + 2 - odd];
    }
    return ix[k == 0 ? t + 1 : k == 1 ? t + 2 : 0]; /* fan */
}

static meso_result add_primitive(loader* L, int node, uint32_t mesh, uint32_t k)
{
    const meso_gltf_model* g = L->g;
    const meso_gltf_mesh* me = &g->meshes[mesh];
    const meso_gltf_primitive* p = &g->primitives[me->first_primitive + k];
    char place[64];
    snprintf(place, sizeof(place), "meshes[%u].primitives[%u]", mesh, k);
    if (p->mode >= 0 && p->mode <= 3) {
        static const char* const names[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"};
        return meso_bake_fail(L->err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_MODE,
                              "%s: %s.mode: %d (%s) is not triangles", L->path, place, p->mode, names[p->mode]);
    }
    if (p->mode > 6)
        return fail(L, MESO_GLTF_ISSUE_SCHEMA, "mode %d is not a glTF primitive mode", place, p->mode);
    if (p->material >= 0 && (uint32_t)p->material >= g->material_count)
        return fail(L, MESO_GLTF_ISSUE_REFERENCE, "material %d does not exist (%d materials)", place, p->material,
                    (int)g->material_count);
    prim_data d = {0};
    meso_result r = p->draco_view != -1 ? read_draco(L, p, place, &d) : read_accessors(L, p, place, &d);
    size_t nt = 0;
    if (r == MESO_OK) {
        if (p->mode == MESO_GLTF_MODE_TRIANGLES && d.ni % 3 != 0)
            r = fail(L, MESO_GLTF_ISSUE_TYPE, "%d indices are not a multiple of 3", place, (int)d.ni);
        nt = p->mode == MESO_GLTF_MODE_TRIANGLES ? d.ni / 3 : d.ni >= 3 ? d.ni - 2 : 0;
    }
    const uint64_t total_v = (uint64_t)L->s.nv + d.nv, total_t = (uint64_t)L->s.nt + nt;
    if (r == MESO_OK && (total_v > UINT32_MAX / 4 || total_t > UINT32_MAX / 8 ||
                         total_v * MESO_MESH_GUARD_BYTES_PER_VERTEX + total_t * MESO_MESH_GUARD_BYTES_PER_TRIANGLE >
                             L->max_bytes))
        r = meso_bake_fail(L->err, MESO_ERR_CORRUPT, MESO_MESH_GUARD_BUDGET,
                           "%s: %s: %llu vertices and %llu triangles would need more than the memory budget", L->path,
                           place, (unsigned long long)total_v, (unsigned long long)total_t);
    if (r == MESO_OK && !reserve(&L->s, d.nv, nt))
        r = oom(L);
    if (r == MESO_OK) {
        const double* w = world_of(L, node);
        const double det = w[0] * (w[5] * w[10] - w[9] * w[6]) - w[4] * (w[1] * w[10] - w[9] * w[2]) +
                           w[8] * (w[1] * w[6] - w[5] * w[2]);
        int identity = 1; /* then positions are kept bit for bit (-0 stays -0) */
        for (int e = 0; e < 16; ++e)
            identity &= w[e] == (e % 5 == 0 ? 1.0 : 0.0);
        for (size_t v = 0; v < d.nv && r == MESO_OK; ++v) {
            const float* x = d.xyz + 3 * v;
            float* o = L->s.xyz + 3 * (L->s.nv + v);
            for (int c = 0; c < 3; ++c) {
                const double y = identity ? x[c] : w[c] * x[0] + w[4 + c] * x[1] + w[8 + c] * x[2] + w[12 + c];
                if (!isfinite(x[c]) || !(fabs(y) <= 3.0e38))
                    r = fail(L, MESO_GLTF_ISSUE_NONFINITE, "vertex %d has a non-finite position", place, (int)v);
                o[c] = (float)y;
            }
            float* u = L->s.uv + 2 * (L->s.nv + v);
            u[0] = d.uv ? d.uv[2 * v] : 0.0f;
            u[1] = d.uv ? 1.0f - d.uv[2 * v + 1] : 0.0f; /* glTF's v runs down, OBJ's up */
            if (d.uv && (!isfinite(u[0]) || !isfinite(u[1])))
                r = fail(L, MESO_GLTF_ISSUE_NONFINITE, "vertex %d has a non-finite TEXCOORD_0", place, (int)v);
        }
        for (size_t t = 0; t < nt && r == MESO_OK; ++t) {
            uint32_t* o = L->s.tri + 3 * (L->s.nt + t);
            for (int c = 0; c < 3; ++c)
                o[c] = (uint32_t)L->s.nv + corner(p->mode, d.ix, t, det < 0.0 ? (c == 0 ? 0 : 3 - c) : c);
            L->s.mat[L->s.nt + t] = p->material >= 0 ? (uint32_t)p->material : UINT32_MAX;
        }
        if (r == MESO_OK) {
            L->s.nv += d.nv;
            L->s.nt += nt;
            L->s.any_uv |= d.uv != NULL;
            if (p->material >= 0)
                L->used_material[p->material] = 1;
        }
    }
    free(d.xyz);
    free(d.uv);
    free(d.ix);
    return r;
}

/* Every primitive drawn by the subtree of `root` (depth first, iteratively). */
static meso_result add_subtree(loader* L, int root, int* stack)
{
    const meso_gltf_model* g = L->g;
    size_t top = 0;
    stack[top++] = root;
    while (top) {
        const int n = stack[--top];
        const meso_gltf_node* node = &g->nodes[n];
        if (node->mesh >= 0) {
            if ((uint32_t)node->mesh >= g->mesh_count) {
                char place[48];
                snprintf(place, sizeof(place), "nodes[%d].mesh", n);
                return fail(L, MESO_GLTF_ISSUE_REFERENCE, "mesh %d does not exist (%d meshes)", place, node->mesh,
                            (int)g->mesh_count);
            }
            const meso_gltf_mesh* me = &g->meshes[node->mesh];
            for (uint32_t k = 0; k < me->primitive_count; ++k) {
                meso_result r = add_primitive(L, n, (uint32_t)node->mesh, k);
                if (r != MESO_OK)
                    return r;
            }
        }
        for (uint32_t k = node->child_count; k-- > 0;) /* a forest: each node is pushed once */
            stack[top++] = g->children[node->first_child + k];
    }
    return MESO_OK;
}

/* >>materials -------------------------------------------------------------- */

static meso_result add_materials(loader* L, meso_mesh_materials* m)
{
    const meso_gltf_model* g = L->g;
    if (!g->material_count)
        return MESO_OK;
    m->materials = calloc(g->material_count, sizeof(meso_mesh_material));
    if (!m->materials)
        return oom(L);
    m->material_count = g->material_count;
    for (uint32_t i = 0; i < g->material_count; ++i) {
        const meso_gltf_material* src = &g->materials[i];
        meso_mesh_material* dst = &m->materials[i];
        char place[96];
        snprintf(place, sizeof(place), "materials[%u].pbrMetallicRoughness", i);
        for (int c = 0; c < 4; ++c) {
            dst->base_color_factor[c] = (float)src->base_color_factor[c];
            if (!(src->base_color_factor[c] >= 0.0 && src->base_color_factor[c] <= 1.0))
                return fail(L, MESO_GLTF_ISSUE_SCHEMA, "baseColorFactor[%d] is not in [0, 1]", place, c);
        }
        const int t = src->base_color_texture;
        if (t < 0 || !L->used_material[i])
            continue;
        if ((uint32_t)t >= g->texture_count)
            return fail(L, MESO_GLTF_ISSUE_REFERENCE, "baseColorTexture: texture %d does not exist (%d textures)",
                        place, t, (int)g->texture_count);
        const int im = g->texture_sources[t];
        if (im < 0 || (uint32_t)im >= g->image_count)
            return fail(L, MESO_GLTF_ISSUE_REFERENCE, "textures[%d].source: image %d does not exist", place, t, im);
        const meso_gltf_image* img = &g->images[im];
        const size_t bpc = (size_t)img->bits / 8, comps = (size_t)img->components;
        const size_t texels = (size_t)img->width * (size_t)img->height;
        if (!img->pixels || img->width <= 0 || img->height <= 0 || (bpc != 1 && bpc != 2) || comps < 1 ||
            comps > 4 || img->size < texels * comps * bpc)
            return fail(L, MESO_GLTF_ISSUE_IMAGE,
                        "baseColorTexture: images[%d] does not decode (PNG and JPEG are read) or its pixels exceed "
                        "the memory budget",
                        place, im);
        if ((uint64_t)texels * 4 > L->max_bytes)
            return fail(L, MESO_MESH_GUARD_BUDGET, "images[%d]: %d texels exceed the memory budget", place, im,
                        (int)texels);
        dst->rgba = malloc(texels * 4);
        if (!dst->rgba)
            return oom(L);
        dst->width = (uint32_t)img->width;
        dst->height = (uint32_t)img->height;
        dst->texcoord = (uint32_t)(src->base_color_texcoord > 0 ? src->base_color_texcoord : 0);
        for (size_t x = 0; x < texels; ++x)
            for (size_t c = 0; c < 4; ++c) {
                /* grey (1), grey+alpha (2), RGB (3), RGBA (4); 16-bit: the high byte */
                const size_t sc = comps >= 3 ? (c < comps ? c : SIZE_MAX) : (c < 3 ? 0 : comps == 2 ? 1 : SIZE_MAX);
                const uint8_t* s = img->pixels + (x * comps + (sc == SIZE_MAX ? 0 : sc)) * bpc;
                dst->rgba[4 * x + c] = sc == SIZE_MAX ? 255 : bpc == 2 ? s[1] : s[0];
            }
    }
    return MESO_OK;
}

/* >>load ------------------------------------------------------------------- */

/* The node `sel` names: a node name, else a decimal index; -1 when none. */
static int find_node(const meso_gltf_model* g, const char* sel)
{
    for (uint32_t i = 0; i < g->node_count; ++i)
        if (g->nodes[i].name && strcmp(g->nodes[i].name, sel) == 0)
            return (int)i;
    char* end;
    const long v = strtol(sel, &end, 10);
    return *sel && !*end && sel[0] >= '0' && sel[0] <= '9' && v >= 0 && v < (int)g->node_count ? (int)v : -1;
}

static meso_result load_model(loader* L, const char* node_sel, meso_mesh* out, meso_mesh_materials* mats,
                              uint32_t* dropped)
{
    const meso_gltf_model* g = L->g;
    if (g->unsupported_extension)
        return meso_bake_fail(L->err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_UNSUPPORTED,
                              "%s: extensionsRequired: %s is not read (only KHR_draco_mesh_compression)", L->path,
                              g->unsupported_extension);
    meso_result r = build_parents(L);
    if (r != MESO_OK)
        return r;
    int* stack = malloc(sizeof(int) * (g->node_count ? g->node_count : 1));
    if (!stack)
        return oom(L);
    if (node_sel) {
        const int n = find_node(g, node_sel);
        r = n < 0 ? meso_bake_fail(L->err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_NODE,
                                   "%s: --node %s: no node has that name or index (%u nodes)", L->path, node_sel,
                                   g->node_count)
                  : add_subtree(L, n, stack);
    } else if (g->scene_count || g->default_scene >= 0) {
        const int sc = g->default_scene >= 0 ? g->default_scene : 0;
        if ((uint32_t)sc >= g->scene_count)
            r = fail(L, MESO_GLTF_ISSUE_REFERENCE, "scene %d does not exist (%d scenes)", "scene", sc,
                     (int)g->scene_count);
        const meso_gltf_scene* s = r == MESO_OK ? &g->scenes[sc] : NULL;
        for (uint32_t k = 0; s && k < s->node_count && r == MESO_OK; ++k) {
            const int n = g->scene_nodes[s->first_node + k];
            char place[64];
            snprintf(place, sizeof(place), "scenes[%d].nodes[%u]", sc, k);
            if (n < 0 || (uint32_t)n >= g->node_count)
                r = fail(L, MESO_GLTF_ISSUE_REFERENCE, "node %d does not exist (%d nodes)", place, n,
                         (int)g->node_count);
            else if (L->parent[n] >= 0)
                r = fail(L, MESO_GLTF_ISSUE_GRAPH, "node %d is not a root (a child of nodes[%d])", place, n,
                         L->parent[n]);
            else
                r = add_subtree(L, n, stack);
        }
    } else {
        for (uint32_t n = 0; n < g->node_count && r == MESO_OK; ++n)
            if (L->parent[n] < 0)
                r = add_subtree(L, (int)n, stack);
    }
    free(stack);
    if (r == MESO_OK && L->s.nt == 0)
        r = meso_bake_fail(L->err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_EMPTY, "%s: %s holds no triangles", L->path,
                           node_sel ? "the chosen node" : "the scene");
    if (r != MESO_OK)
        return r;
    const meso_weld_input in = {L->s.xyz, L->s.any_uv ? L->s.uv : NULL, L->s.nv, L->s.tri, L->s.mat, L->s.nt};
    r = meso_mesh_weld(&in, out, g->material_count ? &mats->triangle_materials : NULL, dropped, L->err);
    if (r == MESO_OK)
        r = add_materials(L, mats);
    return r;
}

#endif /* MESO_HAVE_GLTF */

meso_result meso_gltf_load(const char* path, const char* node, uint64_t max_bytes, meso_mesh* out,
                           meso_mesh_materials* materials, uint32_t* dropped, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    meso_mesh_materials local;
    meso_mesh_materials* mats = materials ? materials : &local;
    memset(mats, 0, sizeof(*mats));
    *dropped = 0;
#if MESO_HAVE_GLTF
    if (max_bytes == 0)
        max_bytes = MESO_MESH_GUARD_DEFAULT_MAX_BYTES;
    meso_gltf_model g;
    meso_result r = meso_gltf_read(path, max_bytes, &g, err);
    if (r != MESO_OK)
        return r;
    loader L;
    memset(&L, 0, sizeof(L));
    L.path = path;
    L.g = &g;
    L.max_bytes = max_bytes;
    L.err = err;
    const size_t nn = g.node_count ? g.node_count : 1;
    L.world = malloc(sizeof(double) * 16 * nn);
    L.done = calloc(nn, 1);
    L.parent = malloc(sizeof(int) * nn);
    L.used_material = calloc(g.material_count ? g.material_count : 1, 1);
    r = L.world && L.done && L.parent && L.used_material ? load_model(&L, node, out, mats, dropped) : oom(&L);
    free(L.world);
    free(L.done);
    free(L.parent);
    free(L.used_material);
    free(L.s.xyz);
    free(L.s.uv);
    free(L.s.tri);
    free(L.s.mat);
    meso_gltf_model_free(&g);
    if (r != MESO_OK)
        meso_mesh_free(out);
    if (r != MESO_OK || !materials)
        meso_mesh_materials_free(mats);
    return r;
#else
    (void)node;
    (void)max_bytes;
    (void)materials;
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "%s: glTF input needs the tinygltf adapter", path);
#endif
}
