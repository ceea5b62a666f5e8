# Reads a `pliant cloth` run of a quad PLY garment back with Blender's own importers (run by
# tests/integration/blender_test.cpp as `blender -b --factory-startup --python THIS -- OUT`):
# frame 0 and the last frame with the PLY importer (io_mesh_ply), then OUT/cloth.mdd onto frame 0
# with the MDD importer (io_shape_mdd). Prints `key value` lines for the test to check.
import os
import sys

import bpy

out = sys.argv[sys.argv.index("--") + 1]
frames = sorted(f for f in os.listdir(os.path.join(out, "frames")) if f.endswith(".ply"))
bpy.ops.wm.read_factory_settings(use_empty=True)
objects = []
for name in (frames[0], frames[-1]):
    bpy.ops.import_mesh.ply(filepath=os.path.join(out, "frames", name))
    objects.append(bpy.context.selected_objects[0])
first, last = objects
me = first.data
print("vertices", len(me.vertices))
print("polygons", len(me.polygons))
print("corners", " ".join(str(len(p.vertices)) for p in me.polygons))
print("uv_layers", len(me.uv_layers))
uv = me.uv_layers[0].data
print("loop_uvs", " ".join(f"{l.vertex_index}:{uv[l.index].uv[0]:.6f},{uv[l.index].uv[1]:.6f}"
                           for l in me.loops))

import addon_utils  # noqa: E402

sys.path.extend(addon_utils.paths())
from io_shape_mdd import import_mdd  # noqa: E402

bpy.context.view_layer.objects.active = first
import_mdd.load(bpy.context, os.path.join(out, "cloth.mdd"), frame_start=0, frame_step=1)
keys = first.data.shape_keys.key_blocks
print("shape_keys", len(keys) - 1)  # without "Basis"
diff = max(abs(a - b) for k in range(len(last.data.vertices))
           for a, b in zip(keys[-1].data[k].co, last.data.vertices[k].co))
print("mdd_last_vs_ply_last", f"{diff:.9g}")
print("done")
