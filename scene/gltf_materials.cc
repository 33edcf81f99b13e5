// The glTF importer's images and materials: tinygltf keeps the encoded bytes of the images the
// baker needs (keep_encoded_image), and they are decoded here (stb_image PNG/JPEG, libwebp WebP
// for EXT_texture_webp, each after a header-only size check), linearised and box-filtered to the
// size cap; then the materials, with KHR_texture_transform folded into uv0 (UvMap).

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_NO_STDIO
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#include <stb_image.h>
#include <webp/decode.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "scene/gltf_internal.hh"

namespace bk_gltf {

bool keep_encoded_image(tinygltf::Image *image, const int idx, std::string *, std::string *, int, int,
                        const unsigned char *bytes, int size, void *user)
{
    const ImageLoaderCtx *ctx = static_cast<const ImageLoaderCtx *>(user);
    // bufferView images are read later from the validated view; tinygltf's pointer is not used.
    if (image->bufferView >= 0) return true;
    if (idx < 0 || (size_t)idx >= ctx->needed->size()) return true;
    const char want = (*ctx->needed)[(size_t)idx] & (ctx->skip ? 2 : 3);  // skip_textures keeps normal maps
    if (!want) return true;
    if (bytes && size > 0) image->image.assign(bytes, bytes + size);
    return true;
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

// The RGBA8 pixels of an encoded PNG, JPEG or WebP (*webp: free with WebPFree, else
// stbi_image_free), after its header's size is checked against the pixel cap; nullptr (warned,
// counted) when the bytes are none of them.
unsigned char *Importer::decode_pixels(const unsigned char *bytes, size_t len, const std::string &label, int *w,
                                       int *h, bool *webp)
{
    // stb_image's header probe fails on a PNG past 2^30 bytes of pixels ("too large"), which would
    // read as "not decodable" and be ignored: the IHDR's size is checked against the cap first,
    // so a PNG is refused exactly like a JPEG of that size.
    static const unsigned char png_sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (len >= 24 && !memcmp(bytes, png_sig, 8) && !memcmp(bytes + 12, "IHDR", 4)) {
        auto be32 = [](const unsigned char *q) {
            return (uint64_t)q[0] << 24 | (uint64_t)q[1] << 16 | (uint64_t)q[2] << 8 | (uint64_t)q[3];
        };
        const uint64_t pw = be32(bytes + 16), ph = be32(bytes + 20);
        if (pw == 0 || ph == 0 || pw * ph > o_.max_image_pixels)
            fail("%s: %s: %llux%llu pixels exceeds the %zu-pixel cap", path_.c_str(), label.c_str(),
                 (unsigned long long)pw, (unsigned long long)ph, o_.max_image_pixels);
    }
    *webp = len >= 12 && !memcmp(bytes, "RIFF", 4) && !memcmp(bytes + 8, "WEBP", 4);
    if (*webp) {
        // WebPGetInfo reads the VP8/VP8L/VP8X header only (each side <= 16384 by the format)
        if (!WebPGetInfo(bytes, len, w, h)) {
            if (o_.report) o_.report->ignored_textures++;
            warn("%s: not a decodable WebP (bad header); texture ignored", label.c_str());
            return nullptr;
        }
        if (*w <= 0 || *h <= 0 || (uint64_t)*w * (uint64_t)*h > o_.max_image_pixels)
            fail("%s: %s: %dx%d pixels exceeds the %zu-pixel cap", path_.c_str(), label.c_str(), *w, *h,
                 o_.max_image_pixels);
        int cw = 0, ch = 0;
        unsigned char *px = WebPDecodeRGBA(bytes, len, &cw, &ch);
        if (!px || cw != *w || ch != *h) {
            if (px) WebPFree(px);
            fail("%s: %s: WebP decoding failed", path_.c_str(), label.c_str());
        }
        return px;
    }
    int comp = 0;
    if (!stbi_info_from_memory(bytes, (int)len, w, h, &comp)) {
        if (o_.report) o_.report->ignored_textures++;
        warn("%s: not a decodable PNG, JPEG or WebP (%s); texture ignored", label.c_str(), stbi_failure_reason());
        return nullptr;
    }
    if (*w <= 0 || *h <= 0 || (uint64_t)*w * (uint64_t)*h > o_.max_image_pixels)
        fail("%s: %s: %dx%d pixels exceeds the %zu-pixel cap", path_.c_str(), label.c_str(), *w, *h,
             o_.max_image_pixels);
    int cw = 0, ch = 0;
    unsigned char *px = stbi_load_from_memory(bytes, (int)len, &cw, &ch, &comp, 4);
    if (!px || cw != *w || ch != *h) {
        if (px) stbi_image_free(px);
        fail("%s: %s: decoding failed (%s)", path_.c_str(), label.c_str(), stbi_failure_reason());
    }
    return px;
}

// linear: the texels are data (a normal map), byte / 255 without the sRGB decode; cached apart
// from the colour decode of the same image.
int Importer::decode_image(int gi, bool linear)
{
    std::vector<int> &cache = linear ? linear_map_ : image_map_;
    if (cache[(size_t)gi] != -2) return cache[(size_t)gi];
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
    bool webp = false;
    int w = 0, h = 0;
    unsigned char *px = decode_pixels(bytes, len, label, &w, &h, &webp);
    if (!px) {
        cache[(size_t)gi] = -1;
        return -1;
    }
    auto free_px = [&]() { webp ? WebPFree(px) : stbi_image_free(px); };
    float lut[256];
    for (int i = 0; i < 256; i++) {
        double c = i / 255.0;
        lut[i] = (float)(linear ? c : c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    // Convert and filter in rows so a big texture never exists in float at full size.
    int f = 1;
    while ((w + f - 1) / f > o_.max_texture_size || (h + f - 1) / f > o_.max_texture_size) f++;
    int nw = (w + f - 1) / f, nh = (h + f - 1) / f;
    uint64_t bytes_out = (uint64_t)nw * nh * 16;
    if (image_bytes_ + bytes_out > o_.max_image_bytes) {
        free_px();
        fail("%s: %s: textures exceed the %zu-byte image memory cap", path_.c_str(), label.c_str(), o_.max_image_bytes);
    }
    float *rgba = static_cast<float *>(malloc((size_t)bytes_out));
    if (!rgba) {
        free_px();
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
    free_px();
    if (f > 1 && o_.report) o_.report->downsampled_images++;
    bk_image bi{};
    bi.width = nw;
    bi.height = nh;
    bi.rgba = rgba;
    for (int k = 0; k < 4; k++) bi.mean[k] = (float)(sum[k] / ((double)nw * nh));
    images_.push_back(bi);
    image_bytes_ += bytes_out;
    cache[(size_t)gi] = (int)images_.size() - 1;
    return cache[(size_t)gi];
}

void Importer::decode_images()
{
    image_map_.assign(m_.images.size(), -2);  // -2: not decoded yet
    linear_map_.assign(m_.images.size(), -2);
}

// The image a texture reads: EXT_texture_webp's source when it names one (lbk decodes WebP),
// else the core source, which is also KHR_texture_basisu's fallback; -1 when there is neither.
int Importer::texture_source(int tex) const
{
    const tinygltf::Texture &t = m_.textures[(size_t)tex];
    auto w = t.extensions.find("EXT_texture_webp");
    if (w != t.extensions.end() && w->second.IsObject() && w->second.Has("source") &&
        w->second.Get("source").IsInt())
        return w->second.Get("source").GetNumberAsInt();
    return t.source;
}

// KHR_texture_transform on a texture slot (offset, rotation, scale, texCoord override) as a UvMap:
// uv' = T(offset) · R(rotation) · S(scale) · uv, R = [cos r, sin r; -sin r, cos r] (the extension's).
UvMap Importer::read_uv_map(const tinygltf::TextureInfo &ti, const char *slot, int mi, const std::string &mname)
{
    UvMap m;
    m.texcoord = ti.texCoord;
    auto it = ti.extensions.find("KHR_texture_transform");
    if (it == ti.extensions.end()) return m;
    const tinygltf::Value &x = it->second;
    const std::string mq = qstr(mname);
    if (!x.IsObject())
        fail("%s: material %d %s: %s texture: KHR_texture_transform is not an object", path_.c_str(), mi, mq.c_str(), slot);
    auto pair = [&](const char *key, double dflt, double out[2]) {
        out[0] = out[1] = dflt;
        if (!x.Has(key)) return;
        const tinygltf::Value &v = x.Get(key);
        bool ok = v.IsArray() && v.ArrayLen() == 2;
        for (int k = 0; ok && k < 2; k++) {
            ok = v.Get(k).IsNumber() && std::isfinite(v.Get(k).GetNumberAsDouble());
            if (ok) out[k] = v.Get(k).GetNumberAsDouble();
        }
        if (!ok)
            fail("%s: material %d %s: %s texture: KHR_texture_transform %s must be 2 finite numbers", path_.c_str(),
                 mi, mq.c_str(), slot, key);
    };
    double off[2], sc[2], r = 0;
    pair("offset", 0, off);
    pair("scale", 1, sc);
    if (x.Has("rotation")) {
        const tinygltf::Value &v = x.Get("rotation");
        if (!v.IsNumber() || !std::isfinite(v.GetNumberAsDouble()))
            fail("%s: material %d %s: %s texture: KHR_texture_transform rotation must be a finite number",
                 path_.c_str(), mi, mq.c_str(), slot);
        r = v.GetNumberAsDouble();
    }
    if (x.Has("texCoord")) {
        const tinygltf::Value &v = x.Get("texCoord");
        if (!v.IsInt() || v.GetNumberAsInt() < 0)
            fail("%s: material %d %s: %s texture: KHR_texture_transform texCoord must be an integer >= 0",
                 path_.c_str(), mi, mq.c_str(), slot);
        m.texcoord = v.GetNumberAsInt();
    }
    const double c = std::cos(r), sn = std::sin(r);
    const double a[6] = {c * sc[0], sn * sc[1], off[0], -sn * sc[0], c * sc[1], off[1]};
    for (int k = 0; k < 6; k++) m.a[k] = a[k];
    return m;
}

int Importer::texture_image(const tinygltf::TextureInfo &ti, const char *slot, int mi, const std::string &mname,
                            UvMap *map, bool linear)
{
    if (ti.index < 0 || (o_.skip_textures && !linear)) return -1;  // normal_maps reads normal maps regardless
    if ((size_t)ti.index >= m_.textures.size())
        fail("%s: material %d %s: %s texture %d out of range", path_.c_str(), mi, qstr(mname).c_str(), slot, ti.index);
    int src = texture_source(ti.index);
    if (src < 0) {
        // e.g. a KHR_texture_basisu source only (a required one was refused by the pre-pass)
        if (o_.report) o_.report->ignored_textures++;
        warn("material %d %s: %s texture %d has no PNG/JPEG/WebP source; ignored", mi, qstr(mname).c_str(), slot,
             ti.index);
        return -1;
    }
    if ((size_t)src >= m_.images.size())
        fail("%s: material %d %s: %s texture %d: image %d out of range", path_.c_str(), mi, qstr(mname).c_str(),
             slot, ti.index, src);
    *map = read_uv_map(ti, slot, mi, mname);
    if (map->texcoord > 1) {
        if (o_.report) o_.report->ignored_textures++;
        warn("material %d %s: %s texture uses TEXCOORD_%d (only TEXCOORD_0 and TEXCOORD_1 are sampled); ignored",
             mi, qstr(mname).c_str(), slot, map->texcoord);
        return -1;
    }
    return decode_image(src, linear);
}

// normalTexture (glTF 2.0 §3.9.3), for imports that read normal maps: decoded as data, its scale
// checked; its KHR_texture_transform / texCoord joins the material's one uv (settle_uv_maps) as
// the last slot, so it never changes what the other textures read.
void Importer::read_normal_texture(const tinygltf::Material &gm, int mi, bk_material *bm, UvMap *map)
{
    bm->normal_scale = 1.0f;
    if (!o_.normal_maps || gm.normalTexture.index < 0) return;
    const double sc = gm.normalTexture.scale;
    if (!std::isfinite(sc) || std::fabs(sc) > 1e6)
        fail("%s: material %d %s: normalTexture scale must be a finite number (|scale| <= 1e6)", path_.c_str(), mi,
             qstr(gm.name).c_str());
    tinygltf::TextureInfo ti;
    ti.index = gm.normalTexture.index;
    ti.texCoord = gm.normalTexture.texCoord;
    ti.extensions = gm.normalTexture.extensions;
    bm->normal_tex1 = 1 + texture_image(ti, "normal", mi, gm.name, map, true);
    bm->normal_scale = (float)sc;
}

// One uv per material (it is folded into the primitive's uv0): the first textured slot's map wins;
// a later slot whose transform or texCoord differs is dropped, warned and counted.
void Importer::settle_uv_maps(int mi, const std::string &mname, int *tex[4], const UvMap maps[4])
{
    static const char *const slots[4] = {"baseColor", "emissive", "metallicRoughness", "normal"};
    int first = -1;
    for (int k = 0; k < 4; k++) {
        if (*tex[k] < 0) continue;
        if (first < 0) {
            first = k;
        } else if (!(maps[k] == maps[first])) {
            if (o_.report) o_.report->ignored_textures++;
            warn("material %d %s: the %s texture's KHR_texture_transform/texCoord differs from the %s texture's "
                 "(lbk samples one uv per material); %s texture ignored", mi, qstr(mname).c_str(), slots[k],
                 slots[first], slots[k]);
            *tex[k] = -1;
        }
    }
    uv_maps_[(size_t)mi] = first < 0 ? UvMap{} : maps[first];
}

// Folds the material's UvMap into the primitive's uv0 (see UvMap); TEXCOORD_1 as the source when
// the map says so and the primitive has it (else uv0 stays, with a warning).
void Importer::apply_uv_map(Prim &p, int mi, int pi)
{
    if (p.material >= uv_maps_.size() || uv_maps_[p.material].identity()) return;
    const UvMap &m = uv_maps_[p.material];
    const std::vector<float> *src = &p.uv0;
    if (m.texcoord == 1) {
        if (p.has_uv1)
            src = &p.uv1;
        else
            warn("%s: material %u's textures read TEXCOORD_1, which the primitive lacks; TEXCOORD_0 used",
                 mesh_label(mi, pi).c_str(), p.material);
    }
    std::vector<float> out(src->size());
    for (size_t i = 0; i + 1 < src->size(); i += 2) {
        const double u = (*src)[i], v = (*src)[i + 1];
        out[i] = (float)(m.a[0] * u + m.a[1] * v + m.a[2]);
        out[i + 1] = (float)(m.a[3] * u + m.a[4] * v + m.a[5]);
    }
    p.uv0.swap(out);
}

// ---- KHR_materials_* (spec/authoring.md "Material extensions") -----------------------------------
// lbk bakes diffuse light: a material is a Lambertian albedo, an emission and (GGX.md) a
// metallic-roughness lobe. Each KHR_materials extension is honoured where it says what the
// diffuse albedo or the emission is, approximated where it only scales the diffuse part, and
// otherwise ignored with one warning naming it and the material.

// A textureInfo held inside an extension (tinygltf leaves it a Value): index, texCoord and the
// KHR_texture_transform read_uv_map takes. A malformed one is an error naming the material.
tinygltf::TextureInfo Importer::ext_texture_info(const tinygltf::Value &v, const char *what, int mi,
                                                 const std::string &mname)
{
    tinygltf::TextureInfo ti;
    ti.index = -1;
    bool ok = v.IsObject() && v.Has("index") && v.Get("index").IsInt() && v.Get("index").GetNumberAsInt() >= 0;
    if (ok) ti.index = v.Get("index").GetNumberAsInt();
    if (ok && v.Has("texCoord")) {
        ok = v.Get("texCoord").IsInt() && v.Get("texCoord").GetNumberAsInt() >= 0;
        if (ok) ti.texCoord = v.Get("texCoord").GetNumberAsInt();
    }
    if (!ok)
        fail("%s: material %d %s: %s must be a textureInfo (integer index >= 0, texCoord >= 0)", path_.c_str(), mi,
             qstr(mname).c_str(), what);
    if (v.Has("extensions") && v.Get("extensions").IsObject()) {
        const tinygltf::Value &e = v.Get("extensions");
        for (const std::string &k : e.Keys()) ti.extensions[k] = e.Get(k);
    }
    return ti;
}

// One number of an extension object in [lo, hi] (dflt when absent); an error names the material.
double Importer::ext_number(const tinygltf::Value &x, const char *ext, const char *key, double dflt, double lo,
                            double hi, int mi, const std::string &mname)
{
    if (!x.Has(key)) return dflt;
    const tinygltf::Value &v = x.Get(key);
    if (!v.IsNumber() || !(v.GetNumberAsDouble() >= lo && v.GetNumberAsDouble() <= hi))
        fail("%s: material %d %s: %s %s must be a number in [%g, %g]", path_.c_str(), mi, qstr(mname).c_str(), ext,
             key, lo, hi);
    return v.GetNumberAsDouble();
}

// KHR_materials_pbrSpecularGlossiness (archived; what older exporters wrote): its diffuse is the
// diffuse albedo, exactly as baseColor is for metallic-roughness (diffuseFactor × diffuseTexture,
// sRGB), and the material is a dielectric (metallic 0: the Lambertian path) with roughness
// 1 − glossinessFactor. The specular colour and specularGlossinessTexture are not baked.
void Importer::read_spec_gloss(const tinygltf::Value &x, int mi, const std::string &mname, bk_material *bm,
                               UvMap *map)
{
    const char *ext = "KHR_materials_pbrSpecularGlossiness";
    const std::string mq = qstr(mname);
    if (!x.IsObject()) fail("%s: material %d %s: %s is not an object", path_.c_str(), mi, mq.c_str(), ext);
    double df[4] = {1, 1, 1, 1};
    if (x.Has("diffuseFactor")) {
        const tinygltf::Value &v = x.Get("diffuseFactor");
        bool ok = v.IsArray() && v.ArrayLen() == 4;
        for (int k = 0; ok && k < 4; k++) {
            ok = v.Get(k).IsNumber() && finite_nonneg(v.Get(k).GetNumberAsDouble());
            if (ok) df[k] = v.Get(k).GetNumberAsDouble();
        }
        if (!ok)
            fail("%s: material %d %s: %s diffuseFactor must be 4 finite numbers >= 0", path_.c_str(), mi, mq.c_str(),
                 ext);
    }
    if (df[0] > 1 || df[1] > 1 || df[2] > 1) warn("material %d %s: diffuseFactor above 1 clamped", mi, mq.c_str());
    for (int k = 0; k < 3; k++) bm->albedo[k] = (float)std::min(df[k], 1.0);
    bm->metallic = 0.0f;
    bm->roughness = (float)(1.0 - ext_number(x, ext, "glossinessFactor", 1.0, 0.0, 1.0, mi, mname));
    bm->metal_rough_tex1 = 0;
    bm->albedo_tex = -1;
    if (x.Has("diffuseTexture")) {
        tinygltf::TextureInfo ti = ext_texture_info(x.Get("diffuseTexture"), "diffuseTexture", mi, mname);
        bm->albedo_tex = texture_image(ti, "diffuse", mi, mname, map);
    }
}

// The other KHR_materials_* extensions of material mi, after its core fields: honoured
// (emissive_strength, read with emissiveFactor), approximated (specular-glossiness, unlit,
// transmission, diffuse_transmission) or ignored with one warning each.
void Importer::read_material_extensions(const tinygltf::Material &gm, int mi, bk_material *bm, UvMap *base_map,
                                        int *mr_tex)
{
    const std::string mq = qstr(gm.name);
    for (const auto &kv : gm.extensions) {
        const std::string &e = kv.first;
        const tinygltf::Value &x = kv.second;
        if (e.rfind("KHR_materials_", 0) != 0 || e == "KHR_materials_emissive_strength") continue;
        if (e == "KHR_materials_pbrSpecularGlossiness") {
            *mr_tex = -1;  // a specular-glossiness material has no metallic-roughness lobe
            read_spec_gloss(x, mi, gm.name, bm, base_map);
        } else if (e == "KHR_materials_unlit") {
            // The extension's own fallback: the base colour as a lit surface. Not an emitter:
            // an unlit colour is display-referred, and as nits it would add light nobody placed.
            warn("material %d %s: KHR_materials_unlit approximated: baked as a lit diffuse surface of its base "
                 "colour (not emissive)", mi, mq.c_str());
        } else if (e == "KHR_materials_transmission" || e == "KHR_materials_diffuse_transmission") {
            // What is transmitted is not reflected: the diffuse albedo is (1 − factor) × base
            // colour (both extensions' BRDF mix); lbk traces no light through surfaces, so the
            // transmitted part is lost, never bounced back as if the surface were opaque white.
            const bool diffuse = e == "KHR_materials_diffuse_transmission";
            const char *key = diffuse ? "diffuseTransmissionFactor" : "transmissionFactor";
            if (!x.IsObject()) fail("%s: material %d %s: %s is not an object", path_.c_str(), mi, mq.c_str(), e.c_str());
            const double t = ext_number(x, e.c_str(), key, 0.0, 0.0, 1.0, mi, gm.name);
            for (int k = 0; k < 3; k++) bm->albedo[k] *= (float)(1.0 - t);
            warn("material %d %s: %s approximated: baked opaque, diffuse albedo x %g (1 - %s; its texture and the "
                 "light it transmits are not baked)", mi, mq.c_str(), e.c_str(), 1.0 - t, key);
        } else {
            // ior, specular, sheen, clearcoat, iridescence, anisotropy, dispersion, volume and any
            // newer one: they shape the specular lobes or light inside a volume, not the diffuse
            // albedo or the emission lbk bakes
            warn("material %d %s: %s ignored (lbk bakes the diffuse albedo and emission only)", mi, mq.c_str(),
                 e.c_str());
        }
    }
}

// A material that `lbk export --gltf` wrote carries the baked light in its glTF factors and
// emissive texture (black base colour, emission albedo · E / pi: tools/convert/README.md "In
// engines") and the source material's albedo and emission in extras.lbk: a bake of the export
// takes those, so it is lit as the source was. Returns whether the material is such a one.
static bool lbk_export_material(const tinygltf::Material &gm, bk_material *bm)
{
    if (!gm.extras.IsObject() || !gm.extras.Has("lbk")) return false;
    const tinygltf::Value &l = gm.extras.Get("lbk");
    if (!l.IsObject() || !l.Has("source_material") || !l.Has("albedo") || !l.Has("emission")) return false;
    float v[2][3];
    const char *keys[2] = {"albedo", "emission"};
    for (int k = 0; k < 2; k++) {
        const tinygltf::Value &a = l.Get(keys[k]);
        if (!a.IsArray() || a.ArrayLen() != 3) return false;
        for (int c = 0; c < 3; c++) {
            const tinygltf::Value &x = a.Get(c);
            if (!x.IsNumber() || !finite_nonneg(x.GetNumberAsDouble()) || !std::isfinite((float)x.GetNumberAsDouble()))
                return false;
            v[k][c] = (float)x.GetNumberAsDouble();
        }
    }
    for (int c = 0; c < 3; c++) bm->albedo[c] = std::min(v[0][c], 1.0f), bm->emission[c] = v[1][c];
    return true;
}

void Importer::build_materials()
{
    uv_maps_.assign(m_.materials.size(), UvMap{});
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
        UvMap maps[4];
        const bool exported = lbk_export_material(gm, &bm);  // then no base colour or emissive texture
        bm.albedo_tex =
            exported ? -1 : texture_image(gm.pbrMetallicRoughness.baseColorTexture, "baseColor", mi, gm.name, &maps[0]);
        bm.emission_tex = exported ? -1 : texture_image(gm.emissiveTexture, "emissive", mi, gm.name, &maps[1]);
        bm.double_sided = gm.doubleSided ? 1 : 0;
        // glTF's defaults (1, 1: a rough metal) when pbrMetallicRoughness leaves them out, as
        // tinygltf fills them; our own Lambertian scenes say metallicFactor 0 (GGX.md)
        const double mf = gm.pbrMetallicRoughness.metallicFactor, rf = gm.pbrMetallicRoughness.roughnessFactor;
        if (!(mf >= 0 && mf <= 1)) fail("%s: material %d %s: metallicFactor must lie in [0, 1]", file, mi, mq.c_str());
        if (!(rf >= 0 && rf <= 1)) fail("%s: material %d %s: roughnessFactor must lie in [0, 1]", file, mi, mq.c_str());
        bm.metallic = (float)mf;
        bm.roughness = (float)rf;
        // after the emissive texture: the images of materials without it keep their indices
        int mr = texture_image(gm.pbrMetallicRoughness.metallicRoughnessTexture, "metallicRoughness", mi, gm.name,
                               &maps[2]);
        read_normal_texture(gm, mi, &bm, &maps[3]);  // last: images before it keep their indices
        int nt = bm.normal_tex1 - 1;
        if (!exported) read_material_extensions(gm, mi, &bm, &maps[0], &mr);
        int *tex[4] = {&bm.albedo_tex, &bm.emission_tex, &mr, &nt};
        settle_uv_maps(mi, gm.name, tex, maps);
        bm.metal_rough_tex1 = 1 + mr;
        bm.normal_tex1 = 1 + nt;
        materials_.push_back(bm);
    }
}

}  // namespace bk_gltf
