// gltf_adapter.cpp — tinygltf behind extern "C": a glTF 2.0 document (.gltf
// with external or data: URI buffers, .glb) parsed into gltf_model.h's plain
// arrays, unchecked. Debian's libtinygltf parses the JSON and decodes the
// images with its stb_image (PNG, JPEG). Files are read through our own
// callbacks: no path expansion, each file and their sum bounded by the
// memory budget (code 3201, as the mesh guard). Every check of what the
// document says is C (gltf_scene.c).
//
// libdraco exports a tinygltf of its own (another version, another class
// layout); whichever library is linked first provides every tinygltf symbol
// (bake/meson.build links libtinygltf first). tinygltf_is_ours refuses to run
// on Draco's instead of corrupting the heap.
#include <tiny_gltf.h>

#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <sys/stat.h>
#include <vector>

#include "adapters.h"
#include "mesh_guard.h"

namespace {

struct ReadContext {
    uint64_t max_bytes;
    uint64_t total = 0;
    bool over_budget = false;
    std::string missing; // the first file that could not be read
};

struct Holder {
    tinygltf::Model model;
    std::vector<meso_gltf_buffer> buffers;
    std::vector<meso_gltf_view> views;
    std::vector<meso_gltf_accessor> accessors;
    std::vector<meso_gltf_primitive> primitives;
    std::vector<meso_gltf_mesh> meshes;
    std::vector<meso_gltf_node> nodes;
    std::vector<int> children;
    std::vector<meso_gltf_scene> scenes;
    std::vector<int> scene_nodes;
    std::vector<meso_gltf_material> materials;
    std::vector<int> texture_sources;
    std::vector<meso_gltf_image> images;
    std::string unsupported;
};

bool file_exists(const std::string& path, void*)
{
    struct stat st;
    return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

std::string keep_path(const std::string& path, void*)
{
    return path; // no ~ or $VAR expansion: a URI names a file beside the document
}

bool read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user)
{
    ReadContext* ctx = static_cast<ReadContext*>(user);
    FILE* f = std::fopen(path.c_str(), "rb");
    struct stat st;
    if (!f || fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
        if (f)
            std::fclose(f);
        if (ctx->missing.empty())
            ctx->missing = path;
        if (err)
            *err += "cannot read " + path + "\n";
        return false;
    }
    const uint64_t size = static_cast<uint64_t>(st.st_size);
    if (size > ctx->max_bytes || ctx->total + size > ctx->max_bytes) {
        std::fclose(f);
        ctx->over_budget = true;
        return false;
    }
    ctx->total += size;
    out->resize(static_cast<size_t>(size));
    const bool ok = size == 0 || std::fread(out->data(), 1, out->size(), f) == out->size();
    std::fclose(f);
    if (!ok && ctx->missing.empty())
        ctx->missing = path;
    return ok;
}

bool write_file(std::string* err, const std::string&, const std::vector<unsigned char>&, void*)
{
    if (err)
        *err += "writing is not allowed\n";
    return false;
}

// Width and height from a PNG's IHDR or a JPEG's first SOF marker (the two
// image formats of glTF 2.0 core); false for anything else or a truncated
// header.
bool image_size(const unsigned char* b, size_t n, uint64_t* w, uint64_t* h)
{
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (n >= 24 && std::memcmp(b, png, 8) == 0 && std::memcmp(b + 12, "IHDR", 4) == 0) {
        *w = (uint64_t)b[16] << 24 | (uint64_t)b[17] << 16 | (uint64_t)b[18] << 8 | b[19];
        *h = (uint64_t)b[20] << 24 | (uint64_t)b[21] << 16 | (uint64_t)b[22] << 8 | b[23];
        return true;
    }
    if (n < 4 || b[0] != 0xff || b[1] != 0xd8)
        return false;
    for (size_t i = 2; i + 9 < n;) {
        if (b[i] != 0xff)
            return false;
        const unsigned char m = b[i + 1];
        if (m == 0xff) { // fill byte
            ++i;
            continue;
        }
        const size_t len = (size_t)b[i + 2] << 8 | b[i + 3];
        // SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC)
        if (m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc) {
            *h = (uint64_t)b[i + 5] << 8 | b[i + 6];
            *w = (uint64_t)b[i + 7] << 8 | b[i + 8];
            return true;
        }
        if (len < 2)
            return false;
        i += 2 + len;
    }
    return false;
}

// A texture that does not decode leaves its image empty (width 0): only a
// base-colour texture in use is an error, and gltf_scene.c reports it. An
// image is decoded only when its header says what it is and its RGBA8
// pixels (counted as 16-bit RGBA) fit in what the memory budget has left (the budget counts them):
// a 200 KB PNG of 8000 x 8000 would otherwise take 256 MB before any check.
bool load_image(tinygltf::Image* image, const int index, std::string* err, std::string* warn, int req_width,
                int req_height, const unsigned char* bytes, int size, void* user)
{
    ReadContext* ctx = static_cast<ReadContext*>(user);
    uint64_t w = 0, h = 0;
    const bool known = size > 0 && image_size(bytes, static_cast<size_t>(size), &w, &h);
    const uint64_t need = w * h * 8; // up to 16-bit RGBA; w, h < 2^32: no overflow
    std::string ignored;
    if (!known || need > ctx->max_bytes - ctx->total ||
        !tinygltf::LoadImageData(image, index, &ignored, warn, req_width, req_height, bytes, size, nullptr)) {
        image->width = image->height = image->component = image->bits = 0;
        image->image.clear();
    } else {
        ctx->total += need;
    }
    (void)err;
    return true;
}

int components_of(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
    }
}

