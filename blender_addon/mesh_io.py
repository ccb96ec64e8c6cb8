"""Fast transfer of mesh data between Blender and numpy.

Reading is only ever done on *evaluated* meshes (``depsgraph``-owned copies) or
on the add-on's own result mesh, never on the user's original mesh: a Python
read of an original mesh's positions (``attributes["position"]``, even just
looking the attribute up, or ``vertices.foreach_get("co")``) makes Blender
un-share the position array the evaluated copy shares with it, and every
``MeshVertex`` the user holds then points at the old array (their edits are
lost, later writes land in freed memory). See stack.read_input for where the
evaluated mesh comes from; snapshot.py stores an input on its result.

Positions through ``attributes["position"].data.foreach_get/foreach_set
("vector", ...)`` on float32 buffers (25-50x faster than
``vertices.foreach_get("co")``; a float64 buffer forces a slow per-item
conversion), topology through ``polygons.foreach_get("loop_start")`` (per face: ~2 ms for 70k
faces; the node group's channel carries the face sizes instead) and the
``.corner_vert`` attribute (0.2 ms for 360k corners; ``loops.foreach_get
("vertex_index")``: 14 ms), material indices and edges through their raw attributes
(``material_index``, ``.edge_verts``: 35k-vertex mesh 0.03 ms, against ~20 ms face by
face or edge by edge). New topology is written through ``.corner_vert`` too (0.2 ms
instead of 70 ms for 750k corners).

Shapes: positions (V, 3) float32 as stored (the core gets them as float64);
topology as CSR ``offsets (F+1,)`` int64 and ``corners (C,)`` int32 (vertex of
each face corner, faces in order); material indices (F,) int32.
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass, replace

import numpy as np

from . import ids


@dataclass(frozen=True, eq=False)
class MeshInput:
    """The geometry a surface is built from, exactly as Blender stores it, and what it
    carries (:class:`attributes.Carried`; None when not read)."""

    positions: np.ndarray  # (V, 3) float32
    offsets: np.ndarray  # (F+1,) int64
    corners: np.ndarray  # (C,) int32
    materials: np.ndarray  # (F,) int32
    normals: np.ndarray | None = None  # (V, 3) float32 vertex normals, when used
    corner_loops: np.ndarray | None = None  # (C,) Blender loop of each CSR corner (None: same)
    carried: object = None  # attributes.Carried

    def same_topology(self, other) -> bool:
        """Same faces (the same arrays: an input with new positions only, stack.read_input)."""
        if other is self:
            return True
        return (other is not None
                and (self.offsets is other.offsets or np.array_equal(self.offsets, other.offsets))
                and (self.corners is other.corners or np.array_equal(self.corners, other.corners)))

    def same_geometry(self, other) -> bool:
        """Positions, topology and normals equal (as floats: -0.0 == +0.0, NaN never): the
        surface is the same (what it carries may still differ). An input is the same as
        itself (its record, NaN or not, is what the node group found equal)."""
        if other is self:
            return True
        return (self.same_topology(other) and np.array_equal(self.positions, other.positions)
                and (self.normals is None) == (other.normals is None)
                and (self.normals is None or np.array_equal(self.normals, other.normals)))

    def same(self, other) -> bool:
        """Everything equal: the geometry, the material indices and what it carries."""
        if other is self:
            return self.carried is not None
        return (self.same_geometry(other) and np.array_equal(self.materials, other.materials)
                and self.carried is not None and self.carried.same(other.carried))

    def loops(self) -> np.ndarray:
        """(C,) the Blender loop of each CSR corner."""
        return np.arange(len(self.corners)) if self.corner_loops is None else self.corner_loops

    def faces(self):
        """Faces for the core: an (F, k) array if all faces have k corners, else a list."""
        return faces_from_csr(self.offsets, self.corners)

    def with_carried(self, carried) -> "MeshInput":
        return replace(self, carried=carried)


def faces_from_csr(offsets: np.ndarray, corners: np.ndarray):
    sizes = np.diff(offsets)
    if len(sizes) and np.all(sizes == sizes[0]):
        return corners.reshape(-1, int(sizes[0]))
    return [corners[a:b] for a, b in zip(offsets[:-1], offsets[1:])]


def _get(collection, name, n, dtype, width=1):
    buf = np.empty(n * width, dtype=dtype)
    collection.foreach_get(name, buf)
    return buf.reshape(-1, width) if width > 1 else buf


def _raw(mesh, name, domain, data_type, n, dtype, width=1):
    """Blender's raw attribute `name` (one bulk read), or None where the mesh has no
    attribute of that name, domain and type."""
    attr = mesh.attributes.get(name)
    if attr is None or attr.domain != domain or attr.data_type != data_type:
        return None
    return _get(attr.data, "value", n, dtype, width)


def read_positions(mesh) -> np.ndarray:
    """(V, 3) float32 positions of an evaluated or add-on-owned mesh."""
    return _get(mesh.attributes["position"].data, "vector", len(mesh.vertices), np.float32, 3)


def read_topology(mesh, with_loops: bool = False, sizes=None):
    """Faces of an evaluated or add-on-owned mesh as CSR (offsets int64, corners int32);
    with_loops: also the Blender loop of each CSR corner (None when they coincide).
    `sizes`: (F,) the corners of each face where known (the node group's channel): the
    offsets are their sums and nothing per face is read.

    Else one per-face read (``loop_start``: Blender stores faces as increasing offsets
    into the corners, so the sizes are their differences); ``loop_total`` (a second
    per-face read) only for faces not in loop order."""
    n_faces, n_corners = len(mesh.polygons), len(mesh.loops)
    # raw attribute read: ~70x faster than loops' vertex_index
    corners = _raw(mesh, ".corner_vert", "CORNER", "INT", n_corners, np.int32)
    if corners is None:
        corners = _get(mesh.loops, "vertex_index", n_corners, np.int32)
    offsets = np.empty(n_faces + 1, dtype=np.int64)
    if sizes is not None and len(sizes) == n_faces:
        offsets[0] = 0
        np.cumsum(sizes, out=offsets[1:])
        if offsets[-1] == n_corners and (not n_faces or sizes.min() > 0):
            return (offsets, corners, None) if with_loops else (offsets, corners)
    offsets[:-1] = _get(mesh.polygons, "loop_start", n_faces, np.int32)
    offsets[-1] = n_corners
    loops = None
    if n_faces and (offsets[0] != 0 or np.any(np.diff(offsets) <= 0)):  # not in loop order
        start = offsets[:-1].copy()
        sizes = _get(mesh.polygons, "loop_total", n_faces, np.int32)
        offsets = np.zeros(n_faces + 1, dtype=np.int64)
        np.cumsum(sizes, out=offsets[1:])
        loops = np.concatenate([np.arange(s, s + n) for s, n in zip(start, sizes)])
        corners = corners[loops]
    return (offsets, corners, loops) if with_loops else (offsets, corners)


def read_face_ints(mesh, name: str) -> np.ndarray | None:
    """(F,) int32 values of the FACE INT attribute `name`, or None where there is none."""
    return _raw(mesh, name, "FACE", "INT", len(mesh.polygons), np.int32)


def read_materials(mesh) -> np.ndarray:
    """(F,) int32 material index of each face (the raw ``material_index`` attribute;
    ``polygons.foreach_get("material_index")`` reads face by face, ~100x slower)."""
    out = _raw(mesh, "material_index", "FACE", "INT", len(mesh.polygons), np.int32)
    return np.zeros(len(mesh.polygons), dtype=np.int32) if out is None else out  # none: 0


def read_edge_verts(mesh) -> np.ndarray:
    """(E, 2) int32 vertices of each edge (the raw ``.edge_verts`` attribute; edge by edge
    through ``edges.foreach_get("vertices")`` where a mesh has none)."""
    n_edges = len(mesh.edges)
    out = _raw(mesh, ".edge_verts", "EDGE", "INT32_2D", n_edges, np.int32, 2)
    if out is None:
        out = _get(mesh.edges, "vertices", n_edges, np.int32, 2)
    return out.reshape(-1, 2)


def read_normals(mesh) -> np.ndarray:
    """(V, 3) float32 vertex normals of an evaluated or add-on-owned mesh."""
    return _get(mesh.vertex_normals, "vector", len(mesh.vertices), np.float32, 3)


def read_mesh(mesh, normals: bool = False, positions=None, sizes=None) -> MeshInput:
    """Everything a build needs from an evaluated mesh (never the user's original);
    `positions`: (V, 3) float32 to use instead of the mesh's own; `sizes`: (F,) its face
    sizes where known (read_topology)."""
    offsets, corners, loops = read_topology(mesh, with_loops=True, sizes=sizes)
    return MeshInput(
        positions=read_positions(mesh) if positions is None else positions,
        offsets=offsets, corners=corners, materials=read_materials(mesh),
        normals=read_normals(mesh) if normals else None, corner_loops=loops)


def editing(obj) -> bool:
    """Is `obj`'s mesh in Edit Mode: its own, or a linked duplicate's that shares the mesh
    (Blender then evaluates every user of the mesh from the edit mesh, with the modifiers'
    Edit Mode visibility, while the mesh's own arrays keep the state before Edit Mode; found
    by a test of linked duplicates: the other object's sync read those and found nothing
    changed, or failed reading its attributes)."""
    return obj.mode == "EDIT" or (obj.type == "MESH" and obj.data is not None
                                  and obj.data.is_editmode)


@contextlib.contextmanager
def edit_mesh_copy(mesh):
    """A temporary copy of an original mesh in Edit Mode, made from its BMesh in C
    (``BMesh.to_mesh``; the BMesh's elements stay where they are, nothing of the
    user's is reallocated), so it reads like an evaluated mesh. Removed on exit."""
    import bmesh
    import bpy

    bm = bmesh.from_edit_mesh(mesh)
    tmp = bpy.data.meshes.new(ids.EDIT_COPY_NAME)
    try:
        bm.to_mesh(tmp)
        yield tmp
    finally:
        bpy.data.meshes.remove(tmp)


def write_surface(mesh, points: np.ndarray, offsets: np.ndarray, corners: np.ndarray,
                  edges=None) -> None:
    """Replace the (result) mesh's geometry by points (P, 3) and polygons (CSR: offsets
    (Fo+1,), corners (Co,) point indices).

    edges: optional (edge_verts (E, 2), corner_edges (Co,)) of exactly these
    polygons (every undirected edge once; corner_edges[c] = edge from corner c to
    the next corner of its polygon), e.g. :meth:`gerbs_core.mesh.lattice.Lattice.edges`:
    written as the raw ``.edge_verts`` / ``.corner_edge`` attributes instead of
    letting Blender hash all half-edges (``update(calc_edges=True)``: measured
    14-23 ms for 248k triangles, against ~1.5 ms for the two attribute writes).
    """
    n_points, n_faces, n_corners = len(points), len(offsets) - 1, len(corners)
    mesh.clear_geometry()
    mesh.vertices.add(n_points)
    mesh.loops.add(n_corners)
    mesh.polygons.add(n_faces)
    mesh.attributes["position"].data.foreach_set(
        "vector", np.ascontiguousarray(points, dtype=np.float32).ravel())
    mesh.polygons.foreach_set("loop_start", np.ascontiguousarray(offsets[:-1], dtype=np.int32))
    corner_verts = np.ascontiguousarray(corners, dtype=np.int32)
    attr = mesh.attributes.get(".corner_vert")
    if attr is not None:  # raw attribute write: ~300x faster than loops' vertex_index
        attr.data.foreach_set("value", corner_verts)
    else:
        mesh.loops.foreach_set("vertex_index", corner_verts)
    edge_attr = mesh.attributes.get(".corner_edge")
    if edges is not None and attr is not None and edge_attr is not None:
        edge_verts, corner_edges = edges
        mesh.edges.add(len(edge_verts))
        mesh.attributes[".edge_verts"].data.foreach_set(
            "value", np.ascontiguousarray(edge_verts, dtype=np.int32).ravel())
        edge_attr.data.foreach_set("value", np.ascontiguousarray(corner_edges, dtype=np.int32).ravel())
        mesh.update()
    else:
        mesh.update(calc_edges=True)


def write_positions(mesh, points: np.ndarray) -> None:
    """Overwrite the positions of an existing (result) mesh with the same vertex count."""
    mesh.attributes["position"].data.foreach_set(
        "vector", np.ascontiguousarray(points, dtype=np.float32).ravel())
    mesh.update()
