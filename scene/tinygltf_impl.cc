// tinygltf's implementation, compiled once for the glTF importer: TINYGLTF_IMPLEMENTATION is
// defined in this unit alone, and scene/gltf_internal.hh configures tinygltf the same for every
// unit (no stb_image in tinygltf: images are decoded in gltf_materials.cc; no Draco in tinygltf:
// gltf_geometry.cc decodes it with checks).

#define TINYGLTF_IMPLEMENTATION
#include "scene/gltf_internal.hh"
