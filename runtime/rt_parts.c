/*
 * rt_parts.c — a levelled mesh object drawn part by part (FORMAT.md §7.11,
 * issue 14: "each part ... draws the coarsest level whose projected error
 * is ≤ τ; neighbouring parts may differ by at most one level and never
 * crack").
 *
 * Where the object's whole levels would draw level 0 (some of it is near),
 * an object stored with parts draws each part at its own level instead, so
 * the far end of a long object, or the far side of a near one, draws and
 * holds less. Where they would draw a coarser level L, the parts draw
 * instead when their own levels hold fewer bytes than L does: a
 * mid-distance object's far side is coarser still, while a far object
 * keeps its one small coarsest level (a part's coarsest is larger than its
 * share of the object's). A shell's parts draw so, at any L, when every
 * one of them wants its stand-in patch: then its native level is not
 * needed (where some part wants its prisms, they draw with the native
 * level, below). How:
 *
 *  - each part's level is the coarsest whose error, projected at the
 *    nearest point of that level's bounds (rt_levels.c mesoi_projected_px,
 *    the whole levels' rule), covers at most the draw's pixel error, for
 *    every instance drawn;
 *  - then neighbours (PRTS pairs) are brought within one level of each
 *    other by lowering the coarser (repeated until nothing changes: levels
 *    only fall, so it ends). The bake makes any pair of levels meet edge to
 *    edge (bake/mesh_parts.c), so this rule is the issue's, not what keeps
 *    the surface closed;
 *  - a part level not uploaded is uploaded now (under the memory budget,
 *    evicting what this frame does not use, as whole levels are), else the
 *    part draws the nearest uploaded coarser, else finer, level of its own;
 *    when some part has none, the object draws its whole level 0 as
 *    before. With stream requests (meso_rt_desc.stream_requests) a part
 *    level not uploaded is requested as a level is (rt_stream.c), one
 *    request per part at a time; until every part has a level uploaded, the
 *    object draws the best whole level uploaded, without asking for its
 *    whole level 0 (which the parts replace).
 *
 * The pick hands out one slot (`parent`) whose mesh draw draws the parts
 * this pick chose (mesoi_parts_draw), so every draw path (single,
 * instanced, lists) takes parts through the same call it takes levels.
 */
#include "rt_internal.h"

#include <string.h>


/* Part level i's GPU bytes before its upload, no fewer than it will hold
 * (mesoi_gpu_estimate); a shell's prisms, the PTRI list, in host memory:
 * its bytes. */
static uint64_t part_estimate(const meso_rt* rt, meso_file* f, const mesoi_parts* p, uint32_t i)
{
    const meso_part_level* L = &p->lv[i];
    if (p->shell && L->rec.lod == 0)
        return L->bytes;
    uint64_t b = L->chunk >= 0 ? mesoi_gpu_estimate(rt, meso_file_chunk(f, (uint32_t)L->chunk)) : 0;
    if (L->colours >= 0)
        b += mesoi_gpu_estimate(rt, meso_file_chunk(f, (uint32_t)L->colours));
    return b;
}

void mesoi_parts_free(meso_rt* rt, mesoi_parts* p)
{
    if (!p)
        return;
    for (uint32_t i = 0; p->slot && i < p->level_count; ++i)
        if (p->slot[i].id) {
            meso_rt_release_object(rt, p->slot[i]);
            rt->bytes_resident -= p->gpu[i];
        }
    if (p->tri)
        rt->bytes_resident -= p->gpu[p->first[0]];
    mesoi_object* o = mesoi_lookup(rt, p->parent);
    if (o)
        o->parts = NULL;
    meso_rt_release_object(rt, p->parent);
    mesoi_rt_free(rt, p->lv);
    mesoi_rt_free(rt, p->first);
    mesoi_rt_free(rt, p->edges);
    mesoi_rt_free(rt, p->slot);
    mesoi_rt_free(rt, p->failed);
    mesoi_rt_free(rt, p->used);
    mesoi_rt_free(rt, p->request);
    mesoi_rt_free(rt, p->want);
    mesoi_rt_free(rt, p->chosen);
    mesoi_rt_free(rt, p->drawn);
    mesoi_rt_free(rt, p->gpu);
    mesoi_rt_free(rt, p->tri);
    mesoi_rt_free(rt, p->subset);
    mesoi_rt_free(rt, p);
}

