// The glTF importer's internals, shared by its translation units (scene/gltf_*.cc); nothing here
// is public (scene/import.h is). glTF 2.0 (.gltf / .glb) → bk_scene, the only C++ of the baker:
// tinygltf (scene/tinygltf_impl.cc), Draco (gltf_geometry.cc), meshoptimizer's decoders
// (gltf_meshopt.cc) and stb_image (gltf_materials.cc)
// are compiled into the importer and only bk_import_gltf() is exported (gltf_import.cc).
//
// The input is untrusted. tinygltf 2.7.0 parses JSON, buffers (data URIs, .bin files, the GLB BIN
// chunk) and materials/nodes/lights, but indexes several arrays without bounds checks, so:
//  * a pre-pass over the JSON (nlohmann) caps nesting depth and, before any DOM, what the import
//    may hold (a SAX census against 256 MiB + 16 x the JSON size), checks the node hierarchy's
//    depth and the files URIs name (regular, byteLength long, no NUL), validates image bufferViews before
//    tinygltf takes a pointer into them, and takes KHR_draco_mesh_compression away from tinygltf:
//    its Draco path (TINYGLTF_ENABLE_DRACO) dereferences unchecked indices and a possibly null
//    attribute and overruns a 4-element stack array, so we decode Draco here with checks;
//  * every accessor read is bounds-checked against its bufferView and buffer here, with 64-bit
//    overflow-checked arithmetic; counts that could be derived are never trusted;
//  * file reads go through our callbacks: regular files only, size-capped, no shell expansion
//    (tinygltf's default ExpandFilePath calls wordexp);
//  * images are decoded here (stb_image PNG/JPEG, libwebp WebP) after a header-only size check.
// Internally errors are C++ exceptions carrying the message; bk_import_gltf catches everything.
//
// Where each part lives: gltf_guard.cc the path sandbox, file reads, the JSON pre-pass and the GLB
// container; gltf_materials.cc images and materials; gltf_geometry.cc accessors, Draco, primitives
// and the scene's geometry; gltf_meshopt.cc EXT_meshopt_compression's bufferViews; gltf_extras.cc
// lights, the sky and the lbk_* extras; gltf_import.cc the entry point, loading, the node graph
// and the order of it all (Importer::run).
#ifndef BK_GLTF_INTERNAL_HH
#define BK_GLTF_INTERNAL_HH

// Every unit sees tinygltf configured alike (the TinyGLTF class's members depend on these);
// TINYGLTF_IMPLEMENTATION is defined in scene/tinygltf_impl.cc alone.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "scene/import.h"

namespace bk_gltf {

const int kMaxNodeDepth = 256;  // node hierarchy depth cap (the traversal is recursive; the pre-pass checks it)

struct ImportError {
    std::string msg;
};

std::string vfmt(const char *fmt, va_list ap);
[[noreturn]] void fail(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
std::string qstr(const std::string &s);  // quoted, control bytes as '?', cut at 80 bytes

// ---- files (gltf_guard.cc) ------------------------------------------------------------------

bool is_regular_file(const std::string &p, size_t *size);
bool read_capped(const std::string &p, size_t cap, std::vector<unsigned char> *out, std::string *why);

// Where a scene may read from: its own folder (symlinks resolved), plus one folder the caller
// allows. A scene from an untrusted source must not read /etc/passwd through "../../..".
struct ResourcePolicy {
    std::string root;   // realpath of the scene's folder, with a trailing '/'
    std::string allow;  // realpath of the allowed outside folder with '/', or empty
};

std::string real_dir(const std::string &d);
// True if `p` (after resolving every symlink) lies inside the policy's folders; else *why says so.
bool resource_allowed(const ResourcePolicy &pol, const std::string &p, std::string *why);

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

// tinygltf's file callbacks (FsCallbacks; user data: FsState)
bool fs_exists(const std::string &p, void *);
std::string fs_expand(const std::string &p, void *);
bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &p, void *user);
bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *);

std::string dir_of(const std::string &path);

// ---- small maths (column-major 4x4 in double, as glTF) ----------------------------------------

struct Mat4 {
    double m[16];
};

inline Mat4 identity()
{
    Mat4 r{};
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0;
    return r;
}

inline Mat4 mul(const Mat4 &a, const Mat4 &b)
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

inline void xform_point(const Mat4 &M, const double p[3], double o[3])
{
    for (int r = 0; r < 3; r++) o[r] = M.m[r] * p[0] + M.m[4 + r] * p[1] + M.m[8 + r] * p[2] + M.m[12 + r];
}

