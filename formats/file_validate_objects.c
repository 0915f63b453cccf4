/*
 * file_validate_objects.c — the object tier of the full check: each OBJT
 * object against what its kind is made of (FORMAT.md §7.2, issues 6xxx).
 *
 * The chunk checks (file_validate.c) look at one chunk at a time, so a file
 * whose every chunk is well formed can still hold objects nothing can draw:
 * a shell without its MESH, directors for another vertex count, a frustum
 * whose node index runs past the skeleton. These are the rules that tie an
 * object's chunks together, plus the values of chunks whose layout alone
 * (F32 × 3 directors, F32 thickness) says nothing about their meaning.
 * They apply only to the chunks a kind uses: a chunk of an object whose
 * kind does not use it, or of an id without an OBJT record, is not checked
 * here (the golden files carry such chunks).
 *
 * A chunk that fails its own checks (CRC, element rules, contents) is
 * reported by those; the object checks then skip what depends on it and
 * pass the chunk's issue on (meso_file_validate drops it as a duplicate).
 */
#include "file_internal.h"

#include <math.h>

typedef struct obj_check {
    meso_file* f;
    uint32_t id;
    uint16_t lod; /* the level checked: each type resolves to its chunk with the smallest lod >= this */
    meso_issue_fn fn; /* NULL: stop at the first issue */
    void* user;
    meso_result first;
    int stop;
} obj_check;

static void note(obj_check* c, const meso_error* e)
{
    if (c->first == MESO_OK)
        c->first = e->result;
    if (!c->fn || c->fn(c->user, e))
        c->stop = 1;
}

static int keep_first_issue(void* user, const meso_error* e)
{
    *(meso_error*)user = *e;
    return 1;
}

#define ISSUE(c, code, chunk, ...)                                                                    \
    do {                                                                                              \
        meso_error e_;                                                                                \
        mesoi_file_error(&e_, MESO_ERR_CORRUPT, (code), UINT64_MAX, (chunk), __VA_ARGS__);            \
        note((c), &e_);                                                                               \
    } while (0)

static const char* kind_name(uint32_t kind)
{
    switch (kind) {
    case MESO_OBJECT_MESH: return "mesh";
    case MESO_OBJECT_SHELL: return "shell";
    case MESO_OBJECT_CELLS: return "cells";
    default: return "frusta";
    }
}

/* The object's chunk of `type` at the level checked (lowest lod >= c->lod;
 * level 0: its finest), as the runtime picks it; -1 when there is none. */
static int32_t finest(const obj_check* c, uint32_t type)
{
    return meso_file_find_level(c->f, type, c->id, c->lod);
}

/* The chunk of `type` the kind requires; reports 6001 when it is missing. */
static int32_t required(obj_check* c, uint32_t kind, uint32_t type)
{
    int32_t i = finest(c, type);
    if (i < 0 && !c->stop) {
        char cc[5];
        mesoi_fourcc_str(type, cc);
        ISSUE(c, MESO_ISSUE_OBJ_CHUNKS, -1, "%s object %u has no %s chunk (FORMAT.md 7.2)", kind_name(kind), c->id,
              cc);
    }
    return i;
}

/* The chunk's element rules hold (else their issue is passed on). */
static int rules_ok(obj_check* c, int32_t i)
{
    meso_error e;
    if (mesoi_check_type_rules(&c->f->chunks[i], i, &e) == MESO_OK)
        return 1;
    note(c, &e);
    return 0;
}

/* Read a whole chunk (CRC and content checks included) into a fresh
 * allocation; NULL after passing its issue on. */
static uint8_t* load(obj_check* c, int32_t i)
{
    meso_error e;
    const meso_chunk_info* k = &c->f->chunks[i];
    if (k->decoded_size > SIZE_MAX) {
        mesoi_file_error(&e, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_TOO_LARGE, UINT64_MAX, i,
                         "chunk %d: %llu bytes do not fit in memory", (int)i, (unsigned long long)k->decoded_size);
        note(c, &e);
        return NULL;
    }
    uint8_t* p = (uint8_t*)mesoi_file_alloc(&c->f->alloc, (size_t)k->decoded_size);
    if (!p) {
        mesoi_file_error(&e, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, i,
                         "chunk %d: out of memory for %llu bytes", (int)i, (unsigned long long)k->decoded_size);
        note(c, &e);
        return NULL;
    }
    if (meso_file_read_chunk(c->f, (uint32_t)i, p, (size_t)k->decoded_size, &e) != MESO_OK) {
        note(c, &e);
        mesoi_file_free(&c->f->alloc, p);
        return NULL;
    }
    return p;
}

/* The MESH header (raw or Draco: the stored payload starts with it and
 * describes the decoded layout), checked against decoded_size. */
