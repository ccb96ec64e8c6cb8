"""Every identifier and name the add-on uses, in one place.

Operators, panels, menus, property groups, the Geometry Nodes group and its
sockets, and the custom-property tags on data-blocks are all spelled here, so a
rename is a one-line change and tests can refer to the same constants.
"""
from __future__ import annotations

from dataclasses import dataclass

from .core import module as _core_module

ADDON_ID = "gerbs_blending_surface"  # extension id (blender_manifest.toml)
ADDON_NAME = "GERBS Blending Surface"

# --- operators (bl_idname) ------------------------------------------------------
OP_ADD = "object.gerbs_add_surface"
OP_APPLY = "object.gerbs_apply"
OP_REBUILD = "object.gerbs_rebuild"
OP_REMOVE = "object.gerbs_remove"
OP_SELECT_PROBLEM = "object.gerbs_select_problem"

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
GROUP_VERSION = 11  # 2: checks the result against its input; 3: no Degree / Face Shape, a Rest
# Shape; 4: Merge by Distance, Merge Distance and the Warning line; 5: Render Resolution
# and a render result, the built settings and carried attributes recorded on each result
# (no "Built ..." inputs), the input passed on while stale; 6: the channel says which
# record the input's topology and carried layers equal (CHANNEL_RECORD); 7: the checks
# reduce over a selection (node_helpers.Tree.none_differ), one pass over the faces, one
# comparison per value (node_fresh._differs); 8: with Use Custom Normals the input's vertex
# normals are checked against the record and passed on in the channel (CHANNEL_NORMAL); 9:
# a Render Error: a final render whose build failed shows the input, not the viewport surface;
# 10: carried float layers compare within LAYER_TOLERANCE (Blender's Bevel modifier writes
# UVs that differ by an ulp from one evaluation to the next); 11: an input carrying a crease
# layer (crease_edge, crease_vert) its result's record lacks is stale (SNAP_CREASED)
PART_TAG = "gerbs_part"  # custom property on each nested node group (node_parts.py): its key
PART_VERSION = "gerbs_part_version"  # ... and the GROUP_VERSION it was built for
PART_PREFIX = ".GERBS "  # name prefix of the nested node groups
RESULT_TAG = "gerbs_result"  # custom property on each hidden result object and its mesh
RESULT_NAME = "GERBS Result"  # prefix of the result object / mesh names
RENDER_RESULT_NAME = "GERBS Render Result"
EDIT_COPY_NAME = ".GERBS edit copy"  # temporary copy of a mesh in Edit Mode (mesh_io)

# --- the input a result was built from, stored on the result mesh ---------------
# Hidden attributes ("." prefix); the node group compares them with the geometry
# the modifier receives and strips them from its output. Each uses the first
# V / E / F / C elements of its domain (a surface has P >= V points, at least E
# edges, F faces and C corners).
SNAPSHOT_PREFIX = ".gerbs_src_"  # (no other attribute starts with it)
SNAP_POSITION = ".gerbs_src_position"  # POINT, FLOAT_VECTOR: base vertex positions
SNAP_NORMAL = ".gerbs_src_normal"  # POINT, FLOAT_VECTOR: vertex normals (Use Custom Normals)
SNAP_COUNT = ".gerbs_src_count_"  # + k: POINT, INT, its first point: (V, F, C, E, A)[k] (A: layers)
SNAP_CORNER = ".gerbs_src_corner"  # CORNER, INT: vertex of each base face corner
SNAP_FACE_SIZE = ".gerbs_src_face_size"  # FACE, INT: corners of each base face
SNAP_MATERIAL = ".gerbs_src_material"  # FACE, INT: material index of each base face
SNAP_EDGE_A = ".gerbs_src_edge_a"  # EDGE, INT: first vertex of each base edge
SNAP_EDGE_B = ".gerbs_src_edge_b"  # EDGE, INT: second vertex of each base edge
SNAP_SETTINGS = ".gerbs_src_setting_"  # + k: POINT, FLOAT, its first point: ids.RECORD_SETTINGS[k]
#                                        as built (menus: item position; resolution: the one built)
SNAP_LAYERS = ".gerbs_src_layers"  # POINT, INT: 4 per carried layer i: start and length of its
#                                   name in the modifier's "Attribute Names", its check
#                                   branch (LAYER_KINDS x DOMAINS) and 1 for a vertex group
SNAP_LAYER = ".gerbs_src_layer_"  # + i: the base values of carried layer i (its domain, type)
N_COUNTS = 5  # SNAP_COUNT + 0..4 (one attribute each: any mesh has a first point)
SNAPSHOT_ATTRIBUTES = (SNAP_POSITION, SNAP_NORMAL, SNAP_CORNER, SNAP_FACE_SIZE, SNAP_MATERIAL,
                       SNAP_EDGE_A, SNAP_EDGE_B, SNAP_LAYERS) + tuple(
    f"{SNAP_COUNT}{k}" for k in range(N_COUNTS))  # + SNAP_SETTINGS + k (record_names())
