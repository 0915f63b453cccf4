/*
 * test_export_glb.c — checks what `mesoinspect export` writes, independently
 * of the exporter (export_cli.sh drives it):
 *
 *   test_export_glb gen DIR
 *       writes the inputs of the analytic test: DIR/plane.obj (the unit
 *       square in z = 0, 8 × 8 quads, uv = (x, y), normal +z), a 16-bit
 *       height field DIR/sine.png of h(s, t) = 0.5 + 0.4 sin 2πs cos 2πt
 *       (128², the bottom row at t = 0 as mesobake reads it) and the same
 *       surface as a u8 density volume DIR/sine.raw (64 × 64 × 32: α =
 *       ½ + (h − w) D / 4 at texel centres, clamped, so α = ½ at w = h).
 *
 *   test_export_glb check FILE.meso FILE.glb [OBJECT_ID]
 *       1. tinygltf's own parser (TinyGLTF::LoadBinaryFromFile) accepts the
 *          file with no error and no warning;
 *       2. the glTF 2.0 rules this C code can check: GLB header, version and
 *          length, chunk types, lengths and 4-byte padding; asset.version
 *          "2.0" and a "mesoinspect ..." generator; one buffer that fits the
 *          BIN chunk (at most 3 bytes of padding); bufferViews inside it and
 *          4-byte aligned; accessors inside their views with the allowed
 *          componentType/type for their use (POSITION, NORMAL VEC3 float,
 *          TANGENT VEC4 float, TEXCOORD_0 VEC2 float, indices SCALAR
 *          unsigned), equal counts per primitive, POSITION min/max equal to
 *          the data's, indices < the vertex count and a multiple of 3 for
 *          triangles, finite positions and uvs, unit normals, unit tangents
 *          perpendicular to the normal with w = ±1, every reference in range,
 *          images that decode as PNG (libpng);
 *       3. against the .meso (read with the format library, not the
 *          exporter): one node per object, in order, named after it; for
 *          mesh, shell and cells objects the same triangles as the object's
 *          MESH, corner by corner (positions bit for bit), normals along the
 *          MESH's and uvs (s, 1 − t'), or the barycentric uvs of a
 *          triangle whose (s, t') have no area; shells carry a normal
 *          texture and tangents along increasing u whose bitangent points
 *          along decreasing v (the normal texture's +Y, "up" in the image);
 *          cells are coloured by the linear mean of their non-empty COLR
 *          voxels; every vertex of a frusta object lies on the surface the
 *          reference defines (a frustum's relief or cone, a cap, a ball:
 *          frustum_reference.h) and every frustum and ball has vertices;
 *          4. colour: a shell with a 2D COLR — its base-colour texture,
 *          sampled bilinearly (texels decoded from sRGB before filtering,
 *          REPEAT) at each corner's uv of the set baseColorTexture.texCoord
 *          names (TEXCOORD_1 for a BASE CMAP, TEXCOORD_0 for TILED), equals
 *          the .meso's colour at the corner's texture point (COLR bilinear
 *          at (s, t') × the CMAP scale, both decoded here) within 1/255 in
 *          sRGB; a frusta object with a COLR — COLOR_0 at each vertex equals
 *          meso_ref_frusta_albedo there (on some part the vertex lies on)
 *          within 1/255 in sRGB.
 *
 *   test_export_glb check-hard-corners FILE.meso FILE.glb
 *       the same, but the tangent frames' agreement with the uvs is only
 *       reported (for a box, whose welded corners no one frame fits).
 *
 *   test_export_glb tile3d FILE.meso FILE.glb W_TOP
 *       a TILED W × H × D COLR over a density volume whose columns all
 *       top out at w = W_TOP: each base-colour texel is the COLR there at
 *       w = W_TOP (sRGB decoded, linear between slices), within 1/255.
 *
 *   test_export_glb analytic FILE.glb K TOL_MAX_DEG TOL_MEAN_DEG
 *       the shell of DIR/plane.obj with thickness K (uv scale 1): each texel
 *       of the normal texture, turned to object space through the file's
 *       own TANGENT/NORMAL frame as glTF defines it (bitangent =
 *       cross(normal, tangent.xyz) · w), against the analytic normal of the
 *       height surface z = K h(x, y), normalize(−K ∂h/∂x, −K ∂h/∂y, 1);
 *       and each base-colour texel against sRGB(albedo (0.25 + 0.75 h)).
 *       Texels are decoded by tinygltf (stb_image).
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "export_tinygltf.h"
#include "frustum_reference.h"
#include "meso_file.h"
#include "png_io.h"

static int failures;
/* check-hard-corners: a shell whose MESH welds the corners of a box (its
 * three faces' u directions sum along the normal there, so no one tangent
 * frame fits them; the exporter does not split such vertices): the
 * tangent frame's agreement with the uvs is reported, not asserted. */
static int hard_corners;

#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
static void fail(const char* fmt, ...);

