/* mesh_guard.c — the byte-level check of mesh files before any third-party
 * reader sees them (what is checked and why: mesh_guard.h).
 *
 * Over 1,000 lines on purpose: the six formats share the text tokenizer, the
 * budget check, the directed-edge table and the error helpers, which are
 * this file's first half; each format's checker is one function after them.
 * Split it per format (mesh_guard_ply.c, ...) if a format grows. */
#include "mesh_guard.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Vertex and triangle counts above this are refused (the baker's meshes use
 * 32-bit indices, and the OpenMesh adapter refuses more than this too). */
#define GUARD_MAX_ELEMENTS (UINT32_MAX / 4u)

/* A token: bytes [s, s + n). */
typedef struct tok {
    const uint8_t* s;
    size_t n;
} tok;

/* Directed edges seen so far: open addressing, key (a << 32 | b) + 1, 0 empty;
 * key and face side by side (one cache miss a probe). */
typedef struct edge_slot {
    uint64_t key;
    uint64_t where; /* line or face number of the face that used it */
} edge_slot;
typedef struct edge_set {
    edge_slot* slots;
    size_t cap, count;
} edge_set;

typedef struct guard {
    meso_error* err;
    const uint8_t* base; /* the buffer (for byte offsets) */
    size_t size;
    uint64_t max_bytes;
    const char* where_word; /* "line" or "face" */
    edge_set edges;
    uint32_t* sorted; /* scratch for long faces */
    size_t sorted_cap;
    meso_mesh_guard_stats st;
} guard;

