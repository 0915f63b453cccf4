/*
 * skeleton_swc.c — the SWC reader (skeleton_swc.h).
 *
 * Two passes: lines → nodes (fields checked one by one), then ids → indices
 * (a sorted id table, so ids may be sparse, unsorted and forward-referenced),
 * duplicate ids, unknown parents, cycles (every chain of parents must reach
 * a root), and the child lists. Tokens are copied into a small local buffer
 * before strtod/strtoll, so the input never needs a terminating NUL.
 */
#include "skeleton_swc.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meso_bake.h"

#define SWC_FIELDS 7
#define TOKEN_MAX 63 /* longer tokens are not numbers we accept */

static const char* const field_names[SWC_FIELDS] = {"id", "type", "x", "y", "z", "radius", "parent"};

typedef struct token {
    const char* p;
    size_t n;
} token;

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* Copies a token for printing in a message: at most 24 characters, and
 * non-printable bytes as '?'. */
static void token_show(token t, char* buf, size_t size)
{
    size_t n = t.n < 24 ? t.n : 24, k;
    for (k = 0; k < n && k + 1 < size; ++k) {
        unsigned char c = (unsigned char)t.p[k];
        buf[k] = (c >= 32 && c < 127) ? (char)c : '?';
    }
    buf[k] = '\0';
    if (t.n > n && k + 4 < size)
        memcpy(buf + k, "...", 4);
}

/* The token as a C string in buf; 0 when empty or too long to be a number. */
static int token_cstr(token t, char buf[TOKEN_MAX + 1])
{
    if (t.n == 0 || t.n > TOKEN_MAX)
        return 0;
    memcpy(buf, t.p, t.n);
    buf[t.n] = '\0';
    return 1;
}

/* 1 when the whole token is an integer in int64 range. */
static int parse_int(token t, int64_t* v)
{
    char buf[TOKEN_MAX + 1];
    if (!token_cstr(t, buf))
        return 0;
    char* end = NULL;
    errno = 0;
    long long x = strtoll(buf, &end, 10);
    if (errno != 0 || end != buf + t.n)
        return 0;
    *v = (int64_t)x;
    return 1;
}

/* 1 when the whole token is a number (strtod syntax, which admits "nan" and
 * "inf": the caller checks finiteness separately to say so). */
static int parse_double(token t, double* v)
{
    char buf[TOKEN_MAX + 1];
    if (!token_cstr(t, buf))
        return 0;
    char* end = NULL;
    double x = strtod(buf, &end);
    if (end != buf + t.n)
        return 0;
    *v = x;
    return 1;
}

typedef struct id_entry {
    int64_t id;
    uint32_t index;
} id_entry;

static int id_cmp(const void* a, const void* b)
{
    const id_entry* x = a;
    const id_entry* y = b;
    if (x->id != y->id)
        return x->id < y->id ? -1 : 1;
    return x->index < y->index ? -1 : (x->index > y->index);
}

static int64_t find_id(const id_entry* tab, uint32_t n, int64_t id)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (tab[mid].id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return (lo < n && tab[lo].id == id) ? (int64_t)tab[lo].index : -1;
}

static meso_result out_of_range(meso_error* err, const char* what, uint32_t line, const char* field, double v)
{
    return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_OUT_OF_RANGE,
        "%s line %u: %s %.9g is beyond +-%g (not a skeleton in any sensible unit)", what, line, field, v,
        MESO_SKEL_MAX_COORD);
}

