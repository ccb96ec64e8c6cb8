"""Every identifier and name the add-on uses, in one place.

Operators, panels, menus, property groups, the Geometry Nodes group and its
sockets, and the custom-property tags on data-blocks are all spelled here, so a
rename is a one-line change and tests can refer to the same constants.
"""
from __future__ import annotations

from dataclasses import dataclass

ADDON_ID = "gerbs_blending_surface"  # extension id (blender_manifest.toml)
ADDON_NAME = "GERBS Blending Surface"

# --- operators (bl_idname) ------------------------------------------------------
OP_ADD = "object.gerbs_add_surface"
OP_APPLY = "object.gerbs_apply"
OP_REBUILD = "object.gerbs_rebuild"
OP_REMOVE = "object.gerbs_remove"

# --- UI -------------------------------------------------------------------------
PANEL_STATUS = "GERBS_PT_status"
MENU_PARENT = "OBJECT_MT_modifier_add_generate"  # Add Modifier > Generate (bpy 5.0.1)
MENU_LABEL = "GERBS Blending Surface"
MENU_ICON = "MOD_SUBSURF"

# --- scene property group -------------------------------------------------------
SCENE_PROP = "gerbs"  # bpy.types.Scene.gerbs -> GERBS_PG_scene

# --- Geometry Nodes group and modifier ------------------------------------------
NODE_GROUP_NAME = "GERBS Blending Surface"
MODIFIER_NAME = "GERBS Blending Surface"
GROUP_TAG = "gerbs_group_version"  # custom property on the node group
GROUP_VERSION = 4  # 2: checks the result against its input; 3: no Degree / Face Shape, a Rest Shape;
# 4: Merge by Distance, Merge Distance and the Warning line
RESULT_TAG = "gerbs_result"  # custom property on each hidden result object and its mesh
RESULT_NAME = "GERBS Result"  # prefix of the result object / mesh names

# --- the input a result was built from, stored on the result mesh ---------------
# Hidden attributes ("." prefix); the node group compares them with the geometry
# the modifier receives and strips them from its output. Each uses the first
# V / C / F elements of its domain (a surface has P >= V points, 3T >= C corners
# and T >= F triangles).
SNAPSHOT_PREFIX = ".gerbs_src_"  # (no other attribute starts with it)
SNAP_POSITION = ".gerbs_src_position"  # POINT, FLOAT_VECTOR: base vertex positions
SNAP_NORMAL = ".gerbs_src_normal"  # POINT, FLOAT_VECTOR: vertex normals (Use Custom Normals)
SNAP_COUNT = ".gerbs_src_count"  # POINT, INT: (V, F, C) on points 0, 1, 2
SNAP_CORNER = ".gerbs_src_corner"  # CORNER, INT: vertex of each base face corner
SNAP_FACE_SIZE = ".gerbs_src_face_size"  # FACE, INT: corners of each base face
SNAP_MATERIAL = ".gerbs_src_material"  # FACE, INT: material index of each base face
SNAPSHOT_ATTRIBUTES = (SNAP_POSITION, SNAP_NORMAL, SNAP_COUNT, SNAP_CORNER, SNAP_FACE_SIZE,
                       SNAP_MATERIAL)

STALE_MESSAGE = ("GERBS: the surface is out of date with this mesh or its settings, so the "
                 "base mesh is shown; enable the GERBS Blending Surface add-on to update it")

# enum-like settings: python value -> menu item label (in this order)
KERNELS = {"erbs": "ERBS", "bfbs": "BFBS", "logistic": "Logistic", "affine": "Affine"}
BOUNDARIES = {"keep": "Keep", "straighten": "Straighten"}
REST_SHAPES = {"follow": "Follow", "bound": "Bound"}


@dataclass(frozen=True)
class SocketSpec:
    """One input of the node group: a setting of the surface (or internal state)."""

    key: str  # keyword in api.add_surface(**settings)
    name: str  # socket name shown in the modifier panel
    socket_type: str
    default: object = None
    min: float | None = None
    max: float | None = None
    description: str = ""
    items: dict | None = None  # menu sockets: python value -> label
    hidden: bool = False  # internal: not shown in the modifier panel
    scale: float = 1.0  # api value = socket value * scale (memory budget: MB -> bytes)
    shape: bool = True  # changes the surface (checked by the node group); else only the build


