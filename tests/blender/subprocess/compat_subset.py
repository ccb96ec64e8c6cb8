"""The add-on's compat subset, run by test_versions.py in another bpy (4.2, 4.5, 5.0).

    python compat_subset.py OUT_DIR [--keep-registered] [--no-exit-hook]

Registers the add-on, adds the modifier to Suzanne through its operator,
evaluates, checks the surface, applies it, exports OBJ with Blender's exporter,
re-imports it, unregisters and checks that nothing of the add-on is left, then
registers again and (with --keep-registered) exits registered so the exit path
is exercised. Prints one ``RESULT {json}`` line; failures raise (a traceback and
a non-zero exit status). --leave-handlers registers the add-on's handlers
alone at the end, bypassing register() and its exit hook (the deliberately
broken variant the exit check must catch).
"""
import json
import sys
from pathlib import Path

import bpy
import numpy as np

import blender_addon
from blender_addon import api, compat, ids

out = Path(sys.argv[1])

bpy.ops.wm.read_factory_settings(use_empty=True)
blender_addon.register()
bpy.ops.mesh.primitive_monkey_add()
obj = bpy.context.object
base = np.array([v.co[:] for v in obj.data.vertices])
bpy.ops.object.gerbs_add_surface(resolution=2, kernel="ERBS")
depsgraph = bpy.context.evaluated_depsgraph_get()
surface = obj.evaluated_get(depsgraph).data
points = np.array([v.co[:] for v in surface.vertices])
status = api.status(obj)
assert not status["error"], status["error"]
assert len(points) > 3 * len(base), (len(points), len(base))
# the surface interpolates: every base vertex is a surface point
gap = max(np.min(np.linalg.norm(points - b, axis=1)) for b in base)
assert gap < 1e-5, gap
bpy.ops.object.gerbs_apply()
assert api.get_modifier(obj) is None
applied = len(obj.data.vertices)
assert applied == len(points), (applied, len(points))
bpy.ops.wm.obj_export(filepath=str(out / "surface.obj"), export_selected_objects=True)
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=str(out / "surface.obj"))
reimported = len(bpy.context.selected_objects[0].data.vertices)
assert reimported == applied, (reimported, applied)
blender_addon.unregister()
left = [name for name in (ids.OP_ADD.replace("object.", "OBJECT_OT_"), "GERBS_PT_status")
        if hasattr(bpy.types, name)]
assert not left, left
assert not any(getattr(f, "__module__", "").startswith("blender_addon")
               for f in bpy.app.handlers.depsgraph_update_post), "handler left registered"
if "--keep-registered" in sys.argv:
    blender_addon.register()
    bpy.ops.mesh.primitive_monkey_add()
    api.add_surface(bpy.context.object, resolution=2)
if "--leave-handlers" in sys.argv:
    from blender_addon import handlers
    handlers.register()
print("RESULT " + json.dumps({
    "version": bpy.app.version_string, "points": len(points), "gap": gap,
    "limitations": compat.limitations(), "warning_node": compat.has_node_type(compat.WARNING_NODE),
}), flush=True)