/* Parses one line's tokens into a node, or fails naming the line. */
static meso_result parse_node(const token* tok, uint32_t ntok, uint32_t line, meso_skeleton_node* nd, int64_t* parent_id,
    meso_error* err)
{
    char show[32];
    if (ntok != SWC_FIELDS)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_FIELD_COUNT,
            "swc line %u: %u fields, expected 7 (id type x y z radius parent)", line, ntok);
    int64_t iv[3];
    const int int_field[3] = {0, 1, 6};
    for (int k = 0; k < 3; ++k) {
        if (!parse_int(tok[int_field[k]], &iv[k])) {
            token_show(tok[int_field[k]], show, sizeof(show));
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NOT_A_NUMBER,
                "swc line %u: %s '%s' is not an integer", line, field_names[int_field[k]], show);
        }
    }
    if (iv[1] < INT32_MIN || iv[1] > INT32_MAX)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NOT_A_NUMBER,
            "swc line %u: type %lld is out of range", line, (long long)iv[1]);
    double dv[4];
    for (int k = 0; k < 4; ++k) {
        if (!parse_double(tok[2 + k], &dv[k])) {
            token_show(tok[2 + k], show, sizeof(show));
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NOT_A_NUMBER,
                "swc line %u: %s '%s' is not a number", line, field_names[2 + k], show);
        }
        if (!isfinite(dv[k])) {
            token_show(tok[2 + k], show, sizeof(show));
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NON_FINITE,
                "swc line %u: %s '%s' is not finite", line, field_names[2 + k], show);
        }
        if (fabs(dv[k]) > MESO_SKEL_MAX_COORD)
            return out_of_range(err, "swc", line, field_names[2 + k], dv[k]);
    }
    if (dv[3] < 0.0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NEGATIVE_RADIUS,
            "swc line %u: negative radius %g", line, dv[3]);
    if (iv[2] < 0 && iv[2] != -1)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_UNKNOWN_PARENT,
            "swc line %u: parent %lld (a root's parent is -1)", line, (long long)iv[2]);
    memset(nd, 0, sizeof(*nd));
    nd->id = iv[0];
    nd->type = (int32_t)iv[1];
    nd->line = line;
    nd->pos[0] = dv[0];
    nd->pos[1] = dv[1];
    nd->pos[2] = dv[2];
    nd->radius = dv[3];
    nd->parent = -1;
    *parent_id = iv[2];
    return MESO_OK;
}

/* The `twist=` token of a text-format line, if any: removed from tok[]
 * (the rest keep their order), its value in degrees in *deg. */
static meso_result take_twist(token* tok, uint32_t* ntok, uint32_t line, int* has, double* deg, meso_error* err)
{
    static const char key[] = "twist=";
    const size_t kn = sizeof(key) - 1;
    char show[32];
    uint32_t kept = 0;
    *has = 0;
    for (uint32_t k = 0; k < *ntok; ++k) {
        token t = tok[k];
        if (t.n < kn || memcmp(t.p, key, kn) != 0) {
            tok[kept++] = t;
            continue;
        }
        token v = {t.p + kn, t.n - kn};
        token_show(t, show, sizeof(show));
        if (*has)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_TWIST,
                "skeleton line %u: a second twist field '%s' (one per line)", line, show);
        if (!parse_double(v, deg))
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_TWIST,
                "skeleton line %u: '%s' is not twist=DEG (DEG a number of degrees)", line, show);
        if (!isfinite(*deg) || fabs(*deg) > MESO_SKEL_MAX_TWIST_DEG)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_TWIST,
                "skeleton line %u: twist '%s' is not a finite angle within +-%g degrees (1000 turns)", line, show,
                MESO_SKEL_MAX_TWIST_DEG);
        *has = 1;
    }
    *ntok = kept;
    return MESO_OK;
}

/* One line of the text skeleton format (skeleton_swc.h): x y z radius
 * [parent] [twist=DEG]. `index` is the node's 0-based index; ids are
 * index + 1. `tok` may be reordered. */