int attribute(const tinygltf::Primitive& p, const char* name)
{
    auto it = p.attributes.find(name);
    return it == p.attributes.end() ? -1 : it->second;
}

// KHR_draco_mesh_compression: {bufferView, attributes: {POSITION, TEXCOORD_0}};
// draco_view -2 when the extension object is malformed.
void read_draco(const tinygltf::Primitive& p, meso_gltf_primitive* out)
{
    out->draco_view = -1;
    out->draco_position = out->draco_texcoord = -1;
    auto it = p.extensions.find("KHR_draco_mesh_compression");
    if (it == p.extensions.end())
        return;
    const tinygltf::Value& v = it->second;
    const tinygltf::Value& view = v.Get("bufferView");
    const tinygltf::Value& attrs = v.Get("attributes");
    if (!v.IsObject() || !view.IsNumber() || !attrs.IsObject()) {
        out->draco_view = -2;
        return;
    }
    out->draco_view = view.GetNumberAsInt();
    if (attrs.Has("POSITION"))
        out->draco_position = attrs.Get("POSITION").IsNumber() ? attrs.Get("POSITION").GetNumberAsInt() : -2;
    if (attrs.Has("TEXCOORD_0"))
        out->draco_texcoord = attrs.Get("TEXCOORD_0").IsNumber() ? attrs.Get("TEXCOORD_0").GetNumberAsInt() : -2;
}

