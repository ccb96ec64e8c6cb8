"""Helpers for the Blender tests: test meshes as objects, evaluated positions, rings."""
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
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    return positions(obj.evaluated_get(dg).data)


def evaluated_triangles(obj) -> np.ndarray:
    dg = bpy.context.evaluated_depsgraph_get()
    mesh = obj.evaluated_get(dg).data
    loops = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", loops)
    return loops.reshape(-1, 3)


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
