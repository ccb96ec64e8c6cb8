"""What the surface carries (issue 13, item 2), in real bpy, against Subdivision Surface.

UV maps and other face-corner attributes with their seams, vertex attributes and
vertex-group weights through the surface's own linear map, face and edge
attributes, materials live, quads where the input has quads.
"""
import bpy
import numpy as np
import pytest

from .helpers import evaluated, evaluated_faces, positions

pytestmark = pytest.mark.blender


def _final(obj):
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    return obj.evaluated_get(dg).data


def _attr(mesh, name):
    from blender_addon import ids
    attr = mesh.attributes[name]
    prop, width, dtype, _ = ids.CARRIED_TYPES[attr.data_type]
    n = {"POINT": len(mesh.vertices), "EDGE": len(mesh.edges), "FACE": len(mesh.polygons),
         "CORNER": len(mesh.loops)}[attr.domain]
    buf = np.empty(n * width, dtype=dtype)
    attr.data.foreach_get(prop, buf)
    return buf.reshape(n, width)


def _corner_vertices(mesh):
    buf = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", buf)
    return buf


def _monkey(uv_maps=2, seed=0):
    """Blender's Suzanne (with its UV map) and a second UV map with random values at
    every face corner: a seam at every edge."""
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    mesh = obj.data
    rng = np.random.default_rng(seed)
    for k in range(1, uv_maps):
        uv = mesh.uv_layers.new(name=f"Random{k}")
        uv.data.foreach_set("uv", rng.random(2 * len(mesh.loops)).astype(np.float32))
    mesh.update()
    return obj


def _subsurf(obj, levels=2):
    mod = obj.modifiers.new("Subdivision", "SUBSURF")
    mod.levels = mod.render_levels = levels
    mod.uv_smooth = "NONE"  # linear UVs: its corners keep their values too
    return mod


def _face_ids(obj):
    """A custom face attribute: each face's own index (carried to every output face)."""
    attr = obj.data.attributes.new("face_id", "INT", "FACE")
    attr.data.foreach_set("value", np.arange(len(obj.data.polygons), dtype=np.int32))
    obj.data.update()


def test_every_base_face_corner_has_an_output_corner_at_its_position_with_its_uvs(blender):
    """For every UV map: each corner of each input face has an output corner at the
    input vertex's position (to 1e-6) with that corner's UV (to 1e-6), and every output
    corner at a vertex takes the UV of one of that vertex's own corners (seams kept).
    Subdivision Surface (linear UVs) keeps the corner UVs too, not the positions."""
    from blender_addon import api

    obj = _monkey(uv_maps=3)
    X, base = positions(obj.data), obj.data
    base_cv = _corner_vertices(base)
    base_uv = {u.name: _attr(base, u.name) for u in base.uv_layers}
    api.add_surface(obj, resolution=3)
    mesh = _final(obj)
    P, cv = evaluated(obj), _corner_vertices(mesh)
    assert sorted(u.name for u in mesh.uv_layers) == sorted(base_uv)
    V = len(X)
    assert np.abs(P[:V] - X).max() <= 1e-6  # output points at the input vertices
    at_vertex = cv < V
    for name, uv in base_uv.items():
        out = _attr(mesh, name)
        for v in range(0, V, 7):
            want = uv[base_cv == v]
            got = out[at_vertex & (cv == v)]
            assert np.abs(P[cv[at_vertex & (cv == v)]] - X[v]).max() <= 1e-6
            d = np.abs(got[:, None, :] - want[None, :, :]).max(axis=2)
            assert d.min(axis=0).max() <= 1e-6  # every input corner's UV is there
            assert d.min(axis=1).max() <= 1e-6  # and nothing else at the vertex
    # Subdivision Surface on the same mesh: corner UVs kept (positions move inside)
    api.remove(obj)
    _subsurf(obj, 1)
    mesh = _final(obj)
    for name, uv in base_uv.items():
        out = _attr(mesh, name)
        d = np.abs(out[:, None, :] - uv[None, :, :]).max(axis=2)
        assert d.min(axis=0).max() <= 1e-6