static meso_result fail(guard* g, meso_result r, uint32_t code, uint64_t offset, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

static meso_result fail(guard* g, meso_result r, uint32_t code, uint64_t offset, const char* fmt, ...)
{
    char msg[sizeof(g->err->message)];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    meso_bake_fail(g->err, r, code, "%s", msg);
    if (g->err)
        g->err->offset = offset;
    return r;
}

#define CORRUPT(g, code, off, ...) fail((g), MESO_ERR_CORRUPT, (code), (uint64_t)(off), __VA_ARGS__)

/* ---- budget ---------------------------------------------------------- */

static meso_result budget(guard* g, uint64_t vertices, uint64_t triangles, const char* what)
{
    if (vertices > GUARD_MAX_ELEMENTS || triangles > GUARD_MAX_ELEMENTS)
        return CORRUPT(g, MESO_MESH_GUARD_BUDGET, 0,
                       "%s: %llu vertices and %llu triangles exceed the %u the baker handles", what,
                       (unsigned long long)vertices, (unsigned long long)triangles, GUARD_MAX_ELEMENTS);
    double need = (double)vertices * MESO_MESH_GUARD_BYTES_PER_VERTEX +
                  (double)triangles * MESO_MESH_GUARD_BYTES_PER_TRIANGLE + (double)g->size;
    if (need > (double)g->max_bytes)
        return CORRUPT(g, MESO_MESH_GUARD_BUDGET, 0,
                       "%s: %llu vertices and %llu triangles would need about %.0f MB to read, more than the "
                       "%.3g MB allowed (raise it with --max-memory SIZE)",
                       what, (unsigned long long)vertices, (unsigned long long)triangles, need / 1e6,
                       (double)g->max_bytes / 1e6);
    return MESO_OK;
}

/* Where a face or element is, formatted only when a message needs it (the
 * loops would otherwise spend more time on snprintf than on checking). */
typedef struct place {
    const char* kind; /* "line", "triangle", "element 'face'", ... */
    uint64_t index;
    uint64_t byte; /* NO_BYTE for text lines */
} place;
#define NO_BYTE UINT64_MAX

static const char* place_str(const place* pl, char buf[96])
{
    if (pl->byte == NO_BYTE)
        snprintf(buf, 96, "%s %llu", pl->kind, (unsigned long long)pl->index);
    else
        snprintf(buf, 96, "%s %llu at byte %llu", pl->kind, (unsigned long long)pl->index,
                 (unsigned long long)pl->byte);
    return buf;
}

/* ---- faces: corners, repeated vertices, directed edges ----------------- */

static uint64_t edge_hash(uint64_t key)
{
    key ^= key >> 29;
    key *= UINT64_C(0x9E3779B97F4A7C15);
    return key ^ (key >> 32);
}

/* Grow the table to hold `n` edges at half load (rehashing what it holds). */
static int edge_reserve(edge_set* e, size_t n)
{
    size_t cap = e->cap ? e->cap : 1024;
    while (cap / 2 < n)
        cap *= 2;
    if (cap == e->cap)
        return 0;
    edge_slot* slots = calloc(cap, sizeof(edge_slot));
    if (!slots)
        return -1;
    for (size_t i = 0; i < e->cap; ++i)
        if (e->slots[i].key) {
            size_t j = (size_t)edge_hash(e->slots[i].key) & (cap - 1);
            while (slots[j].key)
                j = (j + 1) & (cap - 1);
            slots[j] = e->slots[i];
        }
    free(e->slots);
    e->slots = slots;
    e->cap = cap;
    return 0;
}

/* Reserve for `faces` triangles' edges once the counts passed the budget
 * (a failure only means the table grows as it fills). */
static void edge_presize(guard* g, uint64_t faces)
{
    if (faces <= GUARD_MAX_ELEMENTS)
        (void)edge_reserve(&g->edges, (size_t)(3 * faces));
}

/* Insert a->b; returns the earlier face's number in *prev and 1 when the
 * edge was there already, 0 when inserted, -1 out of memory. */
static int edge_insert(edge_set* e, uint32_t a, uint32_t b, uint64_t where, uint64_t* prev)
{
    if (2 * (e->count + 1) > e->cap && edge_reserve(e, e->count + 1) != 0)
        return -1;
    uint64_t key = (((uint64_t)a << 32) | b) + 1;
    size_t j = (size_t)edge_hash(key) & (e->cap - 1);
    while (e->slots[j].key) {
        if (e->slots[j].key == key) {
            *prev = e->slots[j].where;
            return 1;
        }
        j = (j + 1) & (e->cap - 1);
    }
    e->slots[j].key = key;
    e->slots[j].where = where;
    e->count++;
    return 0;
}

static int cmp_u32(const void* a, const void* b)
{
    uint32_t x = *(const uint32_t*)a, y = *(const uint32_t*)b;
    return (x > y) - (x < y);
}

/* A face of k >= 3 in-range corners v[0..k): distinct vertices, and directed
 * edges no earlier face used. `where` is its line or face number, `pl` the
 * place for messages. */
static meso_result face_check(guard* g, const uint32_t* v, size_t k, uint64_t where, uint64_t offset,
                              const place* pl)
{
    char lb[96];
    if (k <= 16) {
        for (size_t i = 0; i < k; ++i)
            for (size_t j = i + 1; j < k; ++j)
                if (v[i] == v[j])
                    return CORRUPT(g, MESO_MESH_GUARD_REPEATED_CORNER, offset,
                                   "%s: the face names vertex %u twice (corners %zu and %zu)", place_str(pl, lb), v[i], i + 1,
                                   j + 1);
    } else {
        if (k > g->sorted_cap) {
            uint32_t* s = realloc(g->sorted, k * sizeof(uint32_t));
            if (!s)
                return fail(g, MESO_ERR_OUT_OF_MEMORY, 0, offset, "%s: out of memory", place_str(pl, lb));
            g->sorted = s;
            g->sorted_cap = k;
        }
        memcpy(g->sorted, v, k * sizeof(uint32_t));
        qsort(g->sorted, k, sizeof(uint32_t), cmp_u32);
        for (size_t i = 1; i < k; ++i)
            if (g->sorted[i] == g->sorted[i - 1])
                return CORRUPT(g, MESO_MESH_GUARD_REPEATED_CORNER, offset, "%s: the face names vertex %u twice",
                               place_str(pl, lb), g->sorted[i]);
    }
    for (size_t i = 0; i < k; ++i) {
        uint64_t prev = 0;
        int r = edge_insert(&g->edges, v[i], v[(i + 1) % k], where, &prev);
        if (r < 0)
            return fail(g, MESO_ERR_OUT_OF_MEMORY, 0, offset, "%s: out of memory for the edge table", place_str(pl, lb));
        if (r > 0)
            return CORRUPT(g, MESO_MESH_GUARD_DUPLICATE_EDGE, offset,
                           "%s: the edge from vertex %u to vertex %u is also used, in the same direction, by the "
                           "face at %s %llu (a duplicated face, or more than two faces on an edge)",
                           place_str(pl, lb), v[i], v[(i + 1) % k], g->where_word, (unsigned long long)prev);
    }
    g->st.faces++;
    g->st.triangles += k - 2;
    return MESO_OK;
}

/* ---- text: lines, tokens, numbers -------------------------------------- */

typedef struct text {
    const uint8_t* p;   /* next line */
    const uint8_t* end; /* buffer end */
    uint64_t line;      /* number of the line last returned (1-based) */
} text;

/* The next line [*s, *e) without its terminator; 0 at the end. */
static int next_line(text* t, const uint8_t** s, const uint8_t** e)
{
    if (t->p >= t->end)
        return 0;
    const uint8_t* nl = memchr(t->p, '\n', (size_t)(t->end - t->p));
    *s = t->p;
    *e = nl ? nl : t->end;
    t->p = nl ? nl + 1 : t->end;
    t->line++;
    return 1;
}

static int is_space(uint8_t c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* The next whitespace-separated token of [*p, e); 0 when none. A token
 * starting with '#' ends the line (a comment) when `comments` is set. */
static int next_token(const uint8_t** p, const uint8_t* e, int comments, tok* out)
{
    const uint8_t* q = *p;
    while (q < e && is_space(*q))
        ++q;
    if (q >= e || (comments && *q == '#')) {
        *p = e;
        return 0;
    }
    const uint8_t* s = q;
    while (q < e && !is_space(*q))
        ++q;
    out->s = s;
    out->n = (size_t)(q - s);
    *p = q;
    return 1;
}

static int tok_is(tok t, const char* word)
{
    size_t n = strlen(word);
    return t.n == n && memcmp(t.s, word, n) == 0;
}

static int tok_is_nocase(tok t, const char* word)
{
    size_t n = strlen(word);
    if (t.n != n)
        return 0;
    for (size_t i = 0; i < n; ++i) {
        uint8_t c = t.s[i];
        if (c >= 'A' && c <= 'Z')
            c = (uint8_t)(c - 'A' + 'a');
        if (c != (uint8_t)word[i])
            return 0;
    }
    return 1;
}

/* A decimal number (the syntax of strtod without hex floats). Returns 0 and
 * sets *v (possibly NaN or Inf: "nan", "inf" and overflowing values parse),
 * or -1 when the token is not a number. */
static int parse_number(tok t, double* v)
{
    char buf[128];
    if (t.n == 0 || t.n >= sizeof(buf))
        return -1;
    for (size_t i = 0; i < t.n; ++i)
        if (t.s[i] == 'x' || t.s[i] == 'X' || t.s[i] == '(')
            return -1;
    memcpy(buf, t.s, t.n);
    buf[t.n] = 0;
    char* end = NULL;
    *v = strtod(buf, &end);
    return end == buf + t.n ? 0 : -1;
}

/* A finite float: parsed and within the float range. */
static int finite_float(double v)
{
    return v == v && fabs(v) <= (double)FLT_MAX;
}

/* A decimal integer [+-]digits. Returns 0, or -1 when not an integer;
 * magnitudes stop growing past 2^58 (still out of every range, and
 * 10 x 2^58 + 9 cannot overflow). */
static int parse_int(tok t, int64_t* v)
{
    size_t i = 0;
    int neg = 0;
    if (t.n && (t.s[0] == '+' || t.s[0] == '-')) {
        neg = t.s[0] == '-';
        i = 1;
    }
    if (i >= t.n)
        return -1;
    int64_t x = 0;
    for (; i < t.n; ++i) {
        if (t.s[i] < '0' || t.s[i] > '9')
            return -1;
        if (x < (INT64_C(1) << 58))
            x = 10 * x + (t.s[i] - '0');
    }
    *v = neg ? -x : x;
    return 0;
}

static uint64_t off_of(const guard* g, const uint8_t* p)
{
    return (uint64_t)(p - g->base);
}

/* Numbers on the rest of a line: at least `min` of them, each a finite float
 * when `finite`. */
static meso_result line_numbers(guard* g, const uint8_t* p, const uint8_t* e, size_t min, int finite,
                                uint64_t line, const char* what)
{
    size_t n = 0;
    tok t;
    while (next_token(&p, e, 1, &t)) {
        double v;
        if (parse_number(t, &v) != 0)
            return CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, t.s), "line %llu: %s: '%.*s' is not a number",
                           (unsigned long long)line, what, (int)(t.n > 32 ? 32 : t.n), (const char*)t.s);
        if (finite && !finite_float(v))
            return CORRUPT(g, MESO_MESH_GUARD_NONFINITE, off_of(g, t.s),
                           "line %llu: %s: coordinate %zu ('%.*s') is not a finite float", (unsigned long long)line,
                           what, n + 1, (int)(t.n > 32 ? 32 : t.n), (const char*)t.s);
        ++n;
    }
    if (n < min)
        return CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, p), "line %llu: %s has %zu numbers, needs %zu",
                       (unsigned long long)line, what, n, min);
    return MESO_OK;
}

/* A growable corner list. */
static meso_result push_corner(guard* g, uint32_t** v, size_t* n, size_t* cap, uint32_t x)
{
    if (*n == *cap) {
        size_t c = *cap ? 2 * *cap : 16;
        uint32_t* nv = realloc(*v, c * sizeof(uint32_t));
        if (!nv)
            return fail(g, MESO_ERR_OUT_OF_MEMORY, 0, 0, "out of memory");
        *v = nv;
        *cap = c;
    }
    (*v)[(*n)++] = x;
    return MESO_OK;
}

/* ---- OBJ ---------------------------------------------------------------- */

/* One part of an OBJ corner (`v`, `vt` or `vn` index) resolved to 0-based:
 * count_before = elements read before this line, total = in the file. */
