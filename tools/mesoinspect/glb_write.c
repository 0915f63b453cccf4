/*
 * glb_write.c — a glTF 2.0 binary (GLB) from plain arrays: the container
 * `mesoinspect export` writes (export.h). Specification: glTF 2.0 §4.4
 * (binary glTF layout), §3.6 (buffers, bufferViews, accessors), §3.7
 * (meshes), §3.9 (materials), §3.8 (textures, images, samplers).
 *
 * A small C writer on cJSON rather than tinygltf: the document is a dozen
 * kinds of JSON object written once, in order, with byte layout the
 * writer must control anyway (4-byte aligned views, chunk padding); C11
 * keeps all logic out of the C++ adapters (tinygltf is a C++ header whose
 * writer would need a Model built in C++), cJSON is already a dependency,
 * and the output is deterministic (no maps, no timestamps).
 *
 * Layout: the 12-byte header, the JSON chunk (padded with spaces to a
 * multiple of 4), the BIN chunk (padded with zeros). In BIN, per primitive
 * in order: positions, normals, tangents, uvs, second uvs (TEXCOORD_1),
 * vertex colours (COLOR_0, VEC3 float) (float, tightly packed),
 * indices (UNSIGNED_INT), then the PNG images; every bufferView starts at a
 * multiple of 4. POSITION accessors carry min/max (required); the other
 * accessors do not (optional). Arrays that would be empty are left out
 * (glTF forbids empty arrays). One sampler, REPEAT in s and t (shell
 * texture coordinates run past 1), linear filters with mipmaps.
 */
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "export.h"

#define GLB_MAGIC 0x46546C67u /* "glTF" */
#define GLB_CHUNK_JSON 0x4E4F534Au
#define GLB_CHUNK_BIN 0x004E4942u

enum {
    GL_FLOAT_ = 5126,
    GL_UNSIGNED_INT_ = 5125,
    GL_ARRAY_BUFFER_ = 34962,
    GL_ELEMENT_ARRAY_BUFFER_ = 34963,
    GL_LINEAR_ = 9729,
    GL_LINEAR_MIPMAP_LINEAR_ = 9987,
    GL_REPEAT_ = 10497,
};

void mi_glb_prim_free(mi_glb_prim* p)
{
    free(p->positions);
    free(p->normals);
    free(p->tangents);
    free(p->uvs);
    free(p->uvs1);
    free(p->colors);
    free(p->indices);
    free(p->color_png);
    free(p->normal_png);
    memset(p, 0, sizeof(*p));
}

/* The binary chunk being laid out, and the JSON arrays it feeds. */
typedef struct glb_state {
    uint8_t* bin;
    size_t size, cap;
    int failed; /* out of memory, or past 4 GiB */
    cJSON* views;
    cJSON* accessors;
    int view_count, accessor_count;
} glb_state;

static size_t align4(size_t n)
{
    return (n + 3u) & ~(size_t)3u;
}

/* Append `n` bytes as a new bufferView (target 0: none); returns its index
 * or -1. */
static int add_view(glb_state* g, const void* data, size_t n, int target)
{
    if (g->failed)
        return -1;
    const size_t at = align4(g->size);
    if (n > UINT32_MAX || at > UINT32_MAX - n) {
        g->failed = 2;
        return -1;
    }
    if (at + n > g->cap) {
        size_t cap = g->cap ? g->cap : 4096;
        while (cap < at + n)
            cap *= 2;
        uint8_t* b = realloc(g->bin, cap);
        if (!b) {
            g->failed = 1;
            return -1;
        }
        g->bin = b;
        g->cap = cap;
    }
    memset(g->bin + g->size, 0, at - g->size);
    memcpy(g->bin + at, data, n);
    g->size = at + n;
    cJSON* v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    if (at)
        cJSON_AddNumberToObject(v, "byteOffset", (double)at);
    cJSON_AddNumberToObject(v, "byteLength", (double)n);
    if (target)
        cJSON_AddNumberToObject(v, "target", target);
    cJSON_AddItemToArray(g->views, v);
    return g->view_count++;
}

