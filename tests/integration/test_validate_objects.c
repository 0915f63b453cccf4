/*
 * test_validate_objects.c — full validation refuses objects that cannot be
 * drawn (FORMAT.md §7.2, issues 4312, 4902, 4912 and 6xxx), on files baked by mesobake
 * from tests/data and then mutated so that only the content is wrong: every
 * CRC is recomputed, chunks are "removed" by renaming them to an unknown,
 * non-required type (readers skip those), and count mismatches are written
 * through the format library's writer (which checks each chunk alone, as
 * the reader does). For every mutation: `mesoinspect validate --full` exits
 * 3 and lists the expected issue, and `mesoinspect preview` (GL and
 * --reference) exits 3 without writing an image. The unmutated bakes and
 * the golden files validate with exit 0.
 *
 * usage: test_validate_objects MESOBAKE MESOINSPECT TEST_DATA_DIR GOLDEN_DIR
 */
#undef NDEBUG
#include "meso_file.h"
#include "meso_layout.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

static const char *bake, *inspect, *data, *golden;
static char tmp[256];
static int failures;

/* >>files ------------------------------------------------------------------- */

static uint8_t* slurp(const char* path, size_t* size)
{
    FILE* f = fopen(path, "rb");
    assert(f);
    assert(fseek(f, 0, SEEK_END) == 0);
    long n = ftell(f);
    assert(n > 0);
    rewind(f);
    uint8_t* p = malloc((size_t)n);
    assert(p && fread(p, 1, (size_t)n, f) == (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return p;
}

static void spit(const char* path, const uint8_t* p, size_t size)
{
    FILE* f = fopen(path, "wb");
    assert(f && fwrite(p, 1, size, f) == size && fclose(f) == 0);
}

static uint32_t ld32(const uint8_t* p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t ld64(const uint8_t* p) { return (uint64_t)ld32(p) | (uint64_t)ld32(p + 4) << 32; }
static void st32(uint8_t* p, uint32_t v)
{
    for (int k = 0; k < 4; k++)
        p[k] = (uint8_t)(v >> (8 * k));
}
static void stf(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    st32(p, u);
}
static float ldf(const uint8_t* p)
{
    uint32_t u = ld32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

static uint8_t* entry(uint8_t* m, uint32_t i) { return m + MESO_HDR_SIZE + (size_t)i * MESO_TOC_ENTRY_SIZE; }
static uint32_t chunk_count(const uint8_t* m) { return ld32(m + MESO_HDR_OFF_CHUNK_COUNT); }

/* Index of the first chunk of `type` (the bakes hold one object, id 1). */
static uint32_t chunk_of(uint8_t* m, uint32_t type)
{
    for (uint32_t i = 0; i < chunk_count(m); i++)
        if (ld32(entry(m, i)) == type)
            return i;
    assert(0 && "chunk type not in the bake");
    return 0;
}

static uint8_t* payload(uint8_t* m, uint32_t i) { return m + ld64(entry(m, i) + MESO_TOC_OFF_OFFSET); }

/* Every CRC right again: payloads, TOC, header. */
static void fix_crcs(uint8_t* m)
{
    const uint32_t n = chunk_count(m);
    for (uint32_t i = 0; i < n; i++)
        st32(entry(m, i) + MESO_TOC_OFF_CRC,
             meso_crc32c(0, payload(m, i), (size_t)ld64(entry(m, i) + MESO_TOC_OFF_STORED_SIZE)));
    st32(m + MESO_HDR_OFF_TOC_CRC, meso_crc32c(0, m + MESO_HDR_SIZE, (size_t)n * MESO_TOC_ENTRY_SIZE));
    st32(m + MESO_HDR_OFF_HEADER_CRC, 0);
    st32(m + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, m, MESO_HDR_SIZE));
}

/* The chunk becomes an unknown, optional type: readers skip it, so the
 * object no longer has it. */
static void drop(uint8_t* m, uint32_t type)
{
    uint8_t* e = entry(m, chunk_of(m, type));
    st32(e + MESO_TOC_OFF_TYPE, MESO_FOURCC('X', 'X', 'X', 'X'));
    st32(e + MESO_TOC_OFF_FLAGS, 0);
}

/* Rewrite the file through the writer with chunk `type` cut to its first
 * `keep` elements (dims[0] = keep): a count mismatch between chunks that
 * are each well formed. */
static uint8_t* rewrite_cut(const uint8_t* m, size_t size, uint32_t type, uint32_t keep, size_t elem, size_t* out_size)
{
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(m, size, NULL, &f, &e) == MESO_OK);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        uint8_t* buf = malloc((size_t)c->stored_size);
        assert(buf && meso_file_read_stored(f, i, buf, (size_t)c->stored_size, &e) == MESO_OK);
        meso_chunk_desc d = {.type = c->type, .flags = c->flags, .object = c->object, .lod = c->lod,
                             .encoding = c->encoding, .decoded_size = c->decoded_size, .dtype = c->dtype,
                             .components = c->components, .dims = {c->dims[0], c->dims[1], c->dims[2]}};
        size_t n = (size_t)c->stored_size;
        if (c->type == type) {
            assert(keep < c->dims[0] && c->dims[1] == 1 && c->dims[2] == 1);
            d.dims[0] = keep;
            n = keep * elem;
            d.decoded_size = n;
        }
        if (meso_writer_add(w, &d, buf, n, &e) != MESO_OK) {
            fprintf(stderr, "writer refused chunk %u: %s\n", i, e.message);
            assert(0);
        }
        free(buf);
    }
    assert(meso_writer_finish(w, NULL, 0, out_size) == MESO_OK);
    uint8_t* out = malloc(*out_size);
    assert(out && meso_writer_finish(w, out, *out_size, out_size) == MESO_OK);
    meso_writer_destroy(w);
    meso_file_close(f);
    return out;
}

/* >>commands ---------------------------------------------------------------- */

static int run(const char* cmd)
{
    int st = system(cmd);
    assert(st != -1);
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
}

static void bake_file(const char* name, const char* args)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "'%s' %s -o '%s/%s.meso' >/dev/null 2>&1", bake, args, tmp, name);
    if (run(cmd) != 0) {
        fprintf(stderr, "bake failed: %s\n", cmd);
        exit(1);
    }
}