static void fail(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("FAIL: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    ++failures;
}

#define CHECK(cond, ...)          \
    do {                          \
        if (!(cond))              \
            fail(__VA_ARGS__);    \
    } while (0)

static uint32_t rd32(const uint8_t* p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint8_t* read_all(const char* path, size_t* n)
{
    FILE* f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    const long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t* b = malloc((size_t)len + 1);
    if (b && fread(b, 1, (size_t)len, f) != (size_t)len) {
        free(b);
        b = NULL;
    }
    fclose(f);
    *n = (size_t)len;
    return b;
}

/* >>analytic surface -------------------------------------------------------- */

static double sine_h(double s, double t)
{
    return 0.5 + 0.4 * sin(2 * M_PI * s) * cos(2 * M_PI * t);
}

static void sine_grad(double s, double t, double* hs, double* ht)
{
    *hs = 0.4 * 2 * M_PI * cos(2 * M_PI * s) * cos(2 * M_PI * t);
    *ht = -0.4 * 2 * M_PI * sin(2 * M_PI * s) * sin(2 * M_PI * t);
}

static int gen(const char* dir)
{
    char path[4200];
    snprintf(path, sizeof(path), "%s/plane.obj", dir);
    FILE* f = fopen(path, "w");
    if (!f)
        return 1;
    const int n = 8;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            fprintf(f, "v %.9g %.9g 0\n", (double)i / n, (double)j / n);
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            fprintf(f, "vt %.9g %.9g\n", (double)i / n, (double)j / n);
    fprintf(f, "vn 0 0 1\n");
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
            fprintf(f, "f %d/%d/1 %d/%d/1 %d/%d/1\n", a, a, b, b, d, d);
            fprintf(f, "f %d/%d/1 %d/%d/1 %d/%d/1\n", a, a, d, d, c, c);
        }
    fclose(f);
    /* 16-bit height field, rows top to bottom: row r is t = 1 − (r + ½)/H. */
    const int W = 128, H = 128;
    uint16_t* hv = malloc(sizeof(uint16_t) * (size_t)W * H);
    for (int r = 0; r < H; ++r)
        for (int i = 0; i < W; ++i)
            hv[(size_t)r * W + i] = (uint16_t)lrint(sine_h((i + 0.5) / W, 1.0 - (r + 0.5) / H) * 65535.0);
    snprintf(path, sizeof(path), "%s/sine.png", dir);
    char why[256];
    if (meso_png_write_gray(path, hv, W, H, 16, why, sizeof(why)) != 0) {
        fprintf(stderr, "%s\n", why);
        return 1;
    }
    free(hv);
    /* Density volume: x fastest, then t' (row j at (j + ½)/H), then w. */
    const int VW = 64, VH = 64, VD = 32;
    uint8_t* vol = malloc((size_t)VW * VH * VD);
    for (int k = 0; k < VD; ++k)
        for (int j = 0; j < VH; ++j)
            for (int i = 0; i < VW; ++i) {
                const double a = 0.5 + (sine_h((i + 0.5) / VW, (j + 0.5) / VH) - (k + 0.5) / VD) * VD / 4.0;
                vol[((size_t)k * VH + j) * VW + i] = (uint8_t)lrint(fmin(1.0, fmax(0.0, a)) * 255.0);
            }
    snprintf(path, sizeof(path), "%s/sine.raw", dir);
    f = fopen(path, "wb");
    if (!f || fwrite(vol, 1, (size_t)VW * VH * VD, f) != (size_t)VW * VH * VD)
        return 1;
    fclose(f);
    free(vol);
    return 0;
}

/* >>GLB --------------------------------------------------------------------- */

typedef struct glb {
    uint8_t* bytes;
    size_t size;
    cJSON* doc;
    const uint8_t* bin;
    size_t bin_size;
} glb;

static int glb_open(const char* path, glb* g)
{
    memset(g, 0, sizeof(*g));
    g->bytes = read_all(path, &g->size);
    if (!g->bytes) {
        fail("%s: cannot read", path);
        return 0;
    }
    const uint8_t* b = g->bytes;
    if (g->size < 20) {
        fail("%s: %zu bytes, shorter than a GLB header", path, g->size);
        return 0;
    }
    CHECK(rd32(b) == 0x46546C67u, "GLB magic is not 'glTF'");
    CHECK(rd32(b + 4) == 2, "GLB version %u, not 2", rd32(b + 4));
    CHECK(rd32(b + 8) == g->size, "GLB length %u != file size %zu", rd32(b + 8), g->size);
    const uint32_t jlen = rd32(b + 12);
    CHECK(rd32(b + 16) == 0x4E4F534Au, "first chunk is not JSON");
    CHECK(jlen % 4 == 0, "JSON chunk length %u not a multiple of 4", jlen);
    if (20 + (size_t)jlen > g->size) {
        fail("JSON chunk runs past the file");
        return 0;
    }
    /* Padding of the JSON chunk: spaces (0x20). */
    size_t end = jlen;
    while (end > 0 && b[20 + end - 1] == ' ')
        --end;
    g->doc = cJSON_ParseWithLength((const char*)b + 20, end);
    if (!g->doc) {
        fail("JSON chunk does not parse");
        return 0;
    }
    const size_t at = 20 + (size_t)jlen;
    if (at < g->size) {
        CHECK(at + 8 <= g->size, "BIN chunk header runs past the file");
        const uint32_t blen = rd32(b + at);
        CHECK(rd32(b + at + 4) == 0x004E4942u, "second chunk is not BIN");
        CHECK(blen % 4 == 0, "BIN chunk length %u not a multiple of 4", blen);
        CHECK(at + 8 + blen == g->size, "chunks do not end at the file's end");
        g->bin = b + at + 8;
        g->bin_size = blen;
    }
    return failures == 0;
}

static void glb_close(glb* g)
{
    cJSON_Delete(g->doc);
    free(g->bytes);
    memset(g, 0, sizeof(*g));
}

static int num(const cJSON* o, const char* key, int def)
{
    const cJSON* v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(v) ? v->valueint : def;
}

/* An accessor's data, checked against its view and buffer. */
typedef struct acc {
    const uint8_t* data;
    int count, comps, ctype;
    const cJSON* json;
} acc;

static int accessor(const glb* g, int index, acc* out)
{
    memset(out, 0, sizeof(*out));
    const cJSON* accs = cJSON_GetObjectItem(g->doc, "accessors");
    const cJSON* a = cJSON_GetArrayItem(accs, index);
    if (!a) {
        fail("accessor %d does not exist", index);
        return 0;
    }
    const char* type = cJSON_GetStringValue(cJSON_GetObjectItem(a, "type"));
    static const char* const types[5] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    int comps = 0;
    for (int k = 1; k <= 4; ++k)
        if (type && !strcmp(type, types[k]))
            comps = k;
    const int ctype = num(a, "componentType", 0), count = num(a, "count", 0);
    const int csize = ctype == 5126 || ctype == 5125 ? 4 : ctype == 5123 || ctype == 5122 ? 2 : ctype ? 1 : 0;
    CHECK(comps && csize, "accessor %d: bad type/componentType", index);
    CHECK(count >= 1, "accessor %d: count %d < 1", index, count);
    const int view = num(a, "bufferView", -1);
    const cJSON* v = cJSON_GetArrayItem(cJSON_GetObjectItem(g->doc, "bufferViews"), view);
    if (!v || !comps || !csize) {
        fail("accessor %d: bufferView %d does not exist", index, view);
        return 0;
    }
    CHECK(!cJSON_GetObjectItem(v, "byteStride"), "accessor %d: strided view (not written by export)", index);
    const size_t voff = (size_t)num(v, "byteOffset", 0), vlen = (size_t)num(v, "byteLength", 0);
    const size_t aoff = (size_t)num(a, "byteOffset", 0);
    CHECK(aoff % (size_t)csize == 0 && (voff + aoff) % (size_t)csize == 0, "accessor %d misaligned", index);
    if (aoff + (size_t)count * (size_t)comps * (size_t)csize > vlen) {
        fail("accessor %d runs past its bufferView", index);
        return 0;
    }
    out->data = g->bin + voff + aoff;
    out->count = count;
    out->comps = comps;
    out->ctype = ctype;
    out->json = a;
    return 1;
}

static float fget(const acc* a, int i, int k)
{
    float f;
    memcpy(&f, a->data + 4 * ((size_t)i * (size_t)a->comps + (size_t)k), 4);
    return f;
}

static uint32_t iget(const acc* a, int i)
{
    if (a->ctype == 5125)
        return rd32(a->data + 4 * (size_t)i);
    if (a->ctype == 5123)
        return (uint32_t)a->data[2 * (size_t)i] | (uint32_t)a->data[2 * (size_t)i + 1] << 8;
    return a->data[i];
}

/* One exported primitive, checked (part 2 of the header). */
typedef struct prim {
    acc pos, nrm, tan, uv, uv1, col, idx;
    int has_nrm, has_tan, has_uv, has_uv1, has_col, has_idx, mode, material;
} prim;

/* A TEXCOORD_n attribute: VEC2 float, nv of them, finite; 0 when it has no
 * data to read. */
static int uv_set(const glb* g, const cJSON* attr, const char* name, int nv, acc* uv)
{
    if (!accessor(g, num(attr, name, -1), uv))
        return 0;
    CHECK(uv->comps == 2 && uv->ctype == 5126 && uv->count == nv, "%s: type/count", name);
    for (int i = 0; i < nv; ++i)
        if (!isfinite(fget(uv, i, 0)) || !isfinite(fget(uv, i, 1))) {
            fail("%s %d not finite", name, i);
            break;
        }
    return 1;
}

static int check_prim(const glb* g, const cJSON* p, prim* out)
{
    const int failures_before = failures;
    memset(out, 0, sizeof(*out));
    const cJSON* attr = cJSON_GetObjectItem(p, "attributes");
    out->mode = num(p, "mode", 4);
    out->material = num(p, "material", -1);
    if (!accessor(g, num(attr, "POSITION", -1), &out->pos))
        return 0;
    CHECK(out->pos.comps == 3 && out->pos.ctype == 5126, "POSITION is not VEC3 float");
    const cJSON* mn = cJSON_GetObjectItem(out->pos.json, "min");
    const cJSON* mx = cJSON_GetObjectItem(out->pos.json, "max");
    CHECK(cJSON_GetArraySize(mn) == 3 && cJSON_GetArraySize(mx) == 3, "POSITION lacks min/max");
    for (int k = 0; k < 3 && cJSON_GetArraySize(mn) == 3 && cJSON_GetArraySize(mx) == 3; ++k) {
        float lo = INFINITY, hi = -INFINITY;
        for (int i = 0; i < out->pos.count; ++i) {
            const float x = fget(&out->pos, i, k);
            CHECK(isfinite(x), "position %d not finite", i);
            lo = fminf(lo, x);
            hi = fmaxf(hi, x);
        }
        CHECK((float)cJSON_GetArrayItem(mn, k)->valuedouble == lo, "POSITION min[%d] %.9g != data %.9g", k,
              cJSON_GetArrayItem(mn, k)->valuedouble, (double)lo);
        CHECK((float)cJSON_GetArrayItem(mx, k)->valuedouble == hi, "POSITION max[%d] %.9g != data %.9g", k,
              cJSON_GetArrayItem(mx, k)->valuedouble, (double)hi);
    }
    const int nv = out->pos.count;
    if ((out->has_nrm = cJSON_GetObjectItem(attr, "NORMAL") != NULL)) {
        if (!accessor(g, num(attr, "NORMAL", -1), &out->nrm))
            return 0;
        CHECK(out->nrm.comps == 3 && out->nrm.ctype == 5126 && out->nrm.count == nv, "NORMAL: type/count");
        for (int i = 0; i < nv; ++i) {
            const double x = fget(&out->nrm, i, 0), y = fget(&out->nrm, i, 1), z = fget(&out->nrm, i, 2);
            const double l = sqrt(x * x + y * y + z * z);
            if (!(fabs(l - 1) < 1e-5)) {
                fail("normal %d has length %.9g", i, l);
                break;
            }
        }
    }
    if ((out->has_tan = cJSON_GetObjectItem(attr, "TANGENT") != NULL)) {
        if (!accessor(g, num(attr, "TANGENT", -1), &out->tan))
            return 0;
        CHECK(out->has_nrm, "TANGENT without NORMAL");
        CHECK(out->tan.comps == 4 && out->tan.ctype == 5126 && out->tan.count == nv, "TANGENT: type/count");
        for (int i = 0; i < nv && out->has_nrm; ++i) {
            const double t[3] = {fget(&out->tan, i, 0), fget(&out->tan, i, 1), fget(&out->tan, i, 2)};
            const double l = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            const double w = fget(&out->tan, i, 3);
            const double d = t[0] * fget(&out->nrm, i, 0) + t[1] * fget(&out->nrm, i, 1) + t[2] * fget(&out->nrm, i, 2);
            if (!(fabs(l - 1) < 1e-5) || !(w == 1.0 || w == -1.0) || !(fabs(d) < 1e-4)) {
                fail("tangent %d: length %.9g, w %g, normal·tangent %.3g", i, l, w, d);
                break;
            }
        }
    }
    if ((out->has_uv = cJSON_GetObjectItem(attr, "TEXCOORD_0") != NULL) && !uv_set(g, attr, "TEXCOORD_0", nv, &out->uv))
        return 0;
    if ((out->has_uv1 = cJSON_GetObjectItem(attr, "TEXCOORD_1") != NULL) && !uv_set(g, attr, "TEXCOORD_1", nv, &out->uv1))
        return 0;
    if ((out->has_col = cJSON_GetObjectItem(attr, "COLOR_0") != NULL)) {
        if (!accessor(g, num(attr, "COLOR_0", -1), &out->col))
            return 0;
        CHECK(out->col.comps == 3 && out->col.ctype == 5126 && out->col.count == nv, "COLOR_0: not VEC3 float");
        for (int i = 0; i < nv; ++i)
            for (int k = 0; k < 3; ++k)
                if (!(fget(&out->col, i, k) >= 0 && fget(&out->col, i, k) <= 1)) {
                    fail("COLOR_0 %d[%d] = %g, not in [0, 1]", i, k, (double)fget(&out->col, i, k));
                    i = nv;
                    break;
                }
    }
    if ((out->has_idx = cJSON_GetObjectItem(p, "indices") != NULL)) {
        if (!accessor(g, num(p, "indices", -1), &out->idx))
            return 0;
        CHECK(out->idx.comps == 1 && (out->idx.ctype == 5125 || out->idx.ctype == 5123 || out->idx.ctype == 5121),
              "indices: not SCALAR unsigned");
        CHECK(out->mode != 4 || out->idx.count % 3 == 0, "triangle indices: count %d not a multiple of 3",
              out->idx.count);
        for (int i = 0; i < out->idx.count; ++i)
            if (iget(&out->idx, i) >= (uint32_t)nv) {
                fail("index %d = %u >= vertex count %d", i, iget(&out->idx, i), nv);
                break;
            }
    }
    return failures == failures_before;
}

/* Part 2 beyond primitives: document-level rules. */
static void check_document(const glb* g)
{
    const cJSON* asset = cJSON_GetObjectItem(g->doc, "asset");
    const char* version = cJSON_GetStringValue(cJSON_GetObjectItem(asset, "version"));
    const char* gen = cJSON_GetStringValue(cJSON_GetObjectItem(asset, "generator"));
    CHECK(version && !strcmp(version, "2.0"), "asset.version is not \"2.0\"");
    CHECK(gen && !strncmp(gen, "mesoinspect ", 12), "asset.generator is not \"mesoinspect ...\"");
    const cJSON* bufs = cJSON_GetObjectItem(g->doc, "buffers");
    CHECK(cJSON_GetArraySize(bufs) == 1, "not exactly one buffer");
    const size_t blen = (size_t)num(cJSON_GetArrayItem(bufs, 0), "byteLength", 0);
    CHECK(!cJSON_GetObjectItem(cJSON_GetArrayItem(bufs, 0), "uri"), "the GLB buffer has a uri");
    CHECK(blen <= g->bin_size && g->bin_size - blen <= 3, "buffer byteLength %zu vs BIN chunk %zu", blen, g->bin_size);
    const cJSON* v;
    cJSON_ArrayForEach(v, cJSON_GetObjectItem(g->doc, "bufferViews"))
    {
        const size_t off = (size_t)num(v, "byteOffset", 0), len = (size_t)num(v, "byteLength", 0);
        CHECK(num(v, "buffer", -1) == 0, "bufferView names another buffer");
        CHECK(len >= 1 && off + len <= blen, "bufferView [%zu, +%zu) outside the buffer (%zu)", off, len, blen);
        CHECK(off % 4 == 0, "bufferView at %zu is not 4-byte aligned", off);
    }
    /* Arrays that exist are non-empty; references are in range. */
    const cJSON* item;
    cJSON_ArrayForEach(item, g->doc)
    {
        if (cJSON_IsArray(item))
            CHECK(cJSON_GetArraySize(item) > 0, "'%s' is an empty array", item->string);
    }
    const int nimg = cJSON_GetArraySize(cJSON_GetObjectItem(g->doc, "images"));
    const int nsmp = cJSON_GetArraySize(cJSON_GetObjectItem(g->doc, "samplers"));
    const int ntex = cJSON_GetArraySize(cJSON_GetObjectItem(g->doc, "textures"));
    cJSON_ArrayForEach(item, cJSON_GetObjectItem(g->doc, "textures"))
    {
        CHECK(num(item, "source", -1) >= 0 && num(item, "source", -1) < nimg, "texture source out of range");
        CHECK(num(item, "sampler", -1) >= 0 && num(item, "sampler", -1) < nsmp, "texture sampler out of range");
    }
    cJSON_ArrayForEach(item, cJSON_GetObjectItem(g->doc, "samplers"))
    {
        CHECK(num(item, "wrapS", 10497) == 10497 && num(item, "wrapT", 10497) == 10497, "sampler does not repeat");
    }
    cJSON_ArrayForEach(item, cJSON_GetObjectItem(g->doc, "materials"))
    {
        const cJSON* pbr = cJSON_GetObjectItem(item, "pbrMetallicRoughness");
        const cJSON* bct = cJSON_GetObjectItem(pbr, "baseColorTexture");
        const cJSON* nt = cJSON_GetObjectItem(item, "normalTexture");
        CHECK(!bct || (num(bct, "index", -1) >= 0 && num(bct, "index", -1) < ntex), "baseColorTexture out of range");
        CHECK(!nt || (num(nt, "index", -1) >= 0 && num(nt, "index", -1) < ntex), "normalTexture out of range");
        const cJSON* f;
        cJSON_ArrayForEach(f, cJSON_GetObjectItem(pbr, "baseColorFactor"))
        {
            CHECK(f->valuedouble >= 0 && f->valuedouble <= 1, "baseColorFactor outside [0, 1]");
        }
    }
    cJSON_ArrayForEach(item, cJSON_GetObjectItem(g->doc, "images"))
    {
        const char* mime = cJSON_GetStringValue(cJSON_GetObjectItem(item, "mimeType"));
        CHECK(mime && !strcmp(mime, "image/png"), "image mimeType is not image/png");
        const cJSON* bv = cJSON_GetArrayItem(cJSON_GetObjectItem(g->doc, "bufferViews"), num(item, "bufferView", -1));
        if (!bv) {
            fail("image without a bufferView");
            continue;
        }
        uint8_t* px = NULL;
        int w = 0, h = 0;
        char why[256];
        const int rc = meso_png_decode_memory_rgba8(g->bin + num(bv, "byteOffset", 0), (size_t)num(bv, "byteLength", 0),
                                                    &px, &w, &h, why, sizeof(why));
        CHECK(rc == 0 && w > 0 && h > 0, "image does not decode as PNG: %s", rc ? why : "empty");
        free(px);
    }
}

/* >>against the .meso ------------------------------------------------------- */

static int32_t finest(const meso_file* f, uint32_t type, uint32_t id)
{
    int32_t best = -1;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == type && c->object == id && (best < 0 || c->lod < meso_file_chunk(f, (uint32_t)best)->lod))
            best = (int32_t)i;
    }
    return best;
}

