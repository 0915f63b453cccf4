/*
 * shell_update.c — see shell_update.h.
 *
 * The paper (§6, "Deformations") recomputes "only the part which is within
 * the field influence distance from the modified surface part". What that
 * distance is, decided here:
 *
 *  - Moved vertices: those whose position differs bit for bit from OLD's;
 *    changed faces: those with a moved corner, at their old and new
 *    positions (a box around both).
 *  - A director is traced from its vertex for at most h (the side's
 *    thickness), so every field evaluation of vertex v is within h of v;
 *    the paper localises the field to the surface within 2h of the point
 *    (§4, "Localization"). So a director can change only if its vertex is
 *    within 3h of a changed face. meso's field sums the far surface too
 *    (Barnes-Hut, θ = 0.5), so beyond 3h a director still changes, by the
 *    far field of the edit: tests/integration/test_shell_update.c measures that
 *    change against a full re-bake of the edited mesh (it is far below the
 *    integration's own step error).
 *  - The exact checks: a clean face's offset triangle (corners within h of
 *    its base corners, so edges up to L + 2h for the longest mesh edge L)
 *    can meet a changed face's base only if one of its base corners is
 *    within h + (L + 2h) = 3h + L of it. That is R, the same radius: the
 *    region needs no more. It assumes |d| <= h for OLD's directors, which
 *    mesobake's bakes keep (a hand-made OLD that breaks it can only make the
 *    rounds miss a pair, which the final validation then reports, exit 8).
 *    Inside R = 3h + L every vertex is recomputed (normal displacement,
 *    hybrid rounds, repair, regrow) and every face with a recomputed corner
 *    is re-checked; outside, OLD's directors and OLD's verdicts (valid: an
 *    OLD with defects is refused) are kept (meso_shell_checker_prime).
 *  - The final validation (mesoi_shell_update_validate), decided in issue
 *    15 when it was the largest fixed cost of an update (0.23 of
 *    armadillo's 0.62 s at 2 %, a 1 % edit): every prism and the thickness
 *    ratio as always (O(n), cheap), but the exact intersection tests only
 *    of the faces D with a recomputed corner — self pairs with a face in D,
 *    (offset, base) pairs whose offset face is in D. That is the whole
 *    shell's count: a face outside D has no recomputed corner, so neither
 *    moved corners nor new directors: its base and offset triangles are
 *    OLD's, bit for bit. A pair of two such faces (self, or offset/base
 *    where the base face has no moved corner either) is a pair of OLD's,
 *    and OLD is valid (its report is checked, E3119). What is left is an
 *    offset triangle outside D against a base triangle that moved: each
 *    point of that offset triangle is within dmax (its corners' longest
 *    director) of its base triangle, whose points are within L of each of
 *    its corners, so the pair can meet only if a corner lies within
 *    dmax + L of the moved triangle — inside its box grown by R when
 *    dmax + L < R, i.e. recomputed: the face is in D after all. dmax over
 *    the kept directors is measured (O(n)) rather than assumed (<= h, which
 *    mesobake's bakes keep); if the inequality fails, or for envelopes
 *    (their validated "base" is the bottom layer, which moves wherever a
 *    director was recomputed) or without CGAL, the whole shell is
 *    validated as before. tests/integration/test_shell_update.c compares
 *    the counts with meso_shell_validate of the written shell on every
 *    update, including an edit that folds and intersects the shell.
 *  - The base's self-intersection test (E3114) likewise tests only the
 *    pairs with a moved face (mesoi_shell_update_base_check): the other
 *    pairs are OLD's base, which its bake tested (every mesobake shell
 *    does with CGAL; an OLD whose report lacks zero intersection counts is
 *    refused, E3119).
 *
 *  - Growth (issue 15): repair and regrow may change only recomputed
 *    directors. When the rounds end with a bad face (an inverted or
 *    undecided prism, or an offset triangle meeting another or the base)
 *    that has a kept corner, the fix may need that corner's director, which
 *    the update may not touch (spot at 2 %, a 10 % edit: one prism left
 *    inverted after repair's rounds, its other corners OLD's). Then the
 *    region grows by those faces' corners and their 1-ring (every corner of
 *    every face around them), and the side's rounds run again from the
 *    start over the grown region, at most MESOI_SHELL_UPDATE_GROWTH_PASSES
 *    times; if bad faces with kept corners are still left, every vertex is
 *    recomputed, exactly as a full bake does (the rounds without a region),
 *    so the update is valid whenever the full bake is. The 1-ring rather
 *    than everything within R of the bad faces: R = 3h + L covers most of a
 *    small mesh at 5 % (spot), so one growth by R would be about a full
 *    bake; the 1-ring is the least that lets repair shorten every director
 *    of the bad faces and of the faces sharing a corner with them (which
 *    the shortening can fold in turn), and a further pass grows again when
 *    that is not enough. Growing keeps both arguments above: the region
 *    only gains vertices, so it still holds everything within R of the
 *    edit, and kept directors only become fewer. vertices_recomputed
 *    counts the grown region.
 *
 * Region search: a uniform grid of the vertices (cells at least R), each
 * changed face's box grown by R looked up in it: O(vertices + changed faces
 * x the vertices near them).
 */