/* A tightly packed accessor over a new view; `lo`/`hi` (components each)
 * become min/max when given. Returns the accessor index or -1. */
static int add_accessor(glb_state* g, const void* data, uint32_t count, int components, int component_type,
                        int target, const float* lo, const float* hi)
{
    static const char* const types[5] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    const int view = add_view(g, data, (size_t)count * (size_t)components * 4u, target);
    if (view < 0)
        return -1;
    cJSON* a = cJSON_CreateObject();
    cJSON_AddNumberToObject(a, "bufferView", view);
    cJSON_AddNumberToObject(a, "componentType", component_type);
    cJSON_AddNumberToObject(a, "count", count);
    cJSON_AddStringToObject(a, "type", types[components]);
    if (lo && hi) {
        cJSON* mn = cJSON_AddArrayToObject(a, "min");
        cJSON* mx = cJSON_AddArrayToObject(a, "max");
        for (int k = 0; k < components; ++k) {
            cJSON_AddItemToArray(mn, cJSON_CreateNumber((double)lo[k]));
            cJSON_AddItemToArray(mx, cJSON_CreateNumber((double)hi[k]));
        }
    }
    cJSON_AddItemToArray(g->accessors, a);
    return g->accessor_count++;
}

/* A PNG as a new image (on a new view) and texture on sampler 0; returns
 * the textureInfo that refers to it. */
static cJSON* add_texture(glb_state* g, cJSON* images, cJSON* textures, const uint8_t* png, size_t size)
{
    cJSON* img = cJSON_CreateObject();
    cJSON_AddNumberToObject(img, "bufferView", add_view(g, png, size, 0));
    cJSON_AddStringToObject(img, "mimeType", "image/png");
    cJSON_AddItemToArray(images, img);
    cJSON* tex = cJSON_CreateObject();
    cJSON_AddNumberToObject(tex, "sampler", 0);
    cJSON_AddNumberToObject(tex, "source", cJSON_GetArraySize(images) - 1);
    cJSON_AddItemToArray(textures, tex);
    cJSON* info = cJSON_CreateObject();
    cJSON_AddNumberToObject(info, "index", cJSON_GetArraySize(textures) - 1);
    return info;
}

