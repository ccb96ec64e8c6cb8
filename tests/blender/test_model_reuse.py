"""A build reuses the surface's model when, and only when, the BlendingSurface arguments
are exactly those of a surface the modifier still holds (its viewport or render state):
a Resolution change or a final render at Render Resolution makes only the output at the
new resolution (``surface.stencil(r)``), bit for bit what a fresh build gives; any other
change (positions, faces, kernel and its parameters, boundary, merge, memory budget,
creases, normals, rest shape, a Rebuild) constructs a new surface (blender_addon/build.py,
engine._held_models).

Reuse is seen by identity of the held model (``engine.get_state(...).model``) and by
``build.counts`` (surfaces constructed / reused), never by timing."""
import bmesh
import bpy
import numpy as np
import pytest

from .helpers import evaluated, final_render, make_object, modifier_input, topology

pytestmark = pytest.mark.blender


def _state(obj, render=False):
    from blender_addon import api, engine

    return engine.get_state(obj, api.get_modifier(obj), render)


def _counts():
    from blender_addon import build

    return build.counts["built"], build.counts["reused"]


def _core_points(obj, X, resolution, **kw):
    """The core's own fresh build (no add-on code): the points at `resolution` of the
    surface of positions X (float64 of what the modifier receives) and obj's faces."""
    from gerbs_core.mesh.surface import BlendingSurface
    from blender_addon.mesh_io import faces_from_csr

    offsets, corners = topology(obj.data)
    surface = BlendingSurface(X, faces_from_csr(offsets, corners), **kw)
    if kw.get("normals") is not None:
        return surface.tessellate(resolution)[0]
    return surface.stencil(resolution).apply(X)


def _monkey():
    bpy.ops.mesh.primitive_monkey_add()
    return bpy.context.active_object


# --- same arguments: reused ----------------------------------------------------------

def test_a_resolution_change_reuses_the_model_and_gives_a_fresh_builds_surface(blender):
    """Suzanne, Resolution 3 -> 4 -> 3: one surface constructed; each output is bit for bit
    the core's fresh build at that resolution, and what a Rebuild (a new surface) gives."""
    from blender_addon import api

    obj = _monkey()
    api.add_surface(obj, resolution=3)
    X = modifier_input(obj)
    P3 = evaluated(obj)
    model = _state(obj).model
    first = api.status(obj)
    assert not first["surface_held"] and first["surface_seconds"] <= first["build_seconds"]
    built, reused = _counts()
    api.set_settings(obj, resolution=4)
    P4 = evaluated(obj)
    st = _state(obj)
    assert st.model is model and _counts() == (built, reused + 1)
    # the status says the surface was held, with its own build's time (a modelling
    # session read build_seconds after a resolution change as the surface's)
    held = api.status(obj)
    assert held["surface_held"] and held["surface_seconds"] == first["surface_seconds"]
    assert st.n_points == len(P4) != len(P3)
    assert np.array_equal(st.points, _core_points(obj, X, 4))  # float64, bit for bit
    assert np.array_equal(P4, st.points.astype(np.float32))
    api.set_settings(obj, resolution=3)
    assert np.array_equal(evaluated(obj), P3) and _state(obj).model is model
    assert _counts() == (built, reused + 2)
    api.update(obj, force=True)  # Rebuild: constructs the surface anew, the same points
    assert _state(obj).model is not model and _counts() == (built + 1, reused + 2)
    assert np.array_equal(evaluated(obj), P3)


@pytest.mark.parametrize("rest", ["follow", "bound"])
def test_a_final_render_reuses_the_viewport_model(blender, rest):
    """Render Resolution 3 beside Resolution 2: the render builds only its output on the
    viewport's surface, and renders exactly the core's fresh surface at 3; a render after a
    Render Resolution change reuses it too. A Bound surface gives its rest shape from the
    first build on, so its arguments are the same as well."""
    from blender_addon import api

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=2, render_resolution=3, rest=rest)
    X = modifier_input(obj)
    P2 = evaluated(obj)
    model = _state(obj).model
    built, reused = _counts()
    seen = final_render()[obj.name]
    assert _state(obj, render=True).model is model and _counts() == (built, reused + 1)
    assert np.array_equal(seen, _core_points(obj, X, 3).astype(np.float32))
    assert len(seen) != len(P2) and np.array_equal(evaluated(obj), P2)  # viewport kept
    api.set_settings(obj, render_resolution=4)
    seen = final_render()[obj.name]
    assert _state(obj, render=True).model is model and _counts() == (built, reused + 2)
    assert np.array_equal(seen, _core_points(obj, X, 4).astype(np.float32))
    api.set_settings(obj, resolution=4)  # the viewport: the surface the render holds
    assert np.array_equal(evaluated(obj), seen) and _state(obj).model is model
    assert _counts() == (built, reused + 3)