#include "shell_update.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "adapters.h"
#include "bake_threads.h"

void mesoi_shell_prior_free(mesoi_shell_prior* p)
{
    for (uint32_t k = 0; k < p->chain_count; ++k)
        free(p->chain_chunk[k].data);
    free(p->d);
    free(p->redo);
    free(p->moved_at);
    memset(p, 0, sizeof(*p));
}

/* A number of META.parameters, NaN when absent. */
static double param_number(const cJSON* params, const char* key)
{
    const cJSON* j = cJSON_GetObjectItemCaseSensitive(params, key);
    return cJSON_IsNumber(j) ? j->valuedouble : NAN;
}

static const char* param_string(const cJSON* params, const char* key)
{
    const cJSON* j = cJSON_GetObjectItemCaseSensitive(params, key);
    return cJSON_IsString(j) ? j->valuestring : "";
}

/* E3117 naming the first parameter of OLD that differs from this bake's. */
static meso_result check_parameters(const char* path, const cJSON* params, const meso_bake_shell_options* a,
                                    double h, meso_error* err)
{
    char old[64] = "", now[64] = "";
    const char* what = NULL;
    const cJSON* repair = cJSON_GetObjectItemCaseSensitive(params, "repair");
    if (strcmp(param_string(params, "kind"), meso_bake_shell_kind_name(a->kind)) != 0) {
        what = "--kind";
        snprintf(old, sizeof(old), "%s", param_string(params, "kind"));
        snprintf(now, sizeof(now), "%s", meso_bake_shell_kind_name(a->kind));
    } else if (strcmp(param_string(params, "directors"), meso_bake_directors_name(a->directors)) != 0) {
        what = "--directors";
        snprintf(old, sizeof(old), "%s", param_string(params, "directors"));
        snprintf(now, sizeof(now), "%s", meso_bake_directors_name(a->directors));
    } else if (!cJSON_IsBool(repair) || cJSON_IsTrue(repair) != !a->no_repair) {
        what = "--no-repair";
        snprintf(old, sizeof(old), "%s", cJSON_IsTrue(repair) ? "repair" : "no repair");
        snprintf(now, sizeof(now), "%s", a->no_repair ? "no repair" : "repair");
    } else {
        const struct {
            const char* key;
            const char* option;
            double value;
        } num[] = {{"p", "--p", a->p},
                   {"theta", "--theta", a->theta},
                   {"angle_tol_deg", "--angle-tol", a->angle_tol_deg},
                   {"smooth", "--smooth", (double)a->smooth},
                   {"thickness", "--thickness", h}};
        for (size_t i = 0; i < sizeof(num) / sizeof(num[0]) && !what; ++i) {
            const double v = param_number(params, num[i].key);
            if (!(fabs(v - num[i].value) <= 1e-9 * fmax(1.0, fabs(v)))) {
                what = num[i].option;
                snprintf(old, sizeof(old), "%.17g", v);
                snprintf(now, sizeof(now), "%.17g", num[i].value);
            }
        }
    }
    if (!what)
        return MESO_OK;
    return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 3117,
                          "%s: baked with %s %s, this update asks for %s: an update keeps the bake's parameters "
                          "(give %s %s, or bake in full)",
                          mesoi_base_name(path), what, old, now, what, old);
}