/* The object's parts, or NULL (none, or its table not readable: the whole
 * levels draw it). MESO_ERR_PENDING when the table has not arrived. */
meso_result mesoi_parts_load(meso_rt* rt, meso_file* f, const meso_object_record* rec, mesoi_parts** out)
{
    *out = NULL;
    uint32_t nl = 0, np = 0, ne = 0;
    meso_error err;
    meso_result r = meso_file_parts(f, rec->id, NULL, 0, &nl, &np, NULL, 0, &ne, &err);
    if (r != MESO_OK || nl == 0) {
        if (r != MESO_OK && r != MESO_ERR_PENDING)
            mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "object %u: its parts cannot be read (%s); drawn by its whole levels", rec->id, err.message);
        return r == MESO_ERR_PENDING ? r : MESO_OK;
    }
    mesoi_parts* p = mesoi_rt_alloc(rt, sizeof(*p));
    if (!p)
        return MESO_ERR_OUT_OF_MEMORY;
    memset(p, 0, sizeof(*p));
    p->part_count = np;
    p->level_count = nl;
    p->edge_count = ne;
    p->lv = mesoi_rt_alloc(rt, sizeof(meso_part_level) * nl);
    p->first = mesoi_rt_alloc(rt, sizeof(uint32_t) * (np + 1));
    p->edges = mesoi_rt_alloc(rt, sizeof(uint32_t) * 2 * (ne ? ne : 1));
    p->slot = mesoi_rt_alloc(rt, sizeof(meso_rt_object) * nl);
    p->failed = mesoi_rt_alloc(rt, nl);
    p->used = mesoi_rt_alloc(rt, sizeof(uint64_t) * nl);
    p->request = mesoi_rt_alloc(rt, sizeof(struct meso_rt_request*) * nl);
    p->want = mesoi_rt_alloc(rt, sizeof(uint32_t) * np);
    p->chosen = mesoi_rt_alloc(rt, sizeof(meso_rt_object) * np);
    p->drawn = mesoi_rt_alloc(rt, np);
    p->gpu = mesoi_rt_alloc(rt, sizeof(uint64_t) * 2 * nl);
    r = p->lv && p->first && p->edges && p->slot && p->failed && p->used && p->request && p->want && p->chosen && p->drawn &&
                p->gpu
            ? MESO_OK
            : MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_OK) {
        memset(p->slot, 0, sizeof(meso_rt_object) * nl);
        memset(p->failed, 0, nl);
        memset(p->used, 0, sizeof(uint64_t) * nl);
        memset(p->request, 0, sizeof(struct meso_rt_request*) * nl);
        memset(p->drawn, 0, np);
        r = meso_file_parts(f, rec->id, p->lv, nl, &nl, &np, p->edges, ne, &ne, &err);
        if (r != MESO_OK && r != MESO_ERR_PENDING)
            mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "object %u: its parts cannot be read (%s); drawn by its whole levels", rec->id, err.message);
    }
    /* Part p's levels: records are by part (1..), lods consecutive (the
     * format's rules, checked by meso_file_parts). */
    for (uint32_t i = 0, q = 0; r == MESO_OK && q <= np; ++q) {
        while (i < nl && p->lv[i].rec.object < q + 1)
            ++i;
        p->first[q] = i;
    }
    if (r == MESO_OK)
        r = mesoi_empty_slot(rt, rec, &p->parent);
    p->shell = rec->kind == MESO_OBJECT_SHELL;
    for (uint32_t i = 0; r == MESO_OK && i < nl; ++i) /* estimates until uploaded (rt_levels.c's rule) */
        p->gpu[i] = p->gpu[nl + i] = part_estimate(rt, f, p, i);
    if (r == MESO_OK && p->shell) {
        p->subset = mesoi_rt_alloc(rt, sizeof(uint32_t) * (nl ? nl : 1)); /* grown when the list is read */
        r = p->subset ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r == MESO_OK) {
        mesoi_object* o = mesoi_lookup(rt, p->parent);
        o->kind = rec->kind; /* its draw (mesh or shell) draws the parts */
        o->parts = p;
        *out = p;
        return MESO_OK;
    }
    mesoi_parts_free(rt, p);
    return r == MESO_ERR_PENDING ? r : (r == MESO_ERR_OUT_OF_MEMORY ? r : MESO_OK);
}

