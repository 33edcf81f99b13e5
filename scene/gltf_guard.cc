// The glTF importer's guard over its untrusted input (scene/gltf_internal.hh says why): errors (fail,
// qstr), the path sandbox and capped file reads tinygltf goes through, the pre-pass over the JSON
// (depth cap, URIs, image bufferViews, Draco taken from tinygltf) and the GLB container.

#include <nlohmann/json.hpp>

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "scene/gltf_internal.hh"

namespace bk_gltf {

namespace {

const int kMaxJsonDepth = 64;     // deeper JSON is refused (tinygltf converts extras recursively)

const char *kind_of(mode_t m)
{
    return S_ISDIR(m) ? "a directory" : S_ISCHR(m) ? "a character device" : S_ISBLK(m) ? "a block device"
         : S_ISFIFO(m) ? "a FIFO" : S_ISSOCK(m) ? "a socket" : "not a regular file";
}

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

// The JSON text's shape in one linear scan (brackets and commas inside strings do not count):
// its deepest nesting, and how many objects, arrays and commas it holds. nlohmann's callback
// parser would check depth for us, but it re-scans the open container each time an element
// closes, which made 80 k empty nodes take ~17 s and 10^6 nodes effectively never finish; the
// parsers after this scan are linear.
struct Shape {
    int deepest = 0;
    uint64_t objects = 0, arrays = 0, commas = 0;
};

Shape json_shape(const char *p, size_t n)
{
    Shape s;
    int depth = 0;
    bool in_string = false;
    for (size_t i = 0; i < n; i++) {
        const char c = p[i];
        if (in_string) {
            if (c == '\\') i++;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            (c == '[' ? s.arrays : s.objects)++;
            if (++depth > s.deepest) s.deepest = depth;
        } else if (c == ']' || c == '}') {
            depth--;
        } else if (c == ',') {
            s.commas++;
        }
    }
    return s;
}

// ---- the memory budget: what the JSON will cost before anything is built ------------------------
//
// tinygltf builds a DOM of the whole JSON and then a struct per node, mesh, primitive, accessor
// and so on; an empty node `{}` is 3 bytes of JSON but several hundred bytes of tinygltf::Node
// (2*10^7 of them, 57 MiB of JSON, took more than 12.8 GB). The file is refused when what it
// would cost exceeds kBudgetBase + kBudgetPerByte * its JSON size, before the pre-pass's own DOM
// or tinygltf allocate anything: first a floor from the depth scan's counts (the DOM alone), then
// one SAX pass (nlohmann's parser without a DOM: linear, nothing kept but counts) that counts the
// elements of each kind and what tinygltf makes of them, naming the counts.

const uint64_t kBudgetBase = (uint64_t)256 << 20;  // any file may take this much
const uint64_t kBudgetPerByte = 16;                 // and this much more per byte of JSON

enum Kind { K_NODES, K_MESHES, K_PRIMITIVES, K_ACCESSORS, K_BUFFER_VIEWS, K_MATERIALS, K_TEXTURES, K_IMAGES,
            K_SAMPLERS, K_BUFFERS, K_SCENES, K_ANIMATIONS, K_SKINS, K_CAMERAS, K_KINDS };
const char *const kKindName[K_KINDS] = {"nodes", "meshes", "primitives", "accessors", "bufferViews", "materials",
                                        "textures", "images", "samplers", "buffers", "scenes", "animations",
                                        "skins", "cameras"};
// What tinygltf allocates for each element (its struct; vectors and strings inside are counted
// as the JSON values they come from).
const size_t kKindBytes[K_KINDS] = {
    sizeof(tinygltf::Node), sizeof(tinygltf::Mesh), sizeof(tinygltf::Primitive), sizeof(tinygltf::Accessor),
    sizeof(tinygltf::BufferView), sizeof(tinygltf::Material), sizeof(tinygltf::Texture), sizeof(tinygltf::Image),
    sizeof(tinygltf::Sampler), sizeof(tinygltf::Buffer), sizeof(tinygltf::Scene), sizeof(tinygltf::Animation),
    sizeof(tinygltf::Skin), sizeof(tinygltf::Camera)};
const uint64_t kHeap = 16;  // malloc's overhead per block

using json = nlohmann::json;

struct Census {
    uint64_t values = 0, objects = 0, arrays = 0, keys = 0, extras_values = 0;
    uint64_t count[K_KINDS] = {};
};

// The SAX handler: a stack of open containers, each knowing what its elements are.
class CensusSax : public nlohmann::json_sax<json> {
public:
    explicit CensusSax(Census *c) : c_(c) {}
    std::string error;

