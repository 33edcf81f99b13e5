// The glTF importer's lights (KHR_lights_punctual), the sky (lbk_sky: a colour or an EXR) and
// the scene's other lbk_* extras: lbk_playable boxes and lbk_combinations (spec/authoring.md).

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "scene/exr_read.h"
#include "scene/gltf_internal.hh"

namespace bk_gltf {

namespace {

const double kPi = 3.14159265358979323846;

}  // namespace

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

}  // namespace bk_gltf
