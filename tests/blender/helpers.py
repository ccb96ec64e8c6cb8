"""Helpers for the Blender tests: test meshes as objects, evaluated positions, rings, a
final render's positions."""
from __future__ import annotations

from pathlib import Path

import bpy
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SUZANNE = ROOT / "examples" / "suzanne.obj"


def link_object(name, vertices, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(map(float, v)) for v in vertices], [],
                     [tuple(int(i) for i in f) for f in faces])
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def make_object(kind: str):
    """Suzanne (OBJ importer), icosphere / UV sphere / grid (Blender's primitives),
    or the core's mixed mesh (triangles, quads, a pentagon, a hexagon, boundary)."""
    if kind == "suzanne":
        bpy.ops.wm.obj_import(filepath=str(SUZANNE))
        obj = bpy.context.selected_objects[0]
    elif kind == "icosphere":
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2)
        obj = bpy.context.active_object
    elif kind == "uv_sphere":
        bpy.ops.mesh.primitive_uv_sphere_add(segments=12, ring_count=6)
        obj = bpy.context.active_object
    elif kind == "grid":
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=5, y_subdivisions=4, size=2.0)
        obj = bpy.context.active_object
    elif kind == "mixed":
        from gerbs_core.datasets.primitives import mixed_mesh
        obj = link_object("mixed", *mixed_mesh())
    else:
        raise ValueError(kind)
    bpy.context.view_layer.objects.active = obj
    return obj


def positions(mesh) -> np.ndarray:
    buf = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.attributes["position"].data.foreach_get("vector", buf)
    return buf.reshape(-1, 3).astype(np.float64)


def topology(mesh):
    from blender_addon.mesh_io import read_topology
    return read_topology(mesh)


def evaluated(obj) -> np.ndarray:
    """Positions of the object's final evaluated mesh (in Edit Mode through to_mesh:
    the evaluated object's data is the edit cage there)."""
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    obj_eval = obj.evaluated_get(dg)
    if obj.mode != "EDIT":
        return positions(obj_eval.data)
    try:
        return positions(obj_eval.to_mesh())
    finally:
        obj_eval.to_mesh_clear()


def undo_into_edit_mode(name: str):
    """Undo the last pushed step, which must land in Edit Mode; (the object, found again by
    `name`: undo replaces the Python objects, its evaluated positions there), back in
    Object Mode."""
    bpy.ops.ed.undo()
    obj = bpy.data.objects[name]
    assert obj.mode == "EDIT"
    bpy.context.view_layer.update()
    P = evaluated(obj)
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj, P


def base_positions(obj) -> np.ndarray:
    """Positions of the mesh data-block as evaluated (reading the original mesh's
    positions from Python would un-share them and invalidate held references)."""
    dg = bpy.context.evaluated_depsgraph_get()
    return positions(obj.data.evaluated_get(dg))


def modifier_input(obj) -> np.ndarray:
    """Positions the (last) modifier receives: the evaluated mesh with it disabled."""
    mod = obj.modifiers[-1]
    mod.show_viewport = False
    try:
        return evaluated(obj)
    finally:
        mod.show_viewport = True


def fresh_surface(X, offsets, corners, resolution, **kw) -> np.ndarray:
    """The core's surface points (P, 3) built from scratch (no Blender involved)."""
    from blender_addon.mesh_io import faces_from_csr
    from gerbs_core.mesh.surface import BlendingSurface

    faces = faces_from_csr(np.asarray(offsets), np.asarray(corners))
    return BlendingSurface(np.asarray(X, dtype=np.float64), faces, **kw).tessellate(resolution)[0]


def warnings(obj):
    return [(w.type, w.message) for w in obj.modifiers[0].node_warnings]


def evaluated_faces(obj):
    """(offsets (F+1,), corners (C,)) of the object's final evaluated mesh."""
    dg = bpy.context.evaluated_depsgraph_get()
    return topology(obj.evaluated_get(dg).data)


def evaluated_triangles(obj) -> np.ndarray:
    """The final evaluated mesh's faces as triangles (quads split (a, b, c), (a, c, d))."""
    offsets, corners = evaluated_faces(obj)
    return triangulate(offsets, corners)


def triangulate(offsets, corners) -> np.ndarray:
    """Fan triangles of CSR polygons, (T, 3)."""
    out = []
    for a, b in zip(offsets[:-1].tolist(), offsets[1:].tolist()):
        out.extend((corners[a], corners[k], corners[k + 1]) for k in range(a + 1, b - 1))
    return np.array(out, dtype=np.int64).reshape(-1, 3)


def face_rings(offsets, corners, n_vertices, w, kmax=6) -> np.ndarray:
    """ring[f]: 1 for faces around vertex w, k+1 for faces sharing a vertex with ring k."""
    n_faces = len(offsets) - 1
    face_of_corner = np.repeat(np.arange(n_faces), np.diff(offsets))
    ring = np.full(n_faces, np.iinfo(np.int64).max)
    verts = np.zeros(n_vertices, dtype=bool)
    verts[w] = True
    for k in range(1, kmax + 1):
        touched = np.zeros(n_faces, dtype=bool)
        touched[face_of_corner[verts[corners]]] = True
        ring[touched & (ring > k)] = k
        verts[corners[touched[face_of_corner]]] = True
    return ring


def export_and_reimport(obj, path: Path):
    """Export `obj` with its modifiers applied (glTF binary or OBJ by `path`'s suffix,
    at the current frame) into an empty scene, re-import it; return the new object."""
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    if path.suffix == ".glb":
        # (without export_current_frame the glTF exporter evaluates frame 0)
        bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", use_selection=True,
                                  export_apply=True, export_animations=False,
                                  export_current_frame=True)
    else:
        bpy.ops.wm.obj_export(filepath=str(path), export_selected_objects=True,
                              apply_modifiers=True, export_materials=False)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.suffix == ".glb":
        bpy.ops.import_scene.gltf(filepath=str(path), merge_vertices=True)
    else:
        bpy.ops.wm.obj_import(filepath=str(path))
    (imported,) = [o for o in bpy.data.objects if o.type == "MESH"]
    return imported


class _CaptureEngine(bpy.types.RenderEngine):
    """A render engine that keeps the positions of every mesh object it renders."""

    bl_idname = "GERBS_TEST_CAPTURE"
    bl_label = "Capture"
    seen = {}

    def render(self, depsgraph):
        assert depsgraph.mode == "RENDER"
        for inst in depsgraph.object_instances:
            if inst.object.type == "MESH":
                me = inst.object.data
                buf = np.empty(3 * len(me.vertices), np.float32)
                me.attributes["position"].data.foreach_get("vector", buf)
                type(self).seen[inst.object.name] = buf.reshape(-1, 3)
        scene = depsgraph.scene
        result = self.begin_result(0, 0, scene.render.resolution_x, scene.render.resolution_y)
        self.end_result(result)


def final_render() -> dict:
    """A final render (bpy.ops.render.render, a RENDER depsgraph; a camera is added if the
    scene has none): {object name: the positions (n, 3) float32 it rendered}."""
    bpy.utils.register_class(_CaptureEngine)
    try:
        scene = bpy.context.scene
        if scene.camera is None:
            cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
            scene.collection.objects.link(cam)
            scene.camera = cam
        scene.render.engine = _CaptureEngine.bl_idname
        scene.render.resolution_x = scene.render.resolution_y = 4
        _CaptureEngine.seen = {}
        bpy.ops.render.render()
        return dict(_CaptureEngine.seen)
    finally:
        bpy.utils.unregister_class(_CaptureEngine)