/* The longest edge of m. */
static double longest_edge(const meso_mesh* m)
{
    double best = 0;
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; ++i) {
        const float* a = m->positions + 3 * (size_t)m->indices[i];
        const float* b = m->positions + 3 * (size_t)m->indices[i - i % 3 + (i + 1) % 3];
        double l = 0;
        for (int k = 0; k < 3; ++k)
            l += ((double)a[k] - b[k]) * ((double)a[k] - b[k]);
        best = fmax(best, l);
    }
    return sqrt(best);
}

/* redo[v] = 1 for every vertex inside the box of a changed face (old and new
 * corners) grown by R. */
static meso_result grow_region(const meso_mesh* m, const float* old_pos, const uint8_t* moved, double R,
                               uint8_t* redo, meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < 3 * (size_t)nv; ++i) {
        lo[i % 3] = fmin(lo[i % 3], m->positions[i]);
        hi[i % 3] = fmax(hi[i % 3], m->positions[i]);
    }
    int n[3];
    double cell[3];
    size_t cells = 1;
    for (int k = 0; k < 3; ++k) {
        const double ext = hi[k] - lo[k];
        n[k] = ext > 0 && R > 0 ? (int)fmin(128.0, fmax(1.0, floor(ext / R))) : 1;
        cell[k] = ext > 0 ? ext / n[k] : 1.0;
        cells *= (size_t)n[k];
    }
    uint32_t* first = calloc(cells + 1, sizeof(uint32_t));
    uint32_t* order = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    uint32_t* fill = malloc(sizeof(uint32_t) * (cells + 1));
    if (!first || !order || !fill) {
        free(first), free(order), free(fill);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
    }
#define CELL_OF(p, k) ((int)fmin(n[k] - 1, fmax(0.0, floor(((p) - lo[k]) / cell[k]))))
    for (uint32_t v = 0; v < nv; ++v) {
        const float* p = m->positions + 3 * (size_t)v;
        const size_t c = (size_t)CELL_OF(p[0], 0) + (size_t)n[0] * ((size_t)CELL_OF(p[1], 1) + (size_t)n[1] * (size_t)CELL_OF(p[2], 2));
        first[c + 1]++;
    }
    for (size_t c = 0; c < cells; ++c)
        first[c + 1] += first[c];
    memcpy(fill, first, sizeof(uint32_t) * (cells + 1));
    for (uint32_t v = 0; v < nv; ++v) {
        const float* p = m->positions + 3 * (size_t)v;
        const size_t c = (size_t)CELL_OF(p[0], 0) + (size_t)n[0] * ((size_t)CELL_OF(p[1], 1) + (size_t)n[1] * (size_t)CELL_OF(p[2], 2));
        order[fill[c]++] = v;
    }
    for (uint32_t f = 0; f < nt; ++f) {
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        if (!moved[ix[0]] && !moved[ix[1]] && !moved[ix[2]])
            continue;
        double blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) {
                const double a = m->positions[3 * (size_t)ix[c] + k], b = old_pos[3 * (size_t)ix[c] + k];
                blo[k] = fmin(blo[k], fmin(a, b) - R);
                bhi[k] = fmax(bhi[k], fmax(a, b) + R);
            }
        int c0[3], c1[3];
        for (int k = 0; k < 3; ++k) {
            c0[k] = CELL_OF(blo[k], k);
            c1[k] = CELL_OF(bhi[k], k);
        }
        for (int z = c0[2]; z <= c1[2]; ++z)
            for (int y = c0[1]; y <= c1[1]; ++y)
                for (int x = c0[0]; x <= c1[0]; ++x) {
                    const size_t c = (size_t)x + (size_t)n[0] * ((size_t)y + (size_t)n[1] * (size_t)z);
                    for (uint32_t i = first[c]; i < first[c + 1]; ++i) {
                        const uint32_t v = order[i];
                        const float* p = m->positions + 3 * (size_t)v;
                        if (p[0] >= blo[0] && p[0] <= bhi[0] && p[1] >= blo[1] && p[1] <= bhi[1] && p[2] >= blo[2] &&
                            p[2] <= bhi[2])
                            redo[v] = 1;
                    }
                }
    }