static meso_result obj_index(guard* g, tok t, uint64_t before, uint64_t total, uint32_t code, const char* kind,
                             uint64_t line, uint32_t* out)
{
    int64_t i;
    if (parse_int(t, &i) != 0)
        return CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, t.s), "line %llu: %s index '%.*s' is not an integer",
                       (unsigned long long)line, kind, (int)(t.n > 32 ? 32 : t.n), (const char*)t.s);
    if (i == 0)
        return CORRUPT(g, code == MESO_MESH_GUARD_INDEX_RANGE ? MESO_MESH_GUARD_INDEX_ZERO : code, off_of(g, t.s),
                       "line %llu: %s index 0 (OBJ indices start at 1)", (unsigned long long)line, kind);
    int64_t r = i > 0 ? i - 1 : (int64_t)before + i;
    if (r < 0 || (uint64_t)r >= (i > 0 ? total : before))
        return CORRUPT(g, code, off_of(g, t.s),
                       "line %llu: %s index %lld is out of range (%s %llu)", (unsigned long long)line, kind,
                       (long long)i, i > 0 ? "the file has" : "lines before this one define",
                       (unsigned long long)(i > 0 ? total : before));
    *out = (uint32_t)r;
    return MESO_OK;
}

static meso_result check_obj(guard* g)
{
    text t = {g->base, g->base + g->size, 0};
    const uint8_t *s, *e;
    uint64_t nv = 0, nvt = 0, nvn = 0, nf = 0;
    while (next_line(&t, &s, &e)) {
        tok k;
        const uint8_t* p = s;
        if (!next_token(&p, e, 1, &k))
            continue;
        nv += tok_is(k, "v");
        nvt += tok_is(k, "vt");
        nvn += tok_is(k, "vn");
        nf += tok_is(k, "f");
    }
    if (nv == 0 || nf == 0)
        return CORRUPT(g, MESO_MESH_GUARD_EMPTY, 0, "OBJ: no %s", nv == 0 ? "vertices (v lines)" : "faces (f lines)");
    meso_result r = budget(g, nv, nf, "OBJ");
    if (r != MESO_OK)
        return r;
    edge_presize(g, nf);

    uint32_t* corners = NULL;
    size_t cap = 0;
    uint64_t cv = 0, cvt = 0, cvn = 0;
    t = (text){g->base, g->base + g->size, 0};
    while (r == MESO_OK && next_line(&t, &s, &e)) {
        tok k;
        const uint8_t* p = s;
        if (!next_token(&p, e, 1, &k))
            continue;
        if (tok_is(k, "v")) {
            r = line_numbers(g, p, e, 3, 1, t.line, "vertex (v)");
            cv++;
        } else if (tok_is(k, "vt")) {
            r = line_numbers(g, p, e, 1, 1, t.line, "texture coordinate (vt)");
            cvt++;
        } else if (tok_is(k, "vn")) {
            r = line_numbers(g, p, e, 3, 1, t.line, "normal (vn)");
            cvn++;
        } else if (tok_is(k, "f")) {
            size_t n = 0;
            tok c;
            while (r == MESO_OK && next_token(&p, e, 1, &c)) {
                /* v, v/t, v/t/n or v//n */
                tok part[3] = {{c.s, 0}, {NULL, 0}, {NULL, 0}};
                int parts = 1;
                for (size_t i = 0; i < c.n; ++i) {
                    if (c.s[i] != '/') {
                        part[parts - 1].n++;
                        continue;
                    }
                    if (parts == 3) {
                        parts = 4;
                        break;
                    }
                    part[parts++] = (tok){c.s + i + 1, 0};
                }
                if (parts > 3 || part[0].n == 0) {
                    r = CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, c.s),
                                "line %llu: face corner %zu '%.*s' is not v, v/vt, v/vt/vn or v//vn",
                                (unsigned long long)t.line, n + 1, (int)(c.n > 32 ? 32 : c.n), (const char*)c.s);
                    break;
                }
                uint32_t idx, unused;
                r = obj_index(g, part[0], cv, nv, MESO_MESH_GUARD_INDEX_RANGE, "vertex", t.line, &idx);
                if (r == MESO_OK && parts >= 2 && part[1].n)
                    r = obj_index(g, part[1], cvt, nvt, MESO_MESH_GUARD_ATTR_INDEX, "texture coordinate", t.line,
                                  &unused);
                if (r == MESO_OK && parts == 3)
                    r = obj_index(g, part[2], cvn, nvn, MESO_MESH_GUARD_ATTR_INDEX, "normal", t.line, &unused);
                if (r == MESO_OK)
                    r = push_corner(g, &corners, &n, &cap, idx);
            }
            if (r != MESO_OK)
                break;
            char lb[96];
            const place pl_ = {"line", t.line, NO_BYTE}, *pl = &pl_;
            if (n < 3)
                r = CORRUPT(g, MESO_MESH_GUARD_FACE_SIZE, off_of(g, s), "%s: a face with %zu corners (needs 3)", place_str(pl, lb),
                            n);
            else
                r = face_check(g, corners, n, t.line, off_of(g, s), pl);
        }
    }
    free(corners);
    g->st.vertices = nv;
    return r == MESO_OK ? budget(g, nv, g->st.triangles, "OBJ") : r;
}

/* ---- OFF ---------------------------------------------------------------- */

/* The next line that is neither blank nor a comment. */
static int next_data_line(text* t, const uint8_t** s, const uint8_t** e)
{
    while (next_line(t, s, e)) {
        const uint8_t* p = *s;
        while (p < *e && is_space(*p))
            ++p;
        if (p < *e && *p != '#')
            return 1;
    }
    return 0;
}

