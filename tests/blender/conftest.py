"""Fixtures for the Blender tests: real bpy (background), add-on registered per test.

Every test starts from ``read_factory_settings(use_empty=True)`` with the
add-on registered and ends unregistered on an empty factory scene, so the
Blender state left behind for other tests (including tests/core in the same
pytest process) is clean.
"""
from __future__ import annotations

import pytest

import bpy  # noqa: E402  (real bpy 5.0.1; a missing bpy must fail, not skip)


@pytest.fixture
def blender():
    import blender_addon
    from blender_addon import engine

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.edit.undo_steps = 32
    blender_addon.register()
    try:
        yield bpy
    finally:
        blender_addon.unregister()
        bpy.ops.wm.read_factory_settings(use_empty=True)
        engine.clear_caches()
