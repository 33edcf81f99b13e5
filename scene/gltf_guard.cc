// The glTF importer's guard over its untrusted input (scene/gltf_internal.hh says why): errors (fail,
// qstr), the path sandbox and capped file reads tinygltf goes through, the pre-pass over the JSON
// (depth cap, URIs, image bufferViews, Draco taken from tinygltf) and the GLB container.

#include <nlohmann/json.hpp>

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "scene/gltf_internal.hh"

namespace bk_gltf {

namespace {

const int kMaxJsonDepth = 64;     // deeper JSON is refused (tinygltf converts extras recursively)

}  // namespace

std::string vfmt(const char *fmt, va_list ap)
{
    char buf[1024];
    vsnprintf(buf, sizeof buf, fmt, ap);
    return buf;
}

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

namespace {

bool under(const std::string &real, const std::string &dir)
{
    return !dir.empty() && real.compare(0, dir.size(), dir) == 0;
}

}  // namespace

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

// ---- the pre-pass over the JSON ---------------------------------------------------------------

namespace {

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

}  // namespace

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

namespace {

uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

void put32(std::vector<unsigned char> &v, uint32_t x)
{
    for (int i = 0; i < 4; i++) v.push_back((unsigned char)(x >> (8 * i)));
}

}  // namespace

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

}  // namespace bk_gltf