static meso_result parse_text_node(token* tok, uint32_t ntok, uint32_t line, uint32_t index, meso_skeleton_node* nd,
    int64_t* parent_id, meso_error* err)
{
    static const char* const names[4] = {"x", "y", "z", "radius"};
    char show[32];
    int has_twist = 0;
    double twist = 0;
    if (ntok > SWC_FIELDS + 1) /* more than tok[] holds: too many whatever they are */
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_FIELD_COUNT,
            "skeleton line %u: %u fields, expected 4 or 5 (x y z radius [parent], and optionally twist=DEG)", line,
            ntok);
    meso_result r = take_twist(tok, &ntok, line, &has_twist, &twist, err);
    if (r != MESO_OK)
        return r;
    if (ntok != 4 && ntok != 5)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_FIELD_COUNT,
            "skeleton line %u: %u fields, expected 4 or 5 (x y z radius [parent], and optionally twist=DEG)", line,
            ntok);
    double dv[4];
    for (int k = 0; k < 4; ++k) {
        if (!parse_double(tok[k], &dv[k])) {
            token_show(tok[k], show, sizeof(show));
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NOT_A_NUMBER,
                "skeleton line %u: %s '%s' is not a number", line, names[k], show);
        }
        if (!isfinite(dv[k])) {
            token_show(tok[k], show, sizeof(show));
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NON_FINITE,
                "skeleton line %u: %s '%s' is not finite", line, names[k], show);
        }
        if (fabs(dv[k]) > MESO_SKEL_MAX_COORD)
            return out_of_range(err, "skeleton", line, names[k], dv[k]);
    }
    if (dv[3] < 0.0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NEGATIVE_RADIUS,
            "skeleton line %u: negative radius %g", line, dv[3]);
    int64_t parent = index; /* the previous node (1-based id = index) */
    if (ntok == 5) {
        if (!parse_int(tok[4], &parent)) {
            token_show(tok[4], show, sizeof(show));
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NOT_A_NUMBER,
                "skeleton line %u: parent '%s' is not an integer", line, show);
        }
        if (parent < 0)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_UNKNOWN_PARENT,
                "skeleton line %u: parent %lld (0 starts a new tree, k > 0 is the k-th node)", line, (long long)parent);
    }
    if (has_twist && parent == 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_TWIST,
            "skeleton line %u: twist on a root node (a twist belongs to the segment from the node's parent)", line);
    memset(nd, 0, sizeof(*nd));
    nd->id = (int64_t)index + 1;
    nd->line = line;
    for (int k = 0; k < 3; ++k)
        nd->pos[k] = dv[k];
    nd->radius = dv[3];
    nd->twist_deg = twist;
    nd->has_twist = has_twist;
    nd->parent = -1;
    *parent_id = parent == 0 ? -1 : parent;
    return MESO_OK;
}

/* Resolves parents, checks ids and cycles, builds child lists. */
static meso_result link_nodes(meso_skeleton* s, const int64_t* parent_id, meso_error* err)
{
    uint32_t n = s->node_count;
    id_entry* tab = malloc((size_t)n * sizeof(*tab));
    uint8_t* state = calloc(n, 1);
    uint32_t* stack = malloc((size_t)n * sizeof(*stack));
    uint32_t* fill = calloc(n, sizeof(*fill));
    s->children = malloc((size_t)(n ? n : 1) * sizeof(*s->children));
    meso_result r = MESO_OK;
    if (!tab || !state || !stack || !fill || !s->children) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "swc: out of memory (%u nodes)", n);
        goto done;
    }
    for (uint32_t i = 0; i < n; ++i) {
        tab[i].id = s->nodes[i].id;
        tab[i].index = i;
    }
    qsort(tab, n, sizeof(*tab), id_cmp);
    for (uint32_t i = 1; i < n; ++i) {
        if (tab[i].id == tab[i - 1].id) {
            const meso_skeleton_node* a = &s->nodes[tab[i - 1].index];
            const meso_skeleton_node* b = &s->nodes[tab[i].index];
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_DUPLICATE_ID,
                "swc line %u: id %lld is already defined on line %u", b->line, (long long)b->id, a->line);
            goto done;
        }
    }
    s->root_count = 0;
    for (uint32_t i = 0; i < n; ++i) {
        meso_skeleton_node* nd = &s->nodes[i];
        if (parent_id[i] == -1) {
            ++s->root_count;
            continue;
        }
        int64_t p = find_id(tab, n, parent_id[i]);
        if (p < 0) {
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_UNKNOWN_PARENT,
                "swc line %u: parent %lld of node %lld is not defined", nd->line, (long long)parent_id[i],
                (long long)nd->id);
            goto done;
        }
        nd->parent = (int32_t)p;
        s->nodes[p].child_count++;
    }
    /* Cycles: walk up from every unvisited node; state 1 = on the current
     * walk, 2 = known to reach a root. Meeting a 1 closes a cycle. */
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t depth = 0, j = i;
        while (state[j] == 0) {
            state[j] = 1;
            stack[depth++] = j;
            if (s->nodes[j].parent < 0)
                break;
            j = (uint32_t)s->nodes[j].parent;
        }
        if (state[j] == 1 && s->nodes[j].parent >= 0) {
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_CYCLE,
                "swc line %u: node %lld is its own ancestor (the parent links form a cycle)", s->nodes[j].line,
                (long long)s->nodes[j].id);
            goto done;
        }
        for (uint32_t k = 0; k < depth; ++k)
            state[stack[k]] = 2;
    }
    uint32_t off = 0;
    for (uint32_t i = 0; i < n; ++i) {
        s->nodes[i].first_child = off;
        off += s->nodes[i].child_count;
    }
    for (uint32_t i = 0; i < n; ++i) {
        int32_t p = s->nodes[i].parent;
        if (p >= 0)
            s->children[s->nodes[p].first_child + fill[p]++] = i;
    }