inline void xform_dir(const double A[9], const double v[3], double o[3])  // A: column-major 3x3
{
    for (int r = 0; r < 3; r++) o[r] = A[r] * v[0] + A[3 + r] * v[1] + A[6 + r] * v[2];
}

inline void upper3(const Mat4 &M, double A[9])
{
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) A[c * 3 + r] = M.m[c * 4 + r];
}

inline double det3(const double A[9])
{
    return A[0] * (A[4] * A[8] - A[7] * A[5]) - A[3] * (A[1] * A[8] - A[7] * A[2]) +
           A[6] * (A[1] * A[5] - A[4] * A[2]);
}

// Inverse-transpose of A (column-major), for normals. Caller ensures det != 0.
inline void inverse_transpose3(const double A[9], double det, double N[9])
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

inline bool normalize3(double v[3])
{
    double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 1e-30) || !std::isfinite(l)) return false;
    v[0] /= l; v[1] /= l; v[2] /= l;
    return true;
}

// ---- overflow-checked sizes -----------------------------------------------------------------

inline bool add_ok(uint64_t a, uint64_t b, uint64_t *r)
{
    if (a > UINT64_MAX - b) return false;
    *r = a + b;
    return true;
}
inline bool mul_ok(uint64_t a, uint64_t b, uint64_t *r)
{
    if (a && b > UINT64_MAX / a) return false;
    *r = a * b;
    return true;
}

inline bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }

template <typename T>
T *alloc_array(size_t n, size_t per)
{
    uint64_t bytes;
    if (!mul_ok(n, per * sizeof(T), &bytes) || bytes > SIZE_MAX) throw std::bad_alloc();
    T *p = static_cast<T *>(malloc(bytes ? (size_t)bytes : 1));
    if (!p) throw std::bad_alloc();
    return p;
}

// ---- the pre-pass over the JSON (gltf_guard.cc) -----------------------------------------------

struct DracoInfo {
    int buffer_view = -1;
    int indices = -1;  // the primitive's indices accessor (hidden from tinygltf), -1: none
    std::map<std::string, int> attributes;  // glTF semantic -> Draco unique id
};

// EXT_meshopt_compression on one bufferView, as the pre-pass checked it: the compressed range
// (buffer, offset, length) and what it decodes to (count elements of stride bytes).
struct MeshoptView {
    enum Mode { ATTRIBUTES, TRIANGLES, INDICES };
    enum Filter { NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL };
    int view = -1, buffer = -1;
    uint64_t offset = 0, length = 0, stride = 0, count = 0;
    Mode mode = ATTRIBUTES;
    Filter filter = NONE;
};

struct Prepass {
    std::map<std::pair<int, int>, DracoInfo> draco;  // (mesh, primitive)
    std::vector<MeshoptView> meshopt;                // the compressed bufferViews, in view order
    std::vector<char> needed_images;                 // per image: 1 used as base colour / emissive /
                                                     // metallicRoughness, | 2 as a normal texture (only
                                                     // when the import reads normal maps)
    std::string json;                                // rewritten JSON handed to tinygltf
};

// Caps the JSON's depth and what it may cost to import (a SAX census before any DOM), the node
// hierarchy's depth, refuses absolute and non-data: URIs, URIs holding a NUL and files that are
// not regular or not byteLength long (before tinygltf opens them), refuses KHR_texture_basisu
// when required (naming the texture), notes the EXT_meshopt_compression bufferViews (their
// fallback buffers stubbed: the compressed data is decoded instead), validates image
// bufferViews, notes the images the baker needs (EXT_texture_webp's source first) and the Draco
// primitives, and rewrites the JSON for tinygltf.
Prepass prepass(const char *json_begin, size_t json_len, const std::string &file, const ResourcePolicy &pol,
                bool normal_maps);

// ---- GLB container (gltf_guard.cc) ------------------------------------------------------------

struct GlbParts {
    const char *json = nullptr;
    size_t json_len = 0;
    const unsigned char *bin = nullptr;
    size_t bin_len = 0;
};

GlbParts split_glb(const std::vector<unsigned char> &f, const std::string &file);
std::vector<unsigned char> make_glb(const std::string &json_text, const GlbParts &g);

// ---- image loading (tinygltf callback keeps the encoded bytes; we decode later) -----------------

struct ImageLoaderCtx {
    const std::vector<char> *needed;
    bool skip;  // skip_textures: keep normal textures only (bit 2 of needed)
};

// tinygltf's image loader (LoadImageDataFunction; user data: ImageLoaderCtx), gltf_materials.cc
bool keep_encoded_image(tinygltf::Image *image, const int idx, std::string *, std::string *, int, int,
                        const unsigned char *bytes, int size, void *user);

// ---- KHR_texture_transform (gltf_materials.cc) --------------------------------------------------