    bool null() override { return value(); }
    bool boolean(bool) override { return value(); }
    bool number_integer(number_integer_t) override { return value(); }
    bool number_unsigned(number_unsigned_t) override { return value(); }
    bool number_float(number_float_t, const string_t &) override { return value(); }
    bool string(string_t &) override { return value(); }
    bool binary(binary_t &) override { return value(); }
    bool key(string_t &k) override
    {
        c_->keys++;
        key_ = k;
        return true;
    }
    bool start_object(std::size_t) override { return open(false); }
    bool start_array(std::size_t) override { return open(true); }
    bool end_object() override { return close(); }
    bool end_array() override { return close(); }
    bool parse_error(std::size_t, const std::string &, const nlohmann::detail::exception &e) override
    {
        error = e.what();
        return false;
    }

private:
    struct Frame {
        bool array, root, mesh, extras;
        int kind;  // an array whose elements are counted as this kind, or -1
    };
    Census *c_;
    std::vector<Frame> stack_;
    std::string key_;  // the current object's last key (read only while that object is on top)

    bool in_object() const { return !stack_.empty() && !stack_.back().array; }
    bool extras_key() const { return in_object() && (key_ == "extras" || key_ == "extensions"); }
    bool value()
    {
        c_->values++;
        if (!stack_.empty() && stack_.back().array && stack_.back().kind >= 0) c_->count[stack_.back().kind]++;
        if ((!stack_.empty() && stack_.back().extras) || extras_key()) c_->extras_values++;
        return true;
    }
    bool open(bool array)
    {
        Frame f{array, stack_.empty(), false, extras_key() || (!stack_.empty() && stack_.back().extras), -1};
        if (array && in_object() && stack_.back().root) {
            for (int k = 0; k < K_KINDS; k++)
                if (k != K_PRIMITIVES && key_ == kKindName[k]) f.kind = k;
        } else if (array && in_object() && stack_.back().mesh && key_ == "primitives") {
            f.kind = K_PRIMITIVES;
        } else if (!array && !stack_.empty() && stack_.back().array && stack_.back().kind == K_MESHES) {
            f.mesh = true;
        }
        value();
        (array ? c_->arrays : c_->objects)++;
        stack_.push_back(f);
        return true;
    }
    bool close()
    {
        if (!stack_.empty()) stack_.pop_back();
        return true;
    }
};

// Bytes the import is expected to hold at its peak (tinygltf's DOM and model together).
uint64_t census_bytes(const Census &c, size_t json_len)
{
    uint64_t b = 4 * (uint64_t)json_len;  // the file, the rewritten JSON, GLB copies, strings
    b += c.values * (2 * sizeof(json) + 8);  // a DOM slot (arrays grow by doubling) and the parsed number
    b += c.objects * (sizeof(json::object_t) + kHeap) + c.arrays * (sizeof(json::array_t) + kHeap);
    b += c.keys * (sizeof(std::pair<const std::string, json>) + 32 + kHeap);  // a map node
    b += c.extras_values * (sizeof(tinygltf::Value) + sizeof(std::pair<const std::string, tinygltf::Value>) + 32);
    // tinygltf appends each element to a std::vector that grows by doubling: up to twice the size
    for (int k = 0; k < K_KINDS; k++) b += c.count[k] * (2 * kKindBytes[k] + kHeap);
    return b;
}

void check_budget(const char *json_begin, size_t json_len, const Shape &shape, const std::string &file)
{
    const uint64_t allowed = kBudgetBase + kBudgetPerByte * json_len;
    // A lower bound from the scan's counts first (the DOM alone, every comma a value), which
    // refuses 2*10^7 empty nodes without the SAX pass.
    uint64_t floor = 4 * (uint64_t)json_len + shape.objects * (sizeof(json::object_t) + kHeap) +
                     shape.arrays * (sizeof(json::array_t) + kHeap) +
                     std::max(shape.commas, shape.objects + shape.arrays) * (2 * sizeof(json) + 8);
    if (floor > allowed)
        fail("%s: %llu JSON objects, %llu arrays and %llu commas would take at least %llu MiB to import, more than "
             "the %llu MiB allowed for %zu bytes of JSON (256 MiB + 16 per byte)", file.c_str(),
             (unsigned long long)shape.objects, (unsigned long long)shape.arrays, (unsigned long long)shape.commas,
             (unsigned long long)(floor >> 20), (unsigned long long)(allowed >> 20), json_len);
    Census c;
    CensusSax sax(&c);
    if (!json::sax_parse(json_begin, json_begin + json_len, &sax, nlohmann::json::input_format_t::json, true, false) &&
        !sax.error.empty())
        fail("%s: invalid JSON: %s", file.c_str(), sax.error.c_str());
    const uint64_t need = census_bytes(c, json_len);
    if (need <= allowed) return;
    std::string counts;
    for (int k = 0; k < K_KINDS; k++)
        if (c.count[k]) counts += (counts.empty() ? "" : ", ") + std::to_string(c.count[k]) + " " + kKindName[k];
    fail("%s: %s%s%llu JSON values would take about %llu MiB to import, more than the %llu MiB allowed for "
         "%zu bytes of JSON (256 MiB + 16 per byte)", file.c_str(), counts.c_str(), counts.empty() ? "" : ", ",
         (unsigned long long)c.values, (unsigned long long)(need >> 20), (unsigned long long)(allowed >> 20), json_len);
}

// The node graph's depth along `children` (first parent wins; a node with two parents or a cycle
// is refused by the traversal when the scene reaches it), computed on parent indices: a 10^6-deep
// chain is refused here, in milliseconds, before tinygltf builds its nodes.
void check_node_depth(const nlohmann::json &doc, const std::string &file)
{
    const nlohmann::json *nodes = jarr(doc, "nodes");
    if (!nodes) return;
    const size_t n = nodes->size();
    std::vector<int32_t> parent(n, -1), depth(n, -1);  // depth -2: on the walk being resolved
    for (size_t i = 0; i < n; i++) {
        const nlohmann::json *ch = jarr((*nodes)[i], "children");
        if (!ch) continue;
        for (const nlohmann::json &c : *ch)
            if (c.is_number_integer() && c.get<long long>() >= 0 && (size_t)c.get<long long>() < n &&
                (size_t)c.get<long long>() != i && parent[(size_t)c.get<long long>()] < 0)
                parent[(size_t)c.get<long long>()] = (int32_t)i;
    }
    std::vector<int32_t> walk;
    for (size_t i = 0; i < n; i++) {
        walk.clear();
        int32_t j = (int32_t)i;
        while (j >= 0 && depth[(size_t)j] == -1) {
            depth[(size_t)j] = -2;
            walk.push_back(j);
            j = parent[(size_t)j];
        }
        int32_t d = (j >= 0 && depth[(size_t)j] >= 0) ? depth[(size_t)j] : -1;  // a root, or a cycle
        for (size_t k = walk.size(); k-- > 0;) {
            depth[(size_t)walk[k]] = ++d;
            if (d > kMaxNodeDepth) {
                const nlohmann::json &nd = (*nodes)[(size_t)walk[k]];
                std::string nm = nd.is_object() && nd.contains("name") && nd["name"].is_string()
                                     ? " " + qstr(nd["name"].get<std::string>()) : "";
                fail("%s: node %d%s: node hierarchy deeper than %d", file.c_str(), walk[k], nm.c_str(), kMaxNodeDepth);
            }
        }
    }
}

// tinygltf percent-decodes file URIs (dlib::urldecode: %XX and '+' as a space) before it opens
// them; the same decoding, so that what is checked is what is opened.
std::string url_decode(const std::string &s)
{
    auto hex = [](char c) {  // as dlib's from_hex: anything else is 0 ("%zz" decodes to NUL)
        return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : 0;
    };
    std::string out;
    for (size_t i = 0; i < s.size(); i++) {
        if (s[i] == '+') {
            out += ' ';
        } else if (s[i] == '%' && s.size() > i + 2) {
            out += (char)(hex(s[i + 1]) * 16 + hex(s[i + 2]));
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

// Bytes a base64 data: URI decodes to, as tinygltf's decoder counts them (it stops at '=' or at
// the first character outside the alphabet); -1 when the URI is not base64.
long long data_uri_bytes(const std::string &uri)
{
    size_t at = uri.find(";base64,");
    if (at == std::string::npos) return -1;
    long long k = 0;
    for (size_t i = at + 8; i < uri.size() && (isalnum((unsigned char)uri[i]) || uri[i] == '+' || uri[i] == '/'); i++) k++;
    return k / 4 * 3 + (k % 4 > 1 ? k % 4 - 1 : 0);
}

// The files buffers and images name, before tinygltf opens them: a FIFO, folder or device is
// refused by name (tinygltf would say "File not found"), a buffer's file or data: URI must hold
// byteLength bytes (tinygltf would say "File size mismatch" or "Failed to decode 'uri'").
void check_uri_targets(const nlohmann::json &arr, const char *kind, const std::string &file, const ResourcePolicy &pol)
{
    const int klen = (int)strlen(kind) - 1;  // "buffers" -> "buffer"
    const bool buffer = !strcmp(kind, "buffers");
    for (size_t i = 0; i < arr.size(); i++) {
        const nlohmann::json &e = arr[i];
        if (!e.is_object() || !e.contains("uri") || !e["uri"].is_string()) continue;
        const std::string uri = e["uri"].get<std::string>();
        long long blen = -1;
        if (buffer && !jint(e, "byteLength", &blen)) blen = -1;
        if (uri.compare(0, 5, "data:") == 0) {
            const long long have = data_uri_bytes(uri);
            if (buffer && have >= 0 && blen >= 0 && have != blen)
                fail("%s: buffer %zu: its data: URI holds %lld bytes, byteLength says %lld", file.c_str(), i, have, blen);
            continue;
        }
        const std::string dec = url_decode(uri);
        if (dec.find('\0') != std::string::npos)
            fail("%s: %.*s %zu: uri %s holds a NUL byte (%%00): refused, it would name another file", file.c_str(),
                 klen, kind, i, qstr(uri).c_str());
        const std::string p = dir_of(file) + "/" + dec;
        struct stat st;
        if (stat(p.c_str(), &st) != 0) {
            if (buffer)
                fail("%s: buffer %zu: uri %s: %s (%s)", file.c_str(), i, qstr(uri).c_str(), strerror(errno), p.c_str());
            continue;  // an image: a warning, or an error if the baker needs it (decode_image)
        }
        if (!S_ISREG(st.st_mode))
            fail("%s: %.*s %zu: uri %s names %s, not a regular file", file.c_str(), klen, kind, i, qstr(uri).c_str(),
                 kind_of(st.st_mode));
        std::string why;
        if (!resource_allowed(pol, p, &why))
            fail("%s: %.*s %zu: uri %s %s", file.c_str(), klen, kind, i, qstr(uri).c_str(), why.c_str());
        if (buffer && blen >= 0 && (long long)st.st_size != blen)
            fail("%s: buffer %zu: %s is %lld bytes, byteLength says %lld", file.c_str(), i, qstr(uri).c_str(),
                 (long long)st.st_size, blen);
    }
}

// KHR_texture_basisu: lbk does not decode it. Only used, the fallback is read (a texture's core
// source); required, there is none, so the import is refused here, naming the first texture
// that uses the extension, before tinygltf reads anything. (EXT_meshopt_compression is decoded:
// collect_meshopt.)
void check_required_codecs(const nlohmann::json &doc, const std::string &file)
{
    const nlohmann::json *req = jarr(doc, "extensionsRequired");
    if (!req) return;
    auto user = [&](const char *arr_key, const char *ext) -> std::string {
        const nlohmann::json *arr = jarr(doc, arr_key);
        for (size_t i = 0; arr && i < arr->size(); i++) {
            const nlohmann::json &e = (*arr)[i];
            if (!e.is_object() || !e.contains("extensions") || !e["extensions"].is_object() ||
                !e["extensions"].contains(ext))
                continue;
            std::string what = std::string(arr_key).substr(0, strlen(arr_key) - 1) + " " + std::to_string(i);
            if (e.contains("name") && e["name"].is_string()) what += " " + qstr(e["name"].get<std::string>());
            const nlohmann::json &x = e["extensions"][ext];
            long long src;
            const nlohmann::json *images = jarr(doc, "images");
            if (x.is_object() && jint(x, "source", &src) && images && src >= 0 && (size_t)src < images->size()) {
                const nlohmann::json &im = (*images)[(size_t)src];
                what += " (image " + std::to_string(src);
                if (im.is_object() && im.contains("uri") && im["uri"].is_string() &&
                    im["uri"].get<std::string>().compare(0, 5, "data:") != 0)
                    what += " " + qstr(im["uri"].get<std::string>());
                what += ")";
            }
            return what;
        }
        return std::string();
    };
    for (const auto &e : *req) {
        if (!e.is_string()) continue;
        const std::string ext = e.get<std::string>();
        if (ext != "KHR_texture_basisu") continue;
        std::string what = user("textures", ext.c_str());
        fail("%s: requires glTF extension %s (%s), which lbk cannot decode: %s", file.c_str(), ext.c_str(),
             what.empty() ? "no texture uses it" : ("used by " + what).c_str(),
             "export the textures as PNG, JPEG or WebP (or add a fallback source and leave the extension "
             "used, not required)");
    }
}

// EXT_meshopt_compression: every bufferView carrying it, checked as far as the JSON allows (the
// mode, filter, stride and count combinations of the extension's spec, which meshoptimizer's
// decoders assert rather than check), into pp->meshopt; the import decodes them (gltf_meshopt.cc)
// whether the extension is required or only used: the compressed view is preferred. A buffer
// flagged as the extension's fallback that only compressed views read is stubbed with one byte
// before tinygltf sees it: gltfpack writes it without a uri (tinygltf would refuse it, or in a
// GLB take the BIN chunk for it) and its data, when present, is never read.
void collect_meshopt(nlohmann::json &doc, const std::string &file, Prepass *pp)
{
    const char *kExt = "EXT_meshopt_compression";
    auto ext_of = [&](const nlohmann::json &o) -> const nlohmann::json * {
        if (!o.is_object() || !o.contains("extensions") || !o["extensions"].is_object()) return nullptr;
        auto it = o["extensions"].find(kExt);
        return it == o["extensions"].end() ? nullptr : &*it;
    };
    const nlohmann::json *views = jarr(doc, "bufferViews");
    const nlohmann::json *buffers = jarr(doc, "buffers");
    std::vector<char> plain_reader(buffers ? buffers->size() : 0, 0);  // read by a view without the extension
    for (size_t i = 0; views && i < views->size(); i++) {
        const nlohmann::json &v = (*views)[i];
        const nlohmann::json *x = ext_of(v);
        long long vb;
        if (!x) {
            if (jint(v, "buffer", &vb) && vb >= 0 && (size_t)vb < plain_reader.size()) plain_reader[(size_t)vb] = 1;
            continue;
        }
        std::string lbl = "bufferView " + std::to_string(i);
        if (v.contains("name") && v["name"].is_string()) lbl += " " + qstr(v["name"].get<std::string>());
        MeshoptView mv;
        long long b, off = 0, len, stride, count;
        if (!x->is_object() || !jint(*x, "buffer", &b) || !jint(*x, "byteLength", &len) ||
            !jint(*x, "byteStride", &stride) || !jint(*x, "count", &count) || !x->contains("mode") ||
            !(*x)["mode"].is_string() || (x->contains("byteOffset") && !jint(*x, "byteOffset", &off)))
            fail("%s: %s: %s needs integer buffer, byteLength, byteStride and count and a mode", file.c_str(),
                 lbl.c_str(), kExt);
        if (!buffers || b < 0 || (size_t)b >= buffers->size() || off < 0 || len < 0 || count < 0)
            fail("%s: %s: %s: buffer %lld, byteOffset %lld, byteLength %lld or count %lld out of range",
                 file.c_str(), lbl.c_str(), kExt, b, off, len, count);
        const std::string mode = (*x)["mode"].get<std::string>();
        std::string filter = "NONE";
        if (x->contains("filter")) {
            if (!(*x)["filter"].is_string()) fail("%s: %s: %s: filter is not a string", file.c_str(), lbl.c_str(), kExt);
            filter = (*x)["filter"].get<std::string>();
        }
        bool ok;
        if (mode == "ATTRIBUTES") {
            mv.mode = MeshoptView::ATTRIBUTES;
            ok = stride > 0 && stride <= 256 && stride % 4 == 0;
        } else if (mode == "TRIANGLES" || mode == "INDICES") {
            mv.mode = mode == "TRIANGLES" ? MeshoptView::TRIANGLES : MeshoptView::INDICES;
            ok = (stride == 2 || stride == 4) && (mv.mode == MeshoptView::INDICES || count % 3 == 0) &&
                 filter == "NONE";
        } else {
            fail("%s: %s: %s: unknown mode %s (ATTRIBUTES, TRIANGLES or INDICES)", file.c_str(), lbl.c_str(),
                 kExt, qstr(mode).c_str());
        }
        if (filter == "NONE") mv.filter = MeshoptView::NONE;
        else if (filter == "OCTAHEDRAL") mv.filter = MeshoptView::OCTAHEDRAL, ok = ok && (stride == 4 || stride == 8);
        else if (filter == "QUATERNION") mv.filter = MeshoptView::QUATERNION, ok = ok && stride == 8;
        else if (filter == "EXPONENTIAL") mv.filter = MeshoptView::EXPONENTIAL;
        else
            fail("%s: %s: %s: unknown filter %s (NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL)", file.c_str(),
                 lbl.c_str(), kExt, qstr(filter).c_str());
        if (!ok)
            fail("%s: %s: %s: byteStride %lld and count %lld do not fit mode %s with filter %s", file.c_str(),
                 lbl.c_str(), kExt, stride, count, mode.c_str(), filter.c_str());
        mv.view = (int)i;
        mv.buffer = (int)b;
        mv.offset = (uint64_t)off;
        mv.length = (uint64_t)len;
        mv.stride = (uint64_t)stride;
        mv.count = (uint64_t)count;
        pp->meshopt.push_back(mv);
    }
    for (size_t i = 0; buffers && i < buffers->size(); i++) {
        const nlohmann::json *x = ext_of((*buffers)[i]);
        if (!x || !x->is_object() || !x->contains("fallback") || !(*x)["fallback"].is_boolean() ||
            !(*x)["fallback"].get<bool>() || plain_reader[i])
            continue;
        doc["buffers"][i] = nlohmann::json{{"byteLength", 1}, {"uri", "data:application/octet-stream;base64,AA=="}};
    }
}

// Buffers and images name files relative to the scene (or embed data: URIs). An absolute path
// or another URI scheme (file://, http://) would reach outside it: refuse them up front, with the
// entry named; `..` escapes and symlinks are caught when the file is opened (resource_allowed).
void check_uris(const nlohmann::json &doc, const std::string &file, const ResourcePolicy &pol)
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
        check_uri_targets(*arr, kind, file, pol);
    }
}

}  // namespace

Prepass prepass(const char *json_begin, size_t json_len, const std::string &file, const ResourcePolicy &pol,
                bool normal_maps)
{
    Prepass pp;
    const Shape shape = json_shape(json_begin, json_len);
    if (shape.deepest > kMaxJsonDepth)
        fail("%s: JSON nested deeper than %d levels", file.c_str(), kMaxJsonDepth);
    check_budget(json_begin, json_len, shape, file);
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(json_begin, json_begin + json_len, nullptr, true);
    } catch (const nlohmann::json::exception &e) {
        fail("%s: invalid JSON: %s", file.c_str(), e.what());
    }
    if (!doc.is_object()) fail("%s: the JSON root is not an object", file.c_str());
    // glTF 1.0 names its meshes, materials and accessors differently: read as 2.0 it would import
    // no triangles without saying why
    if (doc.contains("asset") && doc["asset"].is_object() && doc["asset"].contains("version") &&
        doc["asset"]["version"].is_string() && doc["asset"]["version"].get<std::string>().rfind("2.", 0) != 0)
        fail("%s: asset.version is %s: lbk reads glTF 2.0 only", file.c_str(),
             qstr(doc["asset"]["version"].get<std::string>()).c_str());
    check_required_codecs(doc, file);
    collect_meshopt(doc, file, &pp);
    check_uris(doc, file, pol);
    check_node_depth(doc, file);

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

