"""Blender objects for the figures: triangle meshes with analytic normals, wire tubes, Subsurf."""
from __future__ import annotations

import bpy
import numpy as np


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def polygon_object(name, vertices, faces, material=None):
    """Object from (V,3) vertices and faces (array or list of int sequences)."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(np.asarray(vertices, dtype=np.float64).tolist(), [],
                     [list(map(int, f)) for f in faces])
    mesh.validate(verbose=False)
    obj = link(bpy.data.objects.new(name, mesh))
    if material is not None:
        mesh.materials.append(material)
    return obj


def surface_object(name, points, triangles, normals=None, material=None):
    """Smooth-shaded triangle mesh with custom normals.

    `normals` (P,3) per point, or (T,3,3) per triangle corner (a point shared by
    triangles of different faces may then carry different normals: a crease).
    Cycles shades with exactly these analytic normals, linearly interpolated
    inside each output triangle, which is what the zebra renders must show.
    """
    mesh = bpy.data.meshes.new(name)
    p = np.ascontiguousarray(points, dtype=np.float32)
    t = np.ascontiguousarray(triangles, dtype=np.int32)
    mesh.vertices.add(len(p))
    mesh.vertices.foreach_set("co", p.ravel())
    mesh.loops.add(t.size)
    mesh.loops.foreach_set("vertex_index", t.ravel())
    mesh.polygons.add(len(t))
    mesh.polygons.foreach_set("loop_start", np.arange(0, t.size, 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    mesh.validate(verbose=False)
    mesh.shade_smooth()
    if normals is not None:
        n = np.asarray(normals, dtype=np.float64)
        n = n / np.linalg.norm(n, axis=-1, keepdims=True)
        if n.ndim == 3:
            mesh.normals_split_custom_set(n.reshape(-1, 3).tolist())
        else:
            mesh.normals_split_custom_set_from_vertices(n.tolist())
    obj = link(bpy.data.objects.new(name, mesh))
    if material is not None:
        mesh.materials.append(material)
    return obj


def subsurf_object(name, vertices, faces, levels, material=None):
    """The control mesh with Blender's Subdivision Surface (Catmull-Clark) modifier, smooth shaded."""
    obj = polygon_object(name, vertices, faces, material)
    obj.data.shade_smooth()
    mod = obj.modifiers.new("Subdivision", "SUBSURF")
    mod.subdivision_type = "CATMULL_CLARK"
    mod.levels = mod.render_levels = int(levels)
    return obj


def evaluated_counts(obj):
    """(vertices, triangles) of an object's evaluated (modified) mesh."""
    deps = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(deps)
    mesh = ev.to_mesh()
    mesh.calc_loop_triangles()
    counts = (len(mesh.vertices), len(mesh.loop_triangles))
    ev.to_mesh_clear()
    return counts


def edge_array(faces):
    """Unique undirected edges (E,2), sorted, of faces given as int sequences."""
    e = set()
    for f in faces:
        f = [int(i) for i in f]
        for a, b in zip(f, f[1:] + f[:1]):
            e.add((min(a, b), max(a, b)))
    return np.array(sorted(e), dtype=np.int64)


def wire_object(name, vertices, faces, radius, material=None, sides=8, dot_scale=2.2, dots=None):
    """Control mesh as round tubes of `radius` along its edges plus a small ball per vertex
    (only at the vertices flagged in the boolean array `dots`, when given)."""
    v = np.asarray(vertices, dtype=np.float64)
    e = edge_array(faces)
    used = np.zeros(len(v), dtype=bool)
    used[e.ravel()] = True
    if dots is not None:
        used &= np.asarray(dots, dtype=bool)
    return tube_object(name, v, e, radius, material, sides, balls=v[used], ball_radius=dot_scale * radius)


def tube_object(name, points, segments, radius, material=None, sides=8, balls=None, ball_radius=None):
    """Round tubes of `radius` along segments (S,2) of points (N,3), optional balls at (B,3)."""
    v = np.asarray(points, dtype=np.float64)
    e = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    a, b = v[e[:, 0]], v[e[:, 1]]
    d = b - a
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    # any unit vector orthogonal to each segment, then a second one
    helper = np.where(np.abs(d[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w = np.cross(d, u)
    ang = 2.0 * np.pi * np.arange(sides) / sides
    ring = radius * (np.cos(ang)[None, :, None] * u[:, None] + np.sin(ang)[None, :, None] * w[:, None])
    pts = np.concatenate([a[:, None] + ring, b[:, None] + ring], axis=1)  # (S, 2*sides, 3)
    base = (2 * sides) * np.arange(len(e))[:, None]
    k = np.arange(sides)
    quads = np.stack([k, (k + 1) % sides, sides + (k + 1) % sides, sides + k], 1)  # (sides, 4)
    tube_faces = (base[:, None, :] + quads[None]).reshape(-1, 4)
    tube_pts = pts.reshape(-1, 3)
    all_pts, all_faces = [tube_pts], tube_faces.tolist()
    if balls is not None and len(balls):
        bv, bf = _ball()
        c = np.asarray(balls, dtype=np.float64)
        all_pts.append((c[:, None] + ball_radius * bv[None]).reshape(-1, 3))
        all_faces += (len(tube_pts) + len(bv) * np.arange(len(c))[:, None, None] + bf[None]).reshape(-1, 3).tolist()
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(np.concatenate(all_pts).tolist(), [], all_faces)
    mesh.validate(verbose=False)
    mesh.shade_smooth()
    obj = link(bpy.data.objects.new(name, mesh))
    if material is not None:
        mesh.materials.append(material)
    return obj


def _ball():
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)
    f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                  [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]], dtype=np.int64)
    # one 4-split, projected to the sphere
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    uniq, inv = np.unique(e, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    mid = v[uniq[:, 0]] + v[uniq[:, 1]]
    mid /= np.linalg.norm(mid, axis=1, keepdims=True)
    n, nf = len(v), len(f)
    ab, bc, ca = n + inv[:nf], n + inv[nf:2 * nf], n + inv[2 * nf:]
    a, b, c = f.T
    f = np.concatenate([np.stack([a, ab, ca], 1), np.stack([b, bc, ab], 1),
                        np.stack([c, ca, bc], 1), np.stack([ab, bc, ca], 1)])
    return np.concatenate([v, mid]), f