static int mesh_header(obj_check* c, int32_t i, meso_mesh_layout* l)
{
    const meso_chunk_info* k = &c->f->chunks[i];
    uint8_t h[MESO_MESH_HDR_SIZE];
    meso_error e;
    if (!rules_ok(c, i))
        return 0;
    if (k->stored_size < MESO_MESH_HDR_SIZE) {
        mesoi_file_error(&e, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_SIZE, k->offset, i,
                         "chunk %d (MESH): payload smaller than the 64-byte mesh header", (int)i);
        note(c, &e);
        return 0;
    }
    if (mesoi_read_at(c->f, k->offset, h, sizeof h, &e) != MESO_OK ||
        mesoi_check_mesh_header(h, k->decoded_size, l, i, k->offset, &e) != MESO_OK) {
        note(c, &e);
        return 0;
    }
    return 1;
}

/* The VCOL that goes with the MESH this level draws (at the MESH's own
 * lod): one U8 x 4 per vertex of it (6002). */
static void vertex_colours(obj_check* c, const meso_mesh_layout* l)
{
    const int32_t i = meso_file_find_vertex_colours(c->f, c->id, c->lod);
    if (i < 0 || !rules_ok(c, i))
        return;
    const meso_chunk_info* k = &c->f->chunks[i];
    if (k->dims[0] != l->vertex_count)
        ISSUE(c, MESO_ISSUE_MESH_VCOL, i,
              "object %u, lod %u: VCOL holds %u vertex colours, its MESH has %u vertices (FORMAT.md 7.3)", c->id,
              (unsigned)k->lod, k->dims[0], l->vertex_count);
}

/* >>shell (kind 2) ---------------------------------------------------------- */

/* The texture function (§7.2 "A shell may carry one texture function"):
 * what the runtime and the reference sample, at the level they pick. */
static void shell_texture(obj_check* c)
{
    const int32_t hi = finest(c, MESO_CHUNK_TX2D), vi = finest(c, MESO_CHUNK_TX3D), xi = finest(c, MESO_CHUNK_DIST);
    const unsigned u8_u16 = MESOI_DT(U8) | MESOI_DT(U16);
    if (hi >= 0 && vi >= 0)
        ISSUE(c, MESO_ISSUE_SHELL_TEXTURE, vi, "shell %u has both a TX2D height field and a TX3D volume", c->id);
    const struct {
        int32_t i;
        unsigned dtypes;
        const char* want;
    } t[3] = {{hi, u8_u16, "TX2D: U8 or U16 x 1"},
              {vi, u8_u16, "TX3D: U8 or U16 x 1"},
              {xi, u8_u16 | MESOI_DT(F32), "DIST: U8, U16 or F32 x 1"}};
    for (int k = 0; k < 3 && !c->stop; k++) {
        if (t[k].i < 0 || !rules_ok(c, t[k].i))
            continue;
        const meso_chunk_info* q = &c->f->chunks[t[k].i];
        if (!mesoi_is_dtype(q, t[k].dtypes) || q->components != 1)
            ISSUE(c, MESO_ISSUE_SHELL_TEXTURE, t[k].i, "shell %u: chunk %d is dtype %u x %u; a shell's %s", c->id,
                  (int)t[k].i, q->dtype, q->components, t[k].want);
    }
    if (xi < 0 || c->stop)
        return;
    if (hi < 0 && vi < 0) {
        ISSUE(c, MESO_ISSUE_SHELL_TEXTURE, xi,
              "shell %u has a DIST distance map but no TX2D or TX3D texture function it could bound", c->id);
        return;
    }
    const meso_chunk_info* q = &c->f->chunks[xi];
    if (q->dtype != MESO_DTYPE_F32 || q->components != 1)
        return;
    uint8_t* d = load(c, xi);
    if (!d)
        return;
    const uint64_t n = q->decoded_size / 4;
    for (uint64_t v = 0; v < n; v++) {
        float x = mesoi_ldf32(d + 4 * v);
        if (!isfinite(x) || x < 0.0f) {
            ISSUE(c, MESO_ISSUE_SHELL_TEXTURE, xi, "shell %u: DIST cell %llu holds %g, not a finite distance >= 0",
                  c->id, (unsigned long long)v, (double)x);
            break;
        }
    }
    mesoi_file_free(&c->f->alloc, d);
}

/* One value per vertex (layer): SDIR finite (6102), STHK finite and > 0 (6103). */
static void shell_values(obj_check* c, int32_t i, int thickness)
{
    uint8_t* d = load(c, i);
    if (!d)
        return;
    const meso_chunk_info* q = &c->f->chunks[i];
    const uint64_t n = q->decoded_size / 4;
    for (uint64_t v = 0; v < n; v++) {
        float x = mesoi_ldf32(d + 4 * v);
        if (thickness && !(isfinite(x) && x > 0.0f)) {
            ISSUE(c, MESO_ISSUE_SHELL_STHK, i, "shell %u: STHK vertex %llu has thickness %g, must be finite and > 0",
                  c->id, (unsigned long long)v, (double)x);
            break;
        }
        if (!thickness && !isfinite(x)) {
            const uint64_t per_layer = (uint64_t)q->dims[0] * 3;
            ISSUE(c, MESO_ISSUE_SHELL_SDIR, i, "shell %u: SDIR layer %llu vertex %llu has a non-finite director",
                  c->id, (unsigned long long)(v / per_layer), (unsigned long long)(v % per_layer / 3));
            break;
        }
    }
    mesoi_file_free(&c->f->alloc, d);
}