/* A shell part's lod 0, its prisms. */
static int prisms(const mesoi_parts* p, uint32_t i) { return p->shell && p->lv[i].rec.lod == 0; }

/* Whether part level i can be drawn: uploaded, or (prisms) the list read. */
static int have(const mesoi_parts* p, uint32_t i) { return prisms(p, i) ? p->tri != NULL : p->slot[i].id != 0; }

/* A shell's prisms: its PTRI list, read once for every part (counted at
 * the first part's lod 0); a list that does not fit the shell marks every
 * part's prisms failed. */
static meso_result read_prisms(meso_rt* rt, meso_file* f, const meso_object_record* rec, mesoi_parts* p)
{
    const uint32_t i0 = p->first[0];
    void* data = NULL;
    size_t size = 0;
    meso_result r = mesoi_read_whole(rt, f, p->lv[i0].chunk, &data, &size);
    uint32_t* grown = r == MESO_OK ? mesoi_rt_alloc(rt, size ? size : 1) : NULL;
    if (r == MESO_OK && !grown)
        r = MESO_ERR_OUT_OF_MEMORY;
    const uint32_t n = (uint32_t)(size / sizeof(uint32_t));
    for (uint32_t q = 0; r == MESO_OK && q < p->part_count; ++q) {
        const meso_part_level* L = &p->lv[p->first[q]];
        if ((uint64_t)L->first_triangle + L->triangle_count > n)
            r = MESO_ERR_CORRUPT;
    }
    if (r == MESO_OK) {
        p->tri = data;
        p->tri_count = n;
        mesoi_rt_free(rt, p->subset);
        p->subset = grown;
        p->subset_key = 0; /* holds nothing yet: the next pick fills it */
        rt->bytes_resident += p->gpu[i0];
        if (!rt->prefetch)
            p->bytes_read += p->lv[i0].bytes;
        return MESO_OK;
    }
    mesoi_rt_free(rt, data);
    mesoi_rt_free(rt, grown);
    if (r != MESO_ERR_PENDING && r != MESO_ERR_OUT_OF_MEMORY) {
        for (uint32_t q = 0; q < p->part_count; ++q)
            p->failed[p->first[q]] = 1;
        mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "object %u: its parts' prisms (PTRI) could not be read; drawn by its whole levels", rec->id);
    }
    return r;
}

/* Upload part level i (its PMSH) into a slot of its own; a shell part's
 * lod 0, its prisms: the PTRI list. */