void copy_model(Holder& h)
{
    const tinygltf::Model& m = h.model;
    for (const tinygltf::Buffer& b : m.buffers)
        h.buffers.push_back({b.data.empty() ? nullptr : b.data.data(), b.data.size(), b.data.size()});
    for (const tinygltf::BufferView& v : m.bufferViews)
        h.views.push_back({v.buffer, v.byteOffset, v.byteLength, v.byteStride});
    for (const tinygltf::Accessor& a : m.accessors) {
        meso_gltf_accessor c;
        c.view = a.bufferView;
        c.offset = a.byteOffset;
        c.component_type = a.componentType;
        c.components = components_of(a.type);
        c.is_matrix = a.type == TINYGLTF_TYPE_MAT2 || a.type == TINYGLTF_TYPE_MAT3 || a.type == TINYGLTF_TYPE_MAT4;
        c.count = a.count;
        c.normalized = a.normalized;
        c.sparse = a.sparse.isSparse;
        h.accessors.push_back(c);
    }
    for (const tinygltf::Mesh& me : m.meshes) {
        h.meshes.push_back({me.name.c_str(), static_cast<uint32_t>(h.primitives.size()),
                            static_cast<uint32_t>(me.primitives.size())});
        for (const tinygltf::Primitive& p : me.primitives) {
            meso_gltf_primitive c;
            c.mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
            c.indices = p.indices;
            c.position = attribute(p, "POSITION");
            c.texcoord = attribute(p, "TEXCOORD_0");
            c.material = p.material;
            read_draco(p, &c);
            h.primitives.push_back(c);
        }
    }
    for (const tinygltf::Node& n : m.nodes) {
        meso_gltf_node c;
        std::memset(&c, 0, sizeof(c));
        c.name = n.name.c_str();
        c.mesh = n.mesh;
        c.has_matrix = n.matrix.size() == 16;
        for (size_t i = 0; c.has_matrix && i < 16; ++i)
            c.matrix[i] = n.matrix[i];
        c.rotation[3] = 1.0;
        c.scale[0] = c.scale[1] = c.scale[2] = 1.0;
        for (size_t i = 0; n.translation.size() == 3 && i < 3; ++i)
            c.translation[i] = n.translation[i];
        for (size_t i = 0; n.rotation.size() == 4 && i < 4; ++i)
            c.rotation[i] = n.rotation[i];
        for (size_t i = 0; n.scale.size() == 3 && i < 3; ++i)
            c.scale[i] = n.scale[i];
        c.first_child = static_cast<uint32_t>(h.children.size());
        c.child_count = static_cast<uint32_t>(n.children.size());
        h.children.insert(h.children.end(), n.children.begin(), n.children.end());
        h.nodes.push_back(c);
    }
    for (const tinygltf::Scene& s : m.scenes) {
        h.scenes.push_back({static_cast<uint32_t>(h.scene_nodes.size()), static_cast<uint32_t>(s.nodes.size())});
        h.scene_nodes.insert(h.scene_nodes.end(), s.nodes.begin(), s.nodes.end());
    }
    for (const tinygltf::Material& mat : m.materials) {
        meso_gltf_material c;
        const std::vector<double>& f = mat.pbrMetallicRoughness.baseColorFactor;
        for (size_t i = 0; i < 4; ++i)
            c.base_color_factor[i] = f.size() == 4 ? f[i] : 1.0;
        c.base_color_texture = mat.pbrMetallicRoughness.baseColorTexture.index;
        c.base_color_texcoord = mat.pbrMetallicRoughness.baseColorTexture.texCoord;
        h.materials.push_back(c);
    }
    for (const tinygltf::Texture& t : m.textures)
        h.texture_sources.push_back(t.source);
    for (const tinygltf::Image& im : m.images)
        h.images.push_back({im.width, im.height, im.component, im.bits, im.image.empty() ? nullptr : im.image.data(),
                            im.image.size()});
    for (const std::string& e : m.extensionsRequired)
        if (e != "KHR_draco_mesh_compression" && h.unsupported.empty())
            h.unsupported = e;
}

template <typename T> T* data_of(std::vector<T>& v)
{
    return v.empty() ? nullptr : v.data();
}

void fill(Holder& h, meso_gltf_model* out)
{
    out->buffers = data_of(h.buffers);
    out->views = data_of(h.views);
    out->accessors = data_of(h.accessors);
    out->primitives = data_of(h.primitives);
    out->meshes = data_of(h.meshes);
    out->nodes = data_of(h.nodes);
    out->children = data_of(h.children);
    out->scenes = data_of(h.scenes);
    out->scene_nodes = data_of(h.scene_nodes);
    out->materials = data_of(h.materials);
    out->texture_sources = data_of(h.texture_sources);
    out->images = data_of(h.images);
    out->buffer_count = static_cast<uint32_t>(h.buffers.size());
    out->view_count = static_cast<uint32_t>(h.views.size());
    out->accessor_count = static_cast<uint32_t>(h.accessors.size());
    out->primitive_count = static_cast<uint32_t>(h.primitives.size());
    out->mesh_count = static_cast<uint32_t>(h.meshes.size());
    out->node_count = static_cast<uint32_t>(h.nodes.size());
    out->child_count = static_cast<uint32_t>(h.children.size());
    out->scene_count = static_cast<uint32_t>(h.scenes.size());
    out->scene_node_count = static_cast<uint32_t>(h.scene_nodes.size());
    out->material_count = static_cast<uint32_t>(h.materials.size());
    out->texture_count = static_cast<uint32_t>(h.texture_sources.size());
    out->image_count = static_cast<uint32_t>(h.images.size());
    out->default_scene = h.model.defaultScene;
    out->unsupported_extension = h.unsupported.empty() ? nullptr : h.unsupported.c_str();
    out->handle = &h;
}