/* One frame sequence chunk (TXFR or DSFR) against the chunk of frame 0 it
 * stacks (TX2D/TX3D or DIST): same element, same W x H, D x frames slabs,
 * slab 0 byte for byte the frame-0 chunk, F32 distances finite and >= 0. */
static void anim_frames(obj_check* c, int32_t fi, int32_t base, uint32_t frames)
{
    const meso_chunk_info *q = &c->f->chunks[fi], *b = &c->f->chunks[base];
    char cq[5], cb[5];
    mesoi_fourcc_str(q->type, cq);
    mesoi_fourcc_str(b->type, cb);
    if (q->dtype != b->dtype || q->components != b->components || q->dims[0] != b->dims[0] ||
        q->dims[1] != b->dims[1] || (uint64_t)q->dims[2] != (uint64_t)b->dims[2] * frames) {
        ISSUE(c, MESO_ISSUE_SHELL_ANIM, fi,
              "shell %u: %s is dtype %u x %u, %ux%ux%u; %u frames of its %s need dtype %u x %u, %ux%ux%llu", c->id, cq,
              q->dtype, q->components, q->dims[0], q->dims[1], q->dims[2], frames, cb, b->dtype, b->components,
              b->dims[0], b->dims[1], (unsigned long long)b->dims[2] * frames);
        return;
    }
    uint8_t* d = load(c, fi);
    uint8_t* d0 = d ? load(c, base) : NULL;
    if (d0 && memcmp(d, d0, (size_t)b->decoded_size) != 0)
        ISSUE(c, MESO_ISSUE_SHELL_ANIM, fi, "shell %u: frame 0 of %s differs from its %s", c->id, cq, cb);
    for (uint64_t v = 0; d0 && q->dtype == MESO_DTYPE_F32 && v < q->decoded_size / 4; v++) {
        const float x = mesoi_ldf32(d + 4 * v);
        if (!isfinite(x) || x < 0.0f) {
            ISSUE(c, MESO_ISSUE_SHELL_ANIM, fi, "shell %u: %s cell %llu holds %g, not a finite distance >= 0", c->id,
                  cq, (unsigned long long)v, (double)x);
            break;
        }
    }
    mesoi_file_free(&c->f->alloc, d);
    mesoi_file_free(&c->f->alloc, d0);
}

/* The animated texture function (§7.2 "Animated texture functions"): an
 * ANIM record with TXFR frames of the TX2D/TX3D, and DSFR frames of the
 * DIST exactly when there is a DIST. */
static void shell_anim(obj_check* c)
{
    const int32_t ai = finest(c, MESO_CHUNK_ANIM), fi = finest(c, MESO_CHUNK_TXFR), si = finest(c, MESO_CHUNK_DSFR);
    const int32_t hi = finest(c, MESO_CHUNK_TX2D), vi = finest(c, MESO_CHUNK_TX3D), xi = finest(c, MESO_CHUNK_DIST);
    const int32_t ti = hi >= 0 ? hi : vi;
    if (ai < 0) {
        if (fi >= 0 || si >= 0)
            ISSUE(c, MESO_ISSUE_SHELL_ANIM, fi >= 0 ? fi : si, "shell %u has %s frames but no ANIM record", c->id,
                  fi >= 0 ? "TXFR" : "DSFR");
        return;
    }
    if (!rules_ok(c, ai))
        return;
    uint8_t* d = load(c, ai);
    if (!d)
        return;
    meso_anim_record r;
    meso_anim_record_decode(d, &r);
    mesoi_file_free(&c->f->alloc, d);
    if (ti < 0 || fi < 0 || (si >= 0) != (xi >= 0)) {
        ISSUE(c, MESO_ISSUE_SHELL_ANIM, ai,
              "shell %u: an ANIM record needs a TX2D or TX3D and its TXFR frames, and DSFR frames exactly when there "
              "is a DIST (%s)",
              c->id, ti < 0 ? "no texture function" : fi < 0 ? "no TXFR" : si < 0 ? "no DSFR" : "DSFR without DIST");
        return;
    }
    if (rules_ok(c, fi) && rules_ok(c, ti) && !c->stop)
        anim_frames(c, fi, ti, r.frame_count);
    if (si >= 0 && !c->stop && rules_ok(c, si) && rules_ok(c, xi))
        anim_frames(c, si, xi, r.frame_count);
}