static void put32(uint8_t* p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static meso_result fail(meso_error* err, meso_result r, const char* msg)
{
    if (err) {
        memset(err, 0, sizeof(*err));
        err->result = r;
        err->code = r == MESO_ERR_OUT_OF_MEMORY ? MESO_ISSUE_API_MEMORY : MESO_ISSUE_API_TOO_LARGE;
        err->offset = UINT64_MAX;
        err->chunk = -1;
        snprintf(err->message, sizeof(err->message), "%s", msg);
    }
    return r;
}

meso_result mi_glb_write(const mi_glb_prim* prims, uint32_t count, const char* generator, uint8_t** out, size_t* size,
                         meso_error* err)
{
    *out = NULL;
    *size = 0;
    glb_state g;
    memset(&g, 0, sizeof(g));
    cJSON* doc = cJSON_CreateObject();
    cJSON* asset = cJSON_AddObjectToObject(doc, "asset");
    cJSON_AddStringToObject(asset, "generator", generator);
    cJSON_AddStringToObject(asset, "version", "2.0");
    cJSON_AddNumberToObject(doc, "scene", 0);
    cJSON* scene = cJSON_CreateObject();
    cJSON_AddItemToArray(cJSON_AddArrayToObject(doc, "scenes"), scene);
    cJSON* scene_nodes = cJSON_AddArrayToObject(scene, "nodes");
    cJSON* nodes = cJSON_CreateArray();
    cJSON* meshes = cJSON_CreateArray();
    cJSON* materials = cJSON_CreateArray();
    cJSON* textures = cJSON_CreateArray();
    cJSON* images = cJSON_CreateArray();
    g.accessors = cJSON_CreateArray();
    g.views = cJSON_CreateArray();
    int mesh_count = 0;
    for (uint32_t i = 0; i < count && !g.failed; ++i) {
        const mi_glb_prim* p = &prims[i];
        cJSON_AddItemToArray(scene_nodes, cJSON_CreateNumber(i));
        cJSON* node = cJSON_CreateObject();
        cJSON_AddStringToObject(node, "name", p->name);
        cJSON_AddItemToArray(nodes, node);
        if (p->vertex_count == 0)
            continue; /* nothing to draw: a node without a mesh */
        cJSON_AddNumberToObject(node, "mesh", mesh_count++);
        float lo[3], hi[3];
        for (int k = 0; k < 3; ++k) {
            lo[k] = p->positions[k];
            hi[k] = p->positions[k];
        }
        for (uint32_t v = 1; v < p->vertex_count; ++v)
            for (int k = 0; k < 3; ++k) {
                const float x = p->positions[3 * (size_t)v + (size_t)k];
                lo[k] = x < lo[k] ? x : lo[k];
                hi[k] = x > hi[k] ? x : hi[k];
            }
        cJSON* prim = cJSON_CreateObject();
        cJSON* attr = cJSON_AddObjectToObject(prim, "attributes");
        cJSON_AddNumberToObject(attr, "POSITION",
                                add_accessor(&g, p->positions, p->vertex_count, 3, GL_FLOAT_, GL_ARRAY_BUFFER_, lo, hi));
        if (p->normals)
            cJSON_AddNumberToObject(attr, "NORMAL",
                                    add_accessor(&g, p->normals, p->vertex_count, 3, GL_FLOAT_, GL_ARRAY_BUFFER_, NULL, NULL));
        if (p->tangents && p->normals)
            cJSON_AddNumberToObject(attr, "TANGENT", add_accessor(&g, p->tangents, p->vertex_count, 4, GL_FLOAT_,
                                                                  GL_ARRAY_BUFFER_, NULL, NULL));
        if (p->uvs)
            cJSON_AddNumberToObject(attr, "TEXCOORD_0",
                                    add_accessor(&g, p->uvs, p->vertex_count, 2, GL_FLOAT_, GL_ARRAY_BUFFER_, NULL, NULL));
        if (p->uvs1)
            cJSON_AddNumberToObject(attr, "TEXCOORD_1",
                                    add_accessor(&g, p->uvs1, p->vertex_count, 2, GL_FLOAT_, GL_ARRAY_BUFFER_, NULL, NULL));
        if (p->colors)
            cJSON_AddNumberToObject(attr, "COLOR_0", add_accessor(&g, p->colors, p->vertex_count, 3, GL_FLOAT_,
                                                                  GL_ARRAY_BUFFER_, NULL, NULL));
        if (p->index_count)
            cJSON_AddNumberToObject(prim, "indices", add_accessor(&g, p->indices, p->index_count, 1, GL_UNSIGNED_INT_,
                                                                  GL_ELEMENT_ARRAY_BUFFER_, NULL, NULL));
        cJSON_AddNumberToObject(prim, "material", cJSON_GetArraySize(materials));
        cJSON_AddNumberToObject(prim, "mode", p->index_count ? 4 : 0);
        cJSON* mesh = cJSON_CreateObject();
        cJSON_AddStringToObject(mesh, "name", p->name);
        cJSON_AddItemToArray(cJSON_AddArrayToObject(mesh, "primitives"), prim);
        cJSON_AddItemToArray(meshes, mesh);

        cJSON* mat = cJSON_CreateObject();
        cJSON_AddStringToObject(mat, "name", p->name);
        cJSON* pbr = cJSON_AddObjectToObject(mat, "pbrMetallicRoughness");
        cJSON* bcf = cJSON_AddArrayToObject(pbr, "baseColorFactor");
        for (int k = 0; k < 4; ++k)
            cJSON_AddItemToArray(bcf, cJSON_CreateNumber((double)p->base_color[k]));
        if (p->color_png) {
            cJSON* info = add_texture(&g, images, textures, p->color_png, p->color_png_size);
            if (p->color_texcoord == 1 && p->uvs1)
                cJSON_AddNumberToObject(info, "texCoord", 1);
            cJSON_AddItemToObject(pbr, "baseColorTexture", info);
        }
        /* Lambertian look, as libmeso shades: no metal, fully rough. */
        cJSON_AddNumberToObject(pbr, "metallicFactor", 0);
        cJSON_AddNumberToObject(pbr, "roughnessFactor", 1);
        if (p->normal_png && p->tangents && p->normals && p->uvs)
            cJSON_AddItemToObject(mat, "normalTexture",
                                  add_texture(&g, images, textures, p->normal_png, p->normal_png_size));
        cJSON_AddItemToArray(materials, mat);
    }
    cJSON_AddItemToObject(doc, "nodes", nodes);
    /* glTF forbids empty arrays: leave out what nothing uses. */
    cJSON_AddItemToObject(doc, "meshes", meshes);
    cJSON_AddItemToObject(doc, "materials", materials);
    if (cJSON_GetArraySize(textures)) {
        cJSON_AddItemToObject(doc, "textures", textures);
        cJSON_AddItemToObject(doc, "images", images);
        cJSON* sampler = cJSON_CreateObject();
        cJSON_AddNumberToObject(sampler, "magFilter", GL_LINEAR_);
        cJSON_AddNumberToObject(sampler, "minFilter", GL_LINEAR_MIPMAP_LINEAR_);
        cJSON_AddNumberToObject(sampler, "wrapS", GL_REPEAT_);
        cJSON_AddNumberToObject(sampler, "wrapT", GL_REPEAT_);
        cJSON_AddItemToArray(cJSON_AddArrayToObject(doc, "samplers"), sampler);
    } else {
        cJSON_Delete(textures);
        cJSON_Delete(images);
    }
    cJSON_AddItemToObject(doc, "accessors", g.accessors);
    cJSON_AddItemToObject(doc, "bufferViews", g.views);
    cJSON* buffer = cJSON_CreateObject();
    cJSON_AddNumberToObject(buffer, "byteLength", (double)g.size);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(doc, "buffers"), buffer);
    if (mesh_count == 0) {
        cJSON_DeleteItemFromObject(doc, "meshes");
        cJSON_DeleteItemFromObject(doc, "materials");
        cJSON_DeleteItemFromObject(doc, "accessors");
        cJSON_DeleteItemFromObject(doc, "bufferViews");
        cJSON_DeleteItemFromObject(doc, "buffers");
    }
    meso_result r = MESO_OK;
    char* json = g.failed ? NULL : cJSON_PrintUnformatted(doc);
    cJSON_Delete(doc);
    if (g.failed == 2) {
        r = fail(err, MESO_ERR_UNSUPPORTED, "the glTF buffer would pass 4 GiB, the most a GLB chunk holds");
    } else if (!json) {
        r = fail(err, MESO_ERR_OUT_OF_MEMORY, "out of memory writing the glTF document");
    } else {
        const size_t jlen = strlen(json), jpad = align4(jlen), bpad = align4(g.size);
        const size_t total = 12 + 8 + jpad + (g.size ? 8 + bpad : 0);
        uint8_t* buf = total <= UINT32_MAX ? malloc(total) : NULL;
        if (total > UINT32_MAX) {
            r = fail(err, MESO_ERR_UNSUPPORTED, "the glTF file would pass 4 GiB, the most a GLB holds");
        } else if (!buf) {
            r = fail(err, MESO_ERR_OUT_OF_MEMORY, "out of memory writing the glTF file");
        } else {
            put32(buf, GLB_MAGIC);
            put32(buf + 4, 2);
            put32(buf + 8, (uint32_t)total);
            put32(buf + 12, (uint32_t)jpad);
            put32(buf + 16, GLB_CHUNK_JSON);
            memcpy(buf + 20, json, jlen);
            memset(buf + 20 + jlen, ' ', jpad - jlen);
            if (g.size) {
                uint8_t* b = buf + 20 + jpad;
                put32(b, (uint32_t)bpad);
                put32(b + 4, GLB_CHUNK_BIN);
                memcpy(b + 8, g.bin, g.size);
                memset(b + 8 + g.size, 0, bpad - g.size);
            }
            *out = buf;
            *size = total;
        }
    }
    if (g.failed == 1)
        r = fail(err, MESO_ERR_OUT_OF_MEMORY, "out of memory laying out the glTF buffer");
    cJSON_free(json);
    free(g.bin);
    return r;
}