static int contains(const char* path, const char* needle)
{
    size_t n;
    FILE* f = fopen(path, "rb");
    if (!f)
        return 0;
    fclose(f);
    uint8_t* p = slurp(path, &n);
    char* s = malloc(n + 1);
    memcpy(s, p, n);
    s[n] = 0;
    int found = strstr(s, needle) != NULL;
    free(p);
    free(s);
    return found;
}

static void check(int ok, const char* what, const char* name)
{
    printf("%s %s: %s\n", ok ? "ok  " : "FAIL", name, what);
    if (!ok)
        failures++;
}

static void expect_valid(const char* path, const char* name)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "'%s' validate --full '%s' >/dev/null", inspect, path);
    check(run(cmd) == 0, "validate --full exits 0", name);
}

/* validate --full exits 3 listing `code`; both previews exit 3 and write
 * nothing. */
static void expect_refused(const uint8_t* m, size_t size, const char* name, uint32_t code)
{
    char path[512], out[600], png[600], cmd[2048], want[32];
    snprintf(path, sizeof path, "%s/%s.meso", tmp, name);
    snprintf(out, sizeof out, "%s/%s.out", tmp, name);
    snprintf(png, sizeof png, "%s/%s.png", tmp, name);
    spit(path, m, size);
    snprintf(cmd, sizeof cmd, "'%s' validate --full '%s' >'%s' 2>&1", inspect, path, out);
    int rc = run(cmd);
    snprintf(want, sizeof want, "error %u", code);
    check(rc == 3, "validate --full exits 3", name);
    check(contains(out, want), want, name);
    if (rc != 3 || !contains(out, want)) {
        snprintf(cmd, sizeof cmd, "cat '%s' >&2", out);
        run(cmd);
    }
    snprintf(cmd, sizeof cmd, "'%s' preview '%s' -o '%s' --size 16x16 >'%s' 2>&1", inspect, path, png, out);
    rc = run(cmd);
    check(rc == 3 && contains(out, want) && access(png, F_OK) != 0, "preview exits 3 listing the issue, no image",
          name);
    snprintf(cmd, sizeof cmd, "'%s' preview '%s' -o '%s' --reference --size 16x16 --samples 8 >'%s' 2>&1", inspect,
             path, png, out);
    rc = run(cmd);
    check(rc == 3 && contains(out, want) && access(png, F_OK) != 0,
          "preview --reference exits 3 listing the issue, no image", name);
    remove(path);
}