done:
    free(tab);
    free(state);
    free(stack);
    free(fill);
    return r;
}

void meso_skeleton_group_children(meso_skeleton* s, uint32_t* count)
{
    const uint32_t n = s->node_count;
    memset(count, 0, sizeof(uint32_t) * n);
    for (uint32_t i = 0; i < n; ++i)
        if (s->nodes[i].parent >= 0)
            count[s->nodes[i].parent]++;
    uint32_t first = 0;
    for (uint32_t i = 0; i < n; ++i) {
        s->nodes[i].first_child = first;
        s->nodes[i].child_count = 0;
        first += count[i];
    }
    for (uint32_t i = 0; i < n; ++i) {
        const int32_t p = s->nodes[i].parent;
        if (p >= 0) {
            meso_skeleton_node* pn = &s->nodes[p];
            s->children[pn->first_child + pn->child_count++] = i;
        }
    }
}

meso_result meso_skeleton_parse(const char* text, size_t len, meso_skeleton_format fmt, meso_skeleton* out,
    meso_error* err)
{
    if (!out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "swc: out is NULL");
    memset(out, 0, sizeof(*out));
    if (!text && len > 0)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "swc: text is NULL");
    meso_skeleton s = {0};
    int64_t* parent_id = NULL;
    uint32_t cap = 0;
    uint32_t line = 0;
    meso_result r = MESO_OK;
    size_t pos = 0;
    while (pos < len) {
        size_t start = pos;
        while (pos < len && text[pos] != '\n' && text[pos] != '\r')
            ++pos;
        size_t end = pos;
        if (pos < len) { /* \n, \r or \r\n */
            if (text[pos] == '\r' && pos + 1 < len && text[pos + 1] == '\n')
                ++pos;
            ++pos;
        }
        if (line == UINT32_MAX) {
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_UNREADABLE, "swc: too many lines");
            goto fail;
        }
        ++line;
        for (size_t k = start; k < end; ++k)
            if (text[k] == '#') {
                end = k;
                break;
            }
        token tok[SWC_FIELDS + 1];
        uint32_t ntok = 0, ntotal = 0;
        size_t k = start;
        for (;;) {
            while (k < end && is_space(text[k]))
                ++k;
            if (k >= end)
                break;
            size_t b = k;
            while (k < end && !is_space(text[k]))
                ++k;
            if (ntok < SWC_FIELDS + 1)
                tok[ntok++] = (token){text + b, k - b};
            ++ntotal;
        }
        if (ntotal == 0)
            continue;
        if (s.node_count == cap) {
            if (cap >= MESO_SKEL_MAX_NODES) {
                r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_UNREADABLE,
                    "swc line %u: more than %u nodes", line, MESO_SKEL_MAX_NODES);
                goto fail;
            }
            uint32_t ncap = cap ? cap * 2 : 64;
            meso_skeleton_node* nn = realloc(s.nodes, (size_t)ncap * sizeof(*nn));
            if (nn)
                s.nodes = nn;
            int64_t* np = realloc(parent_id, (size_t)ncap * sizeof(*np));
            if (np)
                parent_id = np;
            if (!nn || !np) {
                r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "swc: out of memory at line %u", line);
                goto fail;
            }
            cap = ncap;
        }
        r = fmt == MESO_SKELETON_TEXT
                ? parse_text_node(tok, ntotal, line, s.node_count, &s.nodes[s.node_count], &parent_id[s.node_count], err)
                : parse_node(tok, ntotal, line, &s.nodes[s.node_count], &parent_id[s.node_count], err);
        if (r != MESO_OK)
            goto fail;
        ++s.node_count;
    }
    if (s.node_count == 0) {
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_EMPTY, "swc: no node in the input (%u lines)", line);
        goto fail;
    }
    r = link_nodes(&s, parent_id, err);
    if (r != MESO_OK)
        goto fail;
    free(parent_id);
    *out = s;
    return MESO_OK;
