"""Fast transfer of mesh data between Blender and numpy.

Reading is only ever done on *evaluated* meshes (``depsgraph``-owned copies) or
on the add-on's own result mesh, never on the user's original mesh: a Python
read of an original mesh's positions (``attributes["position"]``, even just
looking the attribute up, or ``vertices.foreach_get("co")``) makes Blender
un-share the position array the evaluated copy shares with it, and every
``MeshVertex`` the user holds then points at the old array (their edits are
lost, later writes land in freed memory). See engine.read_input for where the
evaluated mesh comes from.

Positions through ``attributes["position"].data.foreach_get/foreach_set
("vector", ...)`` on float32 buffers (25-50x faster than
``vertices.foreach_get("co")``; a float64 buffer forces a slow per-item
conversion), topology through ``polygons.foreach_get("loop_total"/
"loop_start")`` and the ``.corner_vert`` attribute (0.2 ms for 360k corners;
``loops.foreach_get("vertex_index")``: 14 ms). New topology is written through
``.corner_vert`` too (0.2 ms instead of 70 ms for 750k corners).

Shapes: positions (V, 3) float32 as stored (the core gets them as float64);
topology as CSR ``offsets (F+1,)`` int64 and ``corners (C,)`` int32 (vertex of
each face corner, faces in order); material indices (F,) int32.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import ids


@dataclass(frozen=True, eq=False)
class MeshInput:
    """The geometry a surface is built from, exactly as Blender stores it."""

    positions: np.ndarray  # (V, 3) float32
    offsets: np.ndarray  # (F+1,) int64
    corners: np.ndarray  # (C,) int32
    materials: np.ndarray  # (F,) int32
    normals: np.ndarray | None = None  # (V, 3) float32 vertex normals, when used

    def same_topology(self, other) -> bool:
        return (other is not None and np.array_equal(self.offsets, other.offsets)
                and np.array_equal(self.corners, other.corners))

    def same(self, other) -> bool:
        """Everything equal (bit for bit; NaN never equals)."""
        return (self.same_topology(other) and np.array_equal(self.positions, other.positions)
                and np.array_equal(self.materials, other.materials)
                and (self.normals is None) == (other.normals is None)
                and (self.normals is None or np.array_equal(self.normals, other.normals)))

    def faces(self):
        """Faces for the core: an (F, k) array if all faces have k corners, else a list."""
        return faces_from_csr(self.offsets, self.corners)


def faces_from_csr(offsets: np.ndarray, corners: np.ndarray):
    sizes = np.diff(offsets)
    if len(sizes) and np.all(sizes == sizes[0]):
        return corners.reshape(-1, int(sizes[0]))
    return [corners[a:b] for a, b in zip(offsets[:-1], offsets[1:])]


def _get(collection, name, n, dtype, width=1):
    buf = np.empty(n * width, dtype=dtype)
    collection.foreach_get(name, buf)
    return buf.reshape(-1, width) if width > 1 else buf


def read_positions(mesh) -> np.ndarray:
    """(V, 3) float32 positions of an evaluated or add-on-owned mesh."""
    return _get(mesh.attributes["position"].data, "vector", len(mesh.vertices), np.float32, 3)


def read_topology(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Faces of an evaluated or add-on-owned mesh as CSR (offsets int64, corners int32)."""
    n_faces = len(mesh.polygons)
    sizes = _get(mesh.polygons, "loop_total", n_faces, np.int32)
    attr = mesh.attributes.get(".corner_vert")
    if attr is not None:  # raw attribute read: ~70x faster than loops' vertex_index
        corners = _get(attr.data, "value", len(mesh.loops), np.int32)
    else:
        corners = _get(mesh.loops, "vertex_index", len(mesh.loops), np.int32)
    start = _get(mesh.polygons, "loop_start", n_faces, np.int32)
    offsets = np.zeros(n_faces + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    if n_faces and not np.array_equal(start, offsets[:-1]):  # faces not in loop order
        corners = np.concatenate([corners[s:s + n] for s, n in zip(start, sizes)])
    return offsets, corners


def read_mesh(mesh, normals: bool = False) -> MeshInput:
    """Everything a build needs from an evaluated mesh (never the user's original)."""
    offsets, corners = read_topology(mesh)
    return MeshInput(
        positions=read_positions(mesh), offsets=offsets, corners=corners,
        materials=_get(mesh.polygons, "material_index", len(mesh.polygons), np.int32),
        normals=_get(mesh.vertex_normals, "vector", len(mesh.vertices), np.float32, 3)
        if normals else None)


def read_edit_mesh(mesh, normals: bool = False) -> MeshInput:
    """The same from an original mesh in Edit Mode, through its BMesh (whose
    elements stay where they are: nothing is reallocated)."""
    import bmesh

    bm = bmesh.from_edit_mesh(mesh)
    bm.verts.index_update()
    faces = [[v.index for v in f.verts] for f in bm.faces]
    sizes = np.fromiter((len(f) for f in faces), dtype=np.int64, count=len(faces))
    offsets = np.zeros(len(faces) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    return MeshInput(
        positions=np.array([v.co for v in bm.verts], dtype=np.float32).reshape(-1, 3),
        offsets=offsets,
        corners=np.fromiter((i for f in faces for i in f), dtype=np.int32, count=int(offsets[-1])),
        materials=np.fromiter((f.material_index for f in bm.faces), dtype=np.int32,
                              count=len(faces)),
        normals=np.array([v.normal for v in bm.verts], dtype=np.float32).reshape(-1, 3)
        if normals else None)


def write_surface(mesh, points: np.ndarray, triangles: np.ndarray, edges=None) -> None:
    """Replace the (result) mesh's geometry by a triangle mesh (points (P,3), triangles (T,3)).

    edges: optional (edge_verts (E, 2), corner_edges (T, 3)) of exactly these
    triangles (every undirected edge once; corner_edges[t, i] = edge from corner i
    to corner i+1), e.g. :meth:`gerbs_core.mesh.lattice.Lattice.edges`: written as
    the raw ``.edge_verts`` / ``.corner_edge`` attributes instead of letting
    Blender hash all 3T half-edges (``update(calc_edges=True)``: measured 14-23 ms
    for 248k triangles, against ~1.5 ms for the two attribute writes).
    """
    n_points, n_tris = len(points), len(triangles)
    mesh.clear_geometry()
    mesh.vertices.add(n_points)
    mesh.loops.add(3 * n_tris)
    mesh.polygons.add(n_tris)
    mesh.attributes["position"].data.foreach_set(
        "vector", np.ascontiguousarray(points, dtype=np.float32).ravel())
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * n_tris, 3, dtype=np.int32))
    corner_verts = np.ascontiguousarray(triangles, dtype=np.int32).ravel()
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
    mesh.shade_smooth()