meso_result mesoi_parts_upload(meso_rt* rt, meso_file* f, const meso_object_record* rec, mesoi_parts* p, uint32_t i)
{
    if (have(p, i))
        return MESO_OK;
    if (prisms(p, i))
        return p->failed[i] ? MESO_ERR_NOT_FOUND : read_prisms(rt, f, rec, p);
    if (p->failed[i] || p->lv[i].chunk < 0)
        return MESO_ERR_NOT_FOUND;
    meso_rt_object h;
    meso_result r = mesoi_empty_slot(rt, rec, &h);
    if (r != MESO_OK)
        return r;
    mesoi_object* o = mesoi_lookup(rt, h);
    o->kind = MESO_OBJECT_MESH;
    memcpy(o->bbox_min, p->lv[i].rec.bbox_min, sizeof(o->bbox_min));
    memcpy(o->bbox_max, p->lv[i].rec.bbox_max, sizeof(o->bbox_max));
    const uint64_t before = rt->gpu_count;
    r = mesoi_mesh_upload_chunk(rt, f, p->lv[i].chunk, rec->id, p->lv[i].colours, o);
    if (r == MESO_OK) {
        p->slot[i] = h;
        p->gpu[i] = o->gpu_bytes = rt->gpu_count - before;
        rt->bytes_resident += p->gpu[i];
        if (!rt->prefetch)
            p->bytes_read += p->lv[i].bytes; /* a request counts its own reads */
        return MESO_OK;
    }
    meso_rt_release_object(rt, h);
    if (r != MESO_ERR_PENDING) {
        p->failed[i] = 1;
        mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "object %u: part %u level %u could not be uploaded", rec->id, p->lv[i].rec.object,
                  p->lv[i].rec.lod);
    }
    return r;
}

int mesoi_parts_oldest(const meso_rt* rt, const mesoi_parts* p, uint64_t* oldest, uint32_t* which)
{
    int found = 0;
    for (uint32_t i = 0; i < p->level_count; ++i)
        if (p->slot[i].id && p->used[i] != rt->frame + 1 && p->used[i] < *oldest) {
            *oldest = p->used[i];
            *which = i;
            found = 1;
        }
    return found;
}

void mesoi_parts_evict(meso_rt* rt, mesoi_parts* p, uint32_t i)
{
    meso_rt_release_object(rt, p->slot[i]);
    p->slot[i].id = 0;
    rt->bytes_resident -= p->gpu[i];
    rt->evictions++;
}

/* A shell's prisms the parts drawn at lod 0 hold (the PTRI ranges, part
 * after part) and their key (FNV-1a over the parts), rebuilt only when
 * the parts change: instanced and repeated draws copy nothing. */
static void prism_subset(mesoi_parts* p)
{
    uint64_t key = 1469598103934665603ull;
    for (uint32_t q = 0; q < p->part_count; ++q)
        if (p->drawn[q] == 0)
            key = (key ^ q) * 1099511628211ull;
    if (key == p->subset_key)
        return;
    p->subset_key = key;
    p->subset_count = 0;
    for (uint32_t q = 0; q < p->part_count; ++q)
        if (p->drawn[q] == 0) {
            const meso_part_level* L = &p->lv[p->first[q]];
            memcpy(p->subset + p->subset_count, p->tri + L->first_triangle, sizeof(uint32_t) * L->triangle_count);
            p->subset_count += L->triangle_count;
        }
}

uint64_t mesoi_parts_want(mesoi_parts* p, const meso_rt_draw_desc* d, const meso_rt_instance* inst, uint32_t count,
                          double tau, double height, int* prisms_wanted)
{
    /* Each part's own level. */
    for (uint32_t q = 0; q < p->part_count; ++q) {
        const uint32_t a = p->first[q], b = p->first[q + 1];
        uint32_t l = 0;
        for (uint32_t k = b - a; k-- > 1;) {
            const meso_level_record* r = &p->lv[a + k].rec;
            double px = 0.0;
            if (inst)
                for (uint32_t i = 0; i < count && px <= tau; ++i)
                    px = mesoi_projected_px(r->error, r->bbox_min, r->bbox_max, inst[i].model, d, height);
            else
                px = mesoi_projected_px(r->error, r->bbox_min, r->bbox_max, d->model, d, height);
            if (px <= tau) {
                l = k;
                break;
            }
        }
        p->want[q] = l;
    }
    /* Neighbours within one level: lower the coarser until nothing moves. */
    for (int changed = 1; changed;) {
        changed = 0;
        for (uint32_t e = 0; e < p->edge_count; ++e) {
            const uint32_t a = p->edges[2 * e] - 1, b = p->edges[2 * e + 1] - 1;
            if (p->want[a] > p->want[b] + 1) {
                p->want[a] = p->want[b] + 1;
                changed = 1;
            } else if (p->want[b] > p->want[a] + 1) {
                p->want[b] = p->want[a] + 1;
                changed = 1;
            }
        }
    }
    uint64_t bytes = 0;
    *prisms_wanted = 0;
    for (uint32_t q = 0; q < p->part_count; ++q) {
        const uint32_t i = p->first[q] + p->want[q];
        *prisms_wanted |= prisms(p, i);
        bytes += prisms(p, i) ? 0 : p->lv[i].bytes;
    }
    return bytes + (*prisms_wanted ? p->lv[p->first[0]].bytes : 0);
}