static void* read_chunk(meso_file* f, int32_t ci, size_t* size)
{
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    void* buf = malloc((size_t)c->decoded_size + 1);
    meso_error err;
    if (!buf || meso_file_read_chunk(f, (uint32_t)ci, buf, (size_t)c->decoded_size, &err) != MESO_OK) {
        fail("cannot read chunk %d", ci);
        free(buf);
        return NULL;
    }
    *size = (size_t)c->decoded_size;
    return buf;
}

static double srgb_to_linear(int c)
{
    const double s = c / 255.0;
    return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4);
}

/* Mesh, shell, cells: the MESH's triangles corner by corner. */
/* sRGB encoding of a linear value in [0, 1], on 0..255 (not rounded). */
static double linear_to_srgb255(double c)
{
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    return 255.0 * (c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1 / 2.4) - 0.055);
}

/* Bilinear, wrapping sample of an RGBA8 sRGB image at (x, y) in texel units
 * (texel centres at i + ½), texels decoded to linear before filtering (a
 * GL_SRGB8_ALPHA8 fetch, GL_LINEAR, GL_REPEAT); y counts rows from the
 * image's row 0. */
static void bilinear_srgb(const uint8_t* px, int W, int H, double x, double y, double out[3])
{
    const double fx = floor(x - 0.5), fy = floor(y - 0.5), ax = x - 0.5 - fx, ay = y - 0.5 - fy;
    for (int k = 0; k < 3; ++k)
        out[k] = 0;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            long i = ((long)fx + dx) % W, j = ((long)fy + dy) % H;
            i += i < 0 ? W : 0;
            j += j < 0 ? H : 0;
            const double wgt = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay);
            for (int k = 0; k < 3; ++k)
                out[k] += wgt * srgb_to_linear(px[4 * (j * W + i) + k]);
        }
}