def test_uvs_inside_a_face_are_its_corners_blended_by_the_lattice(blender):
    """At resolution 2 the middle of a quad is the mean of its four corner UVs, every
    output UV lies in its input face's range, and a custom face attribute says which
    input face each output face lies in."""
    from blender_addon import api

    obj = _monkey(uv_maps=2)
    _face_ids(obj)
    base = obj.data
    sizes = np.array([p.loop_total for p in base.polygons])
    starts = np.array([p.loop_start for p in base.polygons])
    uv = _attr(base, "Random1")
    api.add_surface(obj, resolution=2)
    mesh = _final(obj)
    face = _attr(mesh, "face_id")[:, 0]
    offsets, corners = evaluated_faces(obj)
    out = _attr(mesh, "Random1")
    for f in range(0, len(sizes), 5):
        own = np.flatnonzero(face == f)
        ucorner = uv[starts[f]:starts[f] + sizes[f]]
        cs = np.concatenate([np.arange(offsets[o], offsets[o + 1]) for o in own])
        lo, hi = ucorner.min(0) - 1e-6, ucorner.max(0) + 1e-6
        assert np.all((out[cs] >= lo) & (out[cs] <= hi))
        if sizes[f] == 4:  # the middle point is in all four output quads of the face
            shared = set(corners[offsets[own[0]]:offsets[own[0] + 1]].tolist())
            for o in own[1:]:
                shared &= set(corners[offsets[o]:offsets[o + 1]].tolist())
            (mid,) = shared
            at = cs[corners[cs] == mid]
            np.testing.assert_allclose(out[at], np.repeat(ucorner.mean(0)[None], len(at), 0),
                                       atol=1e-6)


def test_weights_go_through_the_surface_map_like_the_positions(blender):
    """A vertex group whose weights are an affine function of the positions comes out as
    the same function of the output positions (the surface's own linear map carries
    both, and it reproduces affine functions); weights equal at the vertices.
    Subdivision Surface keeps them at the vertices too, but blends them linearly over
    the cage while its points follow Catmull-Clark (measured: 0.019 off on Suzanne)."""
    from blender_addon import api

    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    X = positions(obj.data)
    a, b = 0.5, np.array([0.2, -0.1, 0.05])
    w = a + X @ b
    assert 0 < w.min() and w.max() < 1
    group = obj.vertex_groups.new(name="Affine")
    for v, wv in enumerate(w):
        group.add([v], float(wv), "REPLACE")
    for modifier in ("gerbs", "subsurf"):
        if modifier == "gerbs":
            api.add_surface(obj, resolution=3)
        else:
            api.remove(obj)
            _subsurf(obj, 2)
        mesh = _final(obj)
        P = positions(mesh)
        got = np.zeros(len(P))
        for vert in mesh.vertices:
            for g in vert.groups:
                if g.group == group.index:
                    got[vert.index] = g.weight
        assert np.abs(got[:len(X)] - w).max() <= 1e-6, modifier  # at the vertices: theirs
        affine = np.abs(got - (a + P @ b)).max()
        if modifier == "gerbs":
            assert affine <= 2e-6
        else:  # Subdivision Surface blends weights linearly over the cage, not with its
            assert affine > 1e-3  # vertex rule: off the affine function of its own points


def test_vertex_group_weights_stay_in_range_and_the_vertex_marks_on_vertices(blender):
    """A 0/1 step vertex group comes out smooth in [0, 1] (clamped), 1 and 0 exactly at
    its vertices; a vertex crease stays on the input vertices only."""
    from blender_addon import api

    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    X = positions(obj.data)
    inside = X[:, 0] > 0.2
    group = obj.vertex_groups.new(name="Step")
    group.add(np.flatnonzero(inside).tolist(), 1.0, "REPLACE")
    crease = obj.data.attributes.new("crease_vert", "FLOAT", "POINT")
    marks = (np.arange(len(X)) % 5 == 0).astype(np.float32)
    crease.data.foreach_set("value", marks)
    api.add_surface(obj, resolution=4)
    mesh = _final(obj)
    V = len(X)
    got = np.zeros(len(mesh.vertices))
    for vert in mesh.vertices:
        for g in vert.groups:
            got[vert.index] = g.weight
    assert np.array_equal(got[:V] == 1.0, inside) and np.all(got[:V][~inside] == 0)
    assert got.min() >= 0 and got.max() <= 1 and 0 < np.mean((got > 0) & (got < 1))
    c = _attr(mesh, "crease_vert")[:, 0]
    assert np.array_equal(c[:V], marks) and np.all(c[V:] == 0)