#undef CELL_OF
    free(first), free(order), free(fill);
    return MESO_OK;
}

/* OLD's one shell object: its id, or E3116. */
static meso_result find_shell(meso_file* f, const char* path, uint32_t* id, meso_error* err)
{
    meso_object_record rec[2];
    uint32_t count = 0;
    meso_result r = meso_file_objects(f, rec, 2, &count, err);
    if (r != MESO_OK)
        return r;
    if (count != 1 || rec[0].kind != MESO_OBJECT_SHELL)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 3116,
                              "%s: --update needs a file with one shell object, as mesobake shell writes (this one "
                              "has %u object%s%s)",
                              mesoi_base_name(path), count, count == 1 ? "" : "s",
                              count == 1 ? ", not a shell" : "");
    *id = rec[0].id;
    return MESO_OK;
}

/* A whole chunk of OLD into a new malloc'd, 16-byte aligned buffer. */
static meso_result read_whole(meso_file* f, int32_t idx, void** data, size_t* size, meso_error* err)
{
    const meso_chunk_info* ci = meso_file_chunk(f, (uint32_t)idx);
    *size = (size_t)ci->decoded_size;
    *data = aligned_alloc(16, (*size + 15) / 16 * 16 + 16);
    if (!*data)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
    return meso_file_read_chunk(f, (uint32_t)idx, *data, *size, err);
}

/* OLD's stand-in chain: the levels after the base mesh's (level S: the
 * first stand-in, after any native levels) of object `id`, each a raw
 * MESH (what mesobake shell writes). Each one's own bound against OLD's
 * base mesh, from the stored errors: level L stores f32_up(e0 + c_L), e0
 * the base mesh's error, which is level S's stored error f32_up(e0), or,
 * when level S is the mid-surface, the report's standin_chain_base_error
 * (`base_error`, 0 when absent); so c_L <= err_L - e0 + ulp(e0). A file
 * that has no such chain gives chain_count 0. */
