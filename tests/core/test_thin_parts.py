"""The thin_part warning (gerbs_core.mesh.thin_parts): a surface bulging far beyond a thin
cage (a board, a coin) says so and what helps; the usual inputs do not warn."""
import numpy as np
import pytest

from gerbs_core import BlendingSurface
from gerbs_core.datasets import primitives as P
from gerbs_core.mesh import thin_parts
from gerbs_core.mesh.thin_parts import thin_part_warning


def _thin(s):
    return [w for w in s.warnings if w.tag == "thin_part"]


@pytest.mark.parametrize("name, scale, axis", [("board", (1.0, 1.0, 0.1), "z"),
                                               ("plank", (2.0, 0.25, 0.1), "z")])
def test_a_scaled_cube_warns_naming_the_axis_and_the_remedy(name, scale, axis):
    V, F = P.cube()
    s = BlendingSurface(V * np.array(scale), F)
    (w,) = _thin(s)
    assert w.indices == () and w.element == "face"
    assert f"extent along {axis}" in w.message and "bevelling the edges" in w.message
    # the figure it names is the surface's: its extent at r = 8 on that axis
    pts = s.tessellate(8)[0]
    k = "xyz".index(axis)
    ratio = float(w.message.split("reaches ")[1].split("x")[0])
    assert ratio == pytest.approx(np.ptp(pts[:, k]) / np.ptp(s.vertices[:, k]), rel=0.1)
    assert ratio > 2.0


def test_the_coin_warns_and_the_usual_inputs_do_not():
    V, F = P.cylinder(depth=0.2)
    assert len(_thin(BlendingSurface(V, F))) == 1
    for V, F in (P.cube(), P.cylinder(), P.cone(), P.suzanne(), P.icosphere(2), P.torus(),
                 P.grid(6, 6)):
        s = BlendingSurface(V, F)
        assert _thin(s) == []
        assert all(w.tag != "thin_part" for w in s.warnings)


def test_thresholds():
    cage = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.2]])
    inside = np.array([[2.0, 0.5, 0.1]])
    assert thin_part_warning(cage, inside) is None
    # 0.41 / 0.2 in z: beyond 2x, and the excess 0.21 is 5% of the largest extent 4
    w = thin_part_warning(cage, [[1.0, 0.5, 0.41]])
    assert w is not None and "2.0x the cage's extent along z" in w.message
    assert thin_part_warning(cage, [[1.0, 0.5, 0.39]]) is None          # 1.95x: below BULGE
    # a wavy sheet: 3x its tiny height, but the excess is 0.2% of its width
    sheet = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 0.004]])
    assert thin_part_warning(sheet, [[1.0, 1.0, 0.012]]) is None
    assert thin_part_warning(sheet, [[1.0, 1.0, 0.25]]) is not None


def test_the_thresholds_are_read(monkeypatch):
    # the control: the Cube's surface is 1.43x its cage, below the bound of 2x
    V, F = P.cube()
    assert _thin(BlendingSurface(V, F)) == []
    monkeypatch.setattr(thin_parts, "BULGE", 1.4)
    (w,) = _thin(BlendingSurface(V, F))
    assert "1.4x the cage's extent" in w.message


def test_with_positions_reads_its_own_surface():
    # W X is affine covariant, so a binding's bulge ratio travels with it: the board's
    # binding on the Cube's positions is the board's surface stretched (3.3x on z still),
    # the Cube's binding on the board's positions the Cube's surface flattened (1.43x)
    V, F = P.cube()
    board, cube = BlendingSurface(V * [1.0, 1.0, 0.1], F), BlendingSurface(V, F)
    assert _thin(cube) == [] and len(_thin(board)) == 1          # cached on each
    (w,) = _thin(board.with_positions(V))
    assert w.message == _thin(board)[0].message
    assert _thin(cube.with_positions(V * [1.0, 1.0, 0.1])) == []
    # not affine: two top corners of the board raised by 2 (a wedge 2.2 tall): the
    # warning names the wedge's own surface (2.1x its height), not the board's (3.3x)
    W = V * [1.0, 1.0, 0.1]
    W[(W[:, 2] > 0) & (W[:, 0] > 0), 2] += 2.0
    wedge = board.with_positions(W)
    (w,) = _thin(wedge)
    ratio = np.ptp(wedge.tessellate(4)[0][:, 2]) / np.ptp(W[:, 2])
    assert 2.0 < ratio < 2.5 and f"{ratio:.1f}x the cage's extent along z" in w.message
    assert "3.3x" in _thin(board)[0].message


def test_samples_are_the_lattice_at_4_or_2(monkeypatch):
    # the faces' centroids alone would miss a bulge peaking elsewhere: the samples are the
    # output lattice at resolution 4 (the add-on's default), at 2 above MAX_POINTS
    V, F = P.suzanne()
    s = BlendingSurface(V, F)
    assert np.array_equal(thin_parts.thin_part_samples(s)[1], s.tessellate(4)[0])
    monkeypatch.setattr(thin_parts, "MAX_POINTS", 1000)
    assert np.array_equal(thin_parts.thin_part_samples(s)[1], s.tessellate(2)[0])


def test_a_small_memory_budget_reads_less_and_never_raises():
    # the check runs when the warnings are read, after the build: it must not turn a
    # surface that builds into an error (a budget too small for r = 4 reads r = 2, one
    # too small for 2 reads nothing)
    V, F = P.cube()
    board = V * [1.0, 1.0, 0.1]
    s = BlendingSurface(board, F, memory_budget=1e6)     # the estimates at small budgets
    need4, need2 = s.memory_estimate(4), s.memory_estimate(2)
    assert need2 < need4 <= 1e6
    mid = BlendingSurface(board, F, memory_budget=0.5 * (need2 + need4))
    assert (mid.memory_estimate(4), mid.memory_estimate(2)) == (need4, need2)
    assert np.array_equal(thin_parts.thin_part_samples(mid)[1], mid.tessellate(2)[0])
    assert len(_thin(mid)) == 1
    tiny = BlendingSurface(board, F, memory_budget=0.5 * need2)
    assert thin_parts.thin_part_samples(tiny)[1].shape == (0, 3)
    assert _thin(tiny) == []
