"""Scripting API settings: menu values in either case, bad values named."""
import pytest

from .helpers import make_object

pytestmark = pytest.mark.blender


def test_menu_settings_accept_operator_spelling(blender):
    from blender_addon import api

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=2, kernel="LOGISTIC", mode="Regular", boundary="keep")
    settings = api.get_settings(obj)
    assert settings["kernel"] == "logistic"
    assert settings["mode"] == "regular"


def test_unknown_menu_value_is_named(blender):
    from blender_addon import api

    obj = make_object("icosphere")
    with pytest.raises(ValueError, match=r"kernel: expected one of .*'erbs'.*got 'gaussian'"):
        api.add_surface(obj, resolution=2, kernel="gaussian")
    assert api.get_modifier(obj) is None  # nothing half-added is left behind
