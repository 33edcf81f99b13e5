// glTF 2.0 (.gltf / .glb) → bk_scene. The only C++ in lbk: tinygltf, Draco and stb_image are
// compiled into this one translation unit and only bk_import_gltf() is exported.
//
// The input is untrusted. tinygltf 2.7.0 parses JSON, buffers (data URIs, .bin files, the GLB BIN
// chunk) and materials/nodes/lights, but indexes several arrays without bounds checks, so:
//  * a pre-pass over the JSON (nlohmann) caps nesting depth, validates image bufferViews before
//    tinygltf takes a pointer into them, and takes KHR_draco_mesh_compression away from tinygltf:
//    its Draco path (TINYGLTF_ENABLE_DRACO) dereferences unchecked indices and a possibly null
//    attribute and overruns a 4-element stack array, so we decode Draco here with checks;
//  * every accessor read is bounds-checked against its bufferView and buffer here, with 64-bit
//    overflow-checked arithmetic; counts that could be derived are never trusted;
//  * file reads go through our callbacks: regular files only, size-capped, no shell expansion
//    (tinygltf's default ExpandFilePath calls wordexp);
//  * images are decoded here (stb_image, PNG/JPEG only) after a header-only size check.
// Internally errors are C++ exceptions carrying the message; bk_import_gltf catches everything.

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_NO_STDIO
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#include <stb_image.h>

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>
#include <nlohmann/json.hpp>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "scene/exr_read.h"
#include "scene/import.h"

namespace {

const int kMaxJsonDepth = 64;     // deeper JSON is refused (tinygltf converts extras recursively)
const int kMaxNodeDepth = 256;    // node hierarchy depth cap (the traversal is recursive)
const double kPi = 3.14159265358979323846;

struct ImportError {
    std::string msg;
};

std::string vfmt(const char *fmt, va_list ap)
{
    char buf[1024];
    vsnprintf(buf, sizeof buf, fmt, ap);
    return buf;
}

[[noreturn]] void fail(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
void fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    std::string m = vfmt(fmt, ap);
    va_end(ap);
    throw ImportError{m};
}

std::string qstr(const std::string &s)
{
    std::string q = "\"";
    for (char c : s.substr(0, 80)) q += (static_cast<unsigned char>(c) < 32) ? '?' : c;
    if (s.size() > 80) q += "...";
    return q + "\"";
}

// ---- files ----------------------------------------------------------------------------------

bool is_regular_file(const std::string &p, size_t *size)
{
    struct stat st;
    if (stat(p.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
    if (size) *size = static_cast<size_t>(st.st_size);
    return true;
}

bool read_capped(const std::string &p, size_t cap, std::vector<unsigned char> *out, std::string *why)
{
    size_t size = 0;
    if (!is_regular_file(p, &size)) {
        *why = "not found or not a regular file";
        return false;
    }
    if (size > cap) {
        *why = "larger than the " + std::to_string(cap) + "-byte file cap";
        return false;
    }
    FILE *f = fopen(p.c_str(), "rb");
    if (!f) {
        *why = std::string("cannot open: ") + strerror(errno);
        return false;
    }
    out->resize(size);
    size_t got = size ? fread(out->data(), 1, size, f) : 0;
    fclose(f);
    if (got != size) {
        *why = "short read";
        return false;
    }
    return true;
}

// Where a scene may read from: its own folder (symlinks resolved), plus one folder the caller
// allows. A scene from an untrusted source must not read /etc/passwd through "../../..".
struct ResourcePolicy {
    std::string root;   // realpath of the scene's folder, with a trailing '/'
    std::string allow;  // realpath of the allowed outside folder with '/', or empty
};

bool under(const std::string &real, const std::string &dir)
{
    return !dir.empty() && real.compare(0, dir.size(), dir) == 0;
}

std::string real_dir(const std::string &d)
{
    char *r = realpath(d.c_str(), nullptr);
    if (!r) return std::string();
    std::string out(r);
    free(r);
    if (out.empty() || out.back() != '/') out += '/';
    return out;
}

// True if `p` (after resolving every symlink) lies inside the policy's folders; else *why says so.
bool resource_allowed(const ResourcePolicy &pol, const std::string &p, std::string *why)
{
    char *r = realpath(p.c_str(), nullptr);
    if (!r) {
        *why = std::string("cannot open: ") + strerror(errno);
        return false;
    }
    std::string real(r);
    free(r);
    if (under(real, pol.root) || under(real, pol.allow)) return true;
    *why = "resolves to " + real + ", outside the scene's folder " + pol.root +
           " (resources must lie inside it; --allow-outside DIR permits one more folder)";
    return false;
}

// A file the import read, for provenance (META input.files, spec/container.md §6.2).
struct InputRecord {
    std::string path;  // as opened
    const char *role;  // "scene", "buffer", "image", "sky"
    uint64_t bytes, hash;
};

struct FsState {
    size_t cap;
    const ResourcePolicy *policy;
    std::vector<InputRecord> *reads;  // every file tinygltf read through us (buffers, images)
};

bool fs_exists(const std::string &p, void *) { return is_regular_file(p, nullptr); }
std::string fs_expand(const std::string &p, void *) { return p; }
bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &p, void *user)
{
    const FsState *st = static_cast<FsState *>(user);
    std::string why;
    if (resource_allowed(*st->policy, p, &why) && read_capped(p, st->cap, out, &why)) {
        st->reads->push_back(InputRecord{p, "image", out->size(), XXH3_64bits(out->data(), out->size())});
        return true;
    }
    if (err) *err += p + ": " + why;
    return false;
}
bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    if (err) *err += "writing is disabled";
    return false;
}

std::string dir_of(const std::string &path)
{
    size_t s = path.find_last_of('/');
    return s == std::string::npos ? std::string(".") : path.substr(0, s);
}

// ---- small maths (column-major 4x4 in double, as glTF) ----------------------------------------

struct Mat4 {
    double m[16];
};

Mat4 identity()
{
    Mat4 r{};
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0;
    return r;
}

Mat4 mul(const Mat4 &a, const Mat4 &b)
{
    Mat4 r{};
    for (int c = 0; c < 4; c++)
        for (int rr = 0; rr < 4; rr++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += a.m[k * 4 + rr] * b.m[c * 4 + k];
            r.m[c * 4 + rr] = s;
        }
    return r;
}

void xform_point(const Mat4 &M, const double p[3], double o[3])
{
    for (int r = 0; r < 3; r++) o[r] = M.m[r] * p[0] + M.m[4 + r] * p[1] + M.m[8 + r] * p[2] + M.m[12 + r];
}

void xform_dir(const double A[9], const double v[3], double o[3])  // A: column-major 3x3
{
    for (int r = 0; r < 3; r++) o[r] = A[r] * v[0] + A[3 + r] * v[1] + A[6 + r] * v[2];
}

void upper3(const Mat4 &M, double A[9])
{
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) A[c * 3 + r] = M.m[c * 4 + r];
}

double det3(const double A[9])
{
    return A[0] * (A[4] * A[8] - A[7] * A[5]) - A[3] * (A[1] * A[8] - A[7] * A[2]) +
           A[6] * (A[1] * A[5] - A[4] * A[2]);
}

// Inverse-transpose of A (column-major), for normals. Caller ensures det != 0.
void inverse_transpose3(const double A[9], double det, double N[9])
{
    // cofactor matrix C; inverse = C^T / det, so inverse-transpose = C / det.
    auto a = [&](int r, int c) { return A[c * 3 + r]; };
    double C[3][3];
    C[0][0] = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
    C[0][1] = -(a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0));
    C[0][2] = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
    C[1][0] = -(a(0, 1) * a(2, 2) - a(0, 2) * a(2, 1));
    C[1][1] = a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0);
    C[1][2] = -(a(0, 0) * a(2, 1) - a(0, 1) * a(2, 0));
    C[2][0] = a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1);
    C[2][1] = -(a(0, 0) * a(1, 2) - a(0, 2) * a(1, 0));
    C[2][2] = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) N[c * 3 + r] = C[r][c] / det;
}

bool normalize3(double v[3])
{
    double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 1e-30) || !std::isfinite(l)) return false;
    v[0] /= l; v[1] /= l; v[2] /= l;
    return true;
}

// ---- overflow-checked sizes -----------------------------------------------------------------

bool add_ok(uint64_t a, uint64_t b, uint64_t *r)
{
    if (a > UINT64_MAX - b) return false;
    *r = a + b;
    return true;
}
bool mul_ok(uint64_t a, uint64_t b, uint64_t *r)
{
    if (a && b > UINT64_MAX / a) return false;
    *r = a * b;
    return true;
}

// ---- the pre-pass over the JSON ---------------------------------------------------------------

struct DracoInfo {
    int buffer_view = -1;
    std::map<std::string, int> attributes;  // glTF semantic -> Draco unique id
};

struct Prepass {
    std::map<std::pair<int, int>, DracoInfo> draco;  // (mesh, primitive)
    std::vector<char> needed_images;                 // images used as base colour / emissive
    std::string json;                                // rewritten JSON handed to tinygltf
};

bool jint(const nlohmann::json &o, const char *key, long long *out)
{
    if (!o.is_object()) return false;
    auto it = o.find(key);
    if (it == o.end() || !it->is_number_integer()) return false;
    *out = it->get<long long>();
    return true;
}

const nlohmann::json *jarr(const nlohmann::json &o, const char *key)
{
    if (!o.is_object()) return nullptr;
    auto it = o.find(key);
    return (it != o.end() && it->is_array()) ? &*it : nullptr;
}

// Deepest nesting of arrays and objects in JSON text, in one linear scan (brackets inside
// strings do not count). nlohmann's callback parser would check depth for us, but it re-scans
// the open container each time an element closes, which made 80 k empty nodes take ~17 s and
// 10^6 nodes effectively never finish; the plain parser after this scan is linear.
static int json_max_depth(const char *p, size_t n)
{
    int depth = 0, deepest = 0;
    bool in_string = false;
    for (size_t i = 0; i < n; i++) {
        const char c = p[i];
        if (in_string) {
            if (c == '\\') i++;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > deepest) deepest = depth;
        } else if (c == ']' || c == '}') {
            depth--;
        }
    }
    return deepest;
}

// Buffers and images name files relative to the scene (or embed data: URIs). An absolute path
// or another URI scheme (file://, http://) would reach outside it: refuse them up front, with the
// entry named; `..` escapes and symlinks are caught when the file is opened (resource_allowed).
void check_uris(const nlohmann::json &doc, const std::string &file)
{
    for (const char *kind : {"buffers", "images"}) {
        const nlohmann::json *arr = jarr(doc, kind);
        if (!arr) continue;
        for (size_t i = 0; i < arr->size(); i++) {
            const nlohmann::json &e = (*arr)[i];
            if (!e.is_object() || !e.contains("uri") || !e["uri"].is_string()) continue;
            const std::string uri = e["uri"].get<std::string>();
            if (uri.compare(0, 5, "data:") == 0) continue;
            const size_t colon = uri.find(':'), slash = uri.find('/');
            const bool scheme = colon != std::string::npos && (slash == std::string::npos || colon < slash);
            if (uri.empty() || uri[0] == '/' || uri[0] == '\\' || scheme)
                fail("%s: %.*s %zu: uri %s is not a path relative to the scene's folder (absolute paths and "
                     "URI schemes other than data: are refused)",
                     file.c_str(), (int)strlen(kind) - 1, kind, i, qstr(uri).c_str());
        }
    }
}