def test_face_and_edge_attributes_follow_their_faces_and_edges(blender):
    """Material index, flat shading and a custom face value on every output face of
    their input face; a seam and a sharp edge on the r segments of their input edge and
    nowhere inside faces; a corner color equal at the corners."""
    from blender_addon import api

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)
    obj = bpy.context.active_object
    mesh = obj.data
    F, E = len(mesh.polygons), len(mesh.edges)
    _face_ids(obj)
    for name in ("a", "b"):
        mesh.materials.append(bpy.data.materials.new(name))
    mesh.polygons.foreach_set("material_index", (np.arange(F) % 2).astype(np.int32))
    flat = (np.arange(F) % 3 == 0)
    mesh.polygons.foreach_set("use_smooth", ~flat)
    seam = np.zeros(E, dtype=bool)
    seam[::4] = True
    mesh.edges.foreach_set("use_seam", seam)
    ev = np.empty(2 * E, dtype=np.int32)
    mesh.edges.foreach_get("vertices", ev)
    ev = ev.reshape(-1, 2)
    color = mesh.color_attributes.new("Col", "BYTE_COLOR", "CORNER")
    rng = np.random.default_rng(1)
    cols = rng.integers(0, 256, size=(len(mesh.loops), 4)) / 255.0
    color.data.foreach_set("color_srgb", cols.astype(np.float32).ravel())
    mesh.update()
    r = 3
    api.add_surface(obj, resolution=r)
    out = _final(obj)
    face = _attr(out, "face_id")[:, 0]
    got_mat = np.empty(len(out.polygons), dtype=np.int32)
    out.polygons.foreach_get("material_index", got_mat)
    assert np.array_equal(got_mat, face % 2) and np.bincount(face).tolist() == [r * r] * F
    smooth = np.empty(len(out.polygons), dtype=bool)
    out.polygons.foreach_get("use_smooth", smooth)
    assert np.array_equal(~smooth, flat[face])
    # seams: exactly the r segments of each input seam edge (their end points lie on it)
    P = positions(out)
    X = positions(mesh)
    oseam = np.empty(len(out.edges), dtype=bool)
    out.edges.foreach_get("use_seam", oseam)
    oev = np.empty(2 * len(out.edges), dtype=np.int32)
    out.edges.foreach_get("vertices", oev)
    oev = oev.reshape(-1, 2)
    assert oseam.sum() == r * seam.sum()
    V = len(X)
    seam_verts = set(ev[seam].ravel().tolist())
    for a, b in oev[oseam][:40]:
        ends = [p for p in (a, b) if p < V]
        assert all(p in seam_verts for p in ends)
    # the corner color: at the corners exactly (sRGB bytes), in range everywhere
    oc = _attr(out, "Col")
    cv = _corner_vertices(out)
    bcv = _corner_vertices(mesh)
    for v in range(0, V, 3):
        want = cols[bcv == v]
        got = oc[cv == v]
        assert np.abs(got[:, None] - want[None]).max(axis=2).min(axis=0).max() <= 1e-6
    assert out.attributes.active_color_name == "Col"


def test_materials_and_attribute_edits_show_without_a_rebuild(blender):
    """A material added after the modifier, a slot replaced, faces assigned, UVs and
    weights edited: each shows on the surface at the next update, and none rebuilds it."""
    from blender_addon import api, engine

    obj = _monkey(uv_maps=1)
    group = obj.vertex_groups.new(name="G")
    group.add([0, 1, 2], 1.0, "REPLACE")
    api.add_surface(obj, resolution=3)
    mesh = obj.data
    rebuilt = engine.stats["rebuilt"]
    red = bpy.data.materials.new("red")
    mesh.materials.append(red)
    mesh.update()
    assert [m.name for m in _final(obj).materials] == ["red"]
    blue = bpy.data.materials.new("blue")
    mesh.materials.append(blue)
    mesh.polygons[5].material_index = 1
    mesh.update()
    out = _final(obj)
    got = np.empty(len(out.polygons), dtype=np.int32)
    out.polygons.foreach_get("material_index", got)
    assert [m.name for m in out.materials] == ["red", "blue"] and got.sum() == 9
    green = bpy.data.materials.new("green")
    mesh.materials[0] = green
    mesh.update()
    assert [m.name for m in _final(obj).materials] == ["green", "blue"]
    uv = mesh.uv_layers["UVMap"]
    uv.data[0].uv = (0.123, 0.456)
    mesh.update()
    out = _final(obj)
    u = _attr(out, "UVMap")
    assert np.abs(u - np.array([0.123, 0.456])).max(axis=1).min() <= 1e-6
    group.add([3], 0.25, "REPLACE")
    mesh.update()
    out = _final(obj)
    w = [g.weight for g in out.vertices[3].groups]
    assert w and abs(w[0] - 0.25) <= 1e-6
    assert engine.stats["rebuilt"] == rebuilt  # all of it without a rebuild