static meso_result check_off(guard* g)
{
    text t = {g->base, g->base + g->size, 0};
    const uint8_t *s, *e, *p;
    tok k = {0}; /* gcc 12 -O3 cannot see that next_token always sets it */
    if (!next_data_line(&t, &s, &e))
        return CORRUPT(g, MESO_MESH_GUARD_EMPTY, 0, "OFF: empty file");
    p = s;
    next_token(&p, e, 1, &k);
    {
        tok q = k;
        int variant = 0;
        if (q.n >= 2 && q.s[0] == 'S' && q.s[1] == 'T')
            q.s += 2, q.n -= 2;
        if (q.n && q.s[0] == 'C')
            q.s++, q.n--;
        if (q.n && q.s[0] == 'N')
            q.s++, q.n--;
        if (q.n && (q.s[0] == '4' || q.s[0] == 'n'))
            variant = 1, q.s++, q.n--;
        if (!tok_is(q, "OFF"))
            return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, k.s), "OFF: line %llu: '%.*s' is not an OFF header",
                           (unsigned long long)t.line, (int)(k.n > 32 ? 32 : k.n), (const char*)k.s);
        if (variant)
            return CORRUPT(g, MESO_MESH_GUARD_VARIANT, off_of(g, k.s), "OFF: line %llu: '%.*s' (4D or nD) is not supported",
                           (unsigned long long)t.line, (int)k.n, (const char*)k.s);
    }
    tok c[3];
    int nc = 0;
    const uint8_t* q = p;
    if (next_token(&q, e, 1, &c[0]) && tok_is(c[0], "BINARY"))
        return CORRUPT(g, MESO_MESH_GUARD_VARIANT, off_of(g, c[0].s), "OFF: line %llu: binary OFF is not supported",
                       (unsigned long long)t.line);
    while (nc < 3 && next_token(&p, e, 1, &c[nc]))
        ++nc;
    if (nc == 0) {
        if (!next_data_line(&t, &s, &e))
            return CORRUPT(g, MESO_MESH_GUARD_HEADER, g->size, "OFF: the file ends before the counts line");
        p = s;
        while (nc < 3 && next_token(&p, e, 1, &c[nc]))
            ++nc;
    }
    int64_t cnt[3] = {0, 0, 0};
    for (int i = 0; i < nc; ++i)
        if (parse_int(c[i], &cnt[i]) != 0 || cnt[i] < 0)
            return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, c[i].s),
                           "OFF: line %llu: count '%.*s' is not a non-negative integer", (unsigned long long)t.line,
                           (int)(c[i].n > 32 ? 32 : c[i].n), (const char*)c[i].s);
    if (nc < 2)
        return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s),
                       "OFF: line %llu: needs the vertex and face counts", (unsigned long long)t.line);
    uint64_t nv = (uint64_t)cnt[0], nf = (uint64_t)cnt[1];
    if (nv == 0 || nf == 0)
        return CORRUPT(g, MESO_MESH_GUARD_EMPTY, off_of(g, s), "OFF: line %llu: the header counts %llu vertices and %llu faces",
                       (unsigned long long)t.line, (unsigned long long)nv, (unsigned long long)nf);
    /* Smallest encodings: "0 0 0\n" (6 bytes) a vertex, "3\n" a face
     * (refused later, but with its own code). */
    uint64_t left = (uint64_t)(t.end - t.p);
    if (nv > left / 6 || nf > left / 2 || 6 * nv + 2 * nf > left + 1)
        return CORRUPT(g, MESO_MESH_GUARD_SIZE, off_of(g, s),
                       "OFF: line %llu: %llu vertices and %llu faces cannot fit in the %llu bytes that follow",
                       (unsigned long long)t.line, (unsigned long long)nv, (unsigned long long)nf,
                       (unsigned long long)left);
    meso_result r = budget(g, nv, nf, "OFF");
    if (r != MESO_OK)
        return r;
    edge_presize(g, nf);
    for (uint64_t i = 0; i < nv; ++i) {
        if (!next_data_line(&t, &s, &e))
            return CORRUPT(g, MESO_MESH_GUARD_SIZE, g->size, "OFF: the file ends after %llu of %llu vertices",
                           (unsigned long long)i, (unsigned long long)nv);
        if ((r = line_numbers(g, s, e, 3, 1, t.line, "vertex")) != MESO_OK)
            return r;
    }
    uint32_t* corners = NULL;
    size_t cap = 0;
    for (uint64_t f = 0; f < nf && r == MESO_OK; ++f) {
        if (!next_data_line(&t, &s, &e)) {
            r = CORRUPT(g, MESO_MESH_GUARD_SIZE, g->size, "OFF: the file ends after %llu of %llu faces",
                        (unsigned long long)f, (unsigned long long)nf);
            break;
        }
        char lb[96];
        const place pl_ = {"line", t.line, NO_BYTE}, *pl = &pl_;
        p = s;
        int64_t kk;
        next_token(&p, e, 1, &k);
        if (parse_int(k, &kk) != 0) {
            r = CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, k.s), "%s: face size '%.*s' is not an integer", place_str(pl, lb),
                        (int)(k.n > 32 ? 32 : k.n), (const char*)k.s);
            break;
        }
        if (kk < 3) {
            r = CORRUPT(g, MESO_MESH_GUARD_FACE_SIZE, off_of(g, k.s), "%s: a face with %lld corners (needs 3)", place_str(pl, lb),
                        (long long)kk);
            break;
        }
        size_t n = 0;
        for (int64_t j = 0; j < kk && r == MESO_OK; ++j) {
            tok x;
            int64_t v;
            if (!next_token(&p, e, 1, &x)) {
                r = CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, e), "%s: the face has %lld of its %lld indices", place_str(pl, lb),
                            (long long)j, (long long)kk);
            } else if (parse_int(x, &v) != 0) {
                r = CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, x.s), "%s: index '%.*s' is not an integer", place_str(pl, lb),
                            (int)(x.n > 32 ? 32 : x.n), (const char*)x.s);
            } else if (v < 0 || (uint64_t)v >= nv) {
                r = CORRUPT(g, MESO_MESH_GUARD_INDEX_RANGE, off_of(g, x.s),
                            "%s: corner %lld refers to vertex %lld (the file has %llu)", place_str(pl, lb), (long long)j + 1,
                            (long long)v, (unsigned long long)nv);
            } else {
                r = push_corner(g, &corners, &n, &cap, (uint32_t)v);
            }
        }
        if (r == MESO_OK)
            r = face_check(g, corners, n, t.line, off_of(g, s), pl);
    }
    free(corners);
    if (r == MESO_OK && next_data_line(&t, &s, &e))
        r = CORRUPT(g, MESO_MESH_GUARD_TRAILING, off_of(g, s), "OFF: line %llu: data after the last face",
                    (unsigned long long)t.line);
    g->st.vertices = nv;
    return r == MESO_OK ? budget(g, nv, g->st.triangles, "OFF") : r;
}

/* ---- PLY ---------------------------------------------------------------- */

enum { PLY_MAX_ELEMENTS = 32, PLY_MAX_PROPS = 64 };

typedef struct ply_prop {
    uint8_t type;      /* index into ply_types */
    uint8_t list_type; /* count type of a list; 0 when scalar */
    uint8_t is_list;
    uint8_t role; /* 1..3 x y z of vertex, 4 face index list */
} ply_prop;

typedef struct ply_elem {
    tok name;
    uint64_t count;
    int nprops;
    ply_prop props[PLY_MAX_PROPS];
    uint64_t line;
} ply_elem;

static const struct {
    const char* name;
    uint8_t size, is_float, is_signed;
} ply_types[] = {
    {"", 0, 0, 0},         {"char", 1, 0, 1},    {"uchar", 1, 0, 0},  {"short", 2, 0, 1},   {"ushort", 2, 0, 0},
    {"int", 4, 0, 1},      {"uint", 4, 0, 0},    {"float", 4, 1, 1},  {"double", 8, 1, 1},  {"int8", 1, 0, 1},
    {"uint8", 1, 0, 0},    {"int16", 2, 0, 1},   {"uint16", 2, 0, 0}, {"int32", 4, 0, 1},   {"uint32", 4, 0, 0},
    {"float32", 4, 1, 1},  {"float64", 8, 1, 1},
};

static uint8_t ply_type(tok t)
{
    for (uint8_t i = 1; i < sizeof(ply_types) / sizeof(ply_types[0]); ++i)
        if (tok_is(t, ply_types[i].name))
            return i;
    return 0;
}

/* A binary scalar at p (bounds already checked): as double, and as integer
 * for integer types. */