/* A fresh copy of a bake. */
static uint8_t* base(const char* name, size_t* size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s.meso", tmp, name);
    return slurp(path, size);
}

/* >>cases ------------------------------------------------------------------- */

/* Vertex 0's x position (raw MESH: header, then positions). */
static uint8_t* position0(uint8_t* m) { uint8_t* p = payload(m, chunk_of(m, MESO_CHUNK_MESH)); return p + ld64(p + 16); }

#define CASE(src, name, code, ...)                  \
    do {                                            \
        size_t n_;                                  \
        uint8_t* m = base(src, &n_);                \
        __VA_ARGS__;                                \
        fix_crcs(m);                                \
        expect_refused(m, n_, name, code);          \
        free(m);                                    \
    } while (0)

static void mesh_cases(void)
{
    CASE("mesh", "mesh-nan-position", MESO_ISSUE_MESH_VALUE, stf(position0(m), NAN));
    CASE("mesh", "mesh-inf-position", MESO_ISSUE_MESH_VALUE, stf(position0(m) + 4, INFINITY));
    CASE("mesh", "mesh-no-mesh", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_MESH));
    CASE("draco", "draco-no-mesh", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_MESH));
    /* Normals follow positions in the canonical layout. */
    CASE("cells", "cells-nan-normal", MESO_ISSUE_MESH_VALUE, {
        uint8_t* p = payload(m, chunk_of(m, MESO_CHUNK_MESH));
        stf(p + ld64(p + 24) + 8, NAN);
    });
    CASE("cells", "cells-no-mesh", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_MESH));
    CASE("cells", "cells-no-cell", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_CELL));
}

static void shell_cases(void)
{
    CASE("shell", "shell-nan-position", MESO_ISSUE_MESH_VALUE, stf(position0(m) + 8, NAN));
    CASE("shell", "shell-nan-director", MESO_ISSUE_SHELL_SDIR, stf(payload(m, chunk_of(m, MESO_CHUNK_SDIR)) + 40, NAN));
    CASE("shell", "shell-negative-thickness", MESO_ISSUE_SHELL_STHK, {
        uint8_t* t = payload(m, chunk_of(m, MESO_CHUNK_STHK)) + 4 * 7;
        stf(t, -ldf(t));
    });
    CASE("shell", "shell-zero-thickness", MESO_ISSUE_SHELL_STHK, stf(payload(m, chunk_of(m, MESO_CHUNK_STHK)), 0.0f));
    CASE("shell", "shell-no-mesh", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_MESH));
    CASE("shell", "shell-no-sdir", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_SDIR));
    CASE("shell", "shell-no-sthk", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_STHK));
    CASE("shell", "shell-no-tx3d", MESO_ISSUE_SHELL_TEXTURE, drop(m, MESO_CHUNK_TX3D));
    /* A signed volume: same size, a type the texture function does not allow. */
    CASE("shell", "shell-tx3d-i8", MESO_ISSUE_SHELL_TEXTURE,
         m[MESO_TOC_OFF_DTYPE + (size_t)(entry(m, chunk_of(m, MESO_CHUNK_TX3D)) - m)] = MESO_DTYPE_I8);
    size_t n, cut;
    uint8_t* m = base("shell", &n);
    uint32_t nv = ld32(entry(m, chunk_of(m, MESO_CHUNK_SDIR)) + MESO_TOC_OFF_DIMS);
    uint8_t* c = rewrite_cut(m, n, MESO_CHUNK_SDIR, nv - 1, 12, &cut);
    expect_refused(c, cut, "shell-sdir-count", MESO_ISSUE_SHELL_COUNT);
    free(c);
    c = rewrite_cut(m, n, MESO_CHUNK_STHK, nv - 1, 4, &cut);
    expect_refused(c, cut, "shell-sthk-count", MESO_ISSUE_SHELL_COUNT);
    free(c);
    free(m);
}