static meso_result read_chain(meso_file* f, uint32_t id, double base_error, mesoi_shell_prior* out, meso_error* err)
{
    enum { MAX = MESO_BAKE_SHELL_MAX_LEVELS };
    meso_level_info lv[MAX + 1];
    uint32_t count = 0, S = 1;
    meso_result r = meso_file_levels(f, id, lv, MAX + 1, &count, err);
    if (r != MESO_OK || count > MAX) /* count is the file's, lv holds MAX + 1 */
        return r;
    while (S < count && lv[S].rec.form == MESO_LEVEL_NATIVE)
        ++S;
    if (count < S + 2 || lv[S].rec.form != MESO_LEVEL_MESH)
        return r;
    const float e0 = base_error > 0 ? (float)base_error : lv[S].rec.error;
    const double e1 = e0, ulp1 = (double)nextafterf(e0, INFINITY) - e1;
    for (uint32_t L = S + 1; r == MESO_OK && L < count; ++L) {
        const int32_t ci = meso_file_find(f, MESO_CHUNK_MESH, id, (uint16_t)L);
        const meso_chunk_info* c = ci >= 0 ? meso_file_chunk(f, (uint32_t)ci) : NULL;
        if (!c || c->encoding != MESO_ENCODING_RAW || lv[L].rec.form != MESO_LEVEL_MESH)
            break; /* not a chain this bake wrote: build a new one */
        meso_mesh_chunk* mc = &out->chain_chunk[L - S - 1];
        size_t size = 0;
        if ((r = read_whole(f, ci, &mc->data, &size, err)) != MESO_OK) {
            free(mc->data);
            mc->data = NULL;
            break;
        }
        mc->size = size;
        mc->decoded_size = c->decoded_size;
        mc->encoding = c->encoding;
        ++out->chain_count;
        meso_mesh_view view;
        if ((r = meso_mesh_parse(mc->data, mc->size, &view, err)) != MESO_OK)
            break;
        out->chain_triangles[L - S - 1] = view.layout.index_count / 3;
        out->chain_own[L - S - 1] = (double)lv[L].rec.error - e1 + ulp1;
        memcpy(out->chain_bbox[L - S - 1], lv[L].rec.bbox_min, 3 * sizeof(float));
        memcpy(out->chain_bbox[L - S - 1] + 3, lv[L].rec.bbox_max, 3 * sizeof(float));
    }
    if (r != MESO_OK || out->chain_count != count - S - 1) { /* all of it or none */
        for (uint32_t k = 0; k < out->chain_count; ++k)
            free(out->chain_chunk[k].data);
        memset(out->chain_chunk, 0, sizeof(out->chain_chunk));
        out->chain_count = 0;
    }
    return r;
}

