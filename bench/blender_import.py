# Imports one glTF/GLB in Blender (bpy.ops.import_scene.gltf) and exits non-zero on any failure.
# Run by bench/blender_import.sh: blender -b --factory-startup --python blender_import.py -- FILE
import sys
import time

import bpy

try:
    import numpy
    # Blender 3.4's glTF importer uses numpy.bool, which NumPy 1.24 (Debian 12) removed: put the
    # alias back, as it was (the builtin bool), so the importer itself is what is tested.
    if "bool" not in numpy.__dict__:
        numpy.bool = bool
except ImportError:
    print("BLENDER_IMPORT_FAILED numpy is missing (Blender's glTF importer needs it: apt-get install python3-numpy)")
    sys.exit(1)

path = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
t0 = time.monotonic()
try:
    result = bpy.ops.import_scene.gltf(filepath=path)
except Exception as e:  # the importer reports errors by raising
    print("BLENDER_IMPORT_FAILED", path, e)
    sys.exit(1)
seconds = time.monotonic() - t0
if result != {"FINISHED"}:
    print("BLENDER_IMPORT_FAILED", path, result)
    sys.exit(1)
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
lightmapped = sum(1 for o in meshes if "UVMap.001" in o.data.uv_layers or len(o.data.uv_layers) >= 2)
triangles = sum(sum(len(p.vertices) - 2 for p in o.data.polygons) for o in meshes)
print("BLENDER_IMPORT_OK %s: %d mesh objects (%d with a lightmap UV set), %d triangles, %.2f s"
      % (path, len(meshes), lightmapped, triangles, seconds))