Prepass prepass(const char *json_begin, size_t json_len, const std::string &file)
{
    Prepass pp;
    if (json_max_depth(json_begin, json_len) > kMaxJsonDepth)
        fail("%s: JSON nested deeper than %d levels", file.c_str(), kMaxJsonDepth);
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(json_begin, json_begin + json_len, nullptr, true);
    } catch (const nlohmann::json::exception &e) {
        fail("%s: invalid JSON: %s", file.c_str(), e.what());
    }
    if (!doc.is_object()) fail("%s: the JSON root is not an object", file.c_str());
    check_uris(doc, file);

    // Image bufferViews: tinygltf forms a pointer into the buffer before we see it.
    const nlohmann::json *buffers = jarr(doc, "buffers");
    const nlohmann::json *views = jarr(doc, "bufferViews");
    if (const nlohmann::json *images = jarr(doc, "images")) {
        for (size_t i = 0; i < images->size(); i++) {
            const nlohmann::json &im = (*images)[i];
            if (!im.is_object() || !im.contains("bufferView")) continue;
            long long bv, buf, off = 0, len, blen;
            if (!jint(im, "bufferView", &bv) || !views || bv < 0 || (size_t)bv >= views->size())
                fail("%s: image %zu: bufferView missing or out of range", file.c_str(), i);
            const nlohmann::json &v = (*views)[(size_t)bv];
            if (!jint(v, "buffer", &buf) || !buffers || buf < 0 || (size_t)buf >= buffers->size())
                fail("%s: image %zu: bufferView %lld has no valid buffer", file.c_str(), i, bv);
            if (v.contains("byteOffset") && !jint(v, "byteOffset", &off)) off = -1;
            if (!jint(v, "byteLength", &len) || !jint((*buffers)[(size_t)buf], "byteLength", &blen) ||
                off < 0 || len <= 0 || blen < 0 || off > blen || len > blen - off)
                fail("%s: image %zu: bufferView %lld lies outside buffer %lld", file.c_str(), i, bv, buf);
        }
    }

    // Textures that matter to the baker: base colour, metallic-roughness and emissive.
    {
        const nlohmann::json *images = jarr(doc, "images");
        const nlohmann::json *textures = jarr(doc, "textures");
        const nlohmann::json *materials = jarr(doc, "materials");
        pp.needed_images.assign(images ? images->size() : 0, 0);
        auto need = [&](const nlohmann::json &info) {
            long long t, src;
            if (!textures || !jint(info, "index", &t) || t < 0 || (size_t)t >= textures->size()) return;
            if (jint((*textures)[(size_t)t], "source", &src) && src >= 0 &&
                (size_t)src < pp.needed_images.size())
                pp.needed_images[(size_t)src] = 1;
        };
        if (materials)
            for (const auto &m : *materials) {
                if (!m.is_object()) continue;
                auto pbr = m.find("pbrMetallicRoughness");
                if (pbr != m.end() && pbr->is_object() && pbr->contains("baseColorTexture"))
                    need((*pbr)["baseColorTexture"]);
                if (pbr != m.end() && pbr->is_object() && pbr->contains("metallicRoughnessTexture"))
                    need((*pbr)["metallicRoughnessTexture"]);
                if (m.contains("emissiveTexture")) need(m["emissiveTexture"]);
            }
    }

    // Draco: remember what to decode and hide the primitive's indices from tinygltf (whose
    // non-Draco build refuses an index accessor without a bufferView).
    if (doc.contains("meshes") && doc["meshes"].is_array()) {
        nlohmann::json &meshes = doc["meshes"];
        for (size_t mi = 0; mi < meshes.size(); mi++) {
            nlohmann::json &mesh = meshes[mi];
            if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
            nlohmann::json &prims = mesh["primitives"];
            for (size_t pi = 0; pi < prims.size(); pi++) {
                nlohmann::json &prim = prims[pi];
                if (!prim.is_object() || !prim.contains("extensions") || !prim["extensions"].is_object())
                    continue;
                auto ext = prim["extensions"].find("KHR_draco_mesh_compression");
                if (ext == prim["extensions"].end()) continue;
                DracoInfo di;
                long long bv;
                if (!ext->is_object() || !jint(*ext, "bufferView", &bv) || bv < 0 || bv > INT32_MAX ||
                    !ext->contains("attributes") || !(*ext)["attributes"].is_object())
                    fail("%s: mesh %zu primitive %zu: KHR_draco_mesh_compression needs an integer "
                         "bufferView and an attributes object", file.c_str(), mi, pi);
                di.buffer_view = (int)bv;
                for (auto it = (*ext)["attributes"].begin(); it != (*ext)["attributes"].end(); ++it) {
                    if (!it->is_number_integer() || it->get<long long>() < 0 || it->get<long long>() > INT32_MAX)
                        fail("%s: mesh %zu primitive %zu: Draco attribute %s is not a valid id",
                             file.c_str(), mi, pi, qstr(it.key()).c_str());
                    di.attributes[it.key()] = (int)it->get<long long>();
                }
                pp.draco[{(int)mi, (int)pi}] = di;
                prim.erase("indices");
            }
        }
    }
    pp.json = doc.dump();
    return pp;
}

// ---- GLB container ----------------------------------------------------------------------------

uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

void put32(std::vector<unsigned char> &v, uint32_t x)
{
    for (int i = 0; i < 4; i++) v.push_back((unsigned char)(x >> (8 * i)));
}

struct GlbParts {
    const char *json = nullptr;
    size_t json_len = 0;
    const unsigned char *bin = nullptr;
    size_t bin_len = 0;
};

GlbParts split_glb(const std::vector<unsigned char> &f, const std::string &file)
{
    GlbParts g;
    if (f.size() < 20) fail("%s: truncated GLB (%zu bytes, the header alone is 20)", file.c_str(), f.size());
    uint32_t version = le32(&f[4]), length = le32(&f[8]);
    if (version != 2) fail("%s: GLB version %u (only 2 is supported)", file.c_str(), version);
    if (length > f.size()) fail("%s: truncated GLB: header says %u bytes, file has %zu", file.c_str(), length, f.size());
    if (length < 20) fail("%s: GLB length %u is too small", file.c_str(), length);
    uint32_t jlen = le32(&f[12]), jtype = le32(&f[16]);
    if (jtype != 0x4E4F534Au) fail("%s: the first GLB chunk is not JSON", file.c_str());
    if ((uint64_t)jlen + 20 > length || jlen == 0) fail("%s: truncated GLB: JSON chunk of %u bytes does not fit", file.c_str(), jlen);
    g.json = reinterpret_cast<const char *>(&f[20]);
    g.json_len = jlen;
    uint64_t pos = 20ull + jlen;
    pos = (pos + 3) & ~3ull;  // chunks start 4-byte aligned
    if (pos + 8 <= length) {
        uint32_t blen = le32(&f[pos]), btype = le32(&f[pos + 4]);
        if (btype == 0x004E4942u) {
            if (pos + 8 + blen > length)
                fail("%s: truncated GLB: BIN chunk of %u bytes does not fit", file.c_str(), blen);
            g.bin = &f[pos + 8];
            g.bin_len = blen;
        }
    }
    return g;
}

std::vector<unsigned char> make_glb(const std::string &json_text, const GlbParts &g)
{
    std::vector<unsigned char> out;
    size_t jpad = (json_text.size() + 3) & ~(size_t)3;
    size_t bpad = (g.bin_len + 3) & ~(size_t)3;
    size_t total = 12 + 8 + jpad + (g.bin ? 8 + bpad : 0);
    out.reserve(total);
    out.insert(out.end(), {'g', 'l', 'T', 'F'});
    put32(out, 2);
    put32(out, (uint32_t)total);
    put32(out, (uint32_t)jpad);
    put32(out, 0x4E4F534Au);
    out.insert(out.end(), json_text.begin(), json_text.end());
    out.insert(out.end(), jpad - json_text.size(), ' ');
    if (g.bin) {
        put32(out, (uint32_t)bpad);
        put32(out, 0x004E4942u);
        out.insert(out.end(), g.bin, g.bin + g.bin_len);
        out.insert(out.end(), bpad - g.bin_len, 0);
    }
    return out;
}

// ---- image loading (tinygltf callback keeps the encoded bytes; we decode later) -----------------

struct ImageLoaderCtx {
    const std::vector<char> *needed;
    bool skip;
};

bool keep_encoded_image(tinygltf::Image *image, const int idx, std::string *, std::string *, int, int,
                        const unsigned char *bytes, int size, void *user)
{
    const ImageLoaderCtx *ctx = static_cast<const ImageLoaderCtx *>(user);
    // bufferView images are read later from the validated view; tinygltf's pointer is not used.
    if (ctx->skip || image->bufferView >= 0) return true;
    if (idx < 0 || (size_t)idx >= ctx->needed->size() || !(*ctx->needed)[(size_t)idx]) return true;
    if (bytes && size > 0) image->image.assign(bytes, bytes + size);
    return true;
}

// ---- the importer -----------------------------------------------------------------------------

struct Prim {  // one triangle primitive, in mesh-local space, ready to instance
    std::vector<float> pos, nrm, uv0, uv1;
    std::vector<uint32_t> tris;
    std::vector<uint32_t> src;     // per vertex: its index in the glTF primitive (flat shading splits them)
    bool has_nrm = false, has_uv1 = false;
    uint32_t material = 0;
    uint32_t gltf_index = 0;       // index in the glTF mesh's primitives
    uint32_t source_vertices = 0;  // vertices of the glTF primitive (POSITION count or Draco points)
};

struct MeshData {
    bool ready = false;
    std::vector<Prim> prims;
    uint64_t hash = 0;
    bool all_uv1 = true;
    size_t vertices = 0, triangles = 0;
};

struct Instance {
    int node;
    Mat4 world;
    std::string light_set, door;
    int lighting = BK_LIGHTING_AUTO;
    float texel_density = 0;
};

struct PlayableBox {  // world space, double (the origin is chosen later)
    double min[3], max[3];
};

struct LightInstance {
    int node, light;
    Mat4 world;
    std::string light_set;
};

class Importer {
public:
    Importer(const char *path, const bk_import_options &o, bk_scene *out) : path_(path), o_(o), s_(out)
    {
        XXH3_INITSTATE(&hash_);
        XXH3_64bits_reset(&hash_);
        if (o_.report) *o_.report = bk_import_report{};
    }
    ~Importer()
    {
        for (bk_image &im : images_) free(im.rgba);
    }
    Importer(const Importer &) = delete;
    Importer &operator=(const Importer &) = delete;
    void run();

private:
    std::string path_;
    bk_import_options o_;
    bk_scene *s_;
    tinygltf::Model m_;
    Prepass pp_;
    ResourcePolicy policy_;
    XXH3_state_t hash_;
    std::vector<InputRecord> reads_;  // every file read, in the order read
    std::vector<int> image_map_;      // glTF image -> scene image (-1: none)
    std::vector<bk_image> images_;
    size_t image_bytes_ = 0;
    std::vector<bk_material> materials_;
    int default_material_ = -1;
    std::vector<MeshData> meshes_;
    std::vector<Instance> instances_;
    std::vector<LightInstance> light_insts_;
    std::vector<PlayableBox> playable_;
    std::vector<char> visited_;