/* How many chunks of `type` the object has, at any lod. */
static uint32_t count_of(const obj_check* c, uint32_t type)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < c->f->chunk_count; i++)
        n += c->f->chunks[i].type == type && c->f->chunks[i].object == c->id;
    return n;
}

/* The shell's colour (§7.2 "Shell colour"): at most one COLR, exactly when
 * there is one CMAP record; W x H x 1, or W x H x D over a TX3D volume. */
static void shell_color(obj_check* c)
{
    const int32_t ci = finest(c, MESO_CHUNK_COLR), mi = finest(c, MESO_CHUNK_CMAP);
    const uint32_t nc = count_of(c, MESO_CHUNK_COLR), nm = count_of(c, MESO_CHUNK_CMAP);
    if (nc > 1 || nm > 1) {
        ISSUE(c, MESO_ISSUE_SHELL_COLOR, nc > 1 ? ci : mi, "shell %u has %u COLR and %u CMAP chunks, at most one each",
              c->id, nc, nm);
        return;
    }
    if ((ci >= 0) != (mi >= 0)) {
        ISSUE(c, MESO_ISSUE_SHELL_COLOR, ci >= 0 ? ci : mi, "shell %u: %s", c->id,
              ci >= 0 ? "a COLR needs a CMAP record saying how it maps to texture space" : "a CMAP without a COLR");
        return;
    }
    if (ci < 0 || !rules_ok(c, ci))
        return;
    const meso_chunk_info* q = &c->f->chunks[ci]; /* U8 x 4: the §7 element rule */
    if (q->dims[2] != 1 && finest(c, MESO_CHUNK_TX3D) < 0)
        ISSUE(c, MESO_ISSUE_SHELL_COLOR, ci,
              "shell %u: COLR is %ux%ux%u; a 3D colour (depth > 1) needs a TX3D volume, else W x H x 1", c->id,
              q->dims[0], q->dims[1], q->dims[2]);
    /* The record's own contents (4911, 4912) are the chunk tier's. */
}

static void check_shell(obj_check* c)
{
    const int32_t mi = required(c, MESO_OBJECT_SHELL, MESO_CHUNK_MESH);
    const int32_t di = required(c, MESO_OBJECT_SHELL, MESO_CHUNK_SDIR);
    const int32_t ti = required(c, MESO_OBJECT_SHELL, MESO_CHUNK_STHK);
    meso_mesh_layout l;
    const int have_mesh = mi >= 0 && !c->stop && mesh_header(c, mi, &l);
    if (have_mesh && l.index_count == 0 && !c->stop)
        ISSUE(c, MESO_ISSUE_SHELL_COUNT, mi, "shell %u: its MESH has no triangles to grow prisms on", c->id);
    const int32_t per_vertex[2] = {di, ti};
    for (int k = 0; k < 2 && !c->stop; k++) {
        const int32_t i = per_vertex[k];
        if (i < 0 || !rules_ok(c, i))
            continue;
        const meso_chunk_info* q = &c->f->chunks[i];
        if (have_mesh && q->dims[0] != l.vertex_count) {
            ISSUE(c, MESO_ISSUE_SHELL_COUNT, i, "shell %u: %s holds %u vertices, its MESH %u", c->id,
                  k ? "STHK" : "SDIR", q->dims[0], l.vertex_count);
            continue;
        }
        if (!c->stop)
            shell_values(c, i, k);
    }
    if (!c->stop)
        shell_texture(c);
    if (!c->stop)
        shell_anim(c);
    if (!c->stop)
        shell_color(c);
}

/* >>frusta (kind 4) --------------------------------------------------------- */

/* A colour chunk of `type` (FORMAT.md §7.2: frusta COLR, cells TX3D): at
 * most one with the object's id (any lod), U8 x 4, and W x H x 1 when
 * `flat`; else issue `code`. */
static void colour_chunk(obj_check* c, uint32_t type, int flat, uint32_t code)
{
    const char* kind = type == MESO_CHUNK_COLR ? "frusta" : "cells";
    char cc[5];
    mesoi_fourcc_str(type, cc);
    int32_t first = -1;
    for (uint32_t i = 0; i < c->f->chunk_count && !c->stop; i++) {
        const meso_chunk_info* k = &c->f->chunks[i];
        if (k->type != type || k->object != c->id)
            continue;
        if (first >= 0) {
            ISSUE(c, code, (int32_t)i, "%s %u: a second %s chunk (chunk %d; the first is %d)", kind, c->id, cc, (int)i,
                  (int)first);
            return;
        }
        first = (int32_t)i;
        if (!rules_ok(c, first))
            return;
        if (k->dtype != MESO_DTYPE_U8 || k->components != 4 || (flat && k->dims[2] != 1))
            ISSUE(c, code, first, "%s %u: %s is dtype %u x %u, %u x %u x %u; must be U8 x 4%s", kind, c->id, cc,
                  k->dtype, k->components, k->dims[0], k->dims[1], k->dims[2], flat ? ", W x H x 1" : "");
    }
}