meso_result mesoi_shell_prior_load(const char* path, const meso_bake_shell_options* a, double* h_io,
                                   const meso_mesh* m, const uint32_t* out_source, const uint32_t* out_indices,
                                   uint32_t nv_out, mesoi_shell_prior* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    double h = *h_io;
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    if (!out_source) {
        nv_out = nv;
        out_indices = m->indices;
    }
    meso_file* f = NULL;
    meso_result r = mesoi_open_verified(path, &f, err);
    uint32_t id = 0;
    if (r == MESO_OK)
        r = find_shell(f, path, &id, err);
    cJSON *meta = NULL, *rep = NULL;
    if (r == MESO_OK) {
        meta = mesoi_json_chunk(f, MESO_CHUNK_META);
        rep = mesoi_json_chunk(f, MESO_CHUNK_RPRT);
        const cJSON* params = cJSON_GetObjectItemCaseSensitive(meta, "parameters");
        const cJSON* cmd = cJSON_GetObjectItemCaseSensitive(meta, "command");
        if (!cJSON_IsObject(params) || !cJSON_IsString(cmd) || strcmp(cmd->valuestring, "shell") != 0)
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3116,
                               "%s: --update needs a file mesobake shell wrote (its META has no shell parameters)",
                               mesoi_base_name(path));
        else {
            /* A relative thickness is the old bake's: the edit may have moved the diagonal. */
            const double old_h = param_number(params, "thickness");
            if (!(a->thickness > 0) && old_h > 0 && isfinite(old_h))
                h = *h_io = old_h;
            r = check_parameters(path, params, a, h, err);
        }
    }
    if (r == MESO_OK) {
        const char* keys[] = {"inverted_prisms", "offset_self_intersections", "offset_base_intersections"};
        for (size_t i = 0; i < 3 && r == MESO_OK; ++i) {
            const cJSON* j = cJSON_GetObjectItemCaseSensitive(rep, keys[i]);
            if (!cJSON_IsNumber(j) || j->valuedouble != 0)
                r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3119,
                                   "%s: written with defects (%s: %g, --allow-defects): an update keeps its shell "
                                   "outside the edit, so it needs a valid one; bake in full",
                                   mesoi_base_name(path), keys[i], cJSON_IsNumber(j) ? j->valuedouble : NAN);
        }
    }
    void *mesh_data = NULL, *sdir_data = NULL;
    size_t mesh_size = 0, sdir_size = 0;
    meso_mesh_view view;
    const int32_t mi = r == MESO_OK ? meso_file_find_level(f, MESO_CHUNK_MESH, id, 0) : -1;
    const int32_t si = r == MESO_OK ? meso_file_find_level(f, MESO_CHUNK_SDIR, id, 0) : -1;
    if (r == MESO_OK && (mi < 0 || si < 0))
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3116, "%s: the shell has no %s chunk", mesoi_base_name(path),
                           mi < 0 ? "MESH" : "SDIR");
    if (r == MESO_OK)
        r = read_whole(f, mi, &mesh_data, &mesh_size, err);
    if (r == MESO_OK)
        r = meso_mesh_parse(mesh_data, mesh_size, &view, err);
    if (r == MESO_OK)
        r = read_whole(f, si, &sdir_data, &sdir_size, err);
    /* Topology: the same output vertices and triangles. */
    if (r == MESO_OK && (view.layout.vertex_count != nv_out || view.layout.index_count != 3 * nt))
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3118,
                           "%s: the bake has %u vertices and %u triangles, the edited mesh %u and %u: --update needs "
                           "the same topology; bake in full",
                           mesoi_base_name(path), view.layout.vertex_count, view.layout.index_count / 3, nv_out, nt);
    for (uint32_t t = 0; r == MESO_OK && t < nt; ++t)
        if (memcmp(view.indices + 3 * (size_t)t, out_indices + 3 * (size_t)t, 3 * sizeof(uint32_t)) != 0)
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3118,
                               "%s: triangle %u has other corners in the edited mesh (%u %u %u, the bake %u %u %u): "
                               "--update needs the same topology; bake in full",
                               mesoi_base_name(path), t, out_indices[3 * (size_t)t], out_indices[3 * (size_t)t + 1],
                               out_indices[3 * (size_t)t + 2], view.indices[3 * (size_t)t],
                               view.indices[3 * (size_t)t + 1], view.indices[3 * (size_t)t + 2]);
    const meso_chunk_info* sc = r == MESO_OK ? meso_file_chunk(f, (uint32_t)si) : NULL;
    const uint32_t L = sc ? sc->dims[1] : 0;
    const uint32_t want_L = a->kind == MESO_SHELL_EXTERIOR ? 1 : 2;
    if (r == MESO_OK && L != want_L)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3116, "%s: SDIR has %u layers, a %s shell %u",
                           mesoi_base_name(path), L, meso_bake_shell_kind_name(a->kind), want_L);
    const int layers = a->kind == MESO_SHELL_ENVELOPE ? 2 : 1;
    float* old_pos = NULL;
    if (r == MESO_OK) {
        out->d = malloc(sizeof(float) * 3 * (size_t)nv * (size_t)layers + 1);
        out->redo = calloc(nv ? nv : 1, 1);
        old_pos = malloc(sizeof(float) * 3 * (size_t)(nv ? nv : 1));
        out->moved_at = calloc(nv ? nv : 1, 1);
        if (!out->d || !out->redo || !old_pos || !out->moved_at)
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
    }
    if (r == MESO_OK) {
        const float* sdir = sdir_data;
        for (uint32_t o = 0; o < nv_out; ++o) {
            const uint32_t v = out_source ? out_source[o] : o;
            memcpy(old_pos + 3 * (size_t)v, view.positions + 3 * (size_t)o, 3 * sizeof(float));
            for (int l = 0; l < layers; ++l) {
                /* Interior shells store the inward director as layer 1. */
                const uint32_t src = a->kind == MESO_SHELL_INTERIOR ? 1 : (uint32_t)l;
                memcpy(out->d + 3 * ((size_t)l * nv + v), sdir + 3 * ((size_t)src * nv_out + o), 3 * sizeof(float));
            }
        }
        uint8_t* moved = out->moved_at;
        for (uint32_t v = 0; v < nv; ++v) {
            moved[v] = memcmp(old_pos + 3 * (size_t)v, m->positions + 3 * (size_t)v, 3 * sizeof(float)) != 0;
            out->moved += moved[v];
            if (moved[v]) { /* rounded up past the few roundings of the sum and root */
                double q = 0;
                for (int k = 0; k < 3; ++k) {
                    const double e = (double)m->positions[3 * (size_t)v + k] - old_pos[3 * (size_t)v + k];
                    q += e * e;
                }
                out->moved_max = fmax(out->moved_max, sqrt(q) * (1.0 + 8.0 * DBL_EPSILON));
            }
        }
        out->radius = 3.0 * h + longest_edge(m);
        if (out->moved)
            r = grow_region(m, old_pos, moved, out->radius, out->redo, err);
        for (uint32_t v = 0; v < nv; ++v)
            out->redo_count += out->redo[v];
    }
    if (r == MESO_OK) {
        const cJSON* params = cJSON_GetObjectItemCaseSensitive(meta, "parameters");
        const double lv = param_number(params, "levels");
        out->chain_levels = isfinite(lv) ? (int)lv : -1;
        const cJSON* u = cJSON_GetObjectItemCaseSensitive(rep, "update");
        const cJSON* cm = cJSON_GetObjectItemCaseSensitive(u, "chain_moved");
        out->chain_moved = cJSON_IsNumber(cm) && cm->valuedouble > 0 ? cm->valuedouble : 0.0;
        const cJSON* cb = cJSON_GetObjectItemCaseSensitive(rep, "standin_chain_base_error");
        r = read_chain(f, id, cJSON_IsNumber(cb) && cb->valuedouble > 0 ? cb->valuedouble : 0.0, out, err);
    }
    free(old_pos);
    free(mesh_data);
    free(sdir_data);
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    meso_file_close(f);
    if (r != MESO_OK)
        mesoi_shell_prior_free(out);
    return r;
}