    void warn(const char *fmt, ...) __attribute__((format(printf, 2, 3)));
    // Vertex indices are uint32; unshared flat-shaded triangles need 3 vertices each.
    size_t max_vertices() const
    {
        return o_.max_triangles > (UINT32_MAX - 1) / 3 ? (size_t)UINT32_MAX - 1 : o_.max_triangles * 3;
    }
    void load();
    void check_extensions();
    void decode_images();
    int decode_image(int gi);
    void build_materials();
    int texture_image(const tinygltf::TextureInfo &ti, const char *slot, int mi, const std::string &mname);
    void traverse();
    void visit(int n, const Mat4 &parent, const std::string &light_set, const std::string &door, int depth);
    std::string node_label(int n) const;
    std::string mesh_label(int mi, int pi) const;
    Mat4 local_matrix(int n) const;
    void prepare_mesh(int mi);
    void prepare_prim(int mi, int pi, Prim &p, bool *is_triangles);
    void read_accessor(int acc, int want_comps, bool index, std::vector<float> *f, std::vector<uint32_t> *u,
                       const std::string &what);
    void decode_draco(int mi, int pi, const DracoInfo &di, Prim &p, std::vector<uint32_t> &idx, size_t *nverts);
    void emit_geometry();
    void choose_origin(const std::vector<Instance> &kept);
    void emit_lights();
    void read_sky();
    void read_combinations();
    void read_playable(int n, const Mat4 &world, const tinygltf::Value &v);
    void emit_playable();
    void record_inputs();
    std::vector<float> downsample(const float *rgba, int w, int h, int max_side, int *ow, int *oh);
};

void Importer::warn(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    std::string m = path_ + ": " + vfmt(fmt, ap);
    va_end(ap);
    if (o_.report) o_.report->warnings++;
    if (o_.warn) o_.warn(o_.warn_user, m.c_str());
}

std::string Importer::node_label(int n) const
{
    const std::string &nm = m_.nodes[(size_t)n].name;
    return "node " + std::to_string(n) + (nm.empty() ? "" : " " + qstr(nm));
}

std::string Importer::mesh_label(int mi, int pi) const
{
    const std::string &nm = m_.meshes[(size_t)mi].name;
    return "mesh " + std::to_string(mi) + (nm.empty() ? "" : " " + qstr(nm)) + " primitive " + std::to_string(pi);
}

void Importer::load()
{
    const char *file = path_.c_str();
    std::vector<unsigned char> bytes;
    std::string why;
    if (!read_capped(path_, o_.max_file_bytes, &bytes, &why)) fail("%s: %s", file, why.c_str());
    if (bytes.empty()) fail("%s: empty file", file);
    XXH3_64bits_update(&hash_, bytes.data(), bytes.size());
    reads_.push_back(InputRecord{path_, "scene", bytes.size(), XXH3_64bits(bytes.data(), bytes.size())});
    policy_.root = real_dir(dir_of(path_));
    if (policy_.root.empty()) fail("%s: cannot resolve its folder: %s", file, strerror(errno));
    if (o_.allow_outside && *o_.allow_outside) {
        policy_.allow = real_dir(o_.allow_outside);
        if (policy_.allow.empty()) fail("%s: allowed folder %s: %s", file, o_.allow_outside, strerror(errno));
    }

    bool glb = bytes.size() >= 4 && !memcmp(bytes.data(), "glTF", 4);
    GlbParts g;
    if (glb) g = split_glb(bytes, path_);
    size_t json_len = glb ? g.json_len : bytes.size();
    if (json_len > o_.max_json_bytes)
        fail("%s: %zu bytes of JSON exceeds the %zu-byte JSON cap", file, json_len, o_.max_json_bytes);
    pp_ = prepass(glb ? g.json : reinterpret_cast<const char *>(bytes.data()), json_len, path_);

    tinygltf::TinyGLTF loader;
    FsState fss{o_.max_file_bytes, &policy_, &reads_};
    tinygltf::FsCallbacks fs{fs_exists, fs_expand, fs_read, fs_write, &fss};
    loader.SetFsCallbacks(fs);
    ImageLoaderCtx ictx{&pp_.needed_images, o_.skip_textures != 0};
    loader.SetImageLoader(keep_encoded_image, &ictx);
    std::string err, warnings;
    bool ok;
    std::string base = dir_of(path_);
    if (glb) {
        std::vector<unsigned char> rebuilt = make_glb(pp_.json, g);
        if (rebuilt.size() > UINT32_MAX) fail("%s: GLB larger than 4 GiB", file);
        ok = loader.LoadBinaryFromMemory(&m_, &err, &warnings, rebuilt.data(), (unsigned)rebuilt.size(), base);
    } else {
        if (pp_.json.size() > UINT32_MAX) fail("%s: JSON larger than 4 GiB", file);
        ok = loader.LoadASCIIFromString(&m_, &err, &warnings, pp_.json.data(), (unsigned)pp_.json.size(), base);
    }
    size_t start = 0;
    while (start < warnings.size()) {
        size_t nl = warnings.find('\n', start);
        std::string line = warnings.substr(start, nl == std::string::npos ? std::string::npos : nl - start);
        if (!line.empty()) warn("%s", line.c_str());
        if (nl == std::string::npos) break;
        start = nl + 1;
    }
    if (!ok) {
        while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
        for (char &c : err)
            if (c == '\n') c = ';';
        fail("%s: %s", file, err.empty() ? "glTF parse error" : err.c_str());
    }
    for (const auto &b : m_.buffers)
        if (!b.data.empty()) XXH3_64bits_update(&hash_, b.data.data(), b.data.size());
    // tinygltf reads the buffers' files, then the images': a file named by a buffer's uri is a buffer
    for (InputRecord &r : reads_)
        for (const auto &b : m_.buffers)
            if (r.role != std::string("scene") && !b.uri.empty() && b.uri.rfind("data:", 0) != 0 &&
                r.path.size() >= b.uri.size() && r.path.compare(r.path.size() - b.uri.size(), b.uri.size(), b.uri) == 0)
                r.role = "buffer";
}

void Importer::check_extensions()
{
    static const char *const supported[] = {"KHR_draco_mesh_compression", "KHR_lights_punctual",
                                            "KHR_materials_emissive_strength", "KHR_mesh_quantization"};
    for (const std::string &e : m_.extensionsRequired) {
        bool ok = false;
        for (const char *s : supported) ok = ok || e == s;
        if (!ok)
            fail("%s: requires glTF extension %s, which lbk does not support (supported: "
                 "KHR_draco_mesh_compression, KHR_lights_punctual, KHR_materials_emissive_strength, "
                 "KHR_mesh_quantization)", path_.c_str(), e.c_str());
    }
}

// Box filter to at most max_side on the longer side; partial edge blocks average what they cover.
std::vector<float> Importer::downsample(const float *rgba, int w, int h, int max_side, int *ow, int *oh)
{
    int f = 1;
    while ((w + f - 1) / f > max_side || (h + f - 1) / f > max_side) f++;
    int nw = (w + f - 1) / f, nh = (h + f - 1) / f;
    std::vector<float> out((size_t)nw * nh * 4);
    for (int y = 0; y < nh; y++)
        for (int x = 0; x < nw; x++) {
            double acc[4] = {0, 0, 0, 0};
            int n = 0;
            for (int yy = y * f; yy < std::min(h, (y + 1) * f); yy++)
                for (int xx = x * f; xx < std::min(w, (x + 1) * f); xx++, n++)
                    for (int k = 0; k < 4; k++) acc[k] += rgba[4 * ((size_t)yy * w + xx) + k];
            for (int k = 0; k < 4; k++) out[4 * ((size_t)y * nw + x) + k] = (float)(acc[k] / n);
        }
    *ow = nw;
    *oh = nh;
    return out;
}