SETTINGS = (
    SocketSpec("kernel", "Kernel", "NodeSocketMenu", "erbs", items=KERNELS,
               description="Univariate GERBS kernel F of the partition of unity"),
    SocketSpec("alpha", "Alpha", "NodeSocketFloat", 1.0, 0.01, 100.0,
               "ERBS intrinsic parameter alpha"),
    SocketSpec("beta", "Beta", "NodeSocketFloat", 1.0, 0.01, 100.0,
               "ERBS intrinsic parameter beta"),
    SocketSpec("gamma", "Gamma", "NodeSocketFloat", 1.0, 0.01, 100.0,
               "ERBS intrinsic parameter gamma"),
    SocketSpec("lam", "Lambda", "NodeSocketFloat", 0.5, 0.0, 1.0,
               "ERBS intrinsic parameter lambda"),
    SocketSpec("sigma", "Sigma", "NodeSocketFloat", 1.0, 0.0, 100.0,
               "ERBS intrinsic parameter sigma"),
    SocketSpec("bfbs_left", "BFBS Left", "NodeSocketInt", 2, 0, 16,
               "BFBS kernel exponent i_left (F = regularized incomplete beta I_t(i+1, j+1))"),
    SocketSpec("bfbs_right", "BFBS Right", "NodeSocketInt", 2, 0, 16,
               "BFBS kernel exponent i_right"),
    SocketSpec("resolution", "Resolution", "NodeSocketInt", 4, 1, 64,
               "Segments per mesh edge in the output tessellation"),
    SocketSpec("boundary", "Boundary", "NodeSocketMenu", "keep", items=BOUNDARIES,
               description="Boundary vertices: keep the corners or straighten the border"),
    SocketSpec("rest", "Rest Shape", "NodeSocketMenu", "follow", items=REST_SHAPES,
               description="Follow: the surface is always that of the current mesh (rebuilt "
                           "after an edit; during an Edit Mode drag it updates fast and is "
                           "rebuilt when the drag pauses). Bound: the shape at the last "
                           "Rebuild stays the rest shape and edits update the surface as a "
                           "fast linear deformation of it, like a bound deform modifier"),
    SocketSpec("use_normals", "Use Custom Normals", "NodeSocketBool", False,
               description="Use the base mesh's vertex normals as Hermite data"),
    SocketSpec("merge", "Merge by Distance", "NodeSocketBool", False,
               description="Weld vertices closer than Merge Distance before building (unwelded "
                           "seams of imports: split UVs or normals); off: such seams stay open"),
    SocketSpec("merge_distance", "Merge Distance", "NodeSocketFloat", 1.0e-4, 0.0, 1.0e6,
               "Largest distance of vertices welded by Merge by Distance (0: only coincident "
               "ones)"),
    SocketSpec("memory_budget", "Memory Budget (MB)", "NodeSocketFloat", 2000.0, 1.0, 1.0e6,
               "Largest memory (MB) a build may use; larger builds are refused with an error",
               scale=1.0e6, shape=False),
)
INTERNAL = (
    SocketSpec("result", "Result", "NodeSocketObject", hidden=True,
               description="Hidden object holding the surface (written by the add-on)"),
    SocketSpec("error", "Error", "NodeSocketString", "", hidden=True,
               description="Last error of the add-on; shown as a node warning"),
    SocketSpec("warning", "Warning", "NodeSocketString", "", hidden=True,
               description="What the last build repaired in the mesh; shown as a node warning"),
)
SHAPE_SETTINGS = tuple(s for s in SETTINGS if s.shape)
# The settings the result was built from (written by the add-on after each build;
# the node group shows the base mesh while they differ from the current settings).
# Menus and booleans as INT (menu: item position), ints as INT, floats as FLOAT;
# -1 never matches a valid setting.
BUILT = tuple(
    SocketSpec(f"built_{s.key}", f"Built {s.name}",
               "NodeSocketFloat" if s.socket_type == "NodeSocketFloat" else "NodeSocketInt",
               -1, hidden=True, description=f"{s.name} the result was built with (internal)")
    for s in SHAPE_SETTINGS)
SETTING_KEYS = tuple(s.key for s in SETTINGS)
DEFAULTS = {s.key: s.default * s.scale if s.scale != 1.0 else s.default for s in SETTINGS}