/* changed[f] = 1 for the faces with a corner flagged in `at`; their number. */
static uint32_t faces_touching(const meso_mesh* m, const uint8_t* at, uint8_t* changed)
{
    uint32_t n = 0;
    for (uint32_t f = 0; f < m->triangle_count; ++f) {
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        changed[f] = at[ix[0]] | at[ix[1]] | at[ix[2]];
        n += changed[f];
    }
    return n;
}

meso_result mesoi_shell_update_grow(const meso_mesh* m, meso_shell_checker* ck, const float* d, mesoi_shell_prior* p,
                                    uint32_t* added, meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    *added = 0;
    uint8_t* bad = malloc(nt ? nt : 1);
    uint8_t* seed = calloc(nv ? nv : 1, 1);
    meso_result r = bad && seed ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
    uint32_t count = 0;
    if (r == MESO_OK)
        r = meso_shell_checker_bad_faces(ck, d, bad, &count, err);
    /* The corners of the bad faces with a kept corner... */
    uint32_t seeds = 0;
    for (uint32_t f = 0; r == MESO_OK && count && f < nt; ++f) {
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        if (bad[f] && (!p->redo[ix[0]] || !p->redo[ix[1]] || !p->redo[ix[2]]))
            for (int c = 0; c < 3; ++c)
                seeds += !seed[ix[c]], seed[ix[c]] = 1;
    }
    /* ...and every corner of the faces around them. */
    for (uint32_t f = 0; seeds && f < nt; ++f) {
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        if (seed[ix[0]] == 1 || seed[ix[1]] == 1 || seed[ix[2]] == 1)
            for (int c = 0; c < 3; ++c)
                if (!seed[ix[c]])
                    seed[ix[c]] = 2;
    }
    for (uint32_t v = 0; seeds && v < nv; ++v)
        if (seed[v] && !p->redo[v]) {
            p->redo[v] = 1;
            ++*added;
        }
    p->redo_count += *added;
    free(bad), free(seed);
    return r;
}

