/*
 * cells_chunks.c — encode a cells object (cells_chunks.h; FORMAT.md §7.8).
 */
#include "cells_chunks.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"
#include "meso_layout.h"

static void st32(uint8_t* p, uint32_t v)
{
    for (int i = 0; i < 4; ++i)
        p[i] = (uint8_t)(v >> (8 * i));
}

static void stf32(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    st32(p, u);
}

/* >>normals ---------------------------------------------------------------- */

static double sgn1(double v) { return v < 0 ? -1.0 : 1.0; }

static uint16_t unorm16(double v)
{
    double u = floor((v * 0.5 + 0.5) * 65535.0 + 0.5);
    return (uint16_t)(u < 0 ? 0 : u > 65535 ? 65535 : u);
}

void meso_octa_encode(const double n[3], uint16_t out[2])
{
    double l1 = fabs(n[0]) + fabs(n[1]) + fabs(n[2]);
    double px = l1 > 0 ? n[0] / l1 : 0, py = l1 > 0 ? n[1] / l1 : 0;
    if (l1 > 0 && n[2] < 0) {
        double qx = (1 - fabs(py)) * sgn1(px), qy = (1 - fabs(px)) * sgn1(py);
        px = qx;
        py = qy;
    }
    out[0] = unorm16(px);
    out[1] = unorm16(py);
}

void meso_octa_decode(const uint16_t in[2], double n[3])
{
    double x = in[0] / 65535.0 * 2 - 1, y = in[1] / 65535.0 * 2 - 1;
    double z = 1 - fabs(x) - fabs(y);
    if (z < 0) {
        double qx = (1 - fabs(y)) * sgn1(x), qy = (1 - fabs(x)) * sgn1(y);
        x = qx;
        y = qy;
    }
    double l = sqrt(x * x + y * y + z * z);
    n[0] = x / l;
    n[1] = y / l;
    n[2] = z / l;
}

/* exp(-|d|^2 / 2) for |d|^2 = 0..12 (d in [-2, 2]^3). */
static double gauss_weight(int d2)
{
    static const double w[13] = {1.0,
        0.60653065971263342, 0.36787944117144233, 0.22313016014842982, 0.13533528323661270,
        0.082084998623898800, 0.049787068367863944, 0.030197383422318501, 0.018315638888734179,
        0.011108996538242306, 0.0067379469990854671, 0.0040867714384640666, 0.0024787521766663585};
    return w[d2];
}

void meso_cells_normal_sum(const meso_tile_map* m, uint32_t x, uint32_t y, uint32_t z, double out[3])
{
    const int64_t R = m->res;
    const uint16_t* c = m->cells;
    const uint16_t me = c[(size_t)x + (size_t)R * ((size_t)y + (size_t)R * z)];
    double s[3] = {0, 0, 0};
    for (int dz = -2; dz <= 2; ++dz) {
        int64_t zz = (((int64_t)z + dz) % R + R) % R;
        for (int dy = -2; dy <= 2; ++dy) {
            int64_t yy = (((int64_t)y + dy) % R + R) % R;
            const uint16_t* line = c + (size_t)R * ((size_t)yy + (size_t)R * (size_t)zz);
            for (int dx = -2; dx <= 2; ++dx) {
                int64_t xx = (((int64_t)x + dx) % R + R) % R;
                if (line[xx] == me)
                    continue;
                double w = gauss_weight(dx * dx + dy * dy + dz * dz);
                s[0] += w * dx;
                s[1] += w * dy;
                s[2] += w * dz;
            }
        }
    }
    memcpy(out, s, sizeof s);
}

static uint64_t build_normals(const meso_tile_map* m, uint16_t* out, int threads)
{
    const int64_t R = m->res, lines = R * R;
    uint64_t border = 0;
    const int nt = meso_bake_thread_count(threads);
    (void)nt;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : border) num_threads(nt)
    for (int64_t l = 0; l < lines; ++l) {
        uint32_t y = (uint32_t)(l % R), z = (uint32_t)(l / R);
        for (uint32_t x = 0; x < (uint32_t)R; ++x) {
            double s[3];
            meso_cells_normal_sum(m, x, y, z, s);
            double len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
            if (len > 0) {
                s[0] /= len;
                s[1] /= len;
                s[2] /= len;
                border++;
            } else {
                s[0] = s[1] = 0;
                s[2] = 1;
            }
            meso_octa_encode(s, out + 2 * ((size_t)x + (size_t)l * (size_t)R));
        }
    }
    return border;
}