static void check_frusta(obj_check* c)
{
    const int32_t fr = required(c, MESO_OBJECT_FRUSTA, MESO_CHUNK_FRUS);
    const int32_t fs = required(c, MESO_OBJECT_FRUSTA, MESO_CHUNK_FSEG);
    const int32_t sk = required(c, MESO_OBJECT_FRUSTA, MESO_CHUNK_SKEL);
    const int32_t ba = finest(c, MESO_CHUNK_BALL), re = finest(c, MESO_CHUNK_RELF);
    if (re >= 0 && !c->stop && rules_ok(c, re)) {
        const meso_chunk_info* q = &c->f->chunks[re];
        if ((q->dtype != MESO_DTYPE_U8 && q->dtype != MESO_DTYPE_U16) || q->components != 1)
            ISSUE(c, MESO_ISSUE_FRUSTA_RELF, re, "frusta %u: RELF is dtype %u x %u, must be U8 or U16 x 1", c->id,
                  q->dtype, q->components);
    }
    if (!c->stop)
        colour_chunk(c, MESO_CHUNK_COLR, 1, MESO_ISSUE_FRUSTA_COLR);
    if (fr < 0 || fs < 0 || sk < 0 || c->stop)
        return;
    uint8_t* frus = load(c, fr);
    uint8_t* fseg = frus ? load(c, fs) : NULL;
    uint8_t* skel = fseg ? load(c, sk) : NULL;
    uint8_t* ball = skel && ba >= 0 ? load(c, ba) : NULL;
    if (!skel || (ba >= 0 && !ball))
        goto done;
    const uint64_t nf = c->f->chunks[fr].decoded_size / MESO_FRUS_RECORD_SIZE;
    const uint64_t ns = c->f->chunks[fs].decoded_size / MESO_FSEG_RECORD_SIZE;
    const uint64_t nodes = c->f->chunks[sk].decoded_size / MESO_SKEL_RECORD_SIZE;
    if (nf != ns) {
        ISSUE(c, MESO_ISSUE_FRUSTA_COUNT, fs, "frusta %u: FSEG holds %llu records, FRUS %llu (one each per frustum)",
              c->id, (unsigned long long)ns, (unsigned long long)nf);
        goto done;
    }
    for (uint64_t i = 0; i < nf && !c->stop; i++) {
        const uint8_t* s = fseg + i * MESO_FSEG_RECORD_SIZE;
        const uint8_t* p = frus + i * MESO_FRUS_RECORD_SIZE;
        const uint32_t n0 = mesoi_ld32(s + MESO_FSEG_OFF_NODE0), n1 = mesoi_ld32(s + MESO_FSEG_OFF_NODE1);
        const uint32_t sn = mesoi_ld32(p + MESO_FRUS_OFF_SKEL_NODE);
        if (n0 >= nodes || n1 >= nodes || (sn != UINT32_MAX && sn >= nodes)) {
            ISSUE(c, MESO_ISSUE_FRUSTA_NODE, n0 >= nodes || n1 >= nodes ? fs : fr,
                  "frusta %u: frustum %llu refers to SKEL node %u, the skeleton has %llu nodes", c->id,
                  (unsigned long long)i, n0 >= nodes ? n0 : n1 >= nodes ? n1 : sn, (unsigned long long)nodes);
            break;
        }
        double h2 = 0, p0 = 0, p1 = 0;
        for (int k = 0; k < 3; k++) {
            const double a = (double)mesoi_ldf32(p + MESO_FRUS_OFF_CENTER1 + 4 * k) -
                             (double)mesoi_ldf32(p + MESO_FRUS_OFF_CENTER0 + 4 * k);
            const double q0 = mesoi_ldf32(p + MESO_FRUS_OFF_PLANE0 + 4 * k), q1 = mesoi_ldf32(p + MESO_FRUS_OFF_PLANE1 + 4 * k);
            h2 += a * a;
            p0 += q0 * q0;
            p1 += q1 * q1;
        }
        if (!(h2 > 0) || !(p0 > 0) || !(p1 > 0)) {
            ISSUE(c, MESO_ISSUE_FRUSTA_AXIS, fr, "frusta %u: frustum %llu has %s", c->id, (unsigned long long)i,
                  h2 > 0 ? "a zero cutting-plane normal" : "coincident centres (no axis)");
            break;
        }
    }
    const uint64_t nb = ball ? c->f->chunks[ba].decoded_size / MESO_BALL_RECORD_SIZE : 0;
    for (uint64_t i = 0; i < nb && !c->stop; i++) {
        const uint32_t n = mesoi_ld32(ball + i * MESO_BALL_RECORD_SIZE + MESO_BALL_OFF_NODE);
        if (n >= nodes) {
            ISSUE(c, MESO_ISSUE_FRUSTA_NODE, ba, "frusta %u: ball %llu closes SKEL node %u, the skeleton has %llu nodes",
                  c->id, (unsigned long long)i, n, (unsigned long long)nodes);
            break;
        }
    }
done:
    mesoi_file_free(&c->f->alloc, frus);
    mesoi_file_free(&c->f->alloc, fseg);
    mesoi_file_free(&c->f->alloc, skel);
    mesoi_file_free(&c->f->alloc, ball);
}