int Importer::decode_image(int gi)
{
    if (image_map_[(size_t)gi] != -2) return image_map_[(size_t)gi];
    const tinygltf::Image &im = m_.images[(size_t)gi];
    std::string label = "image " + std::to_string(gi) + (im.uri.empty() || im.uri.rfind("data:", 0) == 0
                                                             ? (im.name.empty() ? "" : " " + qstr(im.name))
                                                             : " " + qstr(im.uri));
    const unsigned char *bytes = nullptr;
    size_t len = 0;
    if (im.bufferView >= 0) {
        if ((size_t)im.bufferView >= m_.bufferViews.size()) fail("%s: %s: bufferView out of range", path_.c_str(), label.c_str());
        const tinygltf::BufferView &bv = m_.bufferViews[(size_t)im.bufferView];
        if (bv.buffer < 0 || (size_t)bv.buffer >= m_.buffers.size()) fail("%s: %s: buffer out of range", path_.c_str(), label.c_str());
        const tinygltf::Buffer &b = m_.buffers[(size_t)bv.buffer];
        uint64_t end;
        if (!add_ok(bv.byteOffset, bv.byteLength, &end) || end > b.data.size() || bv.byteLength == 0)
            fail("%s: %s: bufferView %d lies outside its buffer", path_.c_str(), label.c_str(), im.bufferView);
        bytes = b.data.data() + bv.byteOffset;
        len = bv.byteLength;
    } else {
        bytes = im.image.data();
        len = im.image.size();
    }
    if (!bytes || len == 0) fail("%s: %s: could not be read (missing file or empty data)", path_.c_str(), label.c_str());
    if (len > (size_t)INT32_MAX) fail("%s: %s: encoded image larger than 2 GiB", path_.c_str(), label.c_str());
    XXH3_64bits_update(&hash_, bytes, len);
    int w = 0, h = 0, comp = 0;
    if (!stbi_info_from_memory(bytes, (int)len, &w, &h, &comp)) {
        if (o_.report) o_.report->ignored_textures++;
        warn("%s: not a decodable PNG or JPEG (%s); texture ignored", label.c_str(), stbi_failure_reason());
        image_map_[(size_t)gi] = -1;
        return -1;
    }
    if (w <= 0 || h <= 0 || (uint64_t)w * (uint64_t)h > o_.max_image_pixels)
        fail("%s: %s: %dx%d pixels exceeds the %zu-pixel cap", path_.c_str(), label.c_str(), w, h, o_.max_image_pixels);
    int cw = 0, ch = 0;
    unsigned char *px = stbi_load_from_memory(bytes, (int)len, &cw, &ch, &comp, 4);
    if (!px || cw != w || ch != h) {
        if (px) stbi_image_free(px);
        fail("%s: %s: decoding failed (%s)", path_.c_str(), label.c_str(), stbi_failure_reason());
    }
    float lut[256];
    for (int i = 0; i < 256; i++) {
        double c = i / 255.0;
        lut[i] = (float)(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    // Convert and filter in rows so a big texture never exists in float at full size.
    int f = 1;
    while ((w + f - 1) / f > o_.max_texture_size || (h + f - 1) / f > o_.max_texture_size) f++;
    int nw = (w + f - 1) / f, nh = (h + f - 1) / f;
    uint64_t bytes_out = (uint64_t)nw * nh * 16;
    if (image_bytes_ + bytes_out > o_.max_image_bytes) {
        stbi_image_free(px);
        fail("%s: %s: textures exceed the %zu-byte image memory cap", path_.c_str(), label.c_str(), o_.max_image_bytes);
    }
    float *rgba = static_cast<float *>(malloc((size_t)bytes_out));
    if (!rgba) {
        stbi_image_free(px);
        throw std::bad_alloc();
    }
    double sum[4] = {0, 0, 0, 0};
    for (int y = 0; y < nh; y++)
        for (int x = 0; x < nw; x++) {
            double acc[4] = {0, 0, 0, 0};
            int n = 0;
            for (int yy = y * f; yy < std::min(h, (y + 1) * f); yy++)
                for (int xx = x * f; xx < std::min(w, (x + 1) * f); xx++, n++) {
                    const unsigned char *p = px + 4 * ((size_t)yy * w + xx);
                    acc[0] += lut[p[0]]; acc[1] += lut[p[1]]; acc[2] += lut[p[2]]; acc[3] += p[3] / 255.0;
                }
            for (int k = 0; k < 4; k++) {
                float v = (float)(acc[k] / n);
                rgba[4 * ((size_t)y * nw + x) + k] = v;
                sum[k] += v;
            }
        }
    stbi_image_free(px);
    if (f > 1 && o_.report) o_.report->downsampled_images++;
    bk_image bi{};
    bi.width = nw;
    bi.height = nh;
    bi.rgba = rgba;
    for (int k = 0; k < 4; k++) bi.mean[k] = (float)(sum[k] / ((double)nw * nh));
    images_.push_back(bi);
    image_bytes_ += bytes_out;
    image_map_[(size_t)gi] = (int)images_.size() - 1;
    return image_map_[(size_t)gi];
}

void Importer::decode_images()
{
    image_map_.assign(m_.images.size(), -2);  // -2: not decoded yet
}

int Importer::texture_image(const tinygltf::TextureInfo &ti, const char *slot, int mi, const std::string &mname)
{
    if (ti.index < 0 || o_.skip_textures) return -1;
    if ((size_t)ti.index >= m_.textures.size())
        fail("%s: material %d %s: %s texture %d out of range", path_.c_str(), mi, qstr(mname).c_str(), slot, ti.index);
    int src = m_.textures[(size_t)ti.index].source;
    if (src < 0) {
        // e.g. KHR_texture_basisu / EXT_texture_webp sources only
        if (o_.report) o_.report->ignored_textures++;
        warn("material %d %s: %s texture %d has no PNG/JPEG source; ignored", mi, qstr(mname).c_str(), slot, ti.index);
        return -1;
    }
    if ((size_t)src >= m_.images.size())
        fail("%s: material %d %s: %s texture %d: image %d out of range", path_.c_str(), mi, qstr(mname).c_str(),
             slot, ti.index, src);
    if (ti.texCoord != 0) {
        if (o_.report) o_.report->ignored_textures++;
        warn("material %d %s: %s texture uses TEXCOORD_%d (only TEXCOORD_0 is sampled); ignored", mi,
             qstr(mname).c_str(), slot, ti.texCoord);
        return -1;
    }
    if (ti.extensions.count("KHR_texture_transform"))
        warn("material %d %s: KHR_texture_transform on the %s texture is ignored", mi, qstr(mname).c_str(), slot);
    return decode_image(src);
}

bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }

void Importer::build_materials()
{
    for (size_t i = 0; i < m_.materials.size(); i++) {
        const tinygltf::Material &gm = m_.materials[i];
        int mi = (int)i;
        const char *file = path_.c_str();
        std::string mq = qstr(gm.name);
        bk_material bm{};
        snprintf(bm.name, sizeof bm.name, "%s", gm.name.empty() ? ("material" + std::to_string(i)).c_str() : gm.name.c_str());
        const std::vector<double> &bc = gm.pbrMetallicRoughness.baseColorFactor;
        if (bc.size() != 4) fail("%s: material %d %s: baseColorFactor must have 4 numbers", file, mi, mq.c_str());
        for (int k = 0; k < 3; k++) {
            if (!finite_nonneg(bc[k])) fail("%s: material %d %s: baseColorFactor must be finite and >= 0", file, mi, mq.c_str());
            bm.albedo[k] = (float)std::min(bc[k], 1.0);
        }
        if (bc[0] > 1 || bc[1] > 1 || bc[2] > 1) warn("material %d %s: baseColorFactor above 1 clamped", mi, mq.c_str());
        const std::vector<double> &ef = gm.emissiveFactor;
        if (ef.size() != 3) fail("%s: material %d %s: emissiveFactor must have 3 numbers", file, mi, mq.c_str());
        double strength = 1.0;
        auto es = gm.extensions.find("KHR_materials_emissive_strength");
        if (es != gm.extensions.end() && es->second.IsObject() && es->second.Has("emissiveStrength")) {
            const tinygltf::Value &v = es->second.Get("emissiveStrength");
            if (!v.IsNumber() || !finite_nonneg(v.GetNumberAsDouble()))
                fail("%s: material %d %s: emissiveStrength must be a finite number >= 0", file, mi, mq.c_str());
            strength = v.GetNumberAsDouble();
        }
        for (int k = 0; k < 3; k++) {
            if (!finite_nonneg(ef[k])) fail("%s: material %d %s: emissiveFactor must be finite and >= 0", file, mi, mq.c_str());
            double e = ef[k] * strength;
            if (!std::isfinite((float)e)) fail("%s: material %d %s: emission overflows a float", file, mi, mq.c_str());
            bm.emission[k] = (float)e;
        }
        bm.albedo_tex = texture_image(gm.pbrMetallicRoughness.baseColorTexture, "baseColor", mi, gm.name);
        bm.emission_tex = texture_image(gm.emissiveTexture, "emissive", mi, gm.name);
        bm.double_sided = gm.doubleSided ? 1 : 0;
        // glTF's defaults (1, 1: a rough metal) when pbrMetallicRoughness leaves them out, as
        // tinygltf fills them; our own Lambertian scenes say metallicFactor 0 (GGX.md)
        const double mf = gm.pbrMetallicRoughness.metallicFactor, rf = gm.pbrMetallicRoughness.roughnessFactor;
        if (!(mf >= 0 && mf <= 1)) fail("%s: material %d %s: metallicFactor must lie in [0, 1]", file, mi, mq.c_str());
        if (!(rf >= 0 && rf <= 1)) fail("%s: material %d %s: roughnessFactor must lie in [0, 1]", file, mi, mq.c_str());
        bm.metallic = (float)mf;
        bm.roughness = (float)rf;
        // after the emissive texture: the images of materials without it keep their indices
        bm.metal_rough_tex1 =
            1 + texture_image(gm.pbrMetallicRoughness.metallicRoughnessTexture, "metallicRoughness", mi, gm.name);
        materials_.push_back(bm);
    }
}

// ---- nodes ------------------------------------------------------------------------------------

Mat4 Importer::local_matrix(int n) const
{
    const tinygltf::Node &nd = m_.nodes[(size_t)n];
    const char *file = path_.c_str();
    std::string lbl = node_label(n);
    Mat4 M = identity();
    if (!nd.matrix.empty()) {
        if (nd.matrix.size() != 16) fail("%s: %s: matrix must have 16 numbers", file, lbl.c_str());
        for (int i = 0; i < 16; i++) {
            if (!std::isfinite(nd.matrix[i])) fail("%s: %s: matrix has a non-finite value", file, lbl.c_str());
            M.m[i] = nd.matrix[i];
        }
        return M;
    }
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, sc[3] = {1, 1, 1};
    auto take = [&](const std::vector<double> &v, size_t n_, double *dst, const char *what) {
        if (v.empty()) return;
        if (v.size() != n_) fail("%s: %s: %s must have %zu numbers", file, lbl.c_str(), what, n_);
        for (size_t i = 0; i < n_; i++) {
            if (!std::isfinite(v[i])) fail("%s: %s: %s has a non-finite value", file, lbl.c_str(), what);
            dst[i] = v[i];
        }
    };
    take(nd.translation, 3, t, "translation");
    take(nd.rotation, 4, q, "rotation");
    take(nd.scale, 3, sc, "scale");
    double ql = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(ql > 1e-12)) fail("%s: %s: rotation quaternion has zero length", file, lbl.c_str());
    double x = q[0] / ql, y = q[1] / ql, z = q[2] / ql, w = q[3] / ql;
    double R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                   2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) M.m[c * 4 + r] = R[c * 3 + r] * sc[c];
    M.m[12] = t[0]; M.m[13] = t[1]; M.m[14] = t[2];
    return M;
}

bool valid_name(const std::string &s) {
    if (s.empty() || s.size() > 63) return false;
    for (unsigned char c : s)
        if (c < 32 || c == 127) return false;
    return true;
}

void Importer::visit(int n, const Mat4 &parent, const std::string &inh_set, const std::string &inh_door, int depth)
{
    const char *file = path_.c_str();
    if (n < 0 || (size_t)n >= m_.nodes.size()) fail("%s: node index %d out of range (%zu nodes)", file, n, m_.nodes.size());
    if (depth > kMaxNodeDepth) fail("%s: %s: node hierarchy deeper than %d", file, node_label(n).c_str(), kMaxNodeDepth);
    if (visited_[(size_t)n])
        fail("%s: %s is reached twice in the scene graph (a cycle or a node with two parents)", file, node_label(n).c_str());
    visited_[(size_t)n] = 1;
    const tinygltf::Node &nd = m_.nodes[(size_t)n];
    std::string lbl = node_label(n);
    Mat4 world = mul(parent, local_matrix(n));
    for (double v : world.m)
        if (!std::isfinite(v)) fail("%s: %s: world transform overflows", file, lbl.c_str());

    Instance inst;
    inst.node = n;
    inst.world = world;
    inst.light_set = inh_set;
    inst.door = inh_door;
    if (nd.extras.IsObject()) {
        const tinygltf::Value &ex = nd.extras;
        if (ex.Has("lbk_lighting")) {
            const tinygltf::Value &v = ex.Get("lbk_lighting");
            std::string s = v.IsString() ? v.Get<std::string>() : "";
            if (s == "auto") inst.lighting = BK_LIGHTING_AUTO;
            else if (s == "lightmap") inst.lighting = BK_LIGHTING_LIGHTMAP;
            else if (s == "llg") inst.lighting = BK_LIGHTING_LLG;
            else if (s == "none") inst.lighting = BK_LIGHTING_NONE;
            else fail("%s: %s: extras key lbk_lighting must be \"lightmap\", \"llg\", \"none\" or \"auto\"%s",
                      file, lbl.c_str(), v.IsString() ? (", not " + qstr(s)).c_str() : " (a string)");
        }
        if (ex.Has("lbk_texel_density")) {
            const tinygltf::Value &v = ex.Get("lbk_texel_density");
            double d = v.IsNumber() ? v.GetNumberAsDouble() : -1;
            if (!v.IsNumber() || !std::isfinite(d) || d <= 0 || d > 10000)
                fail("%s: %s: extras key lbk_texel_density must be a number of texels per metre in (0, 10000]",
                     file, lbl.c_str());
            inst.texel_density = (float)d;
        }
        for (const char *key : {"lbk_light_set", "lbk_door"}) {
            if (!ex.Has(key)) continue;
            const tinygltf::Value &v = ex.Get(key);
            if (!v.IsString() || !valid_name(v.Get<std::string>()))
                fail("%s: %s: extras key %s must be a string of 1 to 63 printable bytes", file, lbl.c_str(), key);
            (strcmp(key, "lbk_door") == 0 ? inst.door : inst.light_set) = v.Get<std::string>();
        }
        if (ex.Has("lbk_playable")) read_playable(n, world, ex.Get("lbk_playable"));
    }
    if (nd.mesh >= 0) {
        if ((size_t)nd.mesh >= m_.meshes.size()) fail("%s: %s: mesh %d out of range", file, lbl.c_str(), nd.mesh);
        instances_.push_back(inst);
    } else if (nd.mesh < -1) {
        fail("%s: %s: mesh %d out of range", file, lbl.c_str(), nd.mesh);
    }
    auto le = nd.extensions.find("KHR_lights_punctual");
    if (le != nd.extensions.end()) {
        const tinygltf::Value &lv = le->second;
        if (!lv.IsObject() || !lv.Has("light") || !lv.Get("light").IsInt())
            fail("%s: %s: KHR_lights_punctual needs an integer \"light\"", file, lbl.c_str());
        int li = lv.Get("light").Get<int>();
        if (li < 0 || (size_t)li >= m_.lights.size())
            fail("%s: %s: light %d out of range (%zu lights)", file, lbl.c_str(), li, m_.lights.size());
        light_insts_.push_back(LightInstance{n, li, world, inst.light_set});
    }
    for (int c : nd.children) visit(c, world, inst.light_set, inst.door, depth + 1);
}