def test_a_resolution_change_with_custom_normals_reuses_the_model(blender):
    """Hermite normals (tessellate, no stencil): the same surface at another resolution."""
    from blender_addon import api

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=2, use_normals=True)
    model = _state(obj).model
    built, reused = _counts()
    api.set_settings(obj, resolution=3)
    P = evaluated(obj)
    assert _state(obj).model is model and _counts() == (built, reused + 1)
    N = _state(obj).input.normals.astype(np.float64)
    assert np.array_equal(P, _core_points(obj, modifier_input(obj), 3, normals=N)
                          .astype(np.float32))


def test_a_failed_output_keeps_its_surface_for_the_next_resolution(blender):
    """A resolution over the memory budget is refused after the surface was constructed;
    going back to one that fits reuses that surface."""
    from blender_addon import api

    obj = make_object("mixed")
    api.add_surface(obj, resolution=3, memory_budget=1e6)
    P3 = evaluated(obj)
    model = _state(obj).model
    built, reused = _counts()
    api.set_settings(obj, resolution=4)
    evaluated(obj)
    assert "too large" in api.status(obj)["error"].lower()
    api.set_settings(obj, resolution=3)
    assert np.array_equal(evaluated(obj), P3) and api.status(obj)["error"] == ""
    assert _state(obj).model is model and _counts() == (built, reused + 2)


# --- any other argument: a new surface -----------------------------------------------

def _move_a_vertex(obj):
    obj.data.vertices[4].co.z += 0.1
    obj.data.update()


def _split_a_quad(obj):
    """New faces, the same vertices: a quad cut along its diagonal."""
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    quad = next(f for f in bm.faces if len(f.verts) == 4)
    bmesh.ops.connect_verts(bm, verts=[quad.verts[0], quad.verts[2]])
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


def _crease(obj):
    me = obj.data
    attr = me.attributes.get("crease_edge") or me.attributes.new("crease_edge", "FLOAT", "EDGE")
    attr.data.foreach_set("value", np.full(len(me.edges), 0.5, np.float32))
    me.update()


def _vertex_crease(obj):
    me = obj.data
    attr = me.attributes.get("crease_vert") or me.attributes.new("crease_vert", "FLOAT", "POINT")
    values = np.zeros(len(me.vertices), np.float32)
    values[4] = 1.0
    attr.data.foreach_set("value", values)
    me.update()


def _settings(**changes):
    def change(obj):
        from blender_addon import api

        api.set_settings(obj, **changes)
    return change


def _rebuild(obj):
    from blender_addon import api

    api.update(obj, force=True)


# (settings the surface starts with, the change, whether the change moves the surface);
# the core's mixed mesh (triangles, quads, n-gons, a border), flat: normals on a sphere
CHANGES = {
    "moved vertex (Follow)": ({}, _move_a_vertex, True),
    "faces": ({}, _split_a_quad, True),
    "kernel parameter": ({}, _settings(alpha=0.5), True),
    "kernel": ({}, _settings(kernel="logistic"), True),
    "BFBS exponent": ({"kernel": "bfbs"}, _settings(bfbs_left=3), True),
    "boundary": ({}, _settings(boundary="straighten"), True),
    "merge on": ({}, _settings(merge=True), False),
    "merge distance": ({"merge": True}, _settings(merge_distance=0.001), False),
    "memory budget": ({}, _settings(memory_budget=5e8), False),
    "crease": ({}, _crease, True),
    "vertex crease": ({"kind": "icosphere"}, _vertex_crease, True),
    "normals on": ({"kind": "icosphere"}, _settings(use_normals=True), True),
    "normals off": ({"kind": "icosphere", "use_normals": True}, _settings(use_normals=False),
                    True),
    "rest bound": ({}, _settings(rest="bound"), False),
    "rebuild": ({}, _rebuild, False),
}


@pytest.mark.parametrize("change", list(CHANGES))
def test_a_change_of_an_argument_constructs_a_new_surface(blender, change):
    """Each change of what the surface is constructed from (or a Rebuild) builds anew, at
    the same resolution, and shows what a Rebuild then gives; the surface held before is
    neither kept nor shown."""
    from blender_addon import api

    start, act, moves = CHANGES[change]
    start = dict(start)
    obj = make_object(start.pop("kind", "mixed"))
    api.add_surface(obj, resolution=3, **start)
    P = evaluated(obj)
    model = _state(obj).model
    built, reused = _counts()
    act(obj)
    Q = evaluated(obj)
    assert api.status(obj)["error"] == ""
    assert _state(obj).model is not model and _counts() == (built + 1, reused)
    assert moves == (Q.shape != P.shape or not np.array_equal(Q, P))
    api.update(obj, force=True)  # a Rebuild: the same surface
    assert np.array_equal(evaluated(obj), Q)


