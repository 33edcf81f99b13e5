// EXT_meshopt_compression (as gltfpack and glTF-Transform write it): each compressed bufferView
// is decoded by meshoptimizer into a buffer of its own, and the bufferView is pointed at it
// (offset 0, the extension's byteStride for attributes), so the accessor reads of
// gltf_geometry.cc see plain data and keep their bounds checks. The pre-pass (gltf_guard.cc)
// has checked the modes, filters and strides, which meshoptimizer's decoders assert rather than
// check; here the compressed range is checked against the buffer's bytes and the decoded size
// is capped before anything is allocated.

#include <meshoptimizer.h>

#include "scene/gltf_internal.hh"

namespace bk_gltf {

namespace {

// The most bytes one compressed byte can decode to, with a margin. The vertex codec spends at
// least 2 header bits per 16-byte group of a byte lane (64:1 when every delta is zero); the index
// codecs at least one byte per triangle (12:1) or per index (4:1). A stream claiming more is
// malformed, and refusing it before the allocation keeps a tiny file from asking for gigabytes.
const uint64_t kMaxRatio = 128;

const char *mode_name(MeshoptView::Mode m)
{
    return m == MeshoptView::ATTRIBUTES ? "ATTRIBUTES" : m == MeshoptView::TRIANGLES ? "TRIANGLES" : "INDICES";
}

}  // namespace

void Importer::decode_meshopt()
{
    const char *file = path_.c_str();
    for (const MeshoptView &mv : pp_.meshopt) {
        if (mv.view < 0 || (size_t)mv.view >= m_.bufferViews.size() || mv.buffer < 0 ||
            (size_t)mv.buffer >= m_.buffers.size())
            fail("%s: bufferView %d: EXT_meshopt_compression: view or buffer %d out of range", file, mv.view,
                 mv.buffer);
        tinygltf::BufferView &bv = m_.bufferViews[(size_t)mv.view];
        std::string lbl = "bufferView " + std::to_string(mv.view) + (bv.name.empty() ? "" : " " + qstr(bv.name)) +
                          ": EXT_meshopt_compression";
        const std::vector<unsigned char> &src = m_.buffers[(size_t)mv.buffer].data;
        uint64_t end, bytes, cap;
        if (!add_ok(mv.offset, mv.length, &end) || end > src.size())
            fail("%s: %s: byteOffset %llu + byteLength %llu lie outside buffer %d (%zu bytes)", file, lbl.c_str(),
                 (unsigned long long)mv.offset, (unsigned long long)mv.length, mv.buffer, src.size());
        if (!mul_ok(mv.count, mv.stride, &bytes) || bytes > o_.max_file_bytes ||
            !mul_ok(mv.length, kMaxRatio, &cap) || bytes > cap + 256)
            fail("%s: %s: count %llu x byteStride %llu does not fit %llu compressed bytes (or the %zu-byte cap)",
                 file, lbl.c_str(), (unsigned long long)mv.count, (unsigned long long)mv.stride,
                 (unsigned long long)mv.length, o_.max_file_bytes);
        std::vector<unsigned char> out((size_t)bytes);
        const unsigned char *in = src.data() + mv.offset;
        const size_t n = (size_t)mv.count, st = (size_t)mv.stride, len = (size_t)mv.length;
        int rc = 0;
        if (n > 0) {
            switch (mv.mode) {
            case MeshoptView::ATTRIBUTES: rc = meshopt_decodeVertexBuffer(out.data(), n, st, in, len); break;
            case MeshoptView::TRIANGLES: rc = meshopt_decodeIndexBuffer(out.data(), n, st, in, len); break;
            case MeshoptView::INDICES: rc = meshopt_decodeIndexSequence(out.data(), n, st, in, len); break;
            }
        }
        if (rc != 0)
            fail("%s: %s: the %s stream is malformed or truncated (meshoptimizer error %d, %llu bytes for %llu "
                 "elements of %llu bytes)", file, lbl.c_str(), mode_name(mv.mode), rc, (unsigned long long)mv.length,
                 (unsigned long long)mv.count, (unsigned long long)mv.stride);
        switch (mv.filter) {  // in place, over the decoded elements (strides checked by the pre-pass)
        case MeshoptView::NONE: break;
        case MeshoptView::OCTAHEDRAL: meshopt_decodeFilterOct(out.data(), n, st); break;
        case MeshoptView::QUATERNION: meshopt_decodeFilterQuat(out.data(), n, st); break;
        case MeshoptView::EXPONENTIAL: meshopt_decodeFilterExp(out.data(), n, st); break;
        }
        // The decoded view is count x byteStride bytes (what three.js's and glTF-Transform's
        // decoders allocate); accessors are bounds-checked against it like any other view.
        tinygltf::Buffer decoded;
        decoded.name = "EXT_meshopt_compression bufferView " + std::to_string(mv.view);
        decoded.data = std::move(out);
        if (m_.buffers.size() >= (size_t)INT32_MAX) fail("%s: too many buffers", file);
        m_.buffers.push_back(std::move(decoded));
        bv.buffer = (int)m_.buffers.size() - 1;
        bv.byteOffset = 0;
        bv.byteLength = (size_t)bytes;
        bv.byteStride = mv.mode == MeshoptView::ATTRIBUTES ? st : 0;
    }
}

}  // namespace bk_gltf