/* A shell with a COLR: the exported base-colour texture, sampled
 * bilinearly (sRGB decoded before filtering, REPEAT) at each corner's
 * exported uv of the set baseColorTexture.texCoord names, against the
 * .meso's colour at that corner's texture point (s, t'): COLR bilinear at
 * (s·scale0, t'·scale1), the CMAP record decoded here from its bytes
 * (FORMAT.md §7.2 "Shell colour"); within 1/255 per channel in sRGB. A
 * BASE mapping must use TEXCOORD_1, a TILED one TEXCOORD_0. 3D COLRs are
 * not compared per corner (the colour there depends on w). */
static void compare_shell_colour(const glb* g, meso_file* f, const meso_object_record* rec, const prim* p,
                                 const cJSON* material, const meso_mesh_view* v)
{
    const int32_t ci = finest(f, MESO_CHUNK_COLR, rec->id), mi = finest(f, MESO_CHUNK_CMAP, rec->id);
    if (ci < 0)
        return;
    const meso_chunk_info* cc = meso_file_chunk(f, (uint32_t)ci);
    size_t nc = 0, nm = 0;
    uint8_t* colr = read_chunk(f, ci, &nc);
    uint8_t* cmap = mi >= 0 ? read_chunk(f, mi, &nm) : NULL;
    const cJSON* bct = cJSON_GetObjectItem(cJSON_GetObjectItem(material, "pbrMetallicRoughness"), "baseColorTexture");
    CHECK(cmap && nm == 32, "shell %u: COLR without a 32-byte CMAP", rec->id);
    CHECK(bct != NULL, "shell %u: a COLR but no baseColorTexture", rec->id);
    if (!colr || !cmap || nm != 32 || !bct || cc->dims[2] != 1) {
        free(colr);
        free(cmap);
        return;
    }
    const uint32_t mapping = rd32(cmap);
    float scale[2];
    memcpy(&scale[0], cmap + 8, 4);
    memcpy(&scale[1], cmap + 12, 4);
    const int texcoord = num(bct, "texCoord", 0);
    CHECK(texcoord == (mapping == 1 ? 1 : 0), "shell %u: CMAP mapping %u but baseColorTexture.texCoord %d", rec->id,
          mapping, texcoord);
    CHECK(texcoord == 0 || p->has_uv1, "shell %u: texCoord 1 without TEXCOORD_1", rec->id);
    const cJSON* tex = cJSON_GetArrayItem(cJSON_GetObjectItem(g->doc, "textures"), num(bct, "index", -1));
    const cJSON* img = cJSON_GetArrayItem(cJSON_GetObjectItem(g->doc, "images"), num(tex, "source", -1));
    const cJSON* bv = cJSON_GetArrayItem(cJSON_GetObjectItem(g->doc, "bufferViews"), num(img, "bufferView", -1));
    uint8_t* px = NULL;
    int W = 0, H = 0;
    char why[256];
    if (!bv || meso_png_decode_memory_rgba8(g->bin + num(bv, "byteOffset", 0), (size_t)num(bv, "byteLength", 0), &px,
                                            &W, &H, why, sizeof(why)) != 0) {
        fail("shell %u: base-colour image does not decode", rec->id);
        free(colr);
        free(cmap);
        return;
    }
    const acc* uv = texcoord == 1 ? &p->uv1 : &p->uv;
    const uint32_t ni = v->layout.index_count;
    int bad = 0, corners = 0;
    double worst = 0;
    for (uint32_t t = 0; (texcoord == 0 ? p->has_uv : p->has_uv1) && t < ni && p->idx.count == (int)ni; t += 3) {
        double det = 0;
        if (v->uvs) {
            const float *a = v->uvs + 2 * (size_t)v->indices[t], *b = v->uvs + 2 * (size_t)v->indices[t + 1],
                        *c = v->uvs + 2 * (size_t)v->indices[t + 2];
            det = ((double)b[0] - a[0]) * ((double)c[1] - a[1]) - ((double)c[0] - a[0]) * ((double)b[1] - a[1]);
        }
        for (int k = 0; k < 3; ++k) {
            static const double bary[3][2] = {{0, 0}, {1, 0}, {0, 1}};
            const uint32_t m = v->indices[t + (uint32_t)k], e = iget(&p->idx, (int)(t + (uint32_t)k));
            const double st[2] = {fabs(det) < 1e-12 ? bary[k][0] : v->uvs[2 * (size_t)m],
                                  fabs(det) < 1e-12 ? bary[k][1] : v->uvs[2 * (size_t)m + 1]};
            double want[3], got[3];
            /* COLR row 0 is t' = 0; its texel centres at (i + ½)/W. */
            bilinear_srgb(colr, (int)cc->dims[0], (int)cc->dims[1], st[0] * scale[0] * cc->dims[0],
                          st[1] * scale[1] * cc->dims[1], want);
            /* The PNG's row 0 is its top, glTF's v = 0. */
            bilinear_srgb(px, W, H, (double)fget(uv, (int)e, 0) * W, (double)fget(uv, (int)e, 1) * H, got);
            double d = 0;
            for (int c = 0; c < 3; ++c)
                d = fmax(d, fabs(linear_to_srgb255(want[c]) - linear_to_srgb255(got[c])));
            worst = fmax(worst, d);
            bad += !(d <= 1.0);
            ++corners;
        }
    }
    CHECK(corners > 0, "shell %u: no corner's colour compared", rec->id);
    CHECK(!bad, "shell %u: %d of %d corners' base colour differs from the COLR's by > 1/255 (worst %.2f/255)", rec->id,
          bad, corners, worst);
    fprintf(stderr, "shell %u: colour (CMAP mapping %u, TEXCOORD_%d) at %d corners, worst %.3f/255\n", rec->id,
            mapping, texcoord, corners, worst);
    free(px);
    free(colr);
    free(cmap);
}