    // Textures that matter to the baker: base colour, metallic-roughness and emissive (and the
    // normal texture for an import that reads normal maps).
    {
        const nlohmann::json *images = jarr(doc, "images");
        const nlohmann::json *textures = jarr(doc, "textures");
        const nlohmann::json *materials = jarr(doc, "materials");
        pp.needed_images.assign(images ? images->size() : 0, 0);
        auto need = [&](const nlohmann::json &info, char why) {  // why: 1 colour, 2 normal (ImageLoaderCtx)
            long long t, src;
            if (!textures || !jint(info, "index", &t) || t < 0 || (size_t)t >= textures->size()) return;
            const nlohmann::json &tex = (*textures)[(size_t)t];
            bool webp = false;  // EXT_texture_webp's source first, as Importer::texture_source reads it
            if (tex.is_object() && tex.contains("extensions") && tex["extensions"].is_object() &&
                tex["extensions"].contains("EXT_texture_webp"))
                webp = jint(tex["extensions"]["EXT_texture_webp"], "source", &src);
            if ((webp || jint(tex, "source", &src)) && src >= 0 &&
                (size_t)src < pp.needed_images.size())
                pp.needed_images[(size_t)src] |= why;
        };
        if (materials)
            for (const auto &m : *materials) {
                if (!m.is_object()) continue;
                auto pbr = m.find("pbrMetallicRoughness");
                if (pbr != m.end() && pbr->is_object() && pbr->contains("baseColorTexture"))
                    need((*pbr)["baseColorTexture"], 1);
                if (pbr != m.end() && pbr->is_object() && pbr->contains("metallicRoughnessTexture"))
                    need((*pbr)["metallicRoughnessTexture"], 1);
                if (m.contains("emissiveTexture")) need(m["emissiveTexture"], 1);
                auto ext = m.find("extensions");  // the specular-glossiness diffuse is the base colour
                if (ext != m.end() && ext->is_object() && ext->contains("KHR_materials_pbrSpecularGlossiness")) {
                    const nlohmann::json &sg = (*ext)["KHR_materials_pbrSpecularGlossiness"];
                    if (sg.is_object() && sg.contains("diffuseTexture")) need(sg["diffuseTexture"], 1);
                }
                if (normal_maps && m.contains("normalTexture")) need(m["normalTexture"], 2);
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
                long long ia;
                if (jint(prim, "indices", &ia) && ia >= 0 && ia <= INT32_MAX) di.indices = (int)ia;
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
