// export_tinygltf.cpp — tinygltf's own GLB parser behind extern "C", for
// test_export_glb.c: an independent reader of what `mesoinspect export`
// writes (no meso code involved). Thin on purpose: load, copy out the
// warnings, errors and the decoded pixels (stb_image inside Debian's
// libtinygltf) of material 0's two textures.
#include <tiny_gltf.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include "export_tinygltf.h"

namespace {

void copy_text(const std::string& s, char* dst, size_t n)
{
    if (!n)
        return;
    std::snprintf(dst, n, "%s", s.c_str());
}

void copy_image(const tinygltf::Model& m, int texture, tg_image* out)
{
    std::memset(out, 0, sizeof(*out));
    if (texture < 0 || texture >= static_cast<int>(m.textures.size()))
        return;
    const int source = m.textures[static_cast<size_t>(texture)].source;
    if (source < 0 || source >= static_cast<int>(m.images.size()))
        return;
    const tinygltf::Image& im = m.images[static_cast<size_t>(source)];
    if (im.bits != 8 || im.image.empty())
        return;
    out->pixels = static_cast<unsigned char*>(std::malloc(im.image.size()));
    if (!out->pixels)
        return;
    std::memcpy(out->pixels, im.image.data(), im.image.size());
    out->width = im.width;
    out->height = im.height;
    out->components = im.component;
}

} // namespace

extern "C" int tg_load(const char* path, char* warn, size_t warn_size, char* err, size_t err_size, int* node_count,
                       tg_image* normal0, tg_image* color0)
{
    std::memset(normal0, 0, sizeof(*normal0));
    std::memset(color0, 0, sizeof(*color0));
    *node_count = 0;
    try {
        tinygltf::TinyGLTF loader;
        tinygltf::Model model;
        std::string e, w;
        const bool ok = loader.LoadBinaryFromFile(&model, &e, &w, path);
        copy_text(w, warn, warn_size);
        copy_text(e, err, err_size);
        if (!ok)
            return 0;
        *node_count = static_cast<int>(model.nodes.size());
        if (!model.materials.empty()) {
            const tinygltf::Material& mat = model.materials[0];
            copy_image(model, mat.normalTexture.index, normal0);
            copy_image(model, mat.pbrMetallicRoughness.baseColorTexture.index, color0);
        }
        return 1;
    } catch (const std::exception& ex) {
        copy_text(ex.what(), err, err_size);
        return 0;
    } catch (...) {
        copy_text("unknown exception", err, err_size);
        return 0;
    }
}