static void compare_mesh(const glb* g, meso_file* f, const meso_object_record* rec, const prim* p,
                         const cJSON* material)
{
    size_t size = 0;
    const int32_t ci = finest(f, MESO_CHUNK_MESH, rec->id);
    void* buf = ci >= 0 ? read_chunk(f, ci, &size) : NULL;
    meso_mesh_view v;
    meso_error err;
    if (!buf || meso_mesh_parse(buf, size, &v, &err) != MESO_OK) {
        fail("object %u: no readable MESH", rec->id);
        free(buf);
        return;
    }
    const uint32_t ni = v.layout.index_count;
    CHECK((uint32_t)(p->has_idx ? p->idx.count : 0) == ni, "object %u: %d indices exported, MESH has %u", rec->id,
          p->has_idx ? p->idx.count : 0, ni);
    CHECK(p->mode == (ni ? 4 : 0), "object %u: mode %d", rec->id, p->mode);
    if (ni == 0)
        CHECK((uint32_t)p->pos.count == v.layout.vertex_count, "object %u: point count", rec->id);
    const int shell = rec->kind == MESO_OBJECT_SHELL;
    int bad_pos = 0, bad_uv = 0, bad_nrm = 0, bad_frame = 0, framed = 0;
    for (uint32_t t = 0; p->has_idx && t < ni && (uint32_t)p->idx.count == ni; t += 3) {
        double det = 0;
        if (v.uvs) {
            const float *a = v.uvs + 2 * (size_t)v.indices[t], *b = v.uvs + 2 * (size_t)v.indices[t + 1],
                        *c = v.uvs + 2 * (size_t)v.indices[t + 2];
            det = ((double)b[0] - a[0]) * ((double)c[1] - a[1]) - ((double)c[0] - a[0]) * ((double)b[1] - a[1]);
        }
        for (int k = 0; k < 3; ++k) {
            const uint32_t m = v.indices[t + (uint32_t)k], e = iget(&p->idx, (int)(t + (uint32_t)k));
            for (int c = 0; c < 3; ++c)
                bad_pos += fget(&p->pos, (int)e, c) != v.positions[3 * (size_t)m + (size_t)c];
            if (shell && fabs(det) < 1e-12) {
                static const float bary[3][2] = {{0, 1}, {1, 1}, {0, 0}}; /* (s, 1 − t') of (0,0), (1,0), (0,1) */
                bad_uv += !p->has_uv || fget(&p->uv, (int)e, 0) != bary[k][0] || fget(&p->uv, (int)e, 1) != bary[k][1];
            } else if (v.uvs) {
                bad_uv += !p->has_uv || fget(&p->uv, (int)e, 0) != v.uvs[2 * (size_t)m] ||
                          fabsf(fget(&p->uv, (int)e, 1) - (1.0f - v.uvs[2 * (size_t)m + 1])) > 1e-6f;
            }
            if (v.normals) {
                double mn[3], l = 0, d = 0;
                for (int c = 0; c < 3; ++c) {
                    mn[c] = v.normals[3 * (size_t)m + (size_t)c];
                    l += mn[c] * mn[c];
                }
                l = sqrt(l);
                for (int c = 0; c < 3 && p->has_nrm; ++c)
                    d += mn[c] / l * fget(&p->nrm, (int)e, c);
                bad_nrm += l > 1e-6 && (!p->has_nrm || d < 1 - 1e-6);
            }
        }
        if (shell && p->has_tan && p->has_uv) {
            /* The triangle's ∂P/∂u and ∂P/∂v against each corner's frame. */
            const uint32_t e0 = iget(&p->idx, (int)t), e1 = iget(&p->idx, (int)t + 1), e2 = iget(&p->idx, (int)t + 2);
            double E1[3], E2[3];
            for (int c = 0; c < 3; ++c) {
                E1[c] = (double)fget(&p->pos, (int)e1, c) - fget(&p->pos, (int)e0, c);
                E2[c] = (double)fget(&p->pos, (int)e2, c) - fget(&p->pos, (int)e0, c);
            }
            const double du1 = (double)fget(&p->uv, (int)e1, 0) - fget(&p->uv, (int)e0, 0);
            const double dv1 = (double)fget(&p->uv, (int)e1, 1) - fget(&p->uv, (int)e0, 1);
            const double du2 = (double)fget(&p->uv, (int)e2, 0) - fget(&p->uv, (int)e0, 0);
            const double dv2 = (double)fget(&p->uv, (int)e2, 1) - fget(&p->uv, (int)e0, 1);
            const double dd = du1 * dv2 - du2 * dv1;
            if (fabs(dd) > 1e-9) {
                double pu[3], pv[3];
                for (int c = 0; c < 3; ++c) {
                    pu[c] = (dv2 * E1[c] - dv1 * E2[c]) / dd;
                    pv[c] = (du1 * E2[c] - du2 * E1[c]) / dd;
                }
                const uint32_t es[3] = {e0, e1, e2};
                for (int k = 0; k < 3; ++k) {
                    const uint32_t e = es[k];
                    const double n[3] = {fget(&p->nrm, (int)e, 0), fget(&p->nrm, (int)e, 1), fget(&p->nrm, (int)e, 2)};
                    const double T[3] = {fget(&p->tan, (int)e, 0), fget(&p->tan, (int)e, 1), fget(&p->tan, (int)e, 2)};
                    const double w = fget(&p->tan, (int)e, 3);
                    const double B[3] = {(n[1] * T[2] - n[2] * T[1]) * w, (n[2] * T[0] - n[0] * T[2]) * w,
                                         (n[0] * T[1] - n[1] * T[0]) * w};
                    /* Counted when clearly against: tangent against ∂P/∂u, or
                     * bitangent along ∂P/∂v (glTF's +Y is decreasing v). */
                    const double lu = sqrt(pu[0] * pu[0] + pu[1] * pu[1] + pu[2] * pu[2]);
                    const double lv = sqrt(pv[0] * pv[0] + pv[1] * pv[1] + pv[2] * pv[2]);
                    const double tu = (T[0] * pu[0] + T[1] * pu[1] + T[2] * pu[2]) / lu;
                    const double bv = (B[0] * pv[0] + B[1] * pv[1] + B[2] * pv[2]) / lv;
                    bad_frame += tu < -0.1 || bv > 0.1;
                    ++framed;
                }
            }
        }
    }
    CHECK(!bad_pos, "object %u: %d position components differ from the MESH", rec->id, bad_pos);
    CHECK(!bad_uv, "object %u: %d uvs differ from the MESH's (s, 1 - t')", rec->id, bad_uv);
    CHECK(!bad_nrm, "object %u: %d normals not along the MESH's", rec->id, bad_nrm);
    /* A vertex has one frame for all its triangles (the exporter splits
     * vertices where the uv orientation flips), which can still disagree
     * with a strongly sheared triangle at a pole: at most 0.2 % of the
     * corners. */
    CHECK(hard_corners || bad_frame * 500 <= framed,
          "object %u: %d of %d corners whose tangent frame disagrees with the uvs", rec->id, bad_frame, framed);
    if (framed)
        fprintf(stderr, "object %u: tangent frame against the triangle's uv directions at %d of %d corners\n",
                rec->id, framed - bad_frame, framed);
    const cJSON* pbr = cJSON_GetObjectItem(material, "pbrMetallicRoughness");
    if (shell) {
        CHECK(p->has_tan && p->has_uv && p->has_nrm, "shell %u: no tangents, normals or uvs", rec->id);
        const int has_fn = finest(f, MESO_CHUNK_TX2D, rec->id) >= 0 || finest(f, MESO_CHUNK_TX3D, rec->id) >= 0;
        CHECK(!has_fn || cJSON_GetObjectItem(material, "normalTexture"), "shell %u: no normal texture", rec->id);
        CHECK(!has_fn || cJSON_GetObjectItem(pbr, "baseColorTexture"), "shell %u: no base-colour texture", rec->id);
        compare_shell_colour(g, f, rec, p, material, &v);
    }
    if (rec->kind == MESO_OBJECT_CELLS) {
        size_t n = 0;
        const int32_t cc = finest(f, MESO_CHUNK_COLR, rec->id);
        uint8_t* colr = cc >= 0 ? read_chunk(f, cc, &n) : NULL;
        double sum[3] = {0, 0, 0};
        size_t cnt = 0;
        for (size_t i = 0; colr && i + 3 < n; i += 4)
            if (colr[i + 3]) {
                for (int k = 0; k < 3; ++k)
                    sum[k] += srgb_to_linear(colr[i + (size_t)k]);
                ++cnt;
            }
        const cJSON* bcf = cJSON_GetObjectItem(pbr, "baseColorFactor");
        for (int k = 0; k < 3 && cnt; ++k)
            CHECK(fabs(cJSON_GetArrayItem(bcf, k)->valuedouble - sum[k] / (double)cnt) < 1e-6,
                  "cells %u: baseColorFactor[%d] %.6f, mean COLR %.6f", rec->id, k,
                  cJSON_GetArrayItem(bcf, k)->valuedouble, sum[k] / (double)cnt);
        free(colr);
    }
    free(buf);
}