meso_result mesoi_parts_pick(meso_rt* rt, mesoi_levels* lv, meso_rt_object native, meso_rt_object* out)
{
    mesoi_parts* p = lv->parts;
    p->pick_frame = rt->frame + 1;
    p->native = native;
    p->fallback_error = -1.0;
    /* p->want: mesoi_parts_want's, for this draw. A shell none of whose
     * parts is far enough for its patch draws its whole native level:
     * nothing to read or upload. */
    int any = !p->shell;
    for (uint32_t q = 0; !any && q < p->part_count; ++q)
        any = p->want[q] != 0;
    if (!any) {
        memset(p->drawn, 0, p->part_count);
        p->bytes_wanted = 0;
        return MESO_OK;
    }
    /* What each part can draw now: the wanted level, else the finest
     * coarser one that can be had, else the nearest finer one uploaded.
     * With stream requests, the finest of them that can still be had is
     * requested (every part's, before any answer) and not read here. */
    p->bytes_wanted = 0;
    int fell_back = 0;
    double worst = 0.0; /* the largest stated error drawn */
    meso_result missing = MESO_OK; /* MESO_ERR_PENDING: some part waits for its request; MESO_ERR_NOT_FOUND: cannot be had */
    for (uint32_t q = 0; q < p->part_count; ++q) {
        const uint32_t a = p->first[q], n = p->first[q + 1] - a, w = p->want[q];
        p->bytes_wanted += prisms(p, a + w) ? 0 : p->gpu[a + w];
        int32_t got = -1;
        int requested = 0;
        for (uint32_t l = w; got < 0 && l < n; ++l) {
            const uint32_t i = a + l;
            if (!have(p, i) && !p->failed[i]) {
                if (rt->stream_requests) { /* every part's prisms: one request, for the list */
                    if (!requested && mesoi_stream_request_part(rt, lv, prisms(p, i) ? p->first[0] : i) != MESO_OK)
                        return MESO_ERR_OUT_OF_MEMORY;
                    requested = 1;
                } else if (mesoi_make_room(rt, p->gpu[i])) {
                    const meso_result r = mesoi_parts_upload(rt, lv->file, &lv->rec, p, i);
                    if (r == MESO_ERR_OUT_OF_MEMORY)
                        return r;
                }
            }
            if (have(p, i))
                got = (int32_t)l;
        }
        for (uint32_t l = w; got < 0 && l-- > 0;)
            if (have(p, a + l))
                got = (int32_t)l;
        if (got < 0) {
            missing = missing != MESO_OK ? missing : MESO_ERR_PENDING;
            if (!rt->stream_requests || !requested) {
                missing = MESO_ERR_NOT_FOUND; /* not to be had (now, or streamed: at all) */
                break;
            }
            continue;
        }
        p->chosen[q] = prisms(p, a + (uint32_t)got) ? native : p->slot[a + (uint32_t)got];
        p->drawn[q] = (uint8_t)(got > 255 ? 255 : got);
        p->used[a + (uint32_t)got] = rt->frame + 1;
        fell_back |= (uint32_t)got > w;
        worst = (double)p->lv[a + (uint32_t)got].rec.error > worst ? (double)p->lv[a + (uint32_t)got].rec.error : worst;
    }
    for (uint32_t q = 0; p->shell && q < p->part_count; ++q)
        if (p->want[q] == 0) { /* the list, once */
            p->bytes_wanted += p->gpu[p->first[0]];
            break;
        }
    if (missing != MESO_OK)
        return missing; /* a whole level instead */
    p->fallback_error = fell_back ? worst : -1.0;
    if (p->shell)
        prism_subset(p);
    *out = p->parent;
    return MESO_OK;
}