void Importer::traverse()
{
    visited_.assign(m_.nodes.size(), 0);
    std::vector<int> roots;
    if (!m_.scenes.empty()) {
        int si = m_.defaultScene >= 0 ? m_.defaultScene : 0;
        if ((size_t)si >= m_.scenes.size()) fail("%s: default scene %d out of range", path_.c_str(), si);
        roots = m_.scenes[(size_t)si].nodes;
    } else {
        std::vector<char> child(m_.nodes.size(), 0);
        for (const auto &nd : m_.nodes)
            for (int c : nd.children)
                if (c >= 0 && (size_t)c < child.size()) child[(size_t)c] = 1;
        for (size_t i = 0; i < m_.nodes.size(); i++)
            if (!child[i]) roots.push_back((int)i);
    }
    for (int r : roots) visit(r, identity(), "", "", 0);
}

// ---- accessors --------------------------------------------------------------------------------

void Importer::read_accessor(int acc, int want_comps, bool index, std::vector<float> *f, std::vector<uint32_t> *u,
                             const std::string &what)
{
    const char *file = path_.c_str();
    if (acc < 0 || (size_t)acc >= m_.accessors.size())
        fail("%s: %s: accessor %d out of range (%zu accessors)", file, what.c_str(), acc, m_.accessors.size());
    const tinygltf::Accessor &a = m_.accessors[(size_t)acc];
    std::string lbl = what + ": accessor " + std::to_string(acc);
    if (a.sparse.isSparse) fail("%s: %s: sparse accessors are not supported", file, lbl.c_str());
    int comps = tinygltf::GetNumComponentsInType((uint32_t)a.type);
    if (comps != want_comps) fail("%s: %s: has %d components per element, expected %d", file, lbl.c_str(), comps, want_comps);
    int ct = a.componentType;
    int csize = tinygltf::GetComponentSizeInBytes((uint32_t)ct);
    bool ok_type = index ? (ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                            ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
                         : (ct == TINYGLTF_COMPONENT_TYPE_FLOAT || ct == TINYGLTF_COMPONENT_TYPE_BYTE ||
                            ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || ct == TINYGLTF_COMPONENT_TYPE_SHORT ||
                            ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    if (!ok_type || csize <= 0) fail("%s: %s: component type %d not allowed here", file, lbl.c_str(), ct);
    if (a.bufferView < 0)
        fail("%s: %s: has no bufferView (only sparse accessors may omit it)", file, lbl.c_str());
    if ((size_t)a.bufferView >= m_.bufferViews.size())
        fail("%s: %s: bufferView %d out of range", file, lbl.c_str(), a.bufferView);
    const tinygltf::BufferView &bv = m_.bufferViews[(size_t)a.bufferView];
    if (bv.buffer < 0 || (size_t)bv.buffer >= m_.buffers.size())
        fail("%s: %s: bufferView %d: buffer %d out of range", file, lbl.c_str(), a.bufferView, bv.buffer);
    const tinygltf::Buffer &b = m_.buffers[(size_t)bv.buffer];
    uint64_t elem = (uint64_t)comps * (uint64_t)csize;
    uint64_t stride = bv.byteStride > 0 ? (uint64_t)bv.byteStride : elem;
    if (stride < elem) fail("%s: %s: byteStride %zu smaller than an element (%llu bytes)", file, lbl.c_str(),
                            bv.byteStride, (unsigned long long)elem);
    uint64_t view_end, span, acc_end, last;
    if (!add_ok(bv.byteOffset, bv.byteLength, &view_end) || view_end > b.data.size())
        fail("%s: %s: bufferView %d (offset %zu, length %zu) lies outside buffer %d (%zu bytes)", file, lbl.c_str(),
             a.bufferView, bv.byteOffset, bv.byteLength, bv.buffer, b.data.size());
    size_t count = a.count;
    if (count) {
        if (!mul_ok(stride, count - 1, &last) || !add_ok(last, elem, &span) || !add_ok(a.byteOffset, span, &acc_end) ||
            acc_end > bv.byteLength)
            fail("%s: %s: %zu elements at offset %zu (stride %llu) do not fit in bufferView %d (%zu bytes)", file,
                 lbl.c_str(), count, a.byteOffset, (unsigned long long)stride, a.bufferView, bv.byteLength);
    }
    const unsigned char *base = b.data.data() + bv.byteOffset + a.byteOffset;
    if (u) u->resize(count);
    if (f) f->resize(count * (size_t)comps);
    for (size_t i = 0; i < count; i++) {
        const unsigned char *p = base + i * stride;
        for (int c = 0; c < comps; c++, p += csize) {
            double v;
            switch (ct) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: { float x; memcpy(&x, p, 4); v = x; break; }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t x; memcpy(&x, p, 4); v = x; break; }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t x; memcpy(&x, p, 2); v = a.normalized ? x / 65535.0 : x; break; }
            case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t x; memcpy(&x, p, 2); v = a.normalized ? std::max(x / 32767.0, -1.0) : x; break; }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = a.normalized ? p[0] / 255.0 : p[0]; break;
            default: { int8_t x; memcpy(&x, p, 1); v = a.normalized ? std::max(x / 127.0, -1.0) : x; break; }
            }
            if (u) {
                (*u)[i] = (uint32_t)v;
            } else {
                if (!std::isfinite((float)v))
                    fail("%s: %s: element %zu component %d is NaN or infinite", file, lbl.c_str(), i, c);
                (*f)[i * (size_t)comps + (size_t)c] = (float)v;
            }
        }
    }
}

void Importer::decode_draco(int mi, int pi, const DracoInfo &di, Prim &p, std::vector<uint32_t> &idx, size_t *nverts)
{
    const char *file = path_.c_str();
    std::string lbl = mesh_label(mi, pi) + ": KHR_draco_mesh_compression";
    if ((size_t)di.buffer_view >= m_.bufferViews.size())
        fail("%s: %s: bufferView %d out of range", file, lbl.c_str(), di.buffer_view);
    const tinygltf::BufferView &bv = m_.bufferViews[(size_t)di.buffer_view];
    if (bv.buffer < 0 || (size_t)bv.buffer >= m_.buffers.size())
        fail("%s: %s: buffer %d out of range", file, lbl.c_str(), bv.buffer);
    const tinygltf::Buffer &b = m_.buffers[(size_t)bv.buffer];
    uint64_t end;
    if (!add_ok(bv.byteOffset, bv.byteLength, &end) || end > b.data.size() || bv.byteLength == 0)
        fail("%s: %s: bufferView %d lies outside its buffer", file, lbl.c_str(), di.buffer_view);
    draco::DecoderBuffer db;
    db.Init(reinterpret_cast<const char *>(b.data.data() + bv.byteOffset), bv.byteLength);
    auto geom_type = draco::Decoder::GetEncodedGeometryType(&db);
    if (!geom_type.ok() || geom_type.value() != draco::TRIANGULAR_MESH)
        fail("%s: %s: not a Draco triangle mesh", file, lbl.c_str());
    draco::Decoder dec;
    auto res = dec.DecodeMeshFromBuffer(&db);
    if (!res.ok()) fail("%s: %s: Draco decoding failed: %s", file, lbl.c_str(), res.status().error_msg());
    std::unique_ptr<draco::Mesh> mesh = std::move(res).value();
    size_t np = mesh->num_points(), nf = mesh->num_faces();
    if (nf > o_.max_triangles) fail("%s: %s: %zu triangles exceeds the cap of %zu", file, lbl.c_str(), nf, o_.max_triangles);
    if (np > max_vertices()) fail("%s: %s: %zu points exceeds the cap of %zu", file, lbl.c_str(), np, max_vertices());
    *nverts = np;
    idx.resize(nf * 3);
    for (size_t f = 0; f < nf; f++) {
        const draco::Mesh::Face &face = mesh->face(draco::FaceIndex((uint32_t)f));
        for (int k = 0; k < 3; k++) {
            uint32_t v = face[k].value();
            if (v >= np) fail("%s: %s: face %zu references point %u of %zu", file, lbl.c_str(), f, v, np);
            idx[f * 3 + k] = v;
        }
    }
    auto take = [&](const char *sem, int comps, std::vector<float> &out) -> bool {
        auto it = di.attributes.find(sem);
        if (it == di.attributes.end()) return false;
        const draco::PointAttribute *pa = mesh->GetAttributeByUniqueId((uint32_t)it->second);
        if (!pa) fail("%s: %s: attribute %s (id %d) is not in the Draco stream", file, lbl.c_str(), sem, it->second);
        if (pa->num_components() != comps)
            fail("%s: %s: attribute %s has %d components, expected %d", file, lbl.c_str(), sem, (int)pa->num_components(), comps);
        out.resize(np * (size_t)comps);
        float v[4];
        for (size_t i = 0; i < np; i++) {
            draco::AttributeValueIndex avi = pa->mapped_index(draco::PointIndex((uint32_t)i));
            if (avi.value() >= pa->size() || !pa->ConvertValue<float>(avi, (int8_t)comps, v))
                fail("%s: %s: attribute %s: value %zu cannot be read", file, lbl.c_str(), sem, i);
            for (int c = 0; c < comps; c++) {
                if (!std::isfinite(v[c])) fail("%s: %s: attribute %s: value %zu is NaN or infinite", file, lbl.c_str(), sem, i);
                out[i * (size_t)comps + (size_t)c] = v[c];
            }
        }
        return true;
    };
    if (!take("POSITION", 3, p.pos)) fail("%s: %s: POSITION is not in the Draco attributes", file, lbl.c_str());
    p.has_nrm = take("NORMAL", 3, p.nrm);
    take("TEXCOORD_0", 2, p.uv0);
    p.has_uv1 = take("TEXCOORD_1", 2, p.uv1);
}

