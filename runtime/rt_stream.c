/*
 * rt_stream.c — levels streamed off the GL thread (issue 14, "decoding
 * happens off the GL thread"; meso_rt.h >>streaming).
 *
 * With meso_rt_desc.stream_requests, a draw that picks a level not uploaded
 * files a request for it (one per level, rt_levels.c) and draws the best
 * level uploaded. A request moves WAITING -> TAKEN (meso_rt_stream_take, GL
 * thread) -> run (any thread: reads, CRC checks and decodes every chunk the
 * level draws into memory, repacking a MESH drawn as a mesh for the GPU
 * (rt_mesh_repack.c), and for a CELLS level the whole
 * meso_file_check_cells, whose TILE and MEMB copies it keeps, and the tile
 * map's skip radii, rt_cells_skip.c) -> given back
 * (GL thread): DECODED, or WAITING again when its bytes had not arrived, or
 * freed with its level marked failed -> uploaded (meso_rt_stream_upload, GL
 * thread, oldest first, up to a byte budget per call). A whole level larger
 * than what is left of a call's budget is loaded with rt->defer set
 * (rt_transfer.c: its GL objects made, their data queued) into a slot of
 * the request's own -> FILLING, its data moved by this and later calls'
 * budgets -> made the level's (drawable) once all of it is up. Until then
 * draws see it as not uploaded (and ask for it no more: one request per
 * level); a FILLING request whose object is released frees what it made.
 *
 * The upload runs the kind's ordinary loader with rt->prefetch set: every
 * chunk the loader asks for through mesoi_read_whole is handed over from
 * the request instead of being read, so the loaders have one code path for
 * both modes and a streamed level is byte for byte the level a synchronous
 * load uploads. A chunk the request does not hold (none today) is read from
 * the file as before.
 *
 * Decided: `run` touches no context state, so requests may run in parallel
 * on any threads. It allocates with a copy of the context's allocator, so
 * the handed-over buffers are freed by mesoi_rt_free like any read. A
 * request whose object is released while the host holds it is detached
 * (lv = NULL) and freed when given back; the context frees every request
 * on destroy, so taken ones must come back first (meso_rt.h says so).
 */
#include "file_internal.h"
#include "rt_cells_skip.h"
#include "rt_internal.h"

#include <stdio.h>
#include <string.h>

enum { REQ_WAITING = 0, REQ_TAKEN, REQ_DECODED, REQ_FILLING };

struct meso_rt_request {
    struct meso_rt_request* next; /* rt->requests, oldest first */
    mesoi_levels* lv;             /* NULL once the object is released */
    uint32_t level;               /* lv's level, or with `part` the level lv->parts->lv[level] */
    int part;
    int state;
    /* What run needs, copied at take (run never touches the context). */
    meso_file* file;
    meso_allocator alloc;
    uint32_t object, kind;
    uint16_t lod, form;
    int32_t part_chunk, part_colours; /* a part level's PMSH and PVCL (a shell's prisms: its PTRI) */
    /* Run's results. */
    uint32_t count;                 /* chunks decoded */
    int32_t* chunk;                 /* [count] TOC indices */
    void** data;                    /* [count] decoded bytes (alloc); NULL once handed over */
    uint8_t *tile, *memb;           /* CELLS: the check's copies (the file's allocator) */
    int cells_checked;
    int id_bits;                    /* CELLS: tile's skip radii (rt_cells_skip.h), 0 none */
    int32_t mesh_chunk;             /* the MESH-layout chunk run repacked for the GPU (mesh_gpu), -1 none */
    mesoi_mesh_gpu mesh_gpu;
    uint64_t bytes;                 /* stored bytes read */
    meso_result result;
    char why[240];                  /* run's error message, logged when given back ("" none) */
    /* REQ_FILLING: the level loaded with its data deferred (rt_transfer.c),
     * not the level's until the data is all up. */
    meso_rt_object filling;
    uint64_t filling_gpu;
    mesoi_transfers xfer;
};

static void* req_alloc(const meso_rt_request* q, size_t n) { return q->alloc.alloc_fn(n ? n : 1, q->alloc.user); }

static void req_free(const meso_rt_request* q, void* p)
{
    if (p)
        q->alloc.free_fn(p, q->alloc.user);
}

