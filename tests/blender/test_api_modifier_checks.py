"""The API acts on the object's own GERBS modifier only, and refuses an Apply that Blender
would make on another input than the surface's (found by an adversarial test of the
add-on: api.remove(obj, bevel) deleted the user's Bevel, set_settings changed another
object's modifier, api.apply with a Subdivision Surface above dropped the surface)."""
import bpy
import pytest

from .helpers import evaluated, make_object, positions

pytestmark = pytest.mark.blender


def _two_objects():
    from blender_addon import api

    a = make_object("icosphere")
    bevel = a.modifiers.new("Bevel", "BEVEL")
    api.add_surface(a, resolution=2)
    b = make_object("icosphere")
    b.location.x = 3.0
    api.add_surface(b, resolution=3)
    return a, bevel, b


def test_another_modifier_or_another_objects_is_refused_and_left_alone(blender):
    from blender_addon import api
    from gerbs_core.errors import GERBSError

    a, bevel, b = _two_objects()
    theirs = api.get_modifier(b)
    for call in (lambda: api.remove(a, bevel), lambda: api.status(a, bevel),
                 lambda: api.get_settings(a, bevel), lambda: api.set_settings(a, bevel, resolution=4),
                 lambda: api.apply(a, bevel), lambda: api.set_settings(a, theirs, resolution=5),
                 lambda: api.remove(a, theirs), lambda: api.apply(a, theirs),
                 lambda: api.status(a, "Bevel")):
        with pytest.raises(api.NoModifierError) as info:
            call()
        assert isinstance(info.value, GERBSError)
    assert "is not a GERBS Blending Surface modifier of" in str(info.value) or "got 'Bevel'" in str(info.value)
    assert [m.name for m in a.modifiers] == ["Bevel", api.get_modifier(a).name]
    assert api.get_settings(b)["resolution"] == 3 and b.modifiers[0] == theirs
    # its own modifier, passed explicitly, works
    api.set_settings(a, api.get_modifier(a), resolution=3)
    assert api.get_settings(a)["resolution"] == 3


def test_apply_below_an_enabled_modifier_is_refused_and_keeps_everything(blender):
    from blender_addon import api

    obj = make_object("icosphere")
    sub = obj.modifiers.new("Sub", "SUBSURF")
    sub.levels = 1
    api.add_surface(obj, resolution=2)
    X = positions(obj.data)
    shown = evaluated(obj)
    assert len(shown) > len(X)
    with pytest.raises(api.OperationError, match=r"apply the modifier\(s\) above it first \('Sub'\)"):
        api.apply(obj)
    assert [m.type for m in obj.modifiers] == ["SUBSURF", "NODES"]
    assert (positions(obj.data) == X).all() and len(evaluated(obj)) == len(shown)
    # with the modifier above off in the viewport the surface is built from the base mesh,
    # and Blender's apply of GERBS is that surface: allowed
    sub.show_viewport = False
    bpy.context.view_layer.update()
    built = evaluated(obj)
    api.apply(obj)
    assert len(obj.data.vertices) == len(built) > len(X)
    assert [m.type for m in obj.modifiers] == ["SUBSURF"]