/* >>entry points ------------------------------------------------------------ */

/* One level of an object: the kind's rules over the chunks that level draws. */
static meso_result check_level(meso_file* f, const meso_object_record* rec, uint16_t lod, meso_issue_fn fn,
                               void* user)
{
    obj_check c = {f, rec->id, lod, fn, user, MESO_OK, 0};
    meso_mesh_layout l;
    int32_t i;
    switch (rec->kind) {
    case MESO_OBJECT_MESH:
        if ((i = required(&c, rec->kind, MESO_CHUNK_MESH)) >= 0 && mesh_header(&c, i, &l) && !c.stop)
            vertex_colours(&c, &l);
        break;
    case MESO_OBJECT_CELLS:
        /* The CELL record and what it implies: meso_file_check_cells. */
        if ((i = required(&c, rec->kind, MESO_CHUNK_MESH)) >= 0 && !c.stop)
            mesh_header(&c, i, &l);
        if (!c.stop)
            required(&c, rec->kind, MESO_CHUNK_CELL);
        if (!c.stop)
            colour_chunk(&c, MESO_CHUNK_TX3D, 0, MESO_ISSUE_CELLS_COLOUR_GRID);
        /* A native coarser level whose CELL is another lod's: the chunks it
         * resolves to against that CELL (a level with its own CELL is
         * checked by the full tier's pass over every CELL). */
        if (!c.stop && lod > 0 && meso_file_find(f, MESO_CHUNK_CELL, rec->id, lod) < 0) {
            meso_error e;
            if (meso_file_check_cells_level(f, rec->id, lod, &e) != MESO_OK)
                ISSUE(&c, e.code, e.chunk, "%s", e.message);
        }
        break;
    case MESO_OBJECT_SHELL: check_shell(&c); break;
    case MESO_OBJECT_FRUSTA: check_frusta(&c); break;
    default: break; /* OBJT's own check refuses other kinds (4204) */
    }
    return c.first;
}

meso_result mesoi_check_object(meso_file* f, const meso_object_record* rec, meso_issue_fn fn, void* user)
{
    return check_level(f, rec, 0, fn, user);
}

/* Each LODS record against OBJT and the chunks its level draws (6401): the
 * object exists, lod 0 is NATIVE, every coarser NATIVE level passes its
 * kind's rules over the chunks it resolves to, a MESH stand-in has a MESH. */
void mesoi_check_levels(meso_file* f, const meso_object_record* recs, uint32_t count, meso_issue_fn fn, void* user)
{
    const int32_t li = meso_file_find(f, MESO_CHUNK_LODS, 0, UINT16_MAX);
    if (li < 0)
        return;
    obj_check top = {f, 0, 0, fn, user, MESO_OK, 0};
    const meso_chunk_info* lc = &f->chunks[li];
    uint8_t* lods = load(&top, li);
    if (!lods)
        return;
    for (uint64_t k = 0; k < lc->decoded_size / MESO_LODS_RECORD_SIZE && !top.stop; k++) {
        meso_level_record lr;
        meso_level_record_decode(lods + k * MESO_LODS_RECORD_SIZE, &lr);
        const meso_object_record* rec = NULL;
        for (uint32_t i = 0; i < count; i++)
            if (recs[i].id == lr.object)
                rec = &recs[i];
        if (!rec) {
            ISSUE(&top, MESO_ISSUE_LEVELS, li, "chunk %d (LODS): record %llu names object %u, which OBJT has not",
                  (int)li, (unsigned long long)k, lr.object);
            continue;
        }
        if (lr.lod == 0 && lr.form != MESO_LEVEL_NATIVE) {
            ISSUE(&top, MESO_ISSUE_LEVELS, li, "chunk %d (LODS): lod 0 of object %u is a stand-in, must be native",
                  (int)li, lr.object);
            continue;
        }
        if (lr.lod == 0)
            continue; /* level 0 is the object check itself */
        meso_object_record as = *rec;
        if (lr.form == MESO_LEVEL_MESH)
            as.kind = MESO_OBJECT_MESH;
        obj_check c = {f, lr.object, lr.lod, NULL, NULL, MESO_OK, 0};
        meso_error e;
        memset(&e, 0, sizeof e);
        if (check_level(f, &as, lr.lod, keep_first_issue, &e) != MESO_OK) {
            ISSUE(&top, MESO_ISSUE_LEVELS, li, "object %u, level %u (%s): %s", lr.object, lr.lod,
                  lr.form == MESO_LEVEL_MESH ? "mesh stand-in" : "native", e.message);
        }
        (void)c;
    }
    mesoi_file_free(&f->alloc, lods);
}