/* Drop what run produced (back to a request that may run again). */
static void req_clear(meso_rt_request* q)
{
    for (uint32_t k = 0; k < q->count; ++k)
        req_free(q, q->data ? q->data[k] : NULL);
    req_free(q, q->chunk);
    req_free(q, q->data);
    q->chunk = NULL;
    q->data = NULL;
    q->count = 0;
    if (q->file) {
        mesoi_file_free(&q->file->alloc, q->tile);
        mesoi_file_free(&q->file->alloc, q->memb);
    }
    q->tile = q->memb = NULL;
    q->cells_checked = q->id_bits = 0;
    q->mesh_chunk = -1;
    q->bytes = 0;
    q->why[0] = 0;
}

/* Where q's level keeps its request (q->lv set). */
static meso_rt_request** req_slot(const meso_rt_request* q)
{
    return q->part ? &q->lv->parts->request[q->level] : &q->lv->request[q->level];
}

/* Unlink q from rt->requests, clear its level's pointer and free it. */
static void req_destroy(meso_rt* rt, meso_rt_request* q)
{
    for (meso_rt_request** p = &rt->requests; *p; p = &(*p)->next)
        if (*p == q) {
            *p = q->next;
            break;
        }
    if (q->lv)
        *req_slot(q) = NULL;
    if (q->filling.id) { /* dropped part way up: its GPU storage goes */
        meso_rt_release_object(rt, q->filling);
        rt->bytes_resident -= q->filling_gpu;
    }
    mesoi_transfers_free(rt, &q->xfer);
    req_clear(q);
    mesoi_rt_free(rt, q);
}

/* A new request, last in rt->requests, for level l (part level with
 * `part`) of lv. */
static meso_result req_file(meso_rt* rt, mesoi_levels* lv, uint32_t l, int part)
{
    meso_rt_request* q = mesoi_rt_alloc(rt, sizeof *q);
    if (!q)
        return MESO_ERR_OUT_OF_MEMORY;
    memset(q, 0, sizeof *q);
    q->lv = lv;
    q->level = l;
    q->part = part;
    q->mesh_chunk = -1;
    q->state = REQ_WAITING;
    meso_rt_request** p = &rt->requests;
    while (*p)
        p = &(*p)->next;
    *p = q;
    *req_slot(q) = q;
    return MESO_OK;
}

meso_result mesoi_stream_request(meso_rt* rt, mesoi_levels* lv, uint32_t l)
{
    if (lv->request[l] || lv->slot[l].id || lv->failed[l])
        return MESO_OK;
    return req_file(rt, lv, l, 0);
}

meso_result mesoi_stream_request_part(meso_rt* rt, mesoi_levels* lv, uint32_t i)
{
    const mesoi_parts* p = lv->parts;
    if (p->request[i] || p->slot[i].id || p->failed[i])
        return MESO_OK;
    return req_file(rt, lv, i, 1);
}

void mesoi_stream_detach(meso_rt* rt, mesoi_levels* lv)
{
    for (meso_rt_request *q = rt->requests, *next; q; q = next) {
        next = q->next;
        if (q->lv != lv)
            continue;
        *req_slot(q) = NULL;
        q->lv = NULL;
        if (q->state != REQ_TAKEN) /* the host does not hold it: free it now */
            req_destroy(rt, q);
    }
}

void mesoi_stream_destroy(meso_rt* rt)
{
    while (rt->requests)
        req_destroy(rt, rt->requests);
}

/* Chunk ci's decoded bytes from request q (NULL q: none), handed over. */
static void* take(meso_rt_request* q, int32_t ci)
{
    for (uint32_t k = 0; q && k < q->count; ++k)
        if (q->chunk[k] == ci && q->data[k]) {
            void* p = q->data[k];
            q->data[k] = NULL;
            return p;
        }
    return NULL;
}

void* mesoi_stream_take_chunk(meso_rt* rt, int32_t ci)
{
    const meso_rt_request* q = rt->prefetch; /* a repacked mesh is take_mesh's */
    return q && ci == q->mesh_chunk ? NULL : take(rt->prefetch, ci);
}

void* mesoi_stream_take_mesh(meso_rt* rt, int32_t ci, mesoi_mesh_gpu* out)
{
    meso_rt_request* q = rt->prefetch;
    void* p = q && ci == q->mesh_chunk ? take(q, ci) : NULL;
    if (p)
        *out = q->mesh_gpu;
    return p;
}

