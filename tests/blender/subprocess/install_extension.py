"""Install an extension zip into a bare bpy, use it on Suzanne, uninstall it.

    python install_extension.py ZIP [--expect-missing-scipy]

Run by test_extension.py in an interpreter where neither scipy nor gerbs_core
is importable (checked first) and with BLENDER_USER_RESOURCES pointing at a
temporary directory (the user extensions repository lives there). Prints one
``RESULT {json}`` line; any failed check raises.
"""
import importlib.util
import json
import os
import sys
from pathlib import Path

import bpy

zip_path = Path(sys.argv[1])
missing_scipy = "--expect-missing-scipy" in sys.argv
assert importlib.util.find_spec("scipy") is None, "scipy importable outside the extension"
assert importlib.util.find_spec("gerbs_core") is None, "gerbs_core importable outside the zip"
user = Path(os.environ["BLENDER_USER_RESOURCES"])

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default",
                                         enable_on_install=True)
module_name = "bl_ext.user_default.gerbs_blending_surface"
addon = sys.modules[module_name]
installed = Path(addon.__file__).parent
assert user in installed.parents, (installed, user)
core = sys.modules[f"{module_name}.core"]
assert core.PACKAGE == f"{module_name}.gerbs_core", core.PACKAGE
assert Path(core.module().__file__).parent == installed / "gerbs_core"
scipy_spec = importlib.util.find_spec("scipy")
scipy_from = "" if scipy_spec is None else scipy_spec.origin

bpy.ops.mesh.primitive_monkey_add()
obj = bpy.context.object
base = [v.co[:] for v in obj.data.vertices]
try:
    bpy.ops.object.gerbs_add_surface(resolution=2)
    op_error = ""
except RuntimeError as exc:  # an error report raises in background mode
    op_error = str(exc)
api = sys.modules[f"{module_name}.api"]
handlers = sys.modules[f"{module_name}.handlers"]
status = api.status(obj)
points = len(obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.vertices)
assert [v.co[:] for v in obj.data.vertices] == base, "the base mesh changed"
result = {"error": status["error"], "op_error": op_error, "points": points,
          "status_bar": handlers.status_message, "scipy_from": scipy_from,
          "installed": str(installed)}

bpy.ops.preferences.addon_disable(module=module_name)
assert not hasattr(bpy.types, "OBJECT_OT_gerbs_add_surface"), "operator left after disable"
bpy.ops.extensions.package_uninstall(repo_index=[r.module for r in
                                     bpy.context.preferences.extensions.repos].index("user_default"),
                                     pkg_id="gerbs_blending_surface")
result["removed"] = not installed.exists()
print("RESULT " + json.dumps(result), flush=True)
