"""scripts/bench_edit.py (bench_blender --edit) cleans up after itself: the add-on's
handler put back, the do-nothing node group removed, the object back in Object Mode
without modifiers, also when a round fails; and it imports nothing of bench_blender (a
smoke run, not a timing test)."""
import importlib
import sys

import bpy
import pytest

from .helpers import ROOT, make_object

pytestmark = pytest.mark.blender


@pytest.fixture
def bench_edit(blender, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    for name in ("bench_edit", "bench_blender"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    module = importlib.import_module("bench_edit")
    assert "bench_blender" not in sys.modules  # no import cycle
    return module


def _clean(obj):
    from blender_addon import handlers

    assert handlers.on_depsgraph_update in bpy.app.handlers.depsgraph_update_post
    assert not any(group.name.startswith("bench do-nothing") for group in bpy.data.node_groups)
    assert obj.mode == "OBJECT" and len(obj.modifiers) == 0


def test_edit_mode_runs_side_by_side_and_cleans_up(bench_edit, capsys):
    obj = make_object("icosphere")
    rows = bench_edit.edit_mode(bpy, obj, 1)
    assert len(rows) == 3 * 4 and all(len(r) == 7 for r in rows.values())  # 7 rounds
    assert "one-vertex move" in capsys.readouterr().out
    _clean(obj)


def test_edit_mode_cleans_up_when_a_round_fails(bench_edit, monkeypatch):
    obj = make_object("icosphere")

    def fail(bpy_, obj_, mods, rounds):
        with bench_edit.HandlerClock(bpy_):
            raise RuntimeError("a failed round")

    monkeypatch.setattr(bench_edit, "_rounds", fail)
    with pytest.raises(RuntimeError, match="a failed round"):
        bench_edit.edit_mode(bpy, obj, 1)
    _clean(obj)