uint32_t meso_rt_stream_take(meso_rt* rt, meso_rt_request** out, uint32_t max)
{
    uint32_t n = 0;
    for (meso_rt_request* q = rt ? rt->requests : NULL; q && n < max; q = q->next) {
        if (q->state != REQ_WAITING || !q->lv)
            continue;
        const mesoi_levels* lv = q->lv;
        const meso_level_record* rec = q->part ? &lv->parts->lv[q->level].rec : &lv->info[q->level].rec;
        q->file = lv->file;
        q->alloc = rt->alloc;
        q->object = lv->rec.id;
        q->form = q->part ? (uint16_t)MESO_LEVEL_MESH : rec->form;
        q->lod = rec->lod;
        q->kind = q->form == MESO_LEVEL_MESH ? (uint32_t)MESO_OBJECT_MESH : lv->rec.kind;
        q->part_chunk = q->part ? lv->parts->lv[q->level].chunk : -1;
        q->part_colours = q->part ? lv->parts->lv[q->level].colours : -1;
        q->result = MESO_OK;
        q->state = REQ_TAKEN;
        out[n++] = q;
    }
    return n;
}

/* Whether chunk i is one the level draws and the loader reads through
 * mesoi_read_whole (FORMAT.md §7.10: per type the smallest lod >= the
 * level's; a MESH stand-in reads MESH and the VCOL at its lod; TILE and MEMB of a CELLS level
 * come from the cells check) — the chunks meso_file_levels counts. */
static int level_reads(const meso_rt_request* q, const meso_chunk_info* c, uint32_t i)
{
    if (q->part) /* a part level is its PMSH and PVCL, a shell's prisms its PTRI (rt_parts.c upload) */
        return (int32_t)i == q->part_chunk || (int32_t)i == q->part_colours;
    if (c->object != q->object || mesoi_part_chunk(c->type))
        return 0; /* a whole level draws no part's chunks (§7.11) */
    if (c->type == MESO_CHUNK_VCOL) /* a mesh's or stand-in's vertex colours, at its MESH's own lod */
        return q->kind == MESO_OBJECT_MESH && meso_file_find_vertex_colours(q->file, q->object, q->lod) == (int32_t)i;
    if (q->form == MESO_LEVEL_MESH && c->type != MESO_CHUNK_MESH)
        return 0;
    if (q->kind == MESO_OBJECT_FRUSTA && c->type == MESO_CHUNK_MESH)
        return 0; /* a frusta object's MESH is its stand-in's (file_levels.c) */
    if (q->kind == MESO_OBJECT_CELLS &&
        (c->type == MESO_CHUNK_TILE || c->type == MESO_CHUNK_MEMB || c->type == MESO_CHUNK_SPLT))
        return 0; /* TILE, MEMB: the check's copies; SPLT: checked there, not drawn */
    return meso_file_find_level(q->file, c->type, q->object, q->lod) == (int32_t)i;
}

meso_result meso_rt_stream_run(meso_rt_request* q)
{
    if (!q || q->state != REQ_TAKEN)
        return MESO_ERR_INVALID_ARG;
    req_clear(q);
    meso_file* f = q->file;
    const uint32_t total = meso_file_chunk_count(f);
    uint32_t want = 0;
    for (uint32_t i = 0; i < total; ++i)
        want += (uint32_t)level_reads(q, meso_file_chunk(f, i), i);
    q->chunk = req_alloc(q, sizeof(int32_t) * want);
    q->data = req_alloc(q, sizeof(void*) * want);
    if (!q->chunk || !q->data) {
        req_clear(q);
        return q->result = MESO_ERR_OUT_OF_MEMORY;
    }
    meso_result r = MESO_OK;
    meso_error err = {.message = ""};
    for (uint32_t i = 0; i < total && r == MESO_OK; ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (!level_reads(q, c, i))
            continue;
        if (c->decoded_size > (uint64_t)PTRDIFF_MAX) {
            r = MESO_ERR_UNSUPPORTED;
            break;
        }
        void* p = req_alloc(q, (size_t)c->decoded_size);
        if (!p) {
            r = MESO_ERR_OUT_OF_MEMORY;
            break;
        }
        r = meso_file_read_chunk(f, i, p, (size_t)c->decoded_size, &err);
        if (r == MESO_OK)
            q->bytes += c->stored_size;
        /* What rt_mesh.c draws is repacked for the GPU here: a mesh or
         * stand-in level's MESH (kind MESH at take), a part's PMSH, a cells
         * object's hull. Any other MESH (a shell's base mesh) is read as
         * stored; one repacked nowhere else would still be repacked at
         * upload, on the GL thread. */
        const int drawn_as_mesh = c->type == MESO_CHUNK_PMSH ||
                                  (c->type == MESO_CHUNK_MESH &&
                                   (q->kind == MESO_OBJECT_MESH || q->kind == MESO_OBJECT_CELLS));
        if (r == MESO_OK && drawn_as_mesh) {
            r = mesoi_mesh_repack(p, (size_t)c->decoded_size, &q->mesh_gpu, &err);
            q->mesh_chunk = r == MESO_OK ? (int32_t)i : -1;
        }
        if (r != MESO_OK) {
            req_free(q, p);
            break;
        }
        q->chunk[q->count] = (int32_t)i;
        q->data[q->count++] = p;
    }
    if (r == MESO_OK && q->kind == MESO_OBJECT_CELLS) {
        r = mesoi_file_check_cells_keep(f, q->object, q->lod, &q->tile, &q->memb, &err);
        q->cells_checked = r == MESO_OK;
        if (q->cells_checked) /* the radii too are worked out off the GL thread */
            q->id_bits = mesoi_cells_skip_level(f, q->object, q->lod, q->tile, &q->alloc);
    }
    if (r != MESO_OK) {
        const uint64_t bytes = q->bytes; /* bytes read count, failed or not */
        req_clear(q);
        q->bytes = bytes;
        snprintf(q->why, sizeof q->why, "%s", r == MESO_ERR_PENDING ? "" : err.message);
    }
    return q->result = r;
}