/* Animated texture functions (FORMAT.md §7.2, issues 4902 and 6105). */
static uint8_t* anim_record(uint8_t* m) { return payload(m, chunk_of(m, MESO_CHUNK_ANIM)); }

static void anim_cases(void)
{
    CASE("anim", "anim-zero-frames", MESO_ISSUE_ANIM_VALUE, st32(anim_record(m) + MESO_ANIM_OFF_FRAME_COUNT, 0));
    CASE("anim", "anim-nan-fps", MESO_ISSUE_ANIM_VALUE, stf(anim_record(m) + MESO_ANIM_OFF_FPS, NAN));
    CASE("anim", "anim-flags", MESO_ISSUE_ANIM_VALUE, st32(anim_record(m) + MESO_ANIM_OFF_FLAGS, 2));
    CASE("anim", "anim-reserved", MESO_ISSUE_ANIM_VALUE, anim_record(m)[MESO_ANIM_OFF_RESERVED + 3] = 1);
    /* 5 frames claimed, 4 stored */
    CASE("anim", "anim-frame-count", MESO_ISSUE_SHELL_ANIM, st32(anim_record(m) + MESO_ANIM_OFF_FRAME_COUNT, 5));
    CASE("anim", "anim-frame0", MESO_ISSUE_SHELL_ANIM, payload(m, chunk_of(m, MESO_CHUNK_TXFR))[1] ^= 1);
    CASE("anim", "anim-no-txfr", MESO_ISSUE_SHELL_ANIM, drop(m, MESO_CHUNK_TXFR));
    CASE("anim", "anim-no-dsfr", MESO_ISSUE_SHELL_ANIM, drop(m, MESO_CHUNK_DSFR));
    CASE("anim", "anim-no-anim", MESO_ISSUE_SHELL_ANIM, drop(m, MESO_CHUNK_ANIM));
}

/* Shell colour (FORMAT.md §7.2 "Shell colour", issues 4912 and 6106), on a
 * from-mesh bake of the glTF box: COLR 4x4x1 and a BASE CMAP record with
 * scale 1/2 (--tiling 2). */
static uint8_t* cmap_record(uint8_t* m) { return payload(m, chunk_of(m, MESO_CHUNK_CMAP)); }

static void color_cases(void)
{
    CASE("color", "cmap-mapping", MESO_ISSUE_CMAP_VALUE, st32(cmap_record(m) + MESO_CMAP_OFF_MAPPING, 2));
    CASE("color", "cmap-flags", MESO_ISSUE_CMAP_VALUE, st32(cmap_record(m) + MESO_CMAP_OFF_FLAGS, 1));
    CASE("color", "cmap-nan-scale", MESO_ISSUE_CMAP_VALUE, stf(cmap_record(m) + MESO_CMAP_OFF_SCALE, NAN));
    CASE("color", "cmap-zero-scale", MESO_ISSUE_CMAP_VALUE, stf(cmap_record(m) + MESO_CMAP_OFF_SCALE + 4, 0.0f));
    CASE("color", "cmap-reserved", MESO_ISSUE_CMAP_VALUE, cmap_record(m)[MESO_CMAP_OFF_RESERVED + 5] = 1);
    /* a TILED record must have scale 1, 1; this one keeps the bake's 1/2 */
    CASE("color", "cmap-tiled-scale", MESO_ISSUE_CMAP_VALUE,
         st32(cmap_record(m) + MESO_CMAP_OFF_MAPPING, MESO_CMAP_TILED));
    CASE("color", "color-no-cmap", MESO_ISSUE_SHELL_COLOR, drop(m, MESO_CHUNK_CMAP));
    CASE("color", "color-no-colr", MESO_ISSUE_SHELL_COLOR, drop(m, MESO_CHUNK_COLR));
    /* 4x4x1 relabelled 4x2x2 (same bytes): a 3D colour over a height field */
    CASE("color", "color-3d-over-tx2d", MESO_ISSUE_SHELL_COLOR, {
        uint8_t* e = entry(m, chunk_of(m, MESO_CHUNK_COLR));
        st32(e + MESO_TOC_OFF_DIMS + 4, 2);
        st32(e + MESO_TOC_OFF_DIMS + 8, 2);
    });
    /* a second CMAP: the COLR relabelled (BYTES x 1 so the element rules hold) */
    CASE("color", "color-two-cmap", MESO_ISSUE_SHELL_COLOR, {
        uint8_t* e = entry(m, chunk_of(m, MESO_CHUNK_COLR));
        st32(e + MESO_TOC_OFF_TYPE, MESO_CHUNK_CMAP);
        m[(size_t)(e - m) + MESO_TOC_OFF_DTYPE] = MESO_DTYPE_BYTES;
        m[(size_t)(e - m) + MESO_TOC_OFF_COMPONENTS] = 1;
    });
}