/* Frusta: every vertex on the reference's surface. */
static void compare_frusta(meso_file* f, const meso_object_record* rec, const prim* p)
{
    meso_ref_frusta m;
    meso_error err;
    if (meso_ref_frusta_load(f, rec->id, &m, &err) != MESO_OK) {
        fail("frusta %u: %s", rec->id, err.message);
        return;
    }
    const double scale = fmax(fmax(rec->bbox_max[0] - rec->bbox_min[0], rec->bbox_max[1] - rec->bbox_min[1]),
                              rec->bbox_max[2] - rec->bbox_min[2]);
    const double tol = 1e-4 * scale;
    uint32_t* hits = calloc((size_t)m.seg_count + m.ball_count + 1, sizeof(uint32_t));
    double* dist = calloc((size_t)m.seg_count + m.ball_count + 1, sizeof(double));
    int off = 0, col_bad = 0;
    double worst = 0, col_worst = 0;
    for (int i = 0; i < p->pos.count; ++i) {
        const double x[3] = {fget(&p->pos, i, 0), fget(&p->pos, i, 1), fget(&p->pos, i, 2)};
        double best = INFINITY;
        uint32_t who = 0;
        for (uint32_t s = 0; s < m.seg_count; ++s) {
            const meso_ref_frustum* fr = &m.segs[s];
            double a[3], h = 0, q[3], y = 0;
            for (int k = 0; k < 3; ++k) {
                a[k] = fr->c1[k] - fr->c0[k];
                h += a[k] * a[k];
            }
            h = sqrt(h);
            for (int k = 0; k < 3; ++k) {
                a[k] /= h;
                y += (x[k] - fr->c0[k]) * a[k];
            }
            double rho = 0;
            for (int k = 0; k < 3; ++k) {
                q[k] = x[k] - fr->c0[k] - y * a[k];
                rho += q[k] * q[k];
            }
            rho = sqrt(rho);
            const double r = fr->r0 + (fr->r1 - fr->r0) * y / h;
            double relief = 0;
            if (fr->relief_depth > 0 && m.relief.height.kind == 1) {
                double ss, tt;
                meso_ref_frustum_relief_coords(fr, x, &ss, &tt, NULL);
                relief = fr->relief_depth * meso_ref_relief_height(&m.relief.height, ss, tt, NULL, NULL);
            }
            double side[2];
            for (int e = 0; e < 2; ++e)
                side[e] = fr->plane_n[e][0] * x[0] + fr->plane_n[e][1] * x[1] + fr->plane_n[e][2] * x[2] - fr->plane_d[e];
            dist[s] = INFINITY;
            if (side[0] > tol || side[1] > tol)
                continue;
            /* Lateral (relief) surface, or a flagged cap's disc. */
            double d = fabs(rho - (r + relief));
            for (int e = 0; e < 2; ++e)
                if (fr->cap[e] && rho <= r + relief + tol)
                    d = fmin(d, fabs(side[e]));
            dist[s] = d;
            if (d < best) {
                best = d;
                who = s;
            }
        }
        for (uint32_t b = 0; b < m.ball_count; ++b) {
            const meso_ref_ball* bl = &m.balls[b];
            const double d = fabs(sqrt((x[0] - bl->center[0]) * (x[0] - bl->center[0]) +
                                       (x[1] - bl->center[1]) * (x[1] - bl->center[1]) +
                                       (x[2] - bl->center[2]) * (x[2] - bl->center[2])) -
                                  bl->radius);
            dist[m.seg_count + b] = d;
            if (d < best) {
                best = d;
                who = m.seg_count + b;
            }
        }
        worst = fmax(worst, best);
        off += !(best <= tol);
        if (best <= tol)
            hits[who]++;
        if (m.color && p->has_col && best <= tol) {
            /* The colour against the reference's albedo on every part the
             * vertex lies on (at a joint two frusta meet, with their own
             * relief coordinates; a ball inside a joint). */
            double dmin = INFINITY;
            for (uint32_t q = 0; q < m.seg_count + m.ball_count; ++q) {
                if (dist[q] > tol)
                    continue;
                meso_ref_frustum_hit hit;
                memset(&hit, 0, sizeof(hit));
                memcpy(hit.p, x, sizeof(x));
                hit.part = q < m.seg_count ? MESO_REF_PART_LATERAL : MESO_REF_PART_BALL;
                hit.index = (int32_t)(q < m.seg_count ? q : q - m.seg_count);
                double a[3];
                if (!meso_ref_frusta_albedo(&m, &hit, a))
                    continue;
                double d = 0;
                for (int k = 0; k < 3; ++k)
                    d = fmax(d, fabs(linear_to_srgb255(a[k]) - linear_to_srgb255(fget(&p->col, i, k))));
                dmin = fmin(dmin, d);
            }
            col_worst = fmax(col_worst, dmin);
            col_bad += !(dmin <= 1.0);
        }
    }
    CHECK(!m.color || p->has_col, "frusta %u: a COLR but no COLOR_0", rec->id);
    CHECK(col_bad == 0, "frusta %u: %d of %d vertex colours differ from the reference albedo by > 1/255 (worst %.2f)",
          rec->id, col_bad, p->pos.count, col_worst);
    if (m.color)
        fprintf(stderr, "frusta %u: COLOR_0 vs meso_ref_frusta_albedo, worst %.3f/255 in sRGB\n", rec->id, col_worst);
    CHECK(off == 0, "frusta %u: %d of %d vertices off the surface (worst %.3g, tolerance %.3g)", rec->id, off,
          p->pos.count, worst, tol);
    uint32_t empty = 0;
    for (uint32_t s = 0; s < m.seg_count + m.ball_count; ++s)
        empty += hits[s] == 0;
    CHECK(empty == 0, "frusta %u: %u of %u frusta and balls have no vertex", rec->id, empty,
          m.seg_count + m.ball_count);
    CHECK(p->has_nrm && p->has_idx && p->mode == 4, "frusta %u: not an indexed triangle mesh with normals", rec->id);
    fprintf(stderr, "frusta %u: %d vertices on the surface (worst %.2g of %.2g)\n", rec->id, p->pos.count, worst, scale);
    free(hits);
    free(dist);
    meso_ref_frusta_free(&m);
}