// tinygltf's message, one line, without its trailing newline.
std::string one_line(std::string s)
{
    for (char& c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    while (!s.empty() && s.back() == ' ')
        s.pop_back();
    return s.empty() ? std::string("not a glTF document") : s;
}

// 1 when tinygltf's functions resolved to libtinygltf, not libdraco's copy.
bool tinygltf_is_ours()
{
    Dl_info info;
    void* f = reinterpret_cast<void*>(&tinygltf::LoadImageData);
    return !(dladdr(f, &info) && info.dli_fname && std::strstr(info.dli_fname, "libdraco"));
}

} // namespace

extern "C" meso_result meso_gltf_read(const char* path, uint64_t max_bytes, meso_gltf_model* out, meso_error* err)
{
    std::memset(out, 0, sizeof(*out));
    if (max_bytes == 0)
        max_bytes = MESO_MESH_GUARD_DEFAULT_MAX_BYTES;
    if (!tinygltf_is_ours())
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                              "%s: this build resolved tinygltf to libdraco's copy (link libtinygltf first)", path);
    Holder* h = nullptr;
    try {
        ReadContext ctx;
        ctx.max_bytes = max_bytes;
        std::vector<unsigned char> bytes;
        std::string msg;
        if (!read_file(&bytes, &msg, path, &ctx)) {
            if (ctx.over_budget)
                return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_MESH_GUARD_BUDGET,
                                      "%s: larger than the memory budget (%llu bytes)", path,
                                      static_cast<unsigned long long>(max_bytes));
            return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot read", path);
        }
        const std::string full(path);
        const size_t slash = full.find_last_of('/');
        const std::string base_dir = slash == std::string::npos ? std::string(".") : full.substr(0, slash);
        h = new Holder;
        tinygltf::TinyGLTF loader;
        tinygltf::FsCallbacks fs = {&file_exists, &keep_path, &read_file, &write_file, &ctx};
        loader.SetFsCallbacks(fs);
        loader.SetImageLoader(&load_image, &ctx);
        std::string terr, twarn;
        const bool glb = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
        const unsigned n = static_cast<unsigned>(bytes.size());
        if (bytes.size() > 0xffffffffu) {
            delete h;
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_MESH_GUARD_BUDGET, "%s: larger than 4 GiB", path);
        }
        const bool ok = glb ? loader.LoadBinaryFromMemory(&h->model, &terr, &twarn, bytes.data(), n, base_dir)
                            : loader.LoadASCIIFromString(&h->model, &terr, &twarn,
                                                         reinterpret_cast<const char*>(bytes.data()), n, base_dir);
        if (!ok) {
            delete h;
            if (ctx.over_budget)
                return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_MESH_GUARD_BUDGET,
                                      "%s: its buffers are larger than the memory budget (%llu bytes)", path,
                                      static_cast<unsigned long long>(max_bytes));
            const std::string line = one_line(terr);
            // tinygltf's messages about buffers: "... in Buffer", "... file buffer.", "File ...", external files
            const bool buffer = !ctx.missing.empty() || line.find("Buffer") != std::string::npos ||
                                line.find("buffer.") != std::string::npos || line.find("File ") != std::string::npos ||
                                line.find("external") != std::string::npos;
            if (buffer)
                return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_BUFFER, "%s: a buffer cannot be read: %s",
                                      path, line.c_str());
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_SCHEMA, "%s: not valid glTF 2.0: %s", path,
                                  line.c_str());
        }
        copy_model(*h);
        fill(*h, out);
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        delete h;
        std::memset(out, 0, sizeof(*out));
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", path);
    } catch (const std::exception& e) {
        delete h;
        std::memset(out, 0, sizeof(*out));
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_SCHEMA, "%s: not valid glTF 2.0: %s", path,
                              e.what());
    } catch (...) {
        delete h;
        std::memset(out, 0, sizeof(*out));
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_SCHEMA, "%s: not valid glTF 2.0", path);
    }
}

extern "C" void meso_gltf_model_free(meso_gltf_model* m)
{
    if (!m)
        return;
    delete static_cast<Holder*>(m->handle);
    std::memset(m, 0, sizeof(*m));
}