static void frusta_cases(void)
{
    CASE("frusta", "frusta-no-skel", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_SKEL));
    CASE("frusta", "frusta-no-frus", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_FRUS));
    CASE("frusta", "frusta-no-fseg", MESO_ISSUE_OBJ_CHUNKS, drop(m, MESO_CHUNK_FSEG));
    /* node1 of frustum 2 one past the last SKEL node */
    CASE("frusta", "frusta-fseg-node", MESO_ISSUE_FRUSTA_NODE, {
        uint32_t nodes = (uint32_t)(ld64(entry(m, chunk_of(m, MESO_CHUNK_SKEL)) + MESO_TOC_OFF_DECODED_SIZE) /
                                    MESO_SKEL_RECORD_SIZE);
        st32(payload(m, chunk_of(m, MESO_CHUNK_FSEG)) + 2 * MESO_FSEG_RECORD_SIZE + MESO_FSEG_OFF_NODE1, nodes);
    });
    CASE("frusta", "frusta-ball-node", MESO_ISSUE_FRUSTA_NODE,
         st32(payload(m, chunk_of(m, MESO_CHUNK_BALL)) + MESO_BALL_OFF_NODE, 100000));
    CASE("frusta", "frusta-frus-node", MESO_ISSUE_FRUSTA_NODE,
         st32(payload(m, chunk_of(m, MESO_CHUNK_FRUS)) + MESO_FRUS_OFF_SKEL_NODE, 100000));
    CASE("frusta", "frusta-no-axis", MESO_ISSUE_FRUSTA_AXIS, {
        uint8_t* r = payload(m, chunk_of(m, MESO_CHUNK_FRUS)) + MESO_FRUS_RECORD_SIZE;
        memcpy(r + MESO_FRUS_OFF_CENTER1, r + MESO_FRUS_OFF_CENTER0, 12);
    });
    size_t n, cut;
    uint8_t* m = base("frusta", &n);
    uint32_t nf = ld32(entry(m, chunk_of(m, MESO_CHUNK_FRUS)) + MESO_TOC_OFF_DIMS);
    uint8_t* c = rewrite_cut(m, n, MESO_CHUNK_FRUS, nf - 1, MESO_FRUS_RECORD_SIZE, &cut);
    expect_refused(c, cut, "frusta-count", MESO_ISSUE_FRUSTA_COUNT);
    free(c);
    free(m);
}

/* Colour chunks (FORMAT.md §7.2 kinds 3 and 4: issues 6205, 6301), each
 * reshaped in the TOC with its byte count kept (so only the object rule
 * can object). */
static void colour_cases(void)
{
    CASE("frusta_col", "frusta-colr-deep", MESO_ISSUE_FRUSTA_COLR, { /* 16 x 16 x 1 -> 16 x 8 x 2 */
        uint8_t* e = entry(m, chunk_of(m, MESO_CHUNK_COLR));
        st32(e + MESO_TOC_OFF_DIMS + 4, ld32(e + MESO_TOC_OFF_DIMS + 4) / 2);
        st32(e + MESO_TOC_OFF_DIMS + 8, 2);
    });
    CASE("cells_fm", "cells-grid-one-component", MESO_ISSUE_CELLS_COLOUR_GRID, { /* 8^3 x 4 -> (32 x 8 x 8) x 1 */
        uint8_t* e = entry(m, chunk_of(m, MESO_CHUNK_TX3D));
        e[MESO_TOC_OFF_COMPONENTS] = 1;
        st32(e + MESO_TOC_OFF_DIMS, 4 * ld32(e + MESO_TOC_OFF_DIMS));
    });
}