void meso_rt_stream_give(meso_rt* rt, meso_rt_request* const* reqs, uint32_t n)
{
    for (uint32_t i = 0; rt && reqs && i < n; ++i) {
        meso_rt_request* q = reqs[i];
        if (!q || q->state != REQ_TAKEN)
            continue;
        if (!q->lv) { /* its object was released meanwhile */
            req_destroy(rt, q);
            continue;
        }
        if (q->result != MESO_ERR_PENDING) /* as a synchronous read that found its bytes not arrived */
            *(q->part ? &q->lv->parts->bytes_read : &q->lv->bytes_read) += q->bytes;
        if (q->result == MESO_OK && (q->count || q->cells_checked)) {
            q->state = REQ_DECODED;
        } else if (q->result == MESO_OK || q->result == MESO_ERR_PENDING) {
            req_clear(q); /* not run, or not arrived: taken again later */
            q->state = REQ_WAITING;
        } else {
            if (q->part) {
                q->lv->parts->failed[q->level] = 1;
                mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                          "object %u: part %u level %u could not be read (%s%s%s); drawing the nearest level uploaded",
                          q->object, q->lv->parts->lv[q->level].rec.object, q->lod, meso_result_string(q->result),
                          q->why[0] ? ": " : "", q->why);
            } else {
                q->lv->failed[q->level] = 1;
                mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                          "object %u: level %u could not be read (%s%s%s); drawing the nearest level uploaded",
                          q->object, q->level, meso_result_string(q->result), q->why[0] ? ": " : "", q->why);
            }
            req_destroy(rt, q);
        }
    }
}

/* A decoded part level's upload (as a level's, below); its bytes, 0 when
 * not uploaded. Frees q unless it is kept for the next call. */
static uint64_t upload_part(meso_rt* rt, meso_rt_request* q)
{
    mesoi_levels* lv = q->lv;
    mesoi_parts* p = lv->parts;
    const uint32_t i = q->level, part = p->lv[i].rec.object - 1;
    const int room = p->slot[i].id || mesoi_make_room(rt, p->gpu[i]);
    if (!room && p->pick_frame >= rt->frame && p->want[part] <= p->lv[i].rec.lod)
        return 0; /* still wanted: tried again on the next call */
    uint64_t done = 0;
    if (room && !p->slot[i].id) {
        rt->prefetch = q;
        const meso_result r = mesoi_parts_upload(rt, lv->file, &lv->rec, p, i);
        rt->prefetch = NULL;
        if (r == MESO_OK) {
            done = p->lv[i].bytes;
            rt->stream_uploads++;
        }
    }
    req_destroy(rt, q);
    return done;
}

/* Moves a filling level's data, up to `budget` bytes (0: all); once all
 * of it is up, the level is the object's (drawable) and q is freed.
 * Returns the bytes moved. */
static uint64_t fill(meso_rt* rt, meso_rt_request* q, uint64_t budget)
{
    const GLint prev = mesoi_upload_begin(rt);
    const uint64_t moved = mesoi_transfers_run(rt, &q->xfer, budget);
    char what[64];
    snprintf(what, sizeof what, "uploading object %u level %u", q->object, q->level);
    const meso_result r = mesoi_upload_end(rt, prev, MESO_OK, what);
    mesoi_levels* lv = q->lv;
    if (r != MESO_OK) {
        lv->failed[q->level] = 1;
        req_destroy(rt, q); /* releases what was made */
    } else if (q->xfer.next == q->xfer.count) {
        mesoi_levels_publish(lv, q->level, q->filling, q->filling_gpu);
        q->filling.id = 0;
        rt->stream_uploads++;
        req_destroy(rt, q);
    }
    return moved;
}