void Importer::prepare_prim(int mi, int pi, Prim &p, bool *is_triangles)
{
    const char *file = path_.c_str();
    const tinygltf::Primitive &gp = m_.meshes[(size_t)mi].primitives[(size_t)pi];
    std::string lbl = mesh_label(mi, pi);
    int mode = gp.mode;
    if (mode < 0 || mode > 6) fail("%s: %s: unknown primitive mode %d", file, lbl.c_str(), mode);
    *is_triangles = mode >= TINYGLTF_MODE_TRIANGLES;
    if (!*is_triangles) return;
    if (gp.material >= 0) {
        if ((size_t)gp.material >= materials_.size())
            fail("%s: %s: material %d out of range (%zu materials)", file, lbl.c_str(), gp.material, materials_.size());
        p.material = (uint32_t)gp.material;
    } else {
        if (default_material_ < 0) {
            bk_material d{};
            snprintf(d.name, sizeof d.name, "default");
            d.albedo[0] = d.albedo[1] = d.albedo[2] = 1.0f;
            d.albedo_tex = d.emission_tex = -1;
            d.metallic = d.roughness = 1.0f;  // the spec's default material: a rough metal
            materials_.push_back(d);
            default_material_ = (int)materials_.size() - 1;
        }
        p.material = (uint32_t)default_material_;
    }

    std::vector<uint32_t> idx;
    size_t nv = 0;
    auto dit = pp_.draco.find({mi, pi});
    auto attr = [&](const char *sem) -> int {
        auto it = gp.attributes.find(sem);
        return it == gp.attributes.end() ? -1 : it->second;
    };
    if (dit != pp_.draco.end()) {
        decode_draco(mi, pi, dit->second, p, idx, &nv);
        mode = TINYGLTF_MODE_TRIANGLES;  // a decoded Draco mesh is a triangle list
        // Attributes outside the Draco stream are stored plainly (KHR_draco_mesh_compression).
        struct { const char *sem; int comps; std::vector<float> *dst; bool *flag; } plain[] = {
            {"NORMAL", 3, &p.nrm, &p.has_nrm}, {"TEXCOORD_0", 2, &p.uv0, nullptr}, {"TEXCOORD_1", 2, &p.uv1, &p.has_uv1}};
        for (auto &pl : plain) {
            if (!pl.dst->empty() || attr(pl.sem) < 0) continue;
            read_accessor(attr(pl.sem), pl.comps, false, pl.dst, nullptr, lbl + " " + pl.sem);
            if (pl.dst->size() != nv * (size_t)pl.comps)
                fail("%s: %s: %s has %zu elements, the Draco stream %zu points", file, lbl.c_str(), pl.sem,
                     pl.dst->size() / (size_t)pl.comps, nv);
            if (pl.flag) *pl.flag = true;
        }
    } else {
        if (attr("POSITION") < 0) fail("%s: %s: has no POSITION attribute", file, lbl.c_str());
        read_accessor(attr("POSITION"), 3, false, &p.pos, nullptr, lbl + " POSITION");
        nv = p.pos.size() / 3;
        if (nv > max_vertices()) fail("%s: %s: %zu vertices exceeds the cap of %zu", file, lbl.c_str(), nv, max_vertices());
        struct { const char *sem; int comps; std::vector<float> *dst; bool *flag; } opt[] = {
            {"NORMAL", 3, &p.nrm, &p.has_nrm}, {"TEXCOORD_0", 2, &p.uv0, nullptr}, {"TEXCOORD_1", 2, &p.uv1, &p.has_uv1}};
        for (auto &o : opt) {
            if (attr(o.sem) < 0) continue;
            read_accessor(attr(o.sem), o.comps, false, o.dst, nullptr, lbl + " " + o.sem);
            if (o.dst->size() != nv * (size_t)o.comps)
                fail("%s: %s: %s has %zu elements but POSITION has %zu", file, lbl.c_str(), o.sem,
                     o.dst->size() / (size_t)o.comps, nv);
            if (o.flag) *o.flag = true;
        }
        if (nv >= UINT32_MAX) fail("%s: %s: too many vertices", file, lbl.c_str());
        if (gp.indices >= 0) {
            read_accessor(gp.indices, 1, true, nullptr, &idx, lbl + " indices");
            for (size_t i = 0; i < idx.size(); i++)
                if (idx[i] >= nv)
                    fail("%s: %s: indices accessor %d: index %zu is %u but there are %zu vertices", file, lbl.c_str(),
                         gp.indices, i, idx[i], nv);
        } else {
            idx.resize(nv);
            for (size_t i = 0; i < nv; i++) idx[i] = (uint32_t)i;
        }
    }
    // Triangle list from the index stream.
    size_t n = idx.size();
    if (mode == TINYGLTF_MODE_TRIANGLES) {
        if (n % 3) fail("%s: %s: %zu indices is not a multiple of 3", file, lbl.c_str(), n);
        p.tris = std::move(idx);
    } else {
        size_t nt = n >= 3 ? n - 2 : 0;
        p.tris.reserve(nt * 3);
        for (size_t i = 0; i < nt; i++) {
            uint32_t a, b, c;
            if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
                // odd triangles swap their first two vertices to keep the winding
                a = idx[i + (i & 1)]; b = idx[i + 1 - (i & 1)]; c = idx[i + 2];
                if (a == b || b == c || a == c) continue;  // strip restarts
            } else {
                a = idx[0]; b = idx[i + 1]; c = idx[i + 2];
            }
            p.tris.push_back(a); p.tris.push_back(b); p.tris.push_back(c);
        }
    }
    if (p.uv0.empty()) p.uv0.assign(nv * 2, 0.0f);
    if (p.uv1.empty()) p.uv1.assign(nv * 2, 0.0f);
    p.source_vertices = (uint32_t)nv;
    p.src.resize(nv);
    for (size_t i = 0; i < nv; i++) p.src[i] = (uint32_t)i;
    if (!p.has_nrm) {
        // Flat shading: give every triangle its own three vertices; normals come at instancing.
        size_t nt = p.tris.size() / 3;
        std::vector<float> pos(nt * 9), uv0(nt * 6), uv1(nt * 6);
        std::vector<uint32_t> tris(nt * 3), src(nt * 3);
        for (size_t t = 0; t < nt * 3; t++) {
            uint32_t v = p.tris[t];
            memcpy(&pos[t * 3], &p.pos[(size_t)v * 3], 12);
            memcpy(&uv0[t * 2], &p.uv0[(size_t)v * 2], 8);
            memcpy(&uv1[t * 2], &p.uv1[(size_t)v * 2], 8);
            tris[t] = (uint32_t)t;
            src[t] = v;
        }
        p.pos.swap(pos); p.uv0.swap(uv0); p.uv1.swap(uv1); p.tris.swap(tris); p.src.swap(src);
    }
}

void Importer::prepare_mesh(int mi)
{
    MeshData &md = meshes_[(size_t)mi];
    if (md.ready) return;
    md.ready = true;
    const tinygltf::Mesh &gm = m_.meshes[(size_t)mi];
    std::vector<float> hash_pos;
    std::vector<uint32_t> hash_idx;
    for (size_t pi = 0; pi < gm.primitives.size(); pi++) {
        Prim p;
        bool tri = false;
        prepare_prim(mi, (int)pi, p, &tri);
        if (!tri) {
            if (o_.report) o_.report->ignored_primitives++;
            warn("%s: points/lines primitive ignored", mesh_label(mi, (int)pi).c_str());
            continue;
        }
        md.all_uv1 = md.all_uv1 && p.has_uv1;
        p.gltf_index = (uint32_t)pi;
        uint32_t base = (uint32_t)(hash_pos.size() / 3);
        hash_pos.insert(hash_pos.end(), p.pos.begin(), p.pos.end());
        for (uint32_t v : p.tris) hash_idx.push_back(base + v);
        md.vertices += p.pos.size() / 3;
        md.triangles += p.tris.size() / 3;
        if (md.triangles > o_.max_triangles || md.vertices > max_vertices())
            fail("%s: mesh %d: more than %zu triangles or %zu vertices (the caps)", path_.c_str(), mi,
                 o_.max_triangles, max_vertices());
        md.prims.push_back(std::move(p));
    }
    md.hash = bk_geometry_hash(hash_pos.data(), hash_pos.size() / 3, hash_idx.data(), hash_idx.size());
}

template <typename T>
T *alloc_array(size_t n, size_t per)
{
    uint64_t bytes;
    if (!mul_ok(n, per * sizeof(T), &bytes) || bytes > SIZE_MAX) throw std::bad_alloc();
    T *p = static_cast<T *>(malloc(bytes ? (size_t)bytes : 1));
    if (!p) throw std::bad_alloc();
    return p;
}