static int check(const char* meso_path, const char* glb_path, uint32_t only)
{
    char warn[4096] = "", err[4096] = "";
    int nodes = 0;
    tg_image n0, c0;
    const int ok = tg_load(glb_path, warn, sizeof(warn), err, sizeof(err), &nodes, &n0, &c0);
    CHECK(ok, "tinygltf refuses %s: %s", glb_path, err);
    CHECK(!warn[0], "tinygltf warns about %s: %s", glb_path, warn);
    CHECK(!err[0], "tinygltf reports an error for %s: %s", glb_path, err);
    free(n0.pixels);
    free(c0.pixels);
    glb g;
    if (!glb_open(glb_path, &g)) {
        glb_close(&g);
        return 1;
    }
    check_document(&g);
    meso_file* f = NULL;
    meso_error e;
    if (meso_file_open_path(meso_path, NULL, &f, &e) != MESO_OK) {
        fail("%s: %s", meso_path, e.message);
        glb_close(&g);
        return 1;
    }
    uint32_t count = 0;
    meso_file_objects(f, NULL, 0, &count, &e);
    meso_object_record* recs = calloc(count + 1, sizeof(*recs));
    meso_file_objects(f, recs, count, &count, &e);
    const cJSON* gnodes = cJSON_GetObjectItem(g.doc, "nodes");
    const cJSON* scenes = cJSON_GetObjectItem(g.doc, "scenes");
    int n = 0;
    for (uint32_t i = 0; i < count; ++i) {
        if (only && recs[i].id != only)
            continue;
        const cJSON* node = cJSON_GetArrayItem(gnodes, n);
        const char* name = cJSON_GetStringValue(cJSON_GetObjectItem(node, "name"));
        CHECK(name && !strcmp(name, recs[i].name), "node %d is named '%s', object %u '%s'", n, name ? name : "",
              recs[i].id, recs[i].name);
        const cJSON* listed = cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetArrayItem(scenes, 0), "nodes"), n);
        CHECK(cJSON_IsNumber(listed) && listed->valueint == n, "scene 0 does not list node %d in place %d", n, n);
        const cJSON* mesh = cJSON_GetArrayItem(cJSON_GetObjectItem(g.doc, "meshes"), num(node, "mesh", -1));
        const cJSON* pj = cJSON_GetArrayItem(cJSON_GetObjectItem(mesh, "primitives"), 0);
        prim p;
        if (!mesh || !pj || !check_prim(&g, pj, &p)) {
            fail("node %d: no checkable primitive", n);
            ++n;
            continue;
        }
        const cJSON* material = cJSON_GetArrayItem(cJSON_GetObjectItem(g.doc, "materials"), p.material);
        CHECK(material != NULL, "node %d: no material", n);
        if (recs[i].kind == MESO_OBJECT_FRUSTA)
            compare_frusta(f, &recs[i], &p);
        else
            compare_mesh(&g, f, &recs[i], &p, material);
        fprintf(stderr, "object %u '%s' (kind %u): %d vertices, %d indices checked\n", recs[i].id, recs[i].name,
                recs[i].kind, p.pos.count, p.has_idx ? p.idx.count : 0);
        ++n;
    }
    CHECK(n == nodes && n == cJSON_GetArraySize(gnodes), "%d objects, %d nodes", n, nodes);
    CHECK(n > 0, "nothing was checked");
    free(recs);
    meso_file_close(f);
    glb_close(&g);
    return failures != 0;
}

/* >>analytic ---------------------------------------------------------------- */

