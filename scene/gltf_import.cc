// glTF 2.0 (.gltf / .glb) → bk_scene: bk_import_gltf(), the importer's one export, and the
// Importer's flow: loading (the scene file, the pre-pass, tinygltf through our file callbacks),
// the node graph and its node extras, and the order of the steps (Importer::run). What the other
// parts do and why the input is guarded: scene/gltf_internal.hh.

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "scene/gltf_internal.hh"

namespace bk_gltf {

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
    pp_ = prepass(glb ? g.json : reinterpret_cast<const char *>(bytes.data()), json_len, path_, policy_,
                  o_.normal_maps != 0);

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
    // KHR_texture_basisu required: refused by the pre-pass, by name
    static const char *const supported[] = {"EXT_meshopt_compression", "EXT_texture_webp",
                                            "KHR_draco_mesh_compression",
                                            "KHR_lights_punctual", "KHR_materials_emissive_strength",
                                            "KHR_materials_pbrSpecularGlossiness", "KHR_materials_unlit",
                                            "KHR_mesh_quantization", "KHR_texture_transform"};
    for (const std::string &e : m_.extensionsUsed)  // spec/authoring.md "Material extensions"
        if (e == "KHR_materials_variants")
            warn("KHR_materials_variants ignored: each primitive's default material is baked");
    for (const std::string &e : m_.extensionsRequired) {
        bool used = false;
        for (const std::string &u : m_.extensionsUsed) used = used || u == e;
        if (!used)  // glTF 2.0 §3.12: extensionsRequired lists extensions that are also in extensionsUsed
            fail("%s: extensionsRequired names %s, which extensionsUsed does not list", path_.c_str(),
                 qstr(e).c_str());
        bool ok = false;
        std::string list;
        for (const char *s : supported) {
            ok = ok || e == s;
            list += (list.empty() ? "" : ", ") + std::string(s);
        }
        if (!ok)
            fail("%s: requires glTF extension %s, which lbk does not support (supported: %s)", path_.c_str(),
                 e.c_str(), list.c_str());
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

namespace {

bool valid_name(const std::string &s) {
    if (s.empty() || s.size() > 63) return false;
    for (unsigned char c : s)
        if (c < 32 || c == 127) return false;
    return true;
}

}  // namespace

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
            if (!v.IsNumber() || !std::isfinite(d) || d <= 0 || d > BK_TEXEL_DENSITY_MAX)
                fail("%s: %s: extras key lbk_texel_density must be a number of texels per metre in (0, %g]",
                     file, lbl.c_str(), BK_TEXEL_DENSITY_MAX);
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
    decode_meshopt();
    decode_images();
    build_materials();
    meshes_.resize(m_.meshes.size());
    traverse();
    emit_geometry();
    if (s_->tangents && bk_scene_derive_tangents(s_)) throw std::bad_alloc();
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

}  // namespace bk_gltf

using bk_gltf::ImportError;
using bk_gltf::Importer;

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