// The level's origin (bk_scene.origin), from its double-precision world bounds, before any
// position becomes a float: a 1 mm object 1e5 m away (a node translation, a JSON double) keeps
// its shape, where world-space floats (7.8 mm apart there) would collapse it. Per axis an
// integer number of metres, and only where the level lies farther from 0 than twice its
// extent (the rule of the pipeline's recentre, which then finds nothing left to do).
void Importer::choose_origin(const std::vector<Instance> &kept)
{
    double mn[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, mx[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (const Instance &in : kept)
        for (const Prim &p : meshes_[(size_t)m_.nodes[(size_t)in.node].mesh].prims)
            for (size_t v = 0; v < p.pos.size() / 3; v++) {
                double lp[3] = {p.pos[v * 3], p.pos[v * 3 + 1], p.pos[v * 3 + 2]}, wp[3];
                xform_point(in.world, lp, wp);
                for (int k = 0; k < 3; k++) mn[k] = std::min(mn[k], wp[k]), mx[k] = std::max(mx[k], wp[k]);
            }
    double extent = 0;
    for (int k = 0; k < 3; k++) extent = std::max(extent, mx[k] - mn[k]);
    for (int k = 0; k < 3; k++) {
        double mid = 0.5 * (mn[k] + mx[k]);
        s_->origin[k] = std::isfinite(mid) && std::isfinite(extent) && std::fabs(mid) > 2 * extent ? std::nearbyint(mid) : 0;
    }
}

void Importer::emit_geometry()
{
    const char *file = path_.c_str();
    size_t total_v = 0, total_t = 0;
    std::vector<Instance> kept;
    std::vector<double> dets;
    for (const Instance &in : instances_) {
        int mi = m_.nodes[(size_t)in.node].mesh;
        prepare_mesh(mi);
        const MeshData &md = meshes_[(size_t)mi];
        if (md.triangles == 0) continue;
        double A[9];
        upper3(in.world, A);
        double det = det3(A);
        if (!(std::fabs(det) > 1e-300)) {
            if (o_.report) o_.report->skipped_nodes++;
            warn("%s: singular transform (zero scale); its mesh is skipped", node_label(in.node).c_str());
            continue;
        }
        total_v += md.vertices;
        total_t += md.triangles;
        if (total_t > o_.max_triangles)
            fail("%s: more than %zu triangles (the cap) at %s", file, o_.max_triangles, node_label(in.node).c_str());
        if (total_v > max_vertices())
            fail("%s: more than %zu vertices (the cap) at %s", file, max_vertices(), node_label(in.node).c_str());
        kept.push_back(in);
        dets.push_back(det);
    }
    if (o_.recentre) choose_origin(kept);
    s_->positions = alloc_array<float>(total_v, 3);
    s_->normals = alloc_array<float>(total_v, 3);
    s_->uv0 = alloc_array<float>(total_v, 2);
    s_->uv1 = alloc_array<float>(total_v, 2);
    s_->tris = alloc_array<uint32_t>(total_t, 3);
    s_->tri_material = alloc_array<uint32_t>(total_t, 1);
    s_->tri_object = alloc_array<uint32_t>(total_t, 1);
    s_->objects = alloc_array<bk_object>(kept.size(), 1);
    s_->vertex_source = alloc_array<uint32_t>(total_v, 1);
    size_t total_p = 0;
    for (const Instance &in : kept)
        for (const Prim &p : meshes_[(size_t)m_.nodes[(size_t)in.node].mesh].prims) total_p += !p.tris.empty();
    s_->primitives = alloc_array<bk_primitive>(total_p, 1);
    size_t v0 = 0, t0 = 0, p0 = 0;
    for (size_t oi = 0; oi < kept.size(); oi++) {
        const Instance &in = kept[oi];
        const tinygltf::Node &nd = m_.nodes[(size_t)in.node];
        const MeshData &md = meshes_[(size_t)nd.mesh];
        std::string lbl = node_label(in.node);
        bk_object &ob = s_->objects[oi];
        memset(&ob, 0, sizeof ob);
        snprintf(ob.name, sizeof ob.name, "%s", nd.name.empty() ? ("node" + std::to_string(in.node)).c_str() : nd.name.c_str());
        ob.geometry_hash = md.hash;
        ob.first_tri = (uint32_t)t0;
        ob.tri_count = (uint32_t)md.triangles;
        ob.lighting = in.lighting;
        ob.texel_density = in.texel_density;
        snprintf(ob.light_set, sizeof ob.light_set, "%s", in.light_set.c_str());
        snprintf(ob.door, sizeof ob.door, "%s", in.door.c_str());
        ob.has_uv1 = md.all_uv1 ? 1 : 0;
        for (int i = 0; i < 16; i++) ob.local_to_world[i] = (float)in.world.m[i];
        double A[9], N[9];
        upper3(in.world, A);
        double det = dets[oi];
        inverse_transpose3(A, det, N);
        bool flip = det < 0;
        ob.node = in.node;
        ob.mirrored = flip ? 1 : 0;
        for (const Prim &p : md.prims) {
            size_t nv = p.pos.size() / 3, nt = p.tris.size() / 3;
            if (nt) {
                bk_primitive &sp = s_->primitives[p0++];
                sp.object = (uint32_t)oi;
                sp.gltf_primitive = p.gltf_index;
                sp.source_vertex_count = p.source_vertices;
                sp.first_tri = (uint32_t)t0;
                sp.tri_count = (uint32_t)nt;
                sp.first_vertex = (uint32_t)v0;
                sp.vertex_count = (uint32_t)nv;
            }
            if (nv) memcpy(&s_->vertex_source[v0], p.src.data(), nv * sizeof(uint32_t));
            for (size_t v = 0; v < nv; v++) {
                double lp[3] = {p.pos[v * 3], p.pos[v * 3 + 1], p.pos[v * 3 + 2]}, wp[3];
                xform_point(in.world, lp, wp);
                for (int k = 0; k < 3; k++) {
                    float x = (float)(wp[k] - s_->origin[k]);
                    if (!std::isfinite(x)) fail("%s: %s: a vertex position overflows after the node transform", file, lbl.c_str());
                    s_->positions[(v0 + v) * 3 + k] = x;
                }
                float *nrm = &s_->normals[(v0 + v) * 3];
                if (p.has_nrm) {
                    double ln[3] = {p.nrm[v * 3], p.nrm[v * 3 + 1], p.nrm[v * 3 + 2]}, wn[3];
                    xform_dir(N, ln, wn);
                    if (normalize3(wn)) {
                        for (int k = 0; k < 3; k++) nrm[k] = (float)wn[k];
                    } else {
                        nrm[0] = nrm[1] = nrm[2] = 0.0f;  // repaired below from a face
                    }
                } else {
                    nrm[0] = nrm[1] = nrm[2] = 0.0f;
                }
                memcpy(&s_->uv0[(v0 + v) * 2], &p.uv0[v * 2], 8);
                memcpy(&s_->uv1[(v0 + v) * 2], &p.uv1[v * 2], 8);
            }
            for (size_t t = 0; t < nt; t++) {
                uint32_t a = p.tris[t * 3], b = p.tris[t * 3 + 1], c = p.tris[t * 3 + 2];
                if (flip) std::swap(b, c);  // mirrored transform: keep counter-clockwise front faces
                uint32_t *dst = &s_->tris[(t0 + t) * 3];
                dst[0] = (uint32_t)v0 + a; dst[1] = (uint32_t)v0 + b; dst[2] = (uint32_t)v0 + c;
                s_->tri_material[t0 + t] = p.material;
                s_->tri_object[t0 + t] = (uint32_t)oi;
                // Fill missing (flat) or unusable normals from the world-space face.
                for (int k = 0; k < 3; k++) {
                    float *nrm = &s_->normals[(size_t)dst[k] * 3];
                    if (nrm[0] != 0.0f || nrm[1] != 0.0f || nrm[2] != 0.0f) continue;
                    const float *P0 = &s_->positions[(size_t)dst[0] * 3], *P1 = &s_->positions[(size_t)dst[1] * 3],
                                *P2 = &s_->positions[(size_t)dst[2] * 3];
                    double e1[3], e2[3], fn[3];
                    for (int q = 0; q < 3; q++) { e1[q] = (double)P1[q] - P0[q]; e2[q] = (double)P2[q] - P0[q]; }
                    fn[0] = e1[1] * e2[2] - e1[2] * e2[1];
                    fn[1] = e1[2] * e2[0] - e1[0] * e2[2];
                    fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
                    if (!normalize3(fn)) { fn[0] = 0; fn[1] = 1; fn[2] = 0; }  // zero-area triangle
                    if (p.has_nrm && o_.report) o_.report->repaired_normals++;
                    for (int q = 0; q < 3; q++) nrm[q] = (float)fn[q];
                }
            }
            v0 += nv;
            t0 += nt;
        }
    }
    // A vertex not used by any triangle may still have no normal.
    for (size_t v = 0; v < total_v; v++) {
        float *nrm = &s_->normals[v * 3];
        if (nrm[0] == 0.0f && nrm[1] == 0.0f && nrm[2] == 0.0f) nrm[1] = 1.0f;
    }
    s_->vertex_count = total_v;
    s_->tri_count = total_t;
    s_->object_count = kept.size();
    s_->primitive_count = total_p;
}

void Importer::emit_lights()
{
    const char *file = path_.c_str();
    s_->lights = alloc_array<bk_light>(light_insts_.size(), 1);
    size_t n = 0;
    for (const LightInstance &li : light_insts_) {
        const tinygltf::Light &gl = m_.lights[(size_t)li.light];
        std::string lbl = node_label(li.node) + ": light " + std::to_string(li.light) +
                          (gl.name.empty() ? "" : " " + qstr(gl.name));
        bk_light bl{};
        snprintf(bl.name, sizeof bl.name, "%s", gl.name.empty() ? ("light" + std::to_string(li.light)).c_str() : gl.name.c_str());
        if (gl.type == "point") bl.type = BK_LIGHT_POINT;
        else if (gl.type == "spot") bl.type = BK_LIGHT_SPOT;
        else if (gl.type == "directional") bl.type = BK_LIGHT_DIRECTIONAL;
        else fail("%s: %s: unknown light type %s", file, lbl.c_str(), qstr(gl.type).c_str());
        double col[3] = {1, 1, 1};
        if (!gl.color.empty()) {
            if (gl.color.size() != 3) fail("%s: %s: color must have 3 numbers", file, lbl.c_str());
            for (int k = 0; k < 3; k++) col[k] = gl.color[k];
        }
        if (!finite_nonneg(gl.intensity)) fail("%s: %s: intensity must be finite and >= 0", file, lbl.c_str());
        for (int k = 0; k < 3; k++) {
            if (!finite_nonneg(col[k])) fail("%s: %s: color must be finite and >= 0", file, lbl.c_str());
            double c = col[k] * gl.intensity;
            if (!std::isfinite((float)c)) fail("%s: %s: colour × intensity overflows a float", file, lbl.c_str());
            bl.color[k] = (float)c;
        }
        if (!finite_nonneg(gl.range)) fail("%s: %s: range must be finite and >= 0", file, lbl.c_str());
        bl.range = (float)gl.range;
        if (bl.type == BK_LIGHT_SPOT) {
            double in = gl.spot.innerConeAngle, out = gl.spot.outerConeAngle;
            if (!std::isfinite(in) || !std::isfinite(out) || in < 0 || out <= 0 || in > out || out > kPi / 2 + 1e-6)
                fail("%s: %s: spot cone angles must satisfy 0 <= inner <= outer <= pi/2 (got %g, %g)", file,
                     lbl.c_str(), in, out);
            bl.inner_cone = (float)in;
            bl.outer_cone = (float)std::min(out, kPi / 2);
        }
        double o[3] = {0, 0, 0}, wp[3], A[9], dz[3] = {0, 0, -1}, wd[3];
        xform_point(li.world, o, wp);
        upper3(li.world, A);
        xform_dir(A, dz, wd);
        for (int k = 0; k < 3; k++) bl.position[k] = (float)(wp[k] - s_->origin[k]);
        if (!normalize3(wd)) {
            if (bl.type != BK_LIGHT_POINT) {
                if (o_.report) o_.report->skipped_nodes++;
                warn("%s: singular transform gives the light no direction; light skipped", lbl.c_str());
                continue;
            }
            wd[0] = 0; wd[1] = 0; wd[2] = -1;
        }
        for (int k = 0; k < 3; k++) bl.direction[k] = (float)wd[k];
        snprintf(bl.light_set, sizeof bl.light_set, "%s", li.light_set.c_str());
        s_->lights[n++] = bl;
    }
    s_->light_count = n;
}

void Importer::read_sky()
{
    const char *file = path_.c_str();
    s_->sky_image = -1;
    const tinygltf::Value *sky = nullptr;
    std::string where;
    int si = m_.defaultScene >= 0 ? m_.defaultScene : 0;
    if (!m_.scenes.empty() && m_.scenes[(size_t)si].extras.IsObject() && m_.scenes[(size_t)si].extras.Has("lbk_sky")) {
        sky = &m_.scenes[(size_t)si].extras.Get("lbk_sky");
        where = "scene " + std::to_string(si) + " extras";
    } else if (m_.extras.IsObject() && m_.extras.Has("lbk_sky")) {
        sky = &m_.extras.Get("lbk_sky");
        where = "root extras";
    } else if (m_.asset.extras.IsObject() && m_.asset.extras.Has("lbk_sky")) {
        sky = &m_.asset.extras.Get("lbk_sky");
        where = "asset extras";
    }
    if (!sky) return;
    if (sky->IsArray()) {
        bool ok = sky->ArrayLen() == 3;
        for (int k = 0; ok && k < 3; k++) {
            const tinygltf::Value &c = sky->Get(k);
            ok = c.IsNumber() && finite_nonneg(c.GetNumberAsDouble()) && std::isfinite((float)c.GetNumberAsDouble());
            if (ok) s_->sky[k] = (float)c.GetNumberAsDouble();
        }
        if (!ok) fail("%s: %s: key lbk_sky must be [r, g, b] with finite numbers >= 0", file, where.c_str());
        return;
    }
    if (!sky->IsString() || sky->Get<std::string>().empty())
        fail("%s: %s: key lbk_sky must be [r, g, b] or the path of an equirectangular EXR", file, where.c_str());
    std::string rel = sky->Get<std::string>();
    std::string p = rel[0] == '/' ? rel : dir_of(path_) + "/" + rel;
    std::vector<unsigned char> bytes;
    std::string why;
    if (!resource_allowed(policy_, p, &why) || !read_capped(p, o_.max_file_bytes, &bytes, &why))
        fail("%s: %s: lbk_sky %s: %s", file, where.c_str(), qstr(rel).c_str(), why.c_str());
    XXH3_64bits_update(&hash_, bytes.data(), bytes.size());
    reads_.push_back(InputRecord{p, "sky", bytes.size(), XXH3_64bits(bytes.data(), bytes.size())});
    bytes.clear();
    bytes.shrink_to_fit();
    bk_image im{};
    char eerr[512];
    if (bk_exr_read(p.c_str(), o_.max_image_pixels, &im, eerr, sizeof eerr))
        fail("%s: %s: lbk_sky: %s", file, where.c_str(), eerr);
    if (im.width > o_.max_sky_size || im.height > o_.max_sky_size) {
        int nw, nh;
        std::vector<float> small;
        try {
            small = downsample(im.rgba, im.width, im.height, o_.max_sky_size, &nw, &nh);
        } catch (...) {
            free(im.rgba);
            throw;
        }
        free(im.rgba);
        im.rgba = alloc_array<float>((size_t)nw * nh, 4);
        memcpy(im.rgba, small.data(), small.size() * sizeof(float));
        im.width = nw;
        im.height = nh;
        if (o_.report) o_.report->downsampled_images++;
    }
    uint64_t b = (uint64_t)im.width * im.height * 16;
    if (image_bytes_ + b > o_.max_image_bytes) {
        free(im.rgba);
        fail("%s: lbk_sky image exceeds the %zu-byte image memory cap", file, o_.max_image_bytes);
    }
    image_bytes_ += b;
    images_.push_back(im);
    s_->sky_image = (int)images_.size() - 1;
    for (int k = 0; k < 3; k++) s_->sky[k] = im.mean[k];
}

// Node extras lbk_playable (spec/authoring.md): true = the node-local box [-1, 1]³ (a Blender cube
// empty of size 1, scaled by the node), {"min": [x, y, z], "max": [x, y, z]} = that node-local box,
// false = nothing. The scene keeps the world-space bounding box of the transformed box.
void Importer::read_playable(int n, const Mat4 &world, const tinygltf::Value &v)
{
    const char *file = path_.c_str();
    std::string lbl = node_label(n);
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    if (v.IsBool()) {
        if (!v.Get<bool>()) return;
    } else if (v.IsObject()) {
        const char *keys[2] = {"min", "max"};
        double *dst[2] = {lo, hi};
        for (int i = 0; i < 2; i++) {
            bool ok = v.Has(keys[i]) && v.Get(keys[i]).IsArray() && v.Get(keys[i]).ArrayLen() == 3;
            for (int k = 0; ok && k < 3; k++) {
                const tinygltf::Value &e = v.Get(keys[i]).Get(k);
                ok = e.IsNumber() && std::isfinite(e.GetNumberAsDouble());
                if (ok) dst[i][k] = e.GetNumberAsDouble();
            }
            if (!ok)
                fail("%s: %s: extras key lbk_playable: \"%s\" must be an array of 3 finite numbers", file, lbl.c_str(),
                     keys[i]);
        }
        for (int k = 0; k < 3; k++)
            if (!(lo[k] < hi[k]))
                fail("%s: %s: extras key lbk_playable: min must be below max on every axis", file, lbl.c_str());
    } else {
        fail("%s: %s: extras key lbk_playable must be true, false or {\"min\": [x, y, z], \"max\": [x, y, z]}", file,
             lbl.c_str());
    }
    if (playable_.size() >= BK_MAX_PLAYABLE)
        fail("%s: %s: more than %d nodes with lbk_playable (the cap)", file, lbl.c_str(), BK_MAX_PLAYABLE);
    PlayableBox b;
    for (int k = 0; k < 3; k++) { b.min[k] = INFINITY; b.max[k] = -INFINITY; }
    for (int c = 0; c < 8; c++) {
        double p[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]}, w[3];
        xform_point(world, p, w);
        for (int k = 0; k < 3; k++) { b.min[k] = std::min(b.min[k], w[k]); b.max[k] = std::max(b.max[k], w[k]); }
    }
    for (int k = 0; k < 3; k++)
        if (!std::isfinite(b.min[k]) || !std::isfinite(b.max[k]) || !(b.min[k] < b.max[k]) ||
            std::fabs(b.min[k]) > 1e7 || std::fabs(b.max[k]) > 1e7)
            fail("%s: %s: extras key lbk_playable: the box is empty or out of range after the node's transform", file,
                 lbl.c_str());
    playable_.push_back(b);
}

// Playable boxes into the scene, relative to the origin chosen for the geometry.
void Importer::emit_playable()
{
    s_->playable = alloc_array<bk_box>(playable_.empty() ? 1 : playable_.size(), 1);
    for (size_t i = 0; i < playable_.size(); i++)
        for (int k = 0; k < 3; k++) {
            s_->playable[i].min[k] = (float)(playable_[i].min[k] - s_->origin[k]);
            s_->playable[i].max[k] = (float)(playable_[i].max[k] - s_->origin[k]);
            if (!(s_->playable[i].min[k] < s_->playable[i].max[k])) s_->playable[i].max[k] = nextafterf(s_->playable[i].min[k], INFINITY);
        }
    s_->playable_count = playable_.size();
}

// Scene extras lbk_combinations: [[name, name], ...], looked up like lbk_sky (spec/authoring.md).
void Importer::read_combinations()
{
    const char *file = path_.c_str();
    const tinygltf::Value *v = nullptr;
    std::string where;
    int si = m_.defaultScene >= 0 ? m_.defaultScene : 0;
    if (!m_.scenes.empty() && m_.scenes[(size_t)si].extras.IsObject() &&
        m_.scenes[(size_t)si].extras.Has("lbk_combinations")) {
        v = &m_.scenes[(size_t)si].extras.Get("lbk_combinations");
        where = "scene " + std::to_string(si) + " extras";
    } else if (m_.extras.IsObject() && m_.extras.Has("lbk_combinations")) {
        v = &m_.extras.Get("lbk_combinations");
        where = "root extras";
    } else if (m_.asset.extras.IsObject() && m_.asset.extras.Has("lbk_combinations")) {
        v = &m_.asset.extras.Get("lbk_combinations");
        where = "asset extras";
    }
    if (!v) return;
    if (!v->IsArray() || v->ArrayLen() > 4096)
        fail("%s: %s: key lbk_combinations must be an array (at most 4096) of [name, name] pairs", file,
             where.c_str());
    size_t n = v->ArrayLen();
    bk_combination *c = alloc_array<bk_combination>(n, 1);
    memset(c, 0, (n ? n : 1) * sizeof *c);
    s_->combinations = c;
    for (size_t i = 0; i < n; i++) {
        const tinygltf::Value &p = v->Get((int)i);
        bool ok = p.IsArray() && p.ArrayLen() == 2;
        for (int k = 0; ok && k < 2; k++) {
            const tinygltf::Value &e = p.Get(k);
            ok = e.IsString() && !e.Get<std::string>().empty() && e.Get<std::string>().size() <= 63;
            if (ok) snprintf(c[i].members[k], sizeof c[i].members[k], "%s", e.Get<std::string>().c_str());
        }
        if (!ok)
            fail("%s: %s: lbk_combinations[%zu] must be a pair of door or light set names (1 to 63 bytes each)", file,
                 where.c_str(), i);
    }
    s_->combination_count = n;
}

// The files read, into the scene: paths relative to the scene's folder (the scene file by its
// name), so the record does not depend on where the level is checked out.
void Importer::record_inputs()
{
    const std::string dir = dir_of(path_) + "/";
    s_->inputs = alloc_array<bk_input_file>(reads_.empty() ? 1 : reads_.size(), 1);
    memset(s_->inputs, 0, (reads_.empty() ? 1 : reads_.size()) * sizeof *s_->inputs);
    for (size_t i = 0; i < reads_.size(); i++) {
        const InputRecord &r = reads_[i];
        std::string rel = r.path;
        if (r.role == std::string("scene")) {
            size_t sl = rel.find_last_of('/');
            if (sl != std::string::npos) rel = rel.substr(sl + 1);
        } else if (rel.compare(0, dir.size(), dir) == 0) {
            rel = rel.substr(dir.size());
        }
        bk_input_file &f = s_->inputs[i];
        snprintf(f.path, sizeof f.path, "%s", rel.c_str());
        snprintf(f.role, sizeof f.role, "%s", r.role);
        f.bytes = r.bytes;
        f.hash = r.hash;
    }
    s_->input_count = reads_.size();
}

void Importer::run()
{
    load();
    check_extensions();
    decode_images();
    build_materials();
    meshes_.resize(m_.meshes.size());
    traverse();
    emit_geometry();
    emit_lights();
    read_sky();
    read_combinations();
    emit_playable();
    // Tables move into the C struct last, so a failure above frees them with the vectors.
    s_->materials = alloc_array<bk_material>(materials_.size(), 1);
    if (!materials_.empty()) memcpy(s_->materials, materials_.data(), materials_.size() * sizeof(bk_material));
    s_->material_count = materials_.size();
    s_->images = alloc_array<bk_image>(images_.size(), 1);
    if (!images_.empty()) memcpy(s_->images, images_.data(), images_.size() * sizeof(bk_image));
    s_->image_count = images_.size();
    images_.clear();
    record_inputs();
    s_->source_hash = XXH3_64bits_digest(&hash_);
    bk_scene_compute_bounds(s_);
}

}  // namespace