meso_result mesoi_parts_draw(meso_rt* rt, const mesoi_parts* p, const meso_rt_draw_desc* d,
                             const meso_rt_instance* inst, uint32_t count)
{
    /* The stand-in patches (meshes) first, then a shell's prisms in one
     * draw: its stats are the draw's. */
    for (uint32_t q = 0; q < p->part_count; ++q) {
        if (p->shell && p->drawn[q] == 0)
            continue; /* prisms: the subset below */
        mesoi_object* o = mesoi_lookup(rt, p->chosen[q]);
        if (!o)
            continue; /* evicted since the pick: a later frame picks it again */
        const meso_result r = mesoi_mesh_draw(rt, o, d, inst, count);
        if (r != MESO_OK)
            return r;
    }
    mesoi_object* n = p->subset_count ? mesoi_lookup(rt, p->native) : NULL;
    if (!n || !n->shell)
        return MESO_OK;
    n->shell->subset = p->subset;
    n->shell->subset_count = p->subset_count;
    n->shell->subset_key = p->subset_key;
    const meso_result r = mesoi_shell_draw(rt, n, d, inst, count);
    n->shell->subset = NULL;
    return r;
}

int mesoi_parts_finest_patch(const mesoi_parts* p)
{
    int finest = INT32_MAX;
    for (uint32_t q = 0; q < p->part_count; ++q) {
        if (prisms(p, p->first[q] + p->drawn[q]))
            return -1;
        finest = p->drawn[q] < finest ? p->drawn[q] : finest;
    }
    return finest;
}

int mesoi_parts_coarse(const mesoi_parts* p)
{
    int coarse = 0;
    for (uint32_t q = 0; q < p->part_count; ++q) {
        if (p->drawn[q] != p->want[q])
            return 0; /* still arriving (a shell's prisms: their list) */
        coarse |= p->drawn[q] != 0;
    }
    return coarse;
}

uint64_t mesoi_parts_gpu(const mesoi_parts* p, uint64_t* estimated)
{
    uint64_t b = p->tri ? p->gpu[p->first[0]] : 0;
    *estimated += b;
    for (uint32_t i = 0; i < p->level_count; ++i)
        if (p->slot[i].id) {
            b += p->gpu[i];
            *estimated += p->gpu[p->level_count + i];
        }
    return b;
}

uint64_t mesoi_parts_bytes(const mesoi_parts* p, uint64_t* read)
{
    uint64_t b = p->tri ? p->lv[p->first[0]].bytes : 0; /* a shell's prisms: the list, once */
    for (uint32_t i = 0; i < p->level_count; ++i)
        b += p->slot[i].id ? p->lv[i].bytes : 0;
    if (read)
        *read = p->bytes_read;
    return b;
}

meso_result meso_rt_parts_state_get(const meso_rt* rt, meso_rt_object h, uint8_t* levels, uint32_t cap,
                                    uint32_t* part_count)
{
    const mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !part_count || (!levels && cap))
        return MESO_ERR_INVALID_ARG;
    const mesoi_parts* p = o->levels ? o->levels->parts : NULL;
    *part_count = p ? p->part_count : 0;
    for (uint32_t q = 0; p && q < p->part_count && q < cap; ++q)
        levels[q] = o->levels->parts_last ? p->drawn[q] : MESO_RT_PART_NOT_DRAWN;
    return MESO_OK;
}