def write_positions(mesh, points: np.ndarray) -> None:
    """Overwrite the positions of an existing (result) mesh with the same vertex count."""
    mesh.attributes["position"].data.foreach_set(
        "vector", np.ascontiguousarray(points, dtype=np.float32).ravel())
    mesh.update()


def write_material_indices(mesh, indices: np.ndarray) -> None:
    mesh.polygons.foreach_set("material_index", np.ascontiguousarray(indices, dtype=np.int32))
    mesh.update()


def _put(mesh, name, kind, domain, values, size) -> None:
    """Attribute `name` of `mesh` := `values` in its first elements, zeros after."""
    attr = mesh.attributes.get(name)
    if attr is None or attr.data_type != kind or attr.domain != domain:
        if attr is not None:
            mesh.attributes.remove(attr)
        attr = mesh.attributes.new(name, kind, domain)
    width = 3 if kind == "FLOAT_VECTOR" else 1
    buf = np.zeros(size * width, dtype=np.float32 if width == 3 else np.int32)
    flat = np.ravel(values)
    buf[:len(flat)] = flat
    attr.data.foreach_set("vector" if width == 3 else "value", buf)


def write_snapshot(mesh, inp: MeshInput, positions_only: bool = False) -> None:
    """Store `inp` on the result `mesh` (hidden attributes, ids.SNAPSHOT_ATTRIBUTES)."""
    n_points, n_faces, n_corners = len(mesh.vertices), len(mesh.polygons), len(mesh.loops)
    _put(mesh, ids.SNAP_POSITION, "FLOAT_VECTOR", "POINT", inp.positions, n_points)
    if positions_only:
        return
    counts = (len(inp.positions), len(inp.offsets) - 1, len(inp.corners))
    _put(mesh, ids.SNAP_COUNT, "INT", "POINT", counts, n_points)
    _put(mesh, ids.SNAP_CORNER, "INT", "CORNER", inp.corners, n_corners)
    _put(mesh, ids.SNAP_FACE_SIZE, "INT", "FACE", np.diff(inp.offsets), n_faces)
    _put(mesh, ids.SNAP_MATERIAL, "INT", "FACE", inp.materials, n_faces)
    if inp.normals is not None:
        _put(mesh, ids.SNAP_NORMAL, "FLOAT_VECTOR", "POINT", inp.normals, n_points)
    elif mesh.attributes.get(ids.SNAP_NORMAL) is not None:
        mesh.attributes.remove(mesh.attributes[ids.SNAP_NORMAL])


def read_snapshot(mesh) -> MeshInput | None:
    """The input stored by :func:`write_snapshot` (None if the mesh has none)."""
    attrs = mesh.attributes
    if any(attrs.get(name) is None for name in ids.SNAPSHOT_ATTRIBUTES if name != ids.SNAP_NORMAL):
        return None
    n_points, n_faces, n_corners = len(mesh.vertices), len(mesh.polygons), len(mesh.loops)
    if n_points < 3:
        return None
    V, F, C = (int(c) for c in _get(attrs[ids.SNAP_COUNT].data, "value", n_points, np.int32)[:3])
    if not (0 <= V <= n_points and 0 <= F <= n_faces and 0 <= C <= n_corners):
        return None
    sizes = _get(attrs[ids.SNAP_FACE_SIZE].data, "value", n_faces, np.int32)[:F]
    offsets = np.zeros(F + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    normals = attrs.get(ids.SNAP_NORMAL)
    return MeshInput(
        positions=_get(attrs[ids.SNAP_POSITION].data, "vector", n_points, np.float32, 3)[:V].copy(),
        offsets=offsets,
        corners=_get(attrs[ids.SNAP_CORNER].data, "value", n_corners, np.int32)[:C].copy(),
        materials=_get(attrs[ids.SNAP_MATERIAL].data, "value", n_faces, np.int32)[:F].copy(),
        normals=None if normals is None else
        _get(normals.data, "vector", n_points, np.float32, 3)[:V].copy())
