"""A NaN or infinite carried value (a UV, a float attribute) with Live Update on: the sync
refuses it with an error naming the layer and its elements, writes nothing to the user's
mesh, and builds the surface again once the value is finite (blender_addon/finite.py).
Before, the record stored the value, the node group never found it equal, and the base
mesh stayed on screen with the "out of date" warning while the sync counted "updated".

Values are set through ``foreach_set``: Blender's property setters clamp an infinity to
the float32 maximum (``uv.x = inf`` stores 3.4028235e+38)."""
import bpy
import numpy as np
import pytest

from .helpers import evaluated, make_object, warnings

pytestmark = pytest.mark.blender

BAD = 4  # the element given the value


def _uv(mesh):
    """(the UV map's values (C, 2) as stored, a setter of them)."""
    data = mesh.uv_layers.active.data
    buf = np.empty(2 * len(data), dtype=np.float32)
    data.foreach_get("uv", buf)
    return buf.reshape(-1, 2), lambda v: data.foreach_set("uv", v.ravel())


def _attribute(mesh):
    attr = mesh.attributes.get("weight") or mesh.attributes.new("weight", "FLOAT", "POINT")
    buf = np.empty(len(attr.data), dtype=np.float32)
    attr.data.foreach_get("value", buf)
    return buf.reshape(-1, 1), lambda v: attr.data.foreach_set("value", v.ravel())


LAYERS = {"uv": (_uv, "UVMap", "corner"), "attribute": (_attribute, "weight", "vertex")}


def _set(mesh, layer, value):
    values, write = LAYERS[layer][0](mesh)
    values[BAD, 0] = value
    write(values)
    mesh.update()
    return values


@pytest.mark.parametrize("value", [float("nan"), float("inf"), float("-inf")])
@pytest.mark.parametrize("layer", sorted(LAYERS))
def test_a_non_finite_carried_value_is_an_error_naming_the_layer_and_recovers(
        blender, layer, value):
    from blender_addon import api, engine, problems

    bpy.context.scene.gerbs.live_update = True
    obj = make_object("icosphere")
    mod = api.add_surface(obj, resolution=2)
    n_surface, n_base = len(evaluated(obj)), len(obj.data.vertices)
    assert n_surface > n_base
    _set(obj.data, layer, 0.25)  # the layer exists (and is carried) before the bad value
    assert len(evaluated(obj)) == n_surface
    stored = _set(obj.data, layer, value)
    read, _ = LAYERS[layer][0](obj.data)
    assert not np.isfinite(read[BAD, 0])  # a true NaN or infinity, not a clamped one
    assert np.array_equal(read, stored, equal_nan=True)
    before = engine.stats.copy()
    for _ in range(4):
        assert len(evaluated(obj)) == n_base  # the base mesh, with the error
    name, element = LAYERS[layer][1:]
    ((kind, message),) = warnings(obj)
    assert kind == "ERROR" and "out of date" not in message
    assert f'"{name}"' in message and f"{element} indices [{BAD}]" in message
    st = engine.get_state(obj, mod)
    assert st.error == message and engine.stats["error"] > before["error"]
    assert engine.stats["updated"] == before["updated"]
    assert name in problems.headline(st.error, st.problem)
    want = {"vertex": [BAD]} if element == "vertex" else \
        {"face": [next(f.index for f in obj.data.polygons
                       if f.loop_start <= BAD < f.loop_start + f.loop_total)]}
    assert {k: v for k, v in problems.selection(st.problem).items() if v} == want
    read, _ = LAYERS[layer][0](obj.data)
    assert np.array_equal(read, stored, equal_nan=True)  # the user's mesh left as it was
    _set(obj.data, layer, 0.5)  # finite again: the surface comes back
    assert len(evaluated(obj)) == n_surface
    assert warnings(obj) == [] and engine.get_state(obj, mod).error == ""