/* Loads decoded level q with its data deferred (rt->defer), then moves what
 * `budget` allows. Returns the bytes moved; q is freed when it failed. */
static uint64_t start_filling(meso_rt* rt, meso_rt_request* q, uint64_t budget)
{
    mesoi_levels* lv = q->lv;
    rt->prefetch = q;
    rt->defer = &q->xfer;
    meso_result r = mesoi_levels_load(rt, lv, q->level, &q->filling, &q->filling_gpu);
    rt->defer = NULL;
    rt->prefetch = NULL;
    req_clear(q); /* the decoded chunks: what the level needs is queued */
    if (r == MESO_OK && q->xfer.failed) {
        mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "object %u: level %u could not be queued for upload (out of memory)", q->object, q->level);
        lv->failed[q->level] = 1;
        r = MESO_ERR_OUT_OF_MEMORY;
    }
    if (r != MESO_OK) {
        req_destroy(rt, q);
        return 0;
    }
    q->state = REQ_FILLING;
    return fill(rt, q, budget);
}

uint64_t meso_rt_stream_upload(meso_rt* rt, uint64_t max_bytes)
{
    uint64_t done = 0;
    meso_rt_request* q = rt ? rt->requests : NULL;
    while (q && (max_bytes == 0 || done < max_bytes)) {
        meso_rt_request* next = q->next;
        if (q->state == REQ_FILLING) {
            done += fill(rt, q, max_bytes ? max_bytes - done : 0);
        } else if (q->state == REQ_DECODED && q->part) {
            done += upload_part(rt, q);
        } else if (q->state == REQ_DECODED) {
            mesoi_levels* lv = q->lv;
            const uint32_t l = q->level;
            /* The coarsest level always stays (meso_rt_desc.memory_budget):
             * it is uploaded whatever the budget, as a synchronous load does. */
            const int room = lv->slot[l].id || l + 1 == lv->count || mesoi_make_room(rt, lv->gpu[l]);
            /* No room under the budget: kept decoded, and tried again on
             * the next call, while the last frame's or this frame's draws
             * still want this level (or a finer one); dropped once they
             * want a coarser one or none (frame_end then has raised the
             * pixel-error factor, or the object is out of view). Dropping
             * it at once made every frame read and decode it again. */
            if (!room && lv->want_frame >= rt->frame && lv->want_now <= l) {
                q = next;
                continue;
            }
            /* More than this call's budget left: the level goes up over
             * several calls (rt_transfer.c), drawn once it is whole. */
            if (room && !lv->slot[l].id && max_bytes && lv->info[l].bytes > max_bytes - done) {
                done += start_filling(rt, q, max_bytes - done);
                q = next;
                continue;
            }
            if (room && !lv->slot[l].id) {
                rt->prefetch = q;
                const meso_result r = mesoi_levels_upload(rt, lv, l);
                rt->prefetch = NULL;
                if (r == MESO_OK) {
                    done += lv->info[l].bytes;
                    rt->stream_uploads++;
                }
            }
            /* Uploaded, failed (remembered in lv->failed), or no longer
             * wanted: a later draw that wants it asks again. */
            req_destroy(rt, q);
        }
        q = next;
    }
    return done;
}

void meso_rt_stream_state_get(const meso_rt* rt, meso_rt_stream_state* out)
{
    if (!out)
        return;
    memset(out, 0, sizeof *out);
    for (const meso_rt_request* q = rt ? rt->requests : NULL; q; q = q->next) {
        out->waiting += q->state == REQ_WAITING;
        out->taken += q->state == REQ_TAKEN;
        out->decoded += q->state == REQ_DECODED || q->state == REQ_FILLING;
    }
    out->uploads = rt ? rt->stream_uploads : 0;
}

/* The cells check a CELLS request ran, handed to the loader (rt_cells.c). */
int mesoi_stream_take_cells(meso_rt* rt, uint8_t** tile, uint8_t** memb, int* id_bits)
{
    meso_rt_request* q = rt->prefetch;
    if (!q || !q->cells_checked)
        return 0;
    *tile = q->tile;
    *memb = q->memb;
    *id_bits = q->id_bits;
    q->tile = q->memb = NULL;
    q->cells_checked = 0;
    return 1;
}