extern "C" int bk_import_gltf(const char *path, const bk_import_options *opt, bk_scene *out, char *err,
                              size_t err_len)
{
    char dummy[1];
    if (!err || !err_len) { err = dummy; err_len = sizeof dummy; }
    err[0] = '\0';
    if (!out) {
        snprintf(err, err_len, "bk_import_gltf: no output scene");
        return 1;
    }
    memset(out, 0, sizeof *out);
    out->sky_image = -1;
    if (!path) {
        snprintf(err, err_len, "bk_import_gltf: no path");
        return 1;
    }
    bk_import_options o = opt ? *opt : bk_import_options{};
    if (!o.max_triangles) o.max_triangles = (size_t)1 << 24;
    if (!o.max_file_bytes) o.max_file_bytes = (size_t)1 << 30;
    if (!o.max_json_bytes) o.max_json_bytes = (size_t)64 << 20;
    if (!o.max_image_bytes) o.max_image_bytes = (size_t)512 << 20;
    if (o.max_texture_size <= 0) o.max_texture_size = 1024;
    if (o.max_sky_size <= 0) o.max_sky_size = 2048;
    if (!o.max_image_pixels) o.max_image_pixels = (size_t)64 << 20;
    int rc = 1;
    Importer *imp = nullptr;
    try {
        imp = new Importer(path, o, out);
        imp->run();
        rc = 0;
    } catch (const ImportError &e) {
        snprintf(err, err_len, "%s", e.msg.c_str());
    } catch (const std::bad_alloc &) {
        snprintf(err, err_len, "%s: out of memory while importing", path);
    } catch (const std::exception &e) {
        snprintf(err, err_len, "%s: import failed: %s", path, e.what());
    } catch (...) {
        snprintf(err, err_len, "%s: import failed (unknown error)", path);
    }
    try {
        delete imp;
    } catch (...) {
    }
    if (rc) bk_scene_free(out);
    return rc;
}