# + 0 / 1: POINT, INT, its first point: 1 where the input carried crease_edge / crease_vert
# when the record was written (those layers shape the surface: an input that has one the
# record lacks is stale; the node group reads 0 where a record predates them)
SNAP_CREASED = ".gerbs_src_creased_"
CREASE_LAYERS = (("crease_edge", "EDGE"), ("crease_vert", "POINT"))
SNAP_SERIAL = ".gerbs_src_serial_"  # + k: POINT, INT, its first point: (session salt, write
#                                    counter)[k] of the record write (snapshot.stamp); optional
SERIAL_NAMES = tuple(f"{SNAP_SERIAL}{k}" for k in range(2))
SNAP_REST = ".gerbs_src_rest"  # POINT, FLOAT_VECTOR: the rest shape a Rest Shape Bound surface
#                                is bound to (first V points; rest.py); optional, not checked
RECORD_STAMP = "gerbs_record"  # custom property on a result mesh: a new stamp with every
#                                record write (snapshot.stamp; undo restores an old one)
OUT_WEIGHT = ".gerbs_src_weight_"  # + i: POINT FLOAT, output weights of vertex-group layer i
#                                   (the node group stores them into the result's group)
# What the modifier received, on the geometry it passes on while it shows no surface
# (stale or error): the add-on reads it from the final mesh through deform-only
# modifiers below GERBS (they move "position" only).
CHANNEL_PREFIX = ".gerbs_in_"
CHANNEL_POSITION = ".gerbs_in_position"  # POINT, FLOAT_VECTOR
CHANNEL_NORMAL = ".gerbs_in_normal"  # POINT, FLOAT_VECTOR: its vertex normals (Use Custom
#   Normals only): a modifier below moves the final mesh's normals with its positions
CHANNEL_WEIGHT = ".gerbs_in_weight_"  # + i: POINT FLOAT, the weights of vertex-group layer i
CHANNEL_FACE_SIZE = ".gerbs_in_face_size"  # FACE INT: corners of each face, unless CHANNEL_RECORD
#   names a record (one raw read instead of Blender's per-face "loop_start", ~2 ms / 70k faces)
CHANNEL_RECORD = ".gerbs_in_record_"  # + k: POINT INT: the viewport result's SNAP_SERIAL + k
#   when the input's counts, corners, face sizes, material indices, edges and recorded
#   layers equal that record (only positions may differ), else -1 (stack.read_input)

# --- carried attributes ------------------------------------------------------------
DOMAINS = ("POINT", "EDGE", "FACE", "CORNER")
# data type -> (foreach_get property, components, numpy dtype, check kind: 0 vector, 1
# color, 2 integer; the node group compares a layer through that kind of Named Attribute)
CARRIED_TYPES = {
    "FLOAT": ("value", 1, "float32", 0), "FLOAT2": ("vector", 2, "float32", 0),
    "FLOAT_VECTOR": ("vector", 3, "float32", 0), "FLOAT_COLOR": ("color", 4, "float32", 1),
    "BYTE_COLOR": ("color_srgb", 4, "float32", 1), "INT": ("value", 1, "int32", 2),
    "INT8": ("value", 1, "int32", 2), "BOOLEAN": ("value", 1, "bool", 2),
}
LAYER_KINDS = ("FLOAT_VECTOR", "FLOAT_COLOR", "INT")  # the Named Attribute type of each kind
# a carried float value equals the record's when |a - b| <= LAYER_TOLERANCE (1 + |b|) (|b| the
# length of the recorded vector / color) in every component, in the node group and in
# Python alike; a NaN or infinity never does. Measured: Blender's Bevel modifier (bpy 5.0.1)
# writes UVs that differ by 1 ulp (6e-8) in 8-20 of a bevelled Cylinder's 960 corners from
# one evaluation to the next, and exact checks showed the input instead of the surface
# after most evaluations (positions and every integer stay exact)
LAYER_TOLERANCE = 1e-6
NOT_CARRIED = ("position", "custom_normal")  # and every name starting with "."
VERTEX_MARKS = ("crease_vert", "bevel_weight_vert")  # kept at the mesh vertices, 0 between
# modifiers that only move vertices (what GERBS passes on reaches the final mesh intact)
DEFORM_ONLY = ("ARMATURE", "CAST", "CORRECTIVE_SMOOTH", "CURVE", "DISPLACE", "HOOK",
               "LAPLACIANDEFORM", "LAPLACIANSMOOTH", "LATTICE", "MESH_DEFORM", "SHRINKWRAP",
               "SIMPLE_DEFORM", "SMOOTH", "SURFACE_DEFORM", "WARP", "WAVE")