static double ply_read(const uint8_t* p, uint8_t type, int big, int64_t* as_int)
{
    uint8_t b[8];
    unsigned n = ply_types[type].size;
    for (unsigned i = 0; i < n; ++i)
        b[i] = big ? p[n - 1 - i] : p[i];
    uint64_t u = 0;
    for (unsigned i = 0; i < n; ++i)
        u |= (uint64_t)b[i] << (8 * i);
    double v;
    if (ply_types[type].is_float) {
        if (n == 4) {
            uint32_t w = (uint32_t)u;
            float f;
            memcpy(&f, &w, 4);
            v = (double)f;
        } else {
            memcpy(&v, &u, 8);
        }
        *as_int = 0;
        return v;
    }
    int64_t i;
    if (ply_types[type].is_signed && n < 8 && (u >> (8 * n - 1)) & 1u)
        i = (int64_t)u - (int64_t)(UINT64_C(1) << (8 * n));
    else
        i = (int64_t)u;
    *as_int = i;
    return (double)i;
}

/* Parse the header; *body = offset of the first data byte. */
static meso_result ply_header(guard* g, ply_elem* el, int* nel, int* fmt, size_t* body)
{
    size_t limit = g->size < MESO_MESH_GUARD_PLY_HEADER_MAX ? g->size : MESO_MESH_GUARD_PLY_HEADER_MAX;
    text t = {g->base, g->base + limit, 0};
    const uint8_t *s, *e;
    *fmt = -1;
    *nel = 0;
    int ended = 0;
    while (!ended && next_line(&t, &s, &e)) {
        if (e == t.end && t.end != g->base + g->size) /* line cut by the limit */
            break;
        if (e == g->base + g->size) /* the last line, without its newline: truncated */
            break;
        const uint8_t* p = s;
        tok k;
        uint64_t line = t.line;
        if (line == 1) {
            if (!next_token(&p, e, 0, &k) || !tok_is(k, "ply") || next_token(&p, e, 0, &k))
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, 0, "PLY: line 1 is not 'ply'");
            continue;
        }
        if (!next_token(&p, e, 0, &k))
            return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s), "PLY: line %llu: empty header line",
                           (unsigned long long)line);
        if (tok_is(k, "comment") || tok_is(k, "obj_info"))
            continue;
        tok a[5];
        int na = 0;
        while (na < 5 && next_token(&p, e, 0, &a[na]))
            ++na;
        if (tok_is(k, "end_header")) {
            if (na)
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s), "PLY: line %llu: text after end_header",
                               (unsigned long long)line);
            ended = 1;
        } else if (tok_is(k, "format")) {
            if (*fmt >= 0 || na != 2)
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s),
                               "PLY: line %llu: needs one 'format TYPE 1.0' line", (unsigned long long)line);
            *fmt = tok_is(a[0], "ascii") ? 0 : tok_is(a[0], "binary_little_endian") ? 1
                                           : tok_is(a[0], "binary_big_endian")      ? 2
                                                                                    : -1;
            if (*fmt < 0)
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, a[0].s), "PLY: line %llu: unknown format '%.*s'",
                               (unsigned long long)line, (int)(a[0].n > 32 ? 32 : a[0].n), (const char*)a[0].s);
            if (!tok_is(a[1], "1.0"))
                return CORRUPT(g, MESO_MESH_GUARD_VARIANT, off_of(g, a[1].s),
                               "PLY: line %llu: version '%.*s' is not supported (only 1.0)", (unsigned long long)line,
                               (int)(a[1].n > 16 ? 16 : a[1].n), (const char*)a[1].s);
        } else if (tok_is(k, "element")) {
            int64_t cnt;
            if (na != 2 || parse_int(a[1], &cnt) != 0 || a[1].s[0] == '+' || cnt < 0 || a[1].s[0] == '-')
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s),
                               "PLY: line %llu: needs 'element NAME COUNT' with a non-negative count",
                               (unsigned long long)line);
            if (*nel == PLY_MAX_ELEMENTS)
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s), "PLY: line %llu: more than %d elements",
                               (unsigned long long)line, PLY_MAX_ELEMENTS);
            ply_elem* x = &el[(*nel)++];
            memset(x, 0, sizeof(*x));
            x->name = a[0];
            x->count = (uint64_t)cnt;
            x->line = line;
        } else if (tok_is(k, "property")) {
            if (*nel == 0)
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s), "PLY: line %llu: a property before any element",
                               (unsigned long long)line);
            ply_elem* x = &el[*nel - 1];
            if (x->nprops == PLY_MAX_PROPS)
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s), "PLY: line %llu: more than %d properties",
                               (unsigned long long)line, PLY_MAX_PROPS);
            ply_prop pr = {0, 0, 0, 0};
            tok name;
            if (na == 4 && tok_is(a[0], "list")) {
                pr.is_list = 1;
                pr.list_type = ply_type(a[1]);
                pr.type = ply_type(a[2]);
                name = a[3];
                if (!pr.list_type || ply_types[pr.list_type].is_float || !pr.type)
                    return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s),
                                   "PLY: line %llu: a list needs an integer count type and a known item type",
                                   (unsigned long long)line);
            } else if (na == 2) {
                pr.type = ply_type(a[0]);
                name = a[1];
                if (!pr.type)
                    return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s), "PLY: line %llu: unknown type '%.*s'",
                                   (unsigned long long)line, (int)(a[0].n > 16 ? 16 : a[0].n), (const char*)a[0].s);
            } else {
                return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s),
                               "PLY: line %llu: needs 'property TYPE NAME' or 'property list CTYPE TYPE NAME'",
                               (unsigned long long)line);
            }
            if (tok_is(x->name, "vertex") && !pr.is_list)
                pr.role = tok_is(name, "x") ? 1 : tok_is(name, "y") ? 2 : tok_is(name, "z") ? 3 : 0;
            if (tok_is(x->name, "face") && pr.is_list && (tok_is(name, "vertex_indices") || tok_is(name, "vertex_index")))
                pr.role = 4;
            x->props[x->nprops++] = pr;
        } else {
            return CORRUPT(g, MESO_MESH_GUARD_HEADER, off_of(g, s), "PLY: line %llu: unknown keyword '%.*s'",
                           (unsigned long long)line, (int)(k.n > 32 ? 32 : k.n), (const char*)k.s);
        }
    }
    if (!ended)
        return g->size > MESO_MESH_GUARD_PLY_HEADER_MAX
                   ? CORRUPT(g, MESO_MESH_GUARD_HEADER, limit, "PLY: no end_header in the first %u bytes",
                             MESO_MESH_GUARD_PLY_HEADER_MAX)
                   : CORRUPT(g, MESO_MESH_GUARD_HEADER, g->size, "PLY: the header is truncated (no end_header line)");
    if (*fmt < 0)
        return CORRUPT(g, MESO_MESH_GUARD_HEADER, 0, "PLY: no format line");
    *body = (size_t)(t.p - g->base);
    return MESO_OK;
}

/* ASCII body: the next token anywhere (lines counted). */
typedef struct ply_text {
    const uint8_t* p;
    const uint8_t* end;
    uint64_t line;
} ply_text;

static int ply_token(ply_text* pt, tok* out)
{
    const uint8_t* q = pt->p;
    while (q < pt->end && (is_space(*q) || *q == '\n'))
        pt->line += *q++ == '\n';
    if (q >= pt->end) {
        pt->p = q;
        return 0;
    }
    const uint8_t* s = q;
    while (q < pt->end && !is_space(*q) && *q != '\n')
        ++q;
    out->s = s;
    out->n = (size_t)(q - s);
    pt->p = q;
    return 1;
}

/* One value of property type `type`: from text or binary. *v as double,
 * *iv as integer (integer types). Returns MESO_OK or the error. */