meso_result mesoi_shell_update_base_check(const meso_mesh* m, const mesoi_shell_prior* p, const char* path,
                                          int threads, meso_error* err)
{
#if MESO_HAVE_CGAL
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    uint8_t* changed = malloc(nt ? nt : 1);
    double* xyz = malloc(sizeof(double) * 3 * (size_t)(nv ? nv : 1));
    meso_result r = changed && xyz ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
    meso_cgal_pairs self = {0}, cross = {0};
    if (r == MESO_OK && faces_touching(m, p->moved_at, changed)) {
        for (size_t i = 0; i < 3 * (size_t)nv; ++i)
            xyz[i] = m->positions[i];
        r = meso_cgal_shell_pairs(xyz, xyz, nv, m->indices, nt, changed, meso_bake_thread_count(threads), &self,
                                  &cross, err);
        if (r == MESO_OK && self.count)
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3114,
                               "%s: the surface intersects itself (%llu triangle pairs); no shell over it can be "
                               "valid — repair the mesh first",
                               path, (unsigned long long)self.count);
    }
    free(self.pairs), free(cross.pairs);
    free(changed), free(xyz);
    return r;
#else
    (void)m, (void)p, (void)path, (void)threads, (void)err;
    return MESO_OK;
#endif
}

meso_result mesoi_shell_update_validate(const meso_mesh* m, const float* d, double h, int sign,
                                        const mesoi_shell_prior* p, int threads, meso_shell_report* out, int* done,
                                        meso_error* err)
{
    *done = 0;
#if MESO_HAVE_CGAL
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    /* The argument's premise, in O(n): every kept director plus the longest
     * edge stays inside the radius the region was grown by. */
    double dmax = 0;
    for (uint32_t v = 0; v < nv; ++v)
        if (!p->redo[v])
            dmax = fmax(dmax, sqrt((double)d[3 * v] * d[3 * v] + (double)d[3 * v + 1] * d[3 * v + 1] +
                                   (double)d[3 * v + 2] * d[3 * v + 2]));
    if (!(dmax + longest_edge(m) < p->radius * (1.0 - 1e-9)))
        return MESO_OK;
    memset(out, 0, sizeof(*out));
    out->base_self_intersections = UINT64_MAX; /* mesoi_shell_update_base_check's */
    meso_result r = meso_shell_count_inverted(m, d, sign, NULL, &out->inverted_prisms, &out->undecided_prisms, err);
    out->prisms = nt;
    if (r == MESO_OK)
        r = meso_shell_thickness_ratio(m, d, NULL, h, &out->thickness_ratio_min, &out->thickness_ratio_mean, NULL,
                                       err);
    uint8_t* changed = malloc(nt ? nt : 1);
    double* xyz = malloc(sizeof(double) * 6 * (size_t)(nv ? nv : 1));
    if (r == MESO_OK && (!changed || !xyz))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
    meso_cgal_pairs self = {0}, cross = {0};
    if (r == MESO_OK && faces_touching(m, p->redo, changed)) {
        double* top = xyz + 3 * (size_t)nv;
        for (size_t i = 0; i < 3 * (size_t)nv; ++i) {
            xyz[i] = m->positions[i];
            top[i] = (double)m->positions[i] + (double)d[i];
        }
        r = meso_cgal_shell_pairs(top, xyz, nv, m->indices, nt, changed, meso_bake_thread_count(threads), &self,
                                  &cross, err);
    }
    out->offset_self_intersections = self.count;
    out->offset_base_intersections = cross.count;
    free(self.pairs), free(cross.pairs);
    free(changed), free(xyz);
    *done = r == MESO_OK;
    return r;
#else
    (void)m, (void)d, (void)h, (void)sign, (void)p, (void)threads, (void)out, (void)err;
    return MESO_OK;
#endif
}