STALE_MESSAGE = ("GERBS: the surface is out of date with this mesh or its settings, so the "
                 "base mesh is shown; it updates while the GERBS Blending Surface add-on is "
                 "enabled and the scene's Live Update is on (or press Rebuild)")

# enum-like settings: python value -> menu item label (in this order); the kernels are
# the core's one table of kernel names (gerbs_core.kernels.KERNELS)
_CORE_KERNELS = _core_module("kernels").KERNELS
KERNELS = {name: entry.label for name, entry in _CORE_KERNELS.items()}
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
               description="How each vertex's patch hands over to its neighbours. ERBS and "
                           "Logistic: smooth everywhere (no visible seams in reflections). "
                           "BFBS: smooth to the order set by Left / Right. Affine: straight "
                           "ramps, visible creases where patches meet (for comparison)"),
    SocketSpec("alpha", "Alpha", "NodeSocketFloat", 1.0, 0.01, 100.0,
               "ERBS: how long each patch holds on near its vertex and near the end of its "
               "reach before blending. Larger: flatter around the vertices, shorter and "
               "steeper blends between them"),
    SocketSpec("beta", "Beta", "NodeSocketFloat", 1.0, 0.01, 100.0,
               "ERBS: sharpness of the handover between neighbouring patches. Larger: a more "
               "abrupt change around Lambda; smaller: a gentler, wider blend"),
    SocketSpec("gamma", "Gamma", "NodeSocketFloat", 1.0, 0.01, 100.0,
               "ERBS: like Alpha, for the far end of each patch's reach only. Larger: the "
               "neighbours take over later and more steeply"),
    SocketSpec("lam", "Lambda", "NodeSocketFloat", 0.5, 0.0, 1.0,
               "ERBS: where the handover is steepest, from the vertex (0) to the end of its "
               "reach (1). Larger: every vertex shapes more of the surface around it"),
    SocketSpec("sigma", "Sigma", "NodeSocketFloat", 1.0, 0.0, 100.0,
               "ERBS: width of the steep part of the handover around Lambda (larger: wider). "
               "Whole numbers keep the surface smooth everywhere; others make the blend "
               "only finitely smooth at Lambda"),
    SocketSpec("bfbs_left", "BFBS Left", "NodeSocketInt", 2, 0, 16,
               "BFBS: smoothness order where a patch starts to hand over (0: a visible "
               "kink; each step one more derivative continuous). Larger: the patch holds "
               "on longer near its vertex"),
    SocketSpec("bfbs_right", "BFBS Right", "NodeSocketInt", 2, 0, 16,
               "BFBS: smoothness order at the end of a patch's reach (0: a visible kink). "
               "Larger: the neighbours take over more gently"),
    SocketSpec("resolution", "Resolution", "NodeSocketInt", 4, 1, 64,
               "Viewport: segments per mesh edge in the viewport, in Apply and in "
               "exports. More: a smoother-looking surface, more faces (a quad gives r x r)"),
    SocketSpec("render_resolution", "Render Resolution", "NodeSocketInt", 4, 1, 64,
               "Render: segments per mesh edge in final renders (F12). More: a "
               "smoother-looking render, more faces; the shape is the same surface"),
    SocketSpec("boundary", "Boundary", "NodeSocketMenu", "keep", items=BOUNDARIES,
               description="Open borders. Keep: border vertices keep their corners (flat "
                           "meshes stay flat, mesh corners stay sharp). Straighten: the "
                           "border runs smoothly through its vertices; corners get rounded"),
    SocketSpec("rest", "Rest Shape", "NodeSocketMenu", "follow", items=REST_SHAPES,
               description="Follow: the surface is always that of the current mesh (rebuilt "
                           "after an edit; during an Edit Mode drag it updates fast and is "
                           "rebuilt when the drag pauses). Bound: the shape at the last "
                           "Rebuild stays the rest shape and edits update the surface as a "
                           "fast linear deformation of it, like a bound deform modifier"),
    SocketSpec("use_normals", "Use Custom Normals", "NodeSocketBool", False,
               description="Make the surface leave every vertex perpendicular to the "
                           "mesh's vertex normal (edit normals to steer the surface); "
                           "every edit then rebuilds the surface"),
    SocketSpec("merge", "Merge by Distance", "NodeSocketBool", False,
               description="Weld vertices closer than Merge Distance before building, so an "
                           "unwelded seam (split UVs or normals of an import) is smooth "
                           "across; off: the surface has a crack along such seams"),
    SocketSpec("merge_distance", "Merge Distance", "NodeSocketFloat", 1.0e-4, 0.0, 1.0e6,
               "Merge by Distance: vertices closer than this become one, and the surface "
               "passes through it once (0: only coincident ones)"),
    SocketSpec("memory_budget", "Memory Budget (MB)", "NodeSocketFloat", 2000.0, 1.0, 1.0e6,
               "Largest memory (MB) the output (the surface's stencil) may use; the "
               "construction before it may use the larger of this and 2000 MB. A larger "
               "build is refused with an error",
               scale=1.0e6, shape=False),
)
INTERNAL = (
    SocketSpec("result", "Result", "NodeSocketObject", hidden=True,
               description="Hidden object holding the surface (written by the add-on)"),
    SocketSpec("render_result", "Render Result", "NodeSocketObject", hidden=True,
               description="Hidden object holding the surface at the render resolution"),
    SocketSpec("error", "Error", "NodeSocketString", "", hidden=True,
               description="Last error of the add-on; shown as a node warning"),
    SocketSpec("render_error", "Render Error", "NodeSocketString", "", hidden=True,
               description="Error of the last final render's build; while set, final "
                           "renders show the input (the viewport is not affected)"),
    SocketSpec("warning", "Warning", "NodeSocketString", "", hidden=True,
               description="What the last build repaired in the mesh; shown as a node warning"),
    SocketSpec("names", "Attribute Names", "NodeSocketString", "", hidden=True,
               description="Names of the carried attributes, end to end (internal)"),
)
# settings drawn by the add-on's panel only (not in the modifier's own input list)
# The setting of each core kernel parameter whose key is not the parameter's own name
# (the sockets' names are kept by saved files); KERNEL_PARAMETERS: kernel -> its settings,
# in the order of the core's parameters (settings.core_arguments passes them on).
KERNEL_SETTING_KEYS = {"i_left": "bfbs_left", "i_right": "bfbs_right"}
KERNEL_PARAMETERS = {name: tuple(KERNEL_SETTING_KEYS.get(p, p) for p in entry.parameters)
                     for name, entry in _CORE_KERNELS.items()}
SHAPE_SETTINGS = tuple(s for s in SETTINGS if s.shape)
# The settings each result records as built (SNAP_SETTINGS, in this order); the node
# group shows a result only while they equal the current ones, "resolution" standing
# for the resolution the result is for (viewport or render).
RECORD_SETTINGS = tuple(s for s in SHAPE_SETTINGS if s.key != "render_resolution")
SETTING_KEYS = tuple(s.key for s in SETTINGS)


def record_names() -> tuple:
    """Every fixed attribute of a result's record (the settings' included)."""
    return SNAPSHOT_ATTRIBUTES + tuple(f"{SNAP_SETTINGS}{k}" for k in range(len(RECORD_SETTINGS)))


def optional_record_names() -> tuple:
    """Attributes of a record that older records lack (read as 0 where missing)."""
    return tuple(f"{SNAP_CREASED}{k}" for k in range(len(CREASE_LAYERS)))
DEFAULTS = {s.key: s.default * s.scale if s.scale != 1.0 else s.default for s in SETTINGS}