int main(int argc, char** argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: %s MESOBAKE MESOINSPECT TEST_DATA_DIR GOLDEN_DIR\n", argv[0]);
        return 1;
    }
    bake = argv[1];
    inspect = argv[2];
    data = argv[3];
    golden = argv[4];
    snprintf(tmp, sizeof tmp, "/tmp/meso_validate_objects.XXXXXX");
    assert(mkdtemp(tmp));
    char args[1024];
    /* One level: the cases below mutate "the" MESH chunk. */
    snprintf(args, sizeof args, "mesh -i '%s/sphere.obj' --levels 1", data);
    bake_file("mesh", args);
    snprintf(args, sizeof args, "mesh -i '%s/sphere.obj' --draco --levels 1", data);
    bake_file("draco", args);
    snprintf(args, sizeof args, "mesh -i '%s/sphere.obj' --draco", data); /* levels of detail (LODS) */
    bake_file("levels", args);
    /* One level: the cases below drop "the" MESH (a stand-in at lod 1 would stand in for it). */
    snprintf(args, sizeof args, "shell -i '%s/spot_uv.obj' --texture weave --dist-res 8x8x4 --levels 1", data);
    bake_file("shell", args);
    snprintf(args, sizeof args, "frusta -i '%s/neurom_simple.swc'", data);
    bake_file("frusta", args);
    snprintf(args, sizeof args, "shell -i '%s/sphere.obj' --texture boil:16 --frames 4 --dist-res 8x8x8", data);
    bake_file("anim", args);
    /* One level: the cases below mutate and drop "the" MESH too. */
    snprintf(args, sizeof args, "cells -i '%s/sphere.obj' --tiles 2 --tile-res 8 --levels 1", data);
    bake_file("cells", args);
    snprintf(args, sizeof args, "shell -i '%s/gltf/box.gltf' --texture ribs:16 --dist-res 8x8x4 --tiling 2 --color from-mesh",
             data);
    bake_file("color", args);

    const char* names[] = {"mesh", "draco", "levels", "shell", "frusta", "cells", "anim", "color"};
    char path[600];
    for (int i = 0; i < 8; i++) {
        snprintf(path, sizeof path, "%s/%s.meso", tmp, names[i]);
        expect_valid(path, names[i]);
    }
    const char* goldens[] = {"tetra", "all_chunks", "empty"};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s.meso", golden, goldens[i]);
        expect_valid(path, goldens[i]);
    }
    /* The unmutated frusta and cells bakes still render (the reference:
     * no GL needed). */
    const char* drawn[] = {"frusta", "cells"};
    for (int i = 0; i < 2; i++) {
        char cmd[2048];
        snprintf(cmd, sizeof cmd, "'%s' preview '%s/%s.meso' -o '%s/%s.png' --reference --size 16x16 >/dev/null 2>&1",
                 inspect, tmp, drawn[i], tmp, drawn[i]);
        check(run(cmd) == 0, "preview --reference exits 0", drawn[i]);
    }

    /* Colour (issue 16): a frusta COLR from a PNG (the preview above) and a
     * cells TX3D colour grid from a glTF's base colour. */
    snprintf(args, sizeof args, "frusta -i '%s/neurom_simple.swc' --relief-color '%s/frusta.png'", data, tmp);
    bake_file("frusta_col", args);
    snprintf(args, sizeof args, "cells -i '%s/gltf/box.gltf' --tiles 2 --tile-res 8 --colour from-mesh:8", data);
    bake_file("cells_fm", args);
    for (int i = 0; i < 2; i++) {
        const char* coloured[] = {"frusta_col", "cells_fm"};
        snprintf(path, sizeof path, "%s/%s.meso", tmp, coloured[i]);
        expect_valid(path, coloured[i]);
    }

    mesh_cases();
    shell_cases();
    anim_cases();
    color_cases();
    frusta_cases();
    colour_cases();

    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
    run(cmd);
    if (failures)
        fprintf(stderr, "%d checks failed\n", failures);
    return failures ? 1 : 0;
}