/* Each PRTS chunk against OBJT and its PMSH chunks (6501, FORMAT.md §7.11):
 * its object is a mesh or shell object in OBJT with one PRTS; a mesh
 * object's records are native, each with one PMSH at its (part, lod), and
 * it has no PTRI; a shell's PTRI lists each triangle of its level-0 MESH
 * once, its parts' lod 0 are native, without a PMSH, naming all of that
 * list, and its lods 1.. mesh stand-ins, each with one PMSH. Every PMSH has one
 * record. The PMSH contents are checked as MESH chunks by the chunk pass;
 * the ranges by the content check. */
void mesoi_check_parts(meso_file* f, const meso_object_record* recs, uint32_t count, meso_issue_fn fn, void* user)
{
    obj_check top = {f, 0, 0, fn, user, MESO_OK, 0};
    for (uint32_t i = 0; i < f->chunk_count && !top.stop; i++) {
        const meso_chunk_info* c = &f->chunks[i];
        if (c->type == MESO_CHUNK_PMSH && meso_file_find(f, MESO_CHUNK_PRTS, c->object, UINT16_MAX) < 0)
            ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i, "chunk %u (PMSH): object %u has no PRTS to name this part", i,
                  c->object);
        if (c->type == MESO_CHUNK_PVCL) { /* one per PMSH at most, one colour per vertex of it */
            const int32_t mi = mesoi_find_part(f, MESO_CHUNK_PMSH, c->object, c->dims[0], c->lod);
            meso_mesh_layout l;
            if (mi < 0)
                ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i, "chunk %u (PVCL): object %u has no PMSH for part %u, lod %u",
                      i, c->object, c->dims[0], (unsigned)c->lod);
            else if (mesoi_find_part(f, MESO_CHUNK_PVCL, c->object, c->dims[0], c->lod) != (int32_t)i)
                ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i, "chunk %u (PVCL): a second PVCL for part %u, lod %u", i,
                      c->dims[0], (unsigned)c->lod);
            else if (mesh_header(&top, mi, &l) && (uint64_t)l.vertex_count * c->components != c->decoded_size)
                ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i,
                      "chunk %u (PVCL): %llu bytes of %u per vertex for part %u, lod %u, whose PMSH has %u vertices",
                      i, (unsigned long long)c->decoded_size, (unsigned)c->components, c->dims[0], (unsigned)c->lod,
                      l.vertex_count);
        }
        if (c->type != MESO_CHUNK_PRTS)
            continue;
        const meso_object_record* rec = NULL;
        for (uint32_t k = 0; k < count; k++)
            if (recs[k].id == c->object)
                rec = &recs[k];
        if (!rec || (rec->kind != MESO_OBJECT_MESH && rec->kind != MESO_OBJECT_SHELL)) {
            ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i, "chunk %u (PRTS): object %u is %s", i, c->object,
                  rec ? "neither a mesh nor a shell object" : "not in OBJT");
            continue;
        }
        if (meso_file_find(f, MESO_CHUNK_PRTS, c->object, UINT16_MAX) != (int32_t)i) {
            ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i, "chunk %u (PRTS): a second PRTS for object %u", i, c->object);
            continue;
        }
        const int shell = rec->kind == MESO_OBJECT_SHELL;
        meso_mesh_layout l = {0};
        const int32_t mi = shell ? meso_file_find_level(f, MESO_CHUNK_MESH, c->object, 0) : -1;
        if (shell && (mi < 0 || !mesh_header(&top, mi, &l)))
            continue; /* the shell's own rules say what is wrong with its MESH */
        uint8_t* d = load(&top, (int32_t)i);
        if (!d)
            continue;
        const uint32_t records = mesoi_ld32(d + MESO_PRTS_OFF_RECORDS);
        uint32_t found = 0;
        const int32_t ti = meso_file_find(f, MESO_CHUNK_PTRI, c->object, 0);
        const uint32_t tris = ti >= 0 ? f->chunks[ti].dims[0] : 0;
        if (!shell && ti >= 0)
            ISSUE(&top, MESO_ISSUE_PARTS, ti, "chunk %d (PTRI): a triangle list on mesh object %u", (int)ti,
                  c->object);
        if (shell && tris != l.index_count / 3)
            ISSUE(&top, MESO_ISSUE_PARTS, ti >= 0 ? ti : (int32_t)i,
                  "object %u: its parts list %u triangles (PTRI), its level-0 MESH has %u", c->object, tris,
                  l.index_count / 3);
        uint8_t* seen = shell && !top.stop && ti >= 0 && rules_ok(&top, ti) ? mesoi_file_alloc(&f->alloc, tris + 1u)
                                                                            : NULL;
        uint8_t* list = seen ? load(&top, ti) : NULL;
        if (list) {
            memset(seen, 0, tris);
            for (uint32_t k = 0; k < tris && !top.stop; k++) {
                const uint32_t v = mesoi_ld32(list + 4 * (size_t)k);
                if (v >= tris || seen[v]++)
                    ISSUE(&top, MESO_ISSUE_PARTS, ti, "chunk %d (PTRI) of shell %u: entry %u (%u) is %s", (int)ti,
                          c->object, k, v, v >= tris ? "not a triangle of its MESH" : "listed twice");
            }
        }
        mesoi_file_free(&f->alloc, list);
        mesoi_file_free(&f->alloc, seen);
        uint64_t end = 0; /* where the last part's triangles end in the list */
        for (uint32_t r = 0; r < records && !top.stop; r++) {
            const uint8_t* p = d + MESO_PRTS_HDR_SIZE + (size_t)r * MESO_LODS_RECORD_SIZE;
            meso_level_record lr;
            meso_level_record_decode(p, &lr);
            const int32_t pi = mesoi_find_part(f, MESO_CHUNK_PMSH, c->object, lr.object, lr.lod);
            const int prisms = shell && lr.lod == 0; /* drawn by the shell's native levels: no PMSH */
            if (prisms)
                end = mesoi_ld32(p + MESO_PRTS_OFF_FIRST_TRIANGLE) + (uint64_t)mesoi_ld32(p + MESO_PRTS_OFF_TRIANGLE_COUNT);
            const char* why = NULL;
            if (!shell && lr.form != MESO_LEVEL_NATIVE)
                why = "is not native (a mesh object's part levels are)";
            else if (shell && lr.lod > 0 && lr.form != MESO_LEVEL_MESH)
                why = "is not a mesh stand-in (a shell part's lods 1.. are)";
            else if (prisms && pi >= 0)
                why = "has a PMSH (a shell part's lod 0 is its prisms)";
            else if (!prisms && pi < 0)
                why = "has no PMSH";
            if (why)
                ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i, "chunk %u (PRTS): part %u, lod %u of object %u %s", i,
                      lr.object, lr.lod, c->object, why);
            found += pi >= 0;
        }
        if (shell && !top.stop && end != tris)
            ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i, "chunk %u (PRTS): the parts of shell %u hold %llu of its %u prisms",
                  i, c->object, (unsigned long long)end, tris);
        uint32_t pmsh = 0;
        for (uint32_t k = 0; k < f->chunk_count; k++)
            pmsh += f->chunks[k].type == MESO_CHUNK_PMSH && f->chunks[k].object == c->object;
        if (!top.stop && pmsh != found)
            ISSUE(&top, MESO_ISSUE_PARTS, (int32_t)i,
                  "object %u has %u PMSH chunks, but its PRTS names %u part levels (a PMSH without a record, or "
                  "two at one part level)",
                  c->object, pmsh, found);
        mesoi_file_free(&f->alloc, d);
    }
}