def test_a_smaller_memory_budget_is_not_answered_by_the_held_surface(blender):
    """A memory budget the output exceeds is refused even though the surface held (under
    the larger budget) could make it."""
    from blender_addon import api

    obj = make_object("mixed")
    api.add_surface(obj, resolution=4)
    model = _state(obj).model
    api.set_settings(obj, memory_budget=1e6)
    evaluated(obj)
    assert "too large" in api.status(obj)["error"].lower()
    assert _state(obj).model is not model


def test_a_bound_surface_moved_then_at_another_resolution_is_built_anew(blender):
    """Rest Shape Bound, a vertex moved (the linear update), then Resolution 3 -> 4: the
    positions differ from those of the held surface, so it is constructed anew; the points
    are the core's surface of the moved positions bound to the rest shape."""
    from blender_addon import api

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=3, rest="bound")
    R = modifier_input(obj)
    model = _state(obj).model
    _move_a_vertex(obj)
    evaluated(obj)
    assert _state(obj).model is model  # the linear update keeps the state's surface
    built, reused = _counts()
    api.set_settings(obj, resolution=4)
    P = evaluated(obj)
    assert _state(obj).model is not model and _counts() == (built + 1, reused)
    X = modifier_input(obj)
    assert np.array_equal(P, _core_points(obj, X, 4, rest_positions=R).astype(np.float32))


# --- the key ---------------------------------------------------------------------------

def _altered(name, value):
    """`value` changed a little (another value of the same kind), for argument `name`."""
    if name == "kernel":
        from gerbs_core.kernels import ERBS
        return ERBS(alpha=0.75)
    if name == "faces":  # the first face's corners reversed
        first = np.asarray(value[0])[::-1].copy()
        return [first] + list(value[1:]) if isinstance(value, list) else \
            np.concatenate([first[None], value[1:]])
    if name in ("normals", "rest_positions") and value is None:
        return np.zeros((35, 3))
    if isinstance(value, np.ndarray):
        out = value.copy()
        out.flat[-1] += 1
        return out
    if isinstance(value, str):
        return "straighten" if value == "keep" else "keep"
    if value is None:
        return 0.001
    if isinstance(value, tuple):
        return (value[0], value[1] * 0.5)
    return value * 0.5


def test_the_key_covers_every_constructor_argument(blender):
    """The key is a digest of exactly the keyword arguments the surface is constructed
    with: a change of any one (including its dtype, or None for an array) gives another
    key, and make_model then constructs a new surface, which differs where the argument
    shapes it (a rest shape other than the positions, with the positions equal)."""
    import inspect

    from blender_addon import build
    from blender_addon import creases as creases_mod
    from blender_addon.mesh_io import MeshInput
    from gerbs_core.mesh.surface import BlendingSurface

    obj = make_object("mixed")
    from blender_addon import api
    api.add_surface(obj, resolution=2, use_normals=True)
    st = _state(obj)
    settings = api.get_settings(obj)
    inp = st.input
    pairs = np.array([[0, 1]], np.int32)
    crz = creases_mod.Creases(pairs, np.array([0.5], np.float32), np.zeros(35, np.float32))
    arguments = build.surface_arguments(settings, inp, crz, rest=None)
    accepted = inspect.signature(BlendingSurface).parameters
    assert set(arguments) <= set(accepted)
    assert {"vertices", "faces", "kernel", "normals", "rest_positions", "boundary",
            "memory_budget", "merge_distance", "creases", "corners"} == set(arguments)
    key = build.model_key(arguments)
    assert key == build.model_key(build.surface_arguments(settings, inp, crz, rest=None))
    for name, value in arguments.items():
        other = build.model_key({**arguments, name: _altered(name, value)})
        assert other is not None and other != key, name
    # the same values in another dtype, and an array against None
    X = arguments["vertices"]
    assert build.model_key({**arguments, "vertices": X.astype(np.float32)}) != key
    assert build.model_key({**arguments, "rest_positions": X}) != key
    # a rest shape other than the positions: not reused, and another surface
    plain = build.surface_arguments(settings, MeshInput(inp.positions, inp.offsets,
                                                        inp.corners, inp.materials))
    held = build.make_model(plain)
    bent = {**plain, "rest_positions": X * np.array([1.3, 1.0, 1.0])}
    fresh = build.make_model(bent, held=(held,))
    assert fresh is not held
    assert not np.array_equal(build.evaluate(fresh, bent, 2, lambda *a: None).points,
                              build.evaluate(held, plain, 2, lambda *a: None).points)
    assert build.make_model(dict(plain), held=(held,)) is held
