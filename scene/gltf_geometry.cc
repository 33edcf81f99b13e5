// The glTF importer's geometry: bounds-checked accessor reads, Draco decoding (with the checks
// tinygltf's Draco path lacks), triangle primitives per mesh, and the scene's world-space arrays
// (origin, transforms, normals) from the mesh instances.

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>

#include "scene/gltf_internal.hh"

namespace bk_gltf {

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
    check_draco_counts(mi, pi, di, np, idx.size());
}

// KHR_draco_mesh_compression: the accessors of the attributes in the stream, and the indices
// accessor, describe the decoded data; a count that disagrees with it is refused.
void Importer::check_draco_counts(int mi, int pi, const DracoInfo &di, size_t points, size_t indices)
{
    const char *file = path_.c_str();
    std::string lbl = mesh_label(mi, pi) + ": KHR_draco_mesh_compression";
    const tinygltf::Primitive &gp = m_.meshes[(size_t)mi].primitives[(size_t)pi];
    auto check = [&](int acc, size_t decoded, const char *what) {
        if (acc < 0) return;
        if ((size_t)acc >= m_.accessors.size())
            fail("%s: %s: %s accessor %d out of range (%zu accessors)", file, lbl.c_str(), what, acc, m_.accessors.size());
        if (m_.accessors[(size_t)acc].count != decoded)
            fail("%s: %s: %s accessor %d has count %zu, the decoded stream %zu", file, lbl.c_str(), what, acc,
                 m_.accessors[(size_t)acc].count, decoded);
    };
    for (const auto &a : di.attributes) {
        auto it = gp.attributes.find(a.first);
        if (it != gp.attributes.end()) check(it->second, points, a.first.c_str());
    }
    check(di.indices, indices, "indices");
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
    // TANGENT only where a normal map may use it; inside a Draco stream it is derived instead.
    if (o_.normal_maps && attr("TANGENT") >= 0 && p.has_nrm &&
        (dit == pp_.draco.end() || !dit->second.attributes.count("TANGENT"))) {
        read_accessor(attr("TANGENT"), 4, false, &p.tan, nullptr, lbl + " TANGENT");
        if (p.tan.size() != nv * 4)
            fail("%s: %s: TANGENT has %zu elements but the primitive %zu vertices", file, lbl.c_str(), p.tan.size() / 4, nv);
        p.has_tan = true;
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
    apply_uv_map(p, mi, pi);  // KHR_texture_transform / texCoord: uv0 is what textures read
    p.source_vertices = (uint32_t)nv;
    p.src.resize(nv);
    for (size_t i = 0; i < nv; i++) p.src[i] = (uint32_t)i;
    if (!p.has_nrm) {
        // Flat shading: give every triangle its own three vertices; normals come at instancing.
        // (TANGENT is not read without NORMAL: glTF says to ignore it then.)
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

// What float rays can trace, checked once here over the world-space positions (double, after
// every transform) before any of them becomes a float or reaches Embree (scene/tracer.h):
//  * |coordinate| <= kMaxWorldCoord = 1e9 m in the glTF's world, before the origin is taken
//    away: the origin is a double, 1.2e-7 m apart there, so a 1 mm object keeps its shape;
//    1e9 m is 2.6 times the Moon's distance, a level beyond it is a unit error or hostile.
//  * the level's extent (largest axis span) <= kMaxLevelExtent = 1e6 m: float positions of a
//    recentred level reach E/2, 5e5 m, where floats are 3 cm apart and the tracer's ray offset
//    (8 ulps) is 25 cm; 10 times the 1e5 m level the tests bake. Past it the baker's
//    metre-sized grids run out of memory (from ~1e10 m) and past 1.8e18 Embree asserts
//    (ray.valid(): |org|, |dir| <= FLT_LARGE).
//  * M / f <= kMaxFeatureRatio = 2^20, M the largest |coordinate| the bake's tracer gets (after
//    the origin choose_origin picks is taken away, also when this import does not recentre), f
//    the smallest object's size (largest axis span of its bounds; objects of size 0 have no area
//    to trace): floats have 24 bits, so at M they are <= M·2^-23 apart and an object of
//    f = M·2^-20 spans 8 ulps, the tracer's ray offset: a ray leaving a smaller object starts
//    beyond its far side.
// The refusal names the node: for the extent the largest object if it alone is too large, else
// the one farthest from the level's (lower) median object; for the ratio the smallest object.
void Importer::check_extent(const std::vector<Instance> &kept)
{
    const double kMaxWorldCoord = 1e9, kMaxLevelExtent = 1e6, kMaxFeatureRatio = 1048576.0;
    const char *file = path_.c_str();
    size_t n = kept.size();
    if (!n) return;
    std::vector<double> bmin(n * 3, HUGE_VAL), bmax(n * 3, -HUGE_VAL);
    for (size_t i = 0; i < n; i++) {
        const Instance &in = kept[i];
        for (const Prim &p : meshes_[(size_t)m_.nodes[(size_t)in.node].mesh].prims)
            for (size_t v = 0; v < p.pos.size() / 3; v++) {
                double lp[3] = {p.pos[v * 3], p.pos[v * 3 + 1], p.pos[v * 3 + 2]}, wp[3];
                xform_point(in.world, lp, wp);
                for (int k = 0; k < 3; k++) {
                    if (!(std::fabs(wp[k]) <= kMaxWorldCoord))
                        fail("%s: %s: world-space coordinate %.3g m lies beyond +-%.0e m, the importer's limit "
                             "(spec/authoring.md: scene extent)", file, node_label(in.node).c_str(), wp[k], kMaxWorldCoord);
                    bmin[i * 3 + k] = std::min(bmin[i * 3 + k], wp[k]);
                    bmax[i * 3 + k] = std::max(bmax[i * 3 + k], wp[k]);
                }
            }
    }
    double mn[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, mx[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, med[3];
    for (int k = 0; k < 3; k++) {
        std::vector<double> c(n);
        for (size_t i = 0; i < n; i++) {
            mn[k] = std::min(mn[k], bmin[i * 3 + k]);
            mx[k] = std::max(mx[k], bmax[i * 3 + k]);
            c[i] = 0.5 * (bmin[i * 3 + k] + bmax[i * 3 + k]);
        }
        std::nth_element(c.begin(), c.begin() + (long)((n - 1) / 2), c.end());
        med[k] = c[(n - 1) / 2];
    }
    double extent = 0, reach = 0, feature = HUGE_VAL, largest = -1, far_d = -1;
    size_t far = 0, small = 0, big = 0;
    for (int k = 0; k < 3; k++) extent = std::max(extent, mx[k] - mn[k]);
    for (int k = 0; k < 3; k++) {  // the frame the bake traces in: choose_origin's rule, recentred or not
        double mid = 0.5 * (mn[k] + mx[k]), o = std::fabs(mid) > 2 * extent ? std::nearbyint(mid) : 0;
        reach = std::max(reach, std::max(std::fabs(mn[k] - o), std::fabs(mx[k] - o)));
    }
    for (size_t i = 0; i < n; i++) {
        double size = 0, d = 0;
        for (int k = 0; k < 3; k++) {
            size = std::max(size, bmax[i * 3 + k] - bmin[i * 3 + k]);
            d = std::max(d, std::max(std::fabs(bmin[i * 3 + k] - med[k]), std::fabs(bmax[i * 3 + k] - med[k])));
        }
        if (d > far_d) far_d = d, far = i;
        if (size > largest) largest = size, big = i;
        if (size > 0 && size < feature) feature = size, small = i;
    }
    if (largest > kMaxLevelExtent) far = big;  // one object too large by itself
    if (!(extent <= kMaxLevelExtent))
        fail("%s: %s: the level's extent reaches %.3g m, beyond the %.0e m float rays can trace "
             "(spec/authoring.md: scene extent)", file, node_label(kept[far].node).c_str(), extent, kMaxLevelExtent);
    if (feature < HUGE_VAL && !(reach <= kMaxFeatureRatio * feature))
        fail("%s: %s: an object %.3g m across in a level whose coordinates reach %.3g m: a ratio of %.3g, beyond "
             "the 2^20 float rays can resolve (spec/authoring.md: scene extent)", file,
             node_label(kept[small].node).c_str(), feature, reach, reach / feature);
}

// World-space tangents of a primitive's vertices (after their normals, repaired ones included):
// T' = A·T and B' = A·B (B = w·(N × T) in the mesh's frame: A maps surface directions), T' made
// orthogonal to the world normal, w' the side of B' (a mirroring transform flips it). Vertices
// without a usable TANGENT get w = 0: bk_scene_derive_tangents fills them from uv0.
void Importer::emit_tangents(const Prim &p, size_t v0, const double A[9])
{
    const size_t nv = p.pos.size() / 3;
    for (size_t v = 0; v < nv; v++) {
        float *out = &s_->tangents[(v0 + v) * 4];
        out[0] = out[1] = out[2] = out[3] = 0.0f;
        if (!p.has_tan) continue;
        const float *ft = &p.tan[v * 4], *fn = &p.nrm[v * 3], *wn = &s_->normals[(v0 + v) * 3];
        const double lt[3] = {ft[0], ft[1], ft[2]}, ln[3] = {fn[0], fn[1], fn[2]}, n[3] = {wn[0], wn[1], wn[2]};
        const double w = ft[3] < 0 ? -1.0 : 1.0;
        double lb[3] = {w * (ln[1] * lt[2] - ln[2] * lt[1]), w * (ln[2] * lt[0] - ln[0] * lt[2]),
                        w * (ln[0] * lt[1] - ln[1] * lt[0])};
        double t[3], b[3];
        xform_dir(A, lt, t);
        xform_dir(A, lb, b);
        const double d = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
        for (int k = 0; k < 3; k++) t[k] -= d * n[k];
        if (!normalize3(t)) continue;  // parallel to the normal, or zero: derived instead
        const double c[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
        for (int k = 0; k < 3; k++) out[k] = (float)t[k];
        out[3] = c[0] * b[0] + c[1] * b[1] + c[2] * b[2] < 0 ? -1.0f : 1.0f;
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
    check_extent(kept);
    s_->positions = alloc_array<float>(total_v, 3);
    s_->normals = alloc_array<float>(total_v, 3);
    s_->uv0 = alloc_array<float>(total_v, 2);
    s_->uv1 = alloc_array<float>(total_v, 2);
    if (o_.normal_maps) s_->tangents = alloc_array<float>(total_v, 4);
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
            if (s_->tangents) emit_tangents(p, v0, A);
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

}  // namespace bk_gltf
