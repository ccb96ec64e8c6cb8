"""Property definitions: the scene-level add-on state and the settings as bpy.props.

The surface settings themselves live on each modifier (node group inputs); the
same settings are offered as operator properties (``settings_annotations``) so
``bpy.ops.object.gerbs_add_surface(resolution=3, kernel="LOGISTIC")`` works.
"""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from . import ids


def settings_annotations() -> dict:
    """bpy.props for every setting (menus as enums with upper-case identifiers).

    Ranges are soft (slider) limits only: a value outside them reaches
    ``settings.validate`` and is refused with a message instead of being
    clamped silently."""
    out = {}
    for spec in ids.SETTINGS:
        if spec.items:
            items = [(k.upper(), label, "") for k, label in spec.items.items()]
            out[spec.key] = EnumProperty(name=spec.name, description=spec.description,
                                         items=items, default=spec.default.upper())
        elif spec.socket_type == "NodeSocketFloat":
            out[spec.key] = FloatProperty(name=spec.name, description=spec.description,
                                          default=spec.default, soft_min=spec.min,
                                          soft_max=spec.max)
        elif spec.socket_type == "NodeSocketInt":
            out[spec.key] = IntProperty(name=spec.name, description=spec.description,
                                        default=spec.default, soft_min=spec.min,
                                        soft_max=spec.max)
        else:
            out[spec.key] = BoolProperty(name=spec.name, description=spec.description,
                                         default=spec.default)
    return out


def settings_from(props) -> dict:
    """Settings dict (api keywords) from an operator's properties."""
    out = {}
    for spec in ids.SETTINGS:
        value = getattr(props, spec.key)
        if spec.items:
            value = value.lower()
        elif spec.scale != 1.0:
            value = value * spec.scale  # e.g. the memory budget: MB in the UI, bytes in the api
        out[spec.key] = value
    return out


def _live_update_changed(self, context) -> None:
    """Live Update turned on: tag the scene's GERBS objects, so the next depsgraph update
    syncs the edits made while it was off (only marks work; the handler does it). Found by
    a test of the interactive workflow: turning it on again left the base mesh shown until
    the next edit."""
    if not self.live_update:
        return
    from . import geometry_nodes as gn
    scene = self.id_data  # the scene whose property changed (a script may set another's)
    for obj in (scene.objects if isinstance(scene, bpy.types.Scene) else ()):
        if gn.gerbs_modifiers(obj):
            obj.update_tag()


class GERBS_PG_scene(bpy.types.PropertyGroup):
    """Add-on state stored on the scene."""

    live_update: BoolProperty(
        name="Live Update", default=True, update=_live_update_changed,
        description="Recompute GERBS surfaces whenever the base mesh or settings change; "
                    "off, an edited mesh shows its base mesh until Rebuild or until it is "
                    "turned on again")


CLASSES = (GERBS_PG_scene,)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    setattr(bpy.types.Scene, ids.SCENE_PROP, bpy.props.PointerProperty(type=GERBS_PG_scene))


def unregister() -> None:
    if hasattr(bpy.types.Scene, ids.SCENE_PROP):
        delattr(bpy.types.Scene, ids.SCENE_PROP)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