static meso_result ply_value(guard* g, int fmt, ply_text* pt, size_t* at, uint8_t type, double* v, int64_t* iv,
                             const place* pl)
{
    char lb[96];
    if (fmt == 0) {
        tok t;
        if (!ply_token(pt, &t))
            return CORRUPT(g, MESO_MESH_GUARD_SIZE, g->size, "PLY: %s: the file ends inside the element", place_str(pl, lb));
        if (ply_types[type].is_float ? parse_number(t, v) != 0 : parse_int(t, iv) != 0)
            return CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, t.s), "PLY: %s (line %llu): '%.*s' is not %s", place_str(pl, lb),
                           (unsigned long long)pt->line + 1, (int)(t.n > 32 ? 32 : t.n), (const char*)t.s,
                           ply_types[type].is_float ? "a number" : "an integer");
        if (!ply_types[type].is_float)
            *v = (double)*iv;
        else
            *iv = 0;
        return MESO_OK;
    }
    size_t n = ply_types[type].size;
    if (g->size - *at < n)
        return CORRUPT(g, MESO_MESH_GUARD_SIZE, *at, "PLY: %s: the file ends inside the element (byte %zu)", place_str(pl, lb),
                       *at);
    *v = ply_read(g->base + *at, type, fmt == 2, iv);
    *at += n;
    return MESO_OK;
}

/* The smallest size of one instance: ASCII "0 " per property, binary the
 * scalars and the list counts. */
static uint64_t ply_min_size(const ply_elem* x, int fmt)
{
    uint64_t min = 0;
    for (int p = 0; p < x->nprops; ++p)
        min += fmt == 0 ? 2 : x->props[p].is_list ? ply_types[x->props[p].list_type].size
                                                  : ply_types[x->props[p].type].size;
    return min;
}

static meso_result check_ply(guard* g)
{
    ply_elem el[PLY_MAX_ELEMENTS];
    int nel, fmt;
    size_t at;
    meso_result r = ply_header(g, el, &nel, &fmt, &at);
    if (r != MESO_OK)
        return r;
    int iv = -1, jf = -1;
    for (int i = 0; i < nel; ++i) {
        if (tok_is(el[i].name, "vertex") && iv < 0)
            iv = i;
        if (tok_is(el[i].name, "face") && jf < 0)
            jf = i;
        if (el[i].nprops == 0 && el[i].count)
            return CORRUPT(g, MESO_MESH_GUARD_HEADER, 0, "PLY: line %llu: element '%.*s' has no properties",
                           (unsigned long long)el[i].line, (int)(el[i].name.n > 32 ? 32 : el[i].name.n),
                           (const char*)el[i].name.s);
    }
    if (iv < 0 || jf < 0)
        return CORRUPT(g, MESO_MESH_GUARD_EMPTY, 0, "PLY: no '%s' element", iv < 0 ? "vertex" : "face");
    {
        int has[5] = {0, 0, 0, 0, 0};
        for (int p = 0; p < el[iv].nprops; ++p)
            has[el[iv].props[p].role] = 1;
        for (int p = 0; p < el[jf].nprops; ++p)
            if (el[jf].props[p].role == 4 && !ply_types[el[jf].props[p].type].is_float)
                has[4] = 1;
        if (!has[1] || !has[2] || !has[3])
            return CORRUPT(g, MESO_MESH_GUARD_VARIANT, 0, "PLY: line %llu: the vertex element has no x, y and z",
                           (unsigned long long)el[iv].line);
        if (!has[4])
            return CORRUPT(g, MESO_MESH_GUARD_VARIANT, 0,
                           "PLY: line %llu: the face element has no integer list 'vertex_indices'",
                           (unsigned long long)el[jf].line);
    }
    uint64_t nv = el[iv].count, nf = el[jf].count;
    if (nv == 0 || nf == 0)
        return CORRUPT(g, MESO_MESH_GUARD_EMPTY, 0, "PLY: %llu vertices and %llu faces", (unsigned long long)nv,
                       (unsigned long long)nf);
    /* All elements at their smallest against the body, before the budget. */
    uint64_t body = (uint64_t)(g->size - at) + (fmt == 0), need = 0;
    for (int i = 0; i < nel; ++i) {
        uint64_t min = ply_min_size(&el[i], fmt);
        if (el[i].count && (el[i].count > body / min || (need += el[i].count * min) > body))
            return CORRUPT(g, MESO_MESH_GUARD_SIZE, at,
                           "PLY: line %llu: element '%.*s' claims %llu instances of at least %llu bytes; with the "
                           "elements before it that is more than the %llu bytes after the header",
                           (unsigned long long)el[i].line, (int)(el[i].name.n > 32 ? 32 : el[i].name.n),
                           (const char*)el[i].name.s, (unsigned long long)el[i].count, (unsigned long long)min,
                           (unsigned long long)(g->size - at));
    }
    if ((r = budget(g, nv, nf, "PLY")) != MESO_OK)
        return r;
    edge_presize(g, nf);
    ply_text pt = {g->base + at, g->base + g->size, 0};
    {
        /* lines of the header, for ascii line numbers */
        for (const uint8_t* q = g->base; q < g->base + at; ++q)
            pt.line += *q == '\n';
    }
    uint32_t* corners = NULL;
    size_t cap = 0;
    for (int i = 0; i < nel && r == MESO_OK; ++i) {
        const ply_elem* x = &el[i];
        /* Smallest size of one instance against what is left. */
        uint64_t left = fmt == 0 ? (uint64_t)(pt.end - pt.p) : (uint64_t)(g->size - at);
        uint64_t min = ply_min_size(x, fmt);
        if (x->count && (x->count > (left + 1) / min))
            return free(corners),
                   CORRUPT(g, MESO_MESH_GUARD_SIZE, fmt == 0 ? off_of(g, pt.p) : at,
                           "PLY: line %llu: element '%.*s' claims %llu instances of at least %llu bytes, %llu bytes "
                           "are left",
                           (unsigned long long)x->line, (int)(x->name.n > 32 ? 32 : x->name.n),
                           (const char*)x->name.s, (unsigned long long)x->count, (unsigned long long)min,
                           (unsigned long long)left);
        char kind[40];
        snprintf(kind, sizeof(kind), "element '%.*s'", (int)(x->name.n > 24 ? 24 : x->name.n), (const char*)x->name.s);
        for (uint64_t j = 0; j < x->count && r == MESO_OK; ++j) {
            char lb[96];
            uint64_t start = fmt == 0 ? off_of(g, pt.p) : at;
            const place pl_ = {kind, j, start}, *pl = &pl_;
            size_t n = 0;
            for (int p = 0; p < x->nprops && r == MESO_OK; ++p) {
                const ply_prop* pr = &x->props[p];
                double v;
                int64_t ii;
                if (!pr->is_list) {
                    r = ply_value(g, fmt, &pt, &at, pr->type, &v, &ii, pl);
                    if (r == MESO_OK && i == iv && ply_types[pr->type].is_float && !finite_float(v))
                        r = CORRUPT(g, MESO_MESH_GUARD_NONFINITE, start, "PLY: vertex %llu (byte %llu): property %d is not a finite float",
                                    (unsigned long long)j, (unsigned long long)start, p + 1);
                    continue;
                }
                if ((r = ply_value(g, fmt, &pt, &at, pr->list_type, &v, &ii, pl)) != MESO_OK)
                    break;
                uint64_t item = fmt == 0 ? 2 : ply_types[pr->type].size;
                uint64_t rest = fmt == 0 ? (uint64_t)(pt.end - pt.p) + 1 : (uint64_t)(g->size - at);
                if (ii < 0 || (uint64_t)ii > rest / item) {
                    r = CORRUPT(g, MESO_MESH_GUARD_SIZE, start, "PLY: %s: a list of %lld items, %llu bytes are left",
                                place_str(pl, lb), (long long)ii, (unsigned long long)rest);
                    break;
                }
                int face = i == jf && pr->role == 4;
                if (face && ii < 3) {
                    r = CORRUPT(g, MESO_MESH_GUARD_FACE_SIZE, start, "PLY: face %llu (byte %llu): %lld corners (needs 3)",
                                (unsigned long long)j, (unsigned long long)start, (long long)ii);
                    break;
                }
                for (int64_t q = 0; q < ii && r == MESO_OK; ++q) {
                    int64_t w = 0; /* set by ply_value on MESO_OK (gcc 12 -O3 cannot see it) */
                    r = ply_value(g, fmt, &pt, &at, pr->type, &v, &w, pl);
                    if (r != MESO_OK || !face)
                        continue;
                    if (w < 0 || (uint64_t)w >= nv)
                        r = CORRUPT(g, MESO_MESH_GUARD_INDEX_RANGE, start,
                                    "PLY: face %llu (byte %llu): corner %lld refers to vertex %lld (the file has %llu)",
                                    (unsigned long long)j, (unsigned long long)start, (long long)q + 1, (long long)w,
                                    (unsigned long long)nv);
                    else
                        r = push_corner(g, &corners, &n, &cap, (uint32_t)w);
                }
                if (r == MESO_OK && face) {
                    const place fpl = {"PLY: face", j, start};
                    r = face_check(g, corners, n, j, start, &fpl);
                    n = 0;
                }
            }
        }
    }
    free(corners);
    if (r != MESO_OK)
        return r;
    const uint8_t* q = fmt == 0 ? pt.p : g->base + at;
    for (; q < g->base + g->size; ++q)
        if (!is_space(*q) && *q != '\n')
            return CORRUPT(g, MESO_MESH_GUARD_TRAILING, off_of(g, q), "PLY: data after the last element (byte %llu)",
                           (unsigned long long)off_of(g, q));
    g->st.vertices = nv;
    return budget(g, nv, g->st.triangles, "PLY");
}