meso_result meso_file_check_object(meso_file* f, uint32_t object, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (f == NULL || object == 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_file_check_object: NULL file or object 0");
    const int32_t oi = meso_file_find(f, MESO_CHUNK_OBJT, UINT32_MAX, UINT16_MAX);
    const meso_chunk_info* oc = oi >= 0 ? &f->chunks[oi] : NULL;
    uint8_t* objt = NULL;
    meso_error e;
    meso_result r = MESO_OK;
    if (oc) {
        objt = (uint8_t*)mesoi_file_alloc(&f->alloc, (size_t)oc->decoded_size);
        if (!objt)
            return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, oi,
                                    "chunk %d (OBJT): out of memory", (int)oi);
        if ((r = meso_file_read_chunk(f, (uint32_t)oi, objt, (size_t)oc->decoded_size, &e)) != MESO_OK) {
            if (err)
                *err = e;
            mesoi_file_free(&f->alloc, objt);
            return r;
        }
    }
    r = MESO_ERR_NOT_FOUND;
    for (uint64_t k = 0; oc && k < oc->decoded_size / MESO_OBJT_RECORD_SIZE; k++) {
        meso_object_record rec;
        meso_object_record_decode(objt + k * MESO_OBJT_RECORD_SIZE, &rec);
        if (rec.id != object)
            continue;
        memset(&e, 0, sizeof e);
        r = mesoi_check_object(f, &rec, keep_first_issue, &e);
        if (r != MESO_OK && err)
            *err = e;
        break;
    }
    mesoi_file_free(&f->alloc, objt);
    if (r == MESO_ERR_NOT_FOUND)
        return mesoi_file_error(err, MESO_ERR_NOT_FOUND, MESO_ISSUE_API_ARG, UINT64_MAX, oi,
                                "object %u is not in the OBJT table", object);
    return r;
}