fail:
    free(parent_id);
    meso_skeleton_free(&s);
    return r;
}

meso_result meso_skeleton_parse_swc(const char* text, size_t len, meso_skeleton* out, meso_error* err)
{
    return meso_skeleton_parse(text, len, MESO_SKELETON_SWC, out, err);
}

meso_result meso_skeleton_load_swc(const char* path, meso_skeleton* out, meso_error* err)
{
    return meso_skeleton_load(path, MESO_SKELETON_SWC, out, err);
}

meso_result meso_skeleton_load(const char* path, meso_skeleton_format fmt, meso_skeleton* out, meso_error* err)
{
    if (out)
        memset(out, 0, sizeof(*out));
    if (!path || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "swc: path or out is NULL");
    FILE* f = fopen(path, "rb");
    if (!f)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_SKEL_ISSUE_UNREADABLE, "swc: can't open '%s': %s", path,
            strerror(errno));
    char* buf = NULL;
    size_t len = 0, cap = 0;
    meso_result r = MESO_OK;
    for (;;) {
        if (len == cap) {
            if (cap >= ((size_t)1 << 31)) {
                r = meso_bake_fail(err, MESO_ERR_IO, MESO_SKEL_ISSUE_UNREADABLE, "swc: '%s' is larger than 2 GiB", path);
                break;
            }
            size_t ncap = cap ? cap * 2 : 65536;
            char* nb = realloc(buf, ncap);
            if (!nb) {
                r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "swc: out of memory reading '%s'", path);
                break;
            }
            buf = nb;
            cap = ncap;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0) {
            if (ferror(f))
                r = meso_bake_fail(err, MESO_ERR_IO, MESO_SKEL_ISSUE_UNREADABLE, "swc: read error on '%s'", path);
            break;
        }
    }
    fclose(f);
    if (r == MESO_OK)
        r = meso_skeleton_parse(buf, len, fmt, out, err);
    free(buf);
    return r;
}

meso_result meso_skeleton_require_drawable(const meso_skeleton* s, meso_error* err)
{
    if (!s || s->node_count == 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_EMPTY, "skeleton: no node");
    int any_segment = 0, any_radius = 0;
    for (uint32_t i = 0; i < s->node_count; ++i) {
        const meso_skeleton_node* n = &s->nodes[i];
        any_radius |= n->radius > 0;
        if (n->parent < 0)
            continue;
        any_segment = 1;
        const meso_skeleton_node* p = &s->nodes[n->parent];
        const int long_enough = n->pos[0] != p->pos[0] || n->pos[1] != p->pos[1] || n->pos[2] != p->pos[2];
        if (long_enough && (n->radius > 0 || p->radius > 0))
            return MESO_OK;
    }
    const uint32_t last = s->nodes[s->node_count - 1].line;
    if (!any_segment && s->node_count == 1)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NO_SEGMENT,
            "skeleton: one node (line %u) and no segment: nothing to skin", last);
    if (!any_segment)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NO_SEGMENT,
            "skeleton: %u nodes (lines 1-%u), every one a root: no segment, nothing to skin", s->node_count, last);
    if (!any_radius)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NO_RADIUS,
            "skeleton: every radius is 0 (%u nodes, lines 1-%u): the skin would have no surface", s->node_count, last);
    return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKEL_ISSUE_NO_SURFACE,
        "skeleton: no segment has both a length and a radius (%u nodes, lines 1-%u): the skin would have no surface",
        s->node_count, last);
}

void meso_skeleton_free(meso_skeleton* s)
{
    if (!s)
        return;
    free(s->nodes);
    free(s->children);
    memset(s, 0, sizeof(*s));
}