def test_a_new_uv_map_and_vertex_group_are_carried(blender):
    from blender_addon import api

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)
    obj = bpy.context.active_object
    api.add_surface(obj, resolution=2)
    obj.data.uv_layers.new(name="Later")
    obj.data.update()
    assert "Later" in _final(obj).uv_layers
    obj.vertex_groups.new(name="LaterGroup").add([0], 1.0, "REPLACE")
    obj.data.update()
    out = _final(obj)
    assert [g.group for g in out.vertices[0].groups] == [0]


def test_quads_in_give_quads_out_like_subdivision_surface(blender):
    from blender_addon import api

    bpy.ops.mesh.primitive_grid_add(x_subdivisions=4, y_subdivisions=3)
    obj = bpy.context.active_object
    api.add_surface(obj, resolution=3)
    offsets, _ = evaluated_faces(obj)
    gerbs = np.diff(offsets)
    api.remove(obj)
    _subsurf(obj, 2)
    offsets, _ = evaluated_faces(obj)
    assert set(gerbs.tolist()) == set(np.diff(offsets).tolist()) == {4}
    assert len(gerbs) == 9 * len(obj.data.polygons)


def test_a_repaired_mesh_carries_its_attributes_through_the_repair_maps(blender):
    """An icosphere with a loose vertex in the middle of the numbering (left out: every
    later vertex shifts), one flipped face (reoriented: its corners reversed) and a
    duplicate face early on (dropped: every later face shifts): every
    output face says which input face it lies in (a face attribute), every corner of
    every input face has an output corner at its vertex with its UV, and the vertex
    samples keep their own vertices' weights."""
    from blender_addon import api

    from .helpers import link_object

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)
    ico = bpy.context.active_object
    X0 = positions(ico.data)
    faces = [list(p.vertices) for p in ico.data.polygons]
    bpy.data.objects.remove(ico)
    X = np.insert(X0, 3, [5.0, 5.0, 5.0], axis=0)  # loose vertex 3
    faces = [[v + (v >= 3) for v in f] for f in faces]
    faces[0] = faces[0][::-1]  # flipped
    faces.insert(1, faces[5][1:] + faces[5][:1])  # a duplicate: one of faces 1 and 6 dropped
    obj = link_object("repaired", X, faces)
    mesh = obj.data
    _face_ids(obj)
    uv = mesh.uv_layers.new(name="UV")
    rng = np.random.default_rng(3)
    uvs = rng.random((len(mesh.loops), 2)).astype(np.float32)
    uv.data.foreach_set("uv", uvs.ravel())
    group = obj.vertex_groups.new(name="W")
    w = rng.random(len(X))
    for v in range(len(X)):
        group.add([v], float(w[v]), "REPLACE")
    mesh.update()
    r = 2
    api.add_surface(obj, resolution=r)
    status = api.status(obj)
    assert status["error"] == "" and "unused_vertex" in status["warning"]
    assert "inconsistent_orientation" in status["warning"]
    out = _final(obj)
    P, cv = positions(out), _corner_vertices(out)
    face = _attr(out, "face_id")[:, 0]
    counts = np.bincount(face, minlength=len(faces))
    dropped = np.flatnonzero(counts == 0)
    assert len(dropped) == 1 and dropped[0] in (1, 6) and set(counts[counts > 0]) == {r * r}
    assert "duplicate_face" in status["warning"]
    out_uv = _attr(out, "UV")
    offsets, _ = evaluated_faces(obj)
    owner = np.repeat(face, np.diff(offsets))  # the input face of each output corner
    base_cv = _corner_vertices(mesh)
    starts = [p.loop_start for p in mesh.polygons]
    for f, start in enumerate(starts):
        if f == dropped[0]:
            continue
        for c in range(start, start + 3):
            here = (owner == f) & (np.abs(P[cv] - X[base_cv[c]]).max(axis=1) <= 1e-6)
            assert here.any() and np.abs(out_uv[here] - uvs[c]).max() <= 1e-6
    keep = np.delete(np.arange(len(X)), 3)  # the vertex samples: the used vertices in order
    assert np.abs(P[:len(keep)] - X[keep]).max() <= 1e-6
    got = np.array([out.vertices[i].groups[0].weight for i in range(len(keep))])
    assert np.abs(got - w[keep]).max() <= 1e-6