// The uv a material's textures read: TEXCOORD_<texcoord> mapped by the affine
// u' = a[0] u + a[1] v + a[2], v' = a[3] u + a[4] v + a[5] (KHR_texture_transform's T·R·S). The
// import folds it into the primitive's uv0, which only texture lookups read, so every place that
// samples a texture with uv0 (transport, denoiser guide, emitters, lbk render) sees it alike.
struct UvMap {
    int texcoord = 0;
    double a[6] = {1, 0, 0, 0, 1, 0};
    bool operator==(const UvMap &o) const
    {
        if (texcoord != o.texcoord) return false;
        for (int k = 0; k < 6; k++)
            if (a[k] != o.a[k]) return false;
        return true;
    }
    bool identity() const { return *this == UvMap{}; }
};

// ---- the importer -----------------------------------------------------------------------------

struct Prim {  // one triangle primitive, in mesh-local space, ready to instance
    std::vector<float> pos, nrm, uv0, uv1;
    std::vector<float> tan;        // TANGENT (4 per vertex), read only for normal maps and with NORMAL
    std::vector<uint32_t> tris;
    std::vector<uint32_t> src;     // per vertex: its index in the glTF primitive (flat shading splits them)
    bool has_nrm = false, has_uv1 = false, has_tan = false;
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
    std::vector<int> linear_map_;     // the same for images read as data (normal maps: no sRGB decode)
    std::vector<bk_image> images_;
    size_t image_bytes_ = 0;
    std::vector<bk_material> materials_;
    std::vector<UvMap> uv_maps_;      // per glTF material: what its textures read (default: identity)
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
    // gltf_import.cc: loading, the node graph, the inputs record
    void load();
    void check_extensions();
    void traverse();
    void visit(int n, const Mat4 &parent, const std::string &light_set, const std::string &door, int depth);
    std::string node_label(int n) const;
    std::string mesh_label(int mi, int pi) const;
    Mat4 local_matrix(int n) const;
    void record_inputs();
    // gltf_materials.cc
    void decode_images();
    int decode_image(int gi, bool linear = false);
    void build_materials();
    int texture_image(const tinygltf::TextureInfo &ti, const char *slot, int mi, const std::string &mname,
                      UvMap *map, bool linear = false);
    void read_normal_texture(const tinygltf::Material &gm, int mi, bk_material *bm, UvMap *map);
    tinygltf::TextureInfo ext_texture_info(const tinygltf::Value &v, const char *what, int mi,
                                           const std::string &mname);
    double ext_number(const tinygltf::Value &x, const char *ext, const char *key, double dflt, double lo, double hi,
                      int mi, const std::string &mname);
    void read_spec_gloss(const tinygltf::Value &x, int mi, const std::string &mname, bk_material *bm, UvMap *map);
    void read_material_extensions(const tinygltf::Material &gm, int mi, bk_material *bm, UvMap *base_map,
                                  int *mr_tex);
    int texture_source(int tex) const;
    UvMap read_uv_map(const tinygltf::TextureInfo &ti, const char *slot, int mi, const std::string &mname);
    void settle_uv_maps(int mi, const std::string &mname, int *tex[4], const UvMap maps[4]);
    void apply_uv_map(Prim &p, int mi, int pi);
    unsigned char *decode_pixels(const unsigned char *bytes, size_t len, const std::string &label, int *w, int *h,
                                 bool *webp);
    std::vector<float> downsample(const float *rgba, int w, int h, int max_side, int *ow, int *oh);
    // gltf_geometry.cc
    void prepare_mesh(int mi);
    void prepare_prim(int mi, int pi, Prim &p, bool *is_triangles);
    void read_accessor(int acc, int want_comps, bool index, std::vector<float> *f, std::vector<uint32_t> *u,
                       const std::string &what);
    void decode_draco(int mi, int pi, const DracoInfo &di, Prim &p, std::vector<uint32_t> &idx, size_t *nverts);
    void check_draco_counts(int mi, int pi, const DracoInfo &di, size_t points, size_t indices);
    // gltf_meshopt.cc: every EXT_meshopt_compression bufferView decoded into a buffer of its own
    void decode_meshopt();
    void emit_geometry();
    void emit_tangents(const Prim &p, size_t v0, const double A[9]);
    void choose_origin(const std::vector<Instance> &kept);
    void check_extent(const std::vector<Instance> &kept);  // the limits float rays can trace
    // gltf_extras.cc
    void emit_lights();
    void read_sky();
    void read_combinations();
    void read_playable(int n, const Mat4 &world, const tinygltf::Value &v);
    void emit_playable();
};

}  // namespace bk_gltf

#endif