/* ---- STL ---------------------------------------------------------------- */

static float le_float(const uint8_t* p)
{
    uint32_t w = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &w, 4);
    return f;
}

static uint32_t le_u32(const uint8_t* p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static int same_point(const double* a, const double* b)
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

static meso_result stl_triangle(guard* g, const double c[9], uint64_t tri, uint64_t offset, const place* pl)
{
    char lb[96];
    for (int i = 0; i < 9; ++i)
        if (!finite_float(c[i]))
            return CORRUPT(g, MESO_MESH_GUARD_NONFINITE, offset, "STL: %s: corner %d has a non-finite coordinate",
                           place_str(pl, lb), i / 3 + 1);
    if (same_point(c, c + 3) || same_point(c + 3, c + 6) || same_point(c, c + 6))
        return CORRUPT(g, MESO_MESH_GUARD_REPEATED_CORNER, offset, "STL: %s: triangle %llu has two equal corners",
                       place_str(pl, lb), (unsigned long long)tri);
    g->st.faces++;
    g->st.triangles++;
    g->st.vertices += 3;
    return MESO_OK;
}

static meso_result check_stl(guard* g)
{
    if (g->size >= 84) {
        uint64_t n = le_u32(g->base + 80);
        if ((uint64_t)g->size == 84 + 50 * n) {
            if (n == 0)
                return CORRUPT(g, MESO_MESH_GUARD_EMPTY, 80, "STL: binary, 0 triangles");
            meso_result r = budget(g, 3 * n, n, "STL");
            for (uint64_t i = 0; i < n && r == MESO_OK; ++i) {
                const uint8_t* p = g->base + 84 + 50 * i + 12;
                double c[9];
                for (int k = 0; k < 9; ++k)
                    c[k] = (double)le_float(p + 4 * k);
                const place pl = {"triangle", i, 84 + 50 * i};
                r = stl_triangle(g, c, i, 84 + 50 * i, &pl);
            }
            return r;
        }
    }
    ply_text pt = {g->base, g->base + g->size, 0};
    tok t;
    if (!ply_token(&pt, &t) || !tok_is_nocase(t, "solid")) {
        if (g->size >= 84)
            return CORRUPT(g, MESO_MESH_GUARD_SIZE, 80,
                           "STL: neither binary (%zu bytes, but 84 + 50 x %u triangles = %llu) nor ASCII (no 'solid')",
                           g->size, le_u32(g->base + 80), (unsigned long long)(84 + 50 * (uint64_t)le_u32(g->base + 80)));
        return CORRUPT(g, MESO_MESH_GUARD_SIZE, 0, "STL: %zu bytes: neither binary (84 + 50 n) nor ASCII (no 'solid')",
                       g->size);
    }
    /* the name: the rest of the line */
    while (pt.p < pt.end && *pt.p != '\n')
        pt.p++;
    static const char* const facet_words[] = {"normal", "", "", "", "outer", "loop"};
    uint64_t tri = 0;
    for (;;) {
        if (!ply_token(&pt, &t))
            return CORRUPT(g, MESO_MESH_GUARD_STL_STRUCTURE, g->size, "STL: line %llu: the file ends before 'endsolid'",
                           (unsigned long long)pt.line + 1);
        if (tok_is_nocase(t, "endsolid"))
            break;
        char lb[96];
        const place pl_ = {"line", pt.line + 1, NO_BYTE}, *pl = &pl_;
        uint64_t start = off_of(g, t.s);
        if (!tok_is_nocase(t, "facet"))
            return CORRUPT(g, MESO_MESH_GUARD_STL_STRUCTURE, start, "STL: %s: expected 'facet' or 'endsolid'", place_str(pl, lb));
        double c[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
        for (int w = 0; w < 6 + 3 * 4 + 2; ++w) {
            if (!ply_token(&pt, &t))
                return CORRUPT(g, MESO_MESH_GUARD_STL_STRUCTURE, g->size, "STL: %s: the file ends inside the facet", place_str(pl, lb));
            const char* want = w < 6 ? facet_words[w] : w < 18 ? ((w - 6) % 4 == 0 ? "vertex" : "") : w == 18 ? "endloop" : "endfacet";
            if (want[0]) {
                if (!tok_is_nocase(t, want))
                    return CORRUPT(g, MESO_MESH_GUARD_STL_STRUCTURE, off_of(g, t.s),
                                   "STL: line %llu: expected '%s', found '%.*s'", (unsigned long long)pt.line + 1,
                                   want, (int)(t.n > 32 ? 32 : t.n), (const char*)t.s);
                continue;
            }
            double v;
            if (parse_number(t, &v) != 0)
                return CORRUPT(g, MESO_MESH_GUARD_NUMBER, off_of(g, t.s), "STL: line %llu: '%.*s' is not a number",
                               (unsigned long long)pt.line + 1, (int)(t.n > 32 ? 32 : t.n), (const char*)t.s);
            if (w >= 6)
                c[(w - 6) / 4 * 3 + (w - 6) % 4 - 1] = v;
        }
        meso_result r = stl_triangle(g, c, tri++, start, pl);
        if (r != MESO_OK)
            return r;
    }
    if (tri == 0)
        return CORRUPT(g, MESO_MESH_GUARD_EMPTY, 0, "STL: no facets");
    return budget(g, 3 * tri, tri, "STL");
}

/* ---- OM, DRC ------------------------------------------------------------ */

static meso_result check_om(guard* g)
{
    if (g->size < 16 || g->base[0] != 'O' || g->base[1] != 'M')
        return CORRUPT(g, MESO_MESH_GUARD_HEADER, 0, "OM: no 'OM' header");
    uint64_t nv = le_u32(g->base + 4), nf = le_u32(g->base + 8), ne = le_u32(g->base + 12);
    if (nv == 0 || nf == 0)
        return CORRUPT(g, MESO_MESH_GUARD_EMPTY, 4, "OM: %llu vertices and %llu faces", (unsigned long long)nv,
                       (unsigned long long)nf);
    uint64_t left = g->size - 16;
    if (nv > left / 12 || nf > left || ne > left)
        return CORRUPT(g, MESO_MESH_GUARD_SIZE, 4,
                       "OM: the header claims %llu vertices, %llu faces and %llu edges, %llu bytes follow",
                       (unsigned long long)nv, (unsigned long long)nf, (unsigned long long)ne,
                       (unsigned long long)left);
    g->st.vertices = nv;
    g->st.faces = nf;
    g->st.triangles = nf;
    return budget(g, nv, nf, "OM");
}

static meso_result check_drc(guard* g)
{
    if (g->size < 5 || memcmp(g->base, "DRACO", 5) != 0)
        return CORRUPT(g, MESO_MESH_GUARD_HEADER, 0, "DRC: no 'DRACO' header");
    if ((uint64_t)g->size > g->max_bytes / MESO_MESH_GUARD_DRACO_EXPANSION)
        return CORRUPT(g, MESO_MESH_GUARD_BUDGET, 0,
                       "DRC: %zu bytes may decode to more than the %.3g MB allowed (%u x the file size; raise it with "
                       "--max-memory SIZE)", g->size,
                       (double)g->max_bytes / 1e6, MESO_MESH_GUARD_DRACO_EXPANSION);
    return MESO_OK;
}

/* ---- entry points ------------------------------------------------------- */

static const char* const format_ext[] = {"", ".obj", ".off", ".ply", ".stl", ".om", ".drc"};

meso_mesh_format meso_mesh_format_from_path(const char* path)
{
    size_t n = strlen(path);
    for (int f = MESO_MESH_FORMAT_OBJ; f <= MESO_MESH_FORMAT_DRC; ++f) {
        size_t m = strlen(format_ext[f]);
        if (n >= m && tok_is_nocase((tok){(const uint8_t*)path + n - m, m}, format_ext[f]))
            return (meso_mesh_format)f;
    }
    return MESO_MESH_FORMAT_UNKNOWN;
}

const char* meso_mesh_format_name(meso_mesh_format format)
{
    static const char* const names[] = {"unknown", "OBJ", "OFF", "PLY", "STL", "OM", "DRC"};
    return (unsigned)format <= MESO_MESH_FORMAT_DRC ? names[format] : names[0];
}

meso_result meso_mesh_guard_check(meso_mesh_format format, const uint8_t* data, size_t size, uint64_t max_bytes,
                                  meso_mesh_guard_stats* stats, meso_error* err)
{
    guard g;
    memset(&g, 0, sizeof(g));
    g.err = err;
    g.base = data;
    g.size = size;
    g.max_bytes = max_bytes ? max_bytes : MESO_MESH_GUARD_DEFAULT_MAX_BYTES;
    g.where_word = format == MESO_MESH_FORMAT_PLY ? "face" : "line";
    if (stats)
        memset(stats, 0, sizeof(*stats));
    if ((uint64_t)size > g.max_bytes)
        return CORRUPT(&g, MESO_MESH_GUARD_BUDGET, 0, "%zu bytes: larger than the %.3g MB allowed (raise it with --max-memory SIZE)", size,
                       (double)g.max_bytes / 1e6);
    if (size == 0)
        return CORRUPT(&g, MESO_MESH_GUARD_EMPTY, 0, "%s: empty file", meso_mesh_format_name(format));
    meso_result r;
    switch (format) {
    case MESO_MESH_FORMAT_OBJ: r = check_obj(&g); break;
    case MESO_MESH_FORMAT_OFF: r = check_off(&g); break;
    case MESO_MESH_FORMAT_PLY: r = check_ply(&g); break;
    case MESO_MESH_FORMAT_STL: r = check_stl(&g); break;
    case MESO_MESH_FORMAT_OM: r = check_om(&g); break;
    case MESO_MESH_FORMAT_DRC: r = check_drc(&g); break;
    default:
        r = CORRUPT(&g, MESO_MESH_GUARD_EXTENSION, 0, "unknown mesh format (expected .obj .off .ply .stl .om .drc)");
        break;
    }
    free(g.edges.slots);
    free(g.sorted);
    if (stats)
        *stats = g.st;
    return r;
}

meso_result meso_mesh_guard_check_file(const char* path, uint64_t max_bytes, meso_mesh_guard_stats* stats,
                                       meso_error* err)
{
    if (stats)
        memset(stats, 0, sizeof(*stats));
    uint64_t limit = max_bytes ? max_bytes : MESO_MESH_GUARD_DEFAULT_MAX_BYTES;
    meso_mesh_format format = meso_mesh_format_from_path(path);
    if (format == MESO_MESH_FORMAT_UNKNOWN)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_MESH_GUARD_EXTENSION,
                              "%s: unknown mesh extension (expected .obj .off .ply .stl .om .drc)", path);
    FILE* f = fopen(path, "rb");
    if (!f)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", path, strerror(errno));
    long n = -1;
    if (fseek(f, 0, SEEK_END) == 0)
        n = ftell(f);
    if (n < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: not a regular file", path);
    }
    if ((uint64_t)n > limit) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_MESH_GUARD_BUDGET,
                              "%s: %ld bytes: larger than the %.3g MB allowed (raise it with --max-memory SIZE)",
                              path, n, (double)limit / 1e6);
    }
    uint8_t* buf = malloc(n ? (size_t)n : 1);
    if (!buf) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", path);
    }
    size_t got = fread(buf, 1, (size_t)n, f);
    fclose(f);
    if (got != (size_t)n) {
        free(buf);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: read failed", path);
    }
    meso_error local;
    memset(&local, 0, sizeof(local));
    meso_result r = meso_mesh_guard_check(format, buf, (size_t)n, limit, stats, &local);
    free(buf);
    if (r != MESO_OK) {
        meso_bake_fail(err, r, local.code, "%s: %s", path, local.message);
        if (err)
            err->offset = local.offset;
    }
    return r;
}