/* >>colours ---------------------------------------------------------------- */

static uint64_t mix64(uint64_t v)
{
    uint64_t s = v;
    return meso_splitmix64(&s);
}

static meso_result build_colours(const meso_tile_map* m, const char* spec, uint8_t* out, meso_error* err)
{
    const uint32_t R = m->res;
    const size_t n = (size_t)R * R * R;
    if (!spec)
        spec = "hash";
    if (!strncmp(spec, "hash", 4) && (spec[4] == 0 || spec[4] == ':')) {
        uint64_t seed = 0;
        if (spec[4] == ':') {
            char* end = NULL;
            errno = 0;
            unsigned long long v = strtoull(spec + 5, &end, 10);
            if (!end || end == spec + 5 || *end || errno || spec[5] < '0' || spec[5] > '9') /* no sign */
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_CELLS_ISSUE_COLOUR_SPEC,
                                      "colour '%s': hash:SEED expects a non-negative integer seed", spec);
            seed = v;
        }
        for (size_t i = 0; i < n; ++i) {
            const uint16_t idx = m->cells[i];
            uint8_t* p = out + 4 * i;
            if (idx == 0) {
                memset(p, 0, 4);
                continue;
            }
            uint64_t h = mix64(seed * 0x9E3779B97F4A7C15ull + idx);
            uint64_t noise = mix64(h ^ (0xD1B54A32D192ED03ull * (i + 1)));
            int dn = (int)(noise % 21u) - 10; /* one offset for all channels: a brightness grain */
            for (int k = 0; k < 3; ++k)
                p[k] = (uint8_t)(48 + (int)((h >> (16 * k)) % 185u) + dn);
            p[3] = 255;
        }
        return MESO_OK;
    }
    /* FILE.raw:R */
    const char* colon = strrchr(spec, ':');
    if (!colon || colon == spec)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_CELLS_ISSUE_COLOUR_SPEC,
                              "colour '%s': expected hash[:SEED] or FILE.raw:R", spec);
    char* end = NULL;
    unsigned long r = strtoul(colon + 1, &end, 10);
    if (!end || end == colon + 1 || *end || colon[1] < '0' || colon[1] > '9' || r != R)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_CELLS_ISSUE_COLOUR_SPEC,
                              "colour '%s': the raw file's resolution must equal the tile-map resolution %u", spec, R);
    char path[4096];
    size_t plen = (size_t)(colon - spec);
    if (plen >= sizeof path)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_CELLS_ISSUE_COLOUR_SPEC, "colour: path too long");
    memcpy(path, spec, plen);
    path[plen] = 0;
    FILE* f = fopen(path, "rb");
    if (!f)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_CELLS_ISSUE_COLOUR_FILE, "colour file %s: cannot open: %s", path,
                              strerror(errno));
    size_t got = fread(out, 1, 4 * n, f);
    int extra = fgetc(f) != EOF;
    fclose(f);
    if (got != 4 * n || extra)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_CELLS_ISSUE_COLOUR_FILE,
                              "colour file %s: expected exactly %zu bytes (%u^3 RGBA8 texels)", path, 4 * n, R);
    return MESO_OK;
}

/* >>assembly --------------------------------------------------------------- */