static int analytic(const char* glb_path, double K, double tol_max, double tol_mean)
{
    char warn[4096] = "", err[4096] = "";
    int nodes = 0;
    tg_image nimg, cimg;
    if (!tg_load(glb_path, warn, sizeof(warn), err, sizeof(err), &nodes, &nimg, &cimg) || !nimg.pixels ||
        !cimg.pixels) {
        fail("%s: no normal and base-colour textures (%s)", glb_path, err);
        return 1;
    }
    glb g;
    if (!glb_open(glb_path, &g))
        return 1;
    const cJSON* pj =
        cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(g.doc, "meshes"), 0), "primitives"), 0);
    prim p;
    if (!check_prim(&g, pj, &p) || !p.has_tan) {
        fail("no primitive with tangents");
        return 1;
    }
    /* A plane: one frame for every vertex (checked). */
    double N[3], T[3], B[3];
    for (int k = 0; k < 3; ++k) {
        N[k] = fget(&p.nrm, 0, k);
        T[k] = fget(&p.tan, 0, k);
    }
    const double w = fget(&p.tan, 0, 3);
    for (int i = 1; i < p.pos.count; ++i)
        for (int k = 0; k < 3; ++k)
            if (fabs(fget(&p.nrm, i, k) - N[k]) > 1e-6 || fabs(fget(&p.tan, i, k) - T[k]) > 1e-6) {
                fail("vertex %d: frame differs from vertex 0's on a plane", i);
                i = p.pos.count;
                break;
            }
    B[0] = (N[1] * T[2] - N[2] * T[1]) * w;
    B[1] = (N[2] * T[0] - N[0] * T[2]) * w;
    B[2] = (N[0] * T[1] - N[1] * T[0]) * w;
    const int W = nimg.width, H = nimg.height, C = nimg.components;
    double worst = 0, sum = 0;
    int worst_c = 0;
    long csum = 0;
    for (int r = 0; r < H; ++r)
        for (int i = 0; i < W; ++i) {
            /* Image row r (top = 0) is glTF v = (r + ½)/H, t' = 1 − v. */
            const double s = (i + 0.5) / W, t = 1.0 - (r + 0.5) / H;
            const unsigned char* c = nimg.pixels + ((size_t)r * W + i) * (size_t)C;
            double m[3], ts[3];
            for (int k = 0; k < 3; ++k)
                ts[k] = c[k] / 255.0 * 2 - 1;
            double l = 0;
            for (int k = 0; k < 3; ++k) {
                m[k] = ts[0] * T[k] + ts[1] * B[k] + ts[2] * N[k];
                l += m[k] * m[k];
            }
            double hs, ht;
            sine_grad(s, t, &hs, &ht);
            double a[3] = {-K * hs, -K * ht, 1}, la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            const double d = (m[0] * a[0] + m[1] * a[1] + m[2] * a[2]) / (sqrt(l) * la);
            const double ang = acos(fmin(1.0, d)) * 180 / M_PI;
            worst = fmax(worst, ang);
            sum += ang;
            /* Base colour: sRGB(albedo (0.25 + 0.75 h)). */
            const double alb[3] = {0.80, 0.74, 0.66}, occ = 0.25 + 0.75 * sine_h(s, t);
            const unsigned char* cc = cimg.pixels + ((size_t)r * (size_t)cimg.width + i) * (size_t)cimg.components;
            for (int k = 0; k < 3 && cimg.width == W && cimg.height == H; ++k) {
                const double lin = alb[k] * occ;
                const double sr = lin <= 0.0031308 ? 12.92 * lin : 1.055 * pow(lin, 1 / 2.4) - 0.055;
                const int dc = abs((int)cc[k] - (int)lrint(sr * 255));
                worst_c = dc > worst_c ? dc : worst_c;
                csum += dc;
            }
        }
    const double mean = sum / (W * H);
    fprintf(stderr, "analytic: %dx%d normal texels, angle to the analytic normal max %.3f deg, mean %.3f deg; "
                    "base colour max |error| %d/255, mean %.3f/255\n",
            W, H, worst, mean, worst_c, (double)csum / (3.0 * W * H));
    CHECK(worst <= tol_max && mean <= tol_mean, "normal map: max %.3f deg (limit %.3f), mean %.3f deg (limit %.3f)",
          worst, tol_max, mean, tol_mean);
    CHECK(cimg.width == W && cimg.height == H, "base-colour texture %dx%d, normal texture %dx%d", cimg.width,
          cimg.height, W, H);
    CHECK(worst_c <= 3, "base colour: max error %d/255 (limit 3)", worst_c);
    free(nimg.pixels);
    free(cimg.pixels);
    glb_close(&g);
    return failures != 0;
}

/* >>tile3d ------------------------------------------------------------------ */

/* A TILED 3D COLR (object 1 of FILE.meso, W × H × D) over a density volume
 * whose every column's top-most solid w is W_TOP (known from how the test
 * built it): each texel of the exported base-colour image (node 0) is the
 * COLR at that texel's column and w = W_TOP as a GL fetch gives it (decoded
 * to linear, linear between the slices whose centres (k + ½)/D bracket w,
 * clamped), within 1/255 in sRGB; the image is W × H with t' = 1 at the
 * top. */
static int tile3d(const char* meso_path, const char* glb_path, double w_top)
{
    glb g;
    meso_file* f = NULL;
    meso_error e;
    if (!glb_open(glb_path, &g) || meso_file_open_path(meso_path, NULL, &f, &e) != MESO_OK) {
        fail("cannot open %s or %s", meso_path, glb_path);
        glb_close(&g);
        return 1;
    }
    const int32_t ci = finest(f, MESO_CHUNK_COLR, 1);
    size_t n = 0;
    uint8_t* colr = ci >= 0 ? read_chunk(f, ci, &n) : NULL;
    const cJSON* mat = cJSON_GetArrayItem(cJSON_GetObjectItem(g.doc, "materials"), 0);
    const cJSON* bct = cJSON_GetObjectItem(cJSON_GetObjectItem(mat, "pbrMetallicRoughness"), "baseColorTexture");
    const cJSON* tex = cJSON_GetArrayItem(cJSON_GetObjectItem(g.doc, "textures"), num(bct, "index", -1));
    const cJSON* img = cJSON_GetArrayItem(cJSON_GetObjectItem(g.doc, "images"), num(tex, "source", -1));
    const cJSON* bv = cJSON_GetArrayItem(cJSON_GetObjectItem(g.doc, "bufferViews"), num(img, "bufferView", -1));
    uint8_t* px = NULL;
    int W = 0, H = 0;
    char why[256];
    if (!colr || !bv ||
        meso_png_decode_memory_rgba8(g.bin + num(bv, "byteOffset", 0), (size_t)num(bv, "byteLength", 0), &px, &W, &H,
                                     why, sizeof(why)) != 0) {
        fail("no COLR or no decodable base-colour image");
    } else {
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
        const int D = (int)c->dims[2];
        CHECK(W == (int)c->dims[0] && H == (int)c->dims[1] && D > 1, "image %dx%d, COLR %ux%ux%u", W, H, c->dims[0],
              c->dims[1], c->dims[2]);
        const double z = fmin(D - 1.0, fmax(0.0, w_top * D - 0.5));
        const int z0 = (int)floor(z), z1 = z0 + 1 < D ? z0 + 1 : z0;
        double worst = 0;
        for (int j = 0; j < H && W == (int)c->dims[0] && H == (int)c->dims[1]; ++j)
            for (int i = 0; i < W; ++i)
                for (int k = 0; k < 3; ++k) {
                    const double a = srgb_to_linear(colr[4 * (((size_t)z0 * H + j) * W + i) + k]);
                    const double b = srgb_to_linear(colr[4 * (((size_t)z1 * H + j) * W + i) + k]);
                    const double want = linear_to_srgb255((1 - (z - z0)) * a + (z - z0) * b);
                    worst = fmax(worst, fabs(want - px[4 * ((size_t)(H - 1 - j) * W + i) + k]));
                }
        CHECK(worst <= 1.0, "3D colour tile: worst texel %.2f/255 from the COLR at w = %g", worst, w_top);
        fprintf(stderr, "3D colour tile at w = %g: worst %.3f/255\n", w_top, worst);
    }
    free(px);
    free(colr);
    meso_file_close(f);
    glb_close(&g);
    return failures != 0;
}

int main(int argc, char** argv)
{
    if (argc == 3 && !strcmp(argv[1], "gen"))
        return gen(argv[2]);
    if (argc == 5 && !strcmp(argv[1], "tile3d"))
        return tile3d(argv[2], argv[3], atof(argv[4]));
    if (argc == 4 && !strcmp(argv[1], "check-hard-corners")) {
        hard_corners = 1;
        return check(argv[2], argv[3], 0);
    }
    if ((argc == 4 || argc == 5) && !strcmp(argv[1], "check"))
        return check(argv[2], argv[3], argc == 5 ? (uint32_t)strtoul(argv[4], NULL, 10) : 0);
    if (argc == 6 && !strcmp(argv[1], "analytic"))
        return analytic(argv[2], atof(argv[3]), atof(argv[4]), atof(argv[5]));
    fprintf(stderr, "usage: test_export_glb gen DIR | check FILE.meso FILE.glb [ID] | check-hard-corners FILE.meso FILE.glb | tile3d FILE.meso FILE.glb W | analytic FILE.glb K MAXDEG "
                    "MEANDEG\n");
    return 2;
}