meso_result meso_cells_chunks_build(const meso_tile_map* m, const meso_split_cells* sc, const meso_membership* mb,
                                    const double origin[3], double voxel_size, const char* colour, int threads,
                                    meso_cells_chunks* out, meso_error* err)
{
    if (!m || !sc || !mb || !origin || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "cells chunks: NULL argument");
    memset(out, 0, sizeof *out);
    const uint32_t R = m->res, S = sc->split_count;
    if (sc->res != R || mb->split_count != S || S == 0)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_CELLS_ISSUE_SIZE,
                              "cells chunks: tile map (R %u), split cells (R %u, S %u) and membership (S %u) do not "
                              "match, or there are no cells",
                              R, sc->res, S, mb->split_count);
    const size_t n = (size_t)R * R * R;
    const uint64_t class_words = (mb->tile_count + 15) / 16;
    const uint64_t memb_words = 2 * class_words + mb->record_count * mb->words_per_tile;
    if (memb_words > UINT32_MAX)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_CELLS_ISSUE_SIZE, /* --tiles/--tile-res: exit 1 */
                              "cells: the membership map needs %llu words; MEMB holds at most 2^32 - 1",
                              (unsigned long long)memb_words);

    uint8_t* c = out->cell;
    memset(c, 0, sizeof out->cell);
    for (int a = 0; a < 3; ++a) {
        st32(c + MESO_CELL_OFF_TILES + 4 * a, mb->tiles[a]);
        stf32(c + MESO_CELL_OFF_ORIGIN + 4 * a, (float)origin[a]);
    }
    st32(c + MESO_CELL_OFF_TILE_RES, R);
    st32(c + MESO_CELL_OFF_SPLIT_COUNT, S);
    st32(c + MESO_CELL_OFF_CELL_COUNT, sc->cell_count);
    stf32(c + MESO_CELL_OFF_VOXEL_SIZE, (float)voxel_size);
    st32(c + MESO_CELL_OFF_MIXED_TILES, (uint32_t)mb->record_count);
    st32(c + MESO_CELL_OFF_MIXED_TILES + 4, (uint32_t)(mb->record_count >> 32));

    out->tile_dtype = S <= 65535 ? MESO_DTYPE_U16 : MESO_DTYPE_U32;
    out->tile_size = n * (out->tile_dtype == MESO_DTYPE_U16 ? 2 : 4);
    out->splt_size = (size_t)S * MESO_SPLT_COMPONENTS * 4;
    out->memb_size = (size_t)memb_words * 4;
    out->nrmm_size = n * 4;
    out->colr_size = n * 4;
    out->tile = malloc(out->tile_size);
    out->splt = (uint32_t*)malloc(out->splt_size);
    out->memb = (uint32_t*)malloc(out->memb_size);
    out->nrmm = (uint16_t*)malloc(out->nrmm_size);
    out->colr = (uint8_t*)malloc(out->colr_size);
    if (!out->tile || !out->splt || !out->memb || !out->nrmm || !out->colr) {
        meso_cells_chunks_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells chunks: out of memory (R = %u)", R);
    }
    /* Host words: the chunk payloads are little-endian, so this assumes a
     * little-endian host, as membership.c's words do. */
    for (size_t i = 0; i < n; ++i) {
        if (out->tile_dtype == MESO_DTYPE_U16)
            ((uint16_t*)out->tile)[i] = (uint16_t)sc->voxel_split[i];
        else
            ((uint32_t*)out->tile)[i] = sc->voxel_split[i];
    }
    for (uint32_t s = 0; s < S; ++s) {
        const meso_split_cell* p = &sc->splits[s];
        uint32_t* q = out->splt + (size_t)s * MESO_SPLT_COMPONENTS;
        q[MESO_SPLT_CELL] = p->cell;
        q[MESO_SPLT_FACE_CODE] = p->face_code;
        q[MESO_SPLT_TILE_INDEX] = p->tile_index;
        for (int a = 0; a < 3; ++a)
            q[MESO_SPLT_OFFSET + a] = (uint32_t)p->offset[a];
    }
    memcpy(out->memb, mb->classes, (size_t)class_words * 4);
    memcpy(out->memb + class_words, mb->rank, (size_t)class_words * 4);
    if (mb->record_count)
        memcpy(out->memb + 2 * class_words, mb->records, (size_t)(mb->record_count * mb->words_per_tile) * 4);
    out->border_voxels = build_normals(m, out->nrmm, threads);
    meso_result r = build_colours(m, colour, out->colr, err);
    if (r != MESO_OK)
        meso_cells_chunks_free(out);
    return r;
}

void meso_cells_chunks_free(meso_cells_chunks* c)
{
    if (!c)
        return;
    free(c->tile);
    free(c->splt);
    free(c->memb);
    free(c->nrmm);
    free(c->colr);
    memset(c, 0, sizeof *c);
}
