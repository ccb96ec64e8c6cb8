"""The bench_shape prototype variants of scripts/shape/proto (docs/design.md cites their
numbers as reproducible) still run against the production code they patch: each builds
Suzanne's surface, which interpolates every vertex. (Two of them broke silently when the
fold penalty gained an argument.)"""
from __future__ import annotations

import importlib
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

VARIANTS = [("immersion", "variant"), ("adaptive_coupling", "variant"),
            ("spread_coupling", "variant"), ("spread_fits", "variant"),
            ("spread_fits", "gated"), ("flip", "off"), ("flip", "flip135"),
            ("ridges", "half"), ("ridges", "line"), ("ridges", "targeted"),
            ("blend_fold", "b1000"), ("grad_tension", "g1"), ("grad_tension", "g1s90"),
            ("grad_tension", "with_ridges"),
            ("chart_angles", "cap135_obtuse"), ("chart_angles", "cap120"),
            ("cover_knobs", "kappa90_shrink97"), ("turned_planes", "t90"),
            ("pinned_planes", "p75"),
            ("sharp_mu", "sp450t70")]


@pytest.fixture(scope="module")
def suzanne():
    from gerbs_core.datasets.obj import read_obj
    V, F = read_obj(ROOT / "examples" / "suzanne.obj")
    return np.asarray(V, dtype=np.float64), F


@pytest.mark.parametrize("module, name", VARIANTS)
def test_prototype_variant_builds_an_interpolating_surface(suzanne, module, name, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    variant = getattr(importlib.import_module(f"shape.proto.{module}"), name)
    V, F = suzanne
    out = variant(V, F, 2, exact=False)
    P = out["points"]
    assert np.all(np.isfinite(P)) and len(out["triangles"])
    # every cage vertex is an output point (the samples at the vertices come first)
    assert np.abs(P[:len(V)] - V).max() < 1e-9


def test_ridge_prototype_is_a_linear_map_that_changes_the_mouth(suzanne, monkeypatch):
    """The ridge candidate (scripts/shape/proto/ridges.py) is chosen at some of Suzanne's
    vertices, and its non-polynomial basis is evaluated alike by the tessellation and the
    stencil: the output stays W X with rows summing to 1, interpolating, linear; and it
    removes the pairs above 90 degrees at the mouth corners (6 without it). Measured on
    the default before the spread stars' coupling weight (FairnessRule(spread_mu=1)), as
    docs/design.md's row; on today's default it leaves 2 of its 4."""
    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    R = importlib.import_module("shape.proto.ridges")
    from gerbs_core import BlendingSurface
    from gerbs_core.testing import dihedral_angles, edge_adjacency
    V, F = suzanne
    from gerbs_core import FairnessRule
    # (as measured: without the fairing of mesh.fairing and the fillet sides' tension of
    # mesh.fillets, which came later)
    rule = FairnessRule(spread_mu=1.0, turn=180.0, fillet=0.0)
    with R.patched():
        s = BlendingSurface(V, F, fairness=rule)
        active = R.OPTS["active"]
        P, T, _ = s.tessellate(4)
        st = s.stencil(4)
        Y = np.random.default_rng(0).normal(size=V.shape)
        PY = s.with_positions(Y).tessellate(4)[0]
        P8, T8, _ = s.tessellate(8)
    assert active is not None and len(active) >= 2
    assert np.abs(st.apply(V) - P).max() < 1e-12
    assert np.abs(st.apply(Y) - PY).max() < 1e-12
    assert np.abs(st.apply(np.ones_like(V)) - 1.0).max() < 1e-12
    assert np.abs(P[:len(V)] - V).max() < 1e-12
    T8 = np.asarray(T8)
    ang = dihedral_angles(P8, T8, edge_adjacency(T8))
    assert (ang > 90).sum() == 0
    # the default at the same resolution still has them (the control)
    D, TD, _ = BlendingSurface(V, F, fairness=rule).tessellate(8)
    TD = np.asarray(TD)
    assert (dihedral_angles(D, TD, edge_adjacency(TD)) > 90).sum() > 0


def test_fold_cover_prototype_leaves_holes(suzanne, monkeypatch):
    """The fold-aware cover's measured outcome (docs/design.md, "Folds"): the corners it
    caps turn at the vertex itself, so the cap reaches the first lattice ring and the
    cover has holes (found by the samples at r = 8)."""
    from gerbs_core.errors import InvalidParameterError
    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    fc = importlib.import_module("shape.proto.fold_cover")
    V, F = suzanne
    with pytest.raises(InvalidParameterError, match="holes"):
        fc.variant(V, F, 8, exact=False)


def test_sharp_mu_prototype_is_the_rule_mu_when_constant(suzanne, monkeypatch):
    """The per-row mu (scripts/shape/proto/sharp_mu.py) through the coupling's ``mu``:
    with one mu everywhere it is that rule's surface without the spread stars' mu (to
    round-off); its sp450t70, promoted on 2026-12-04, is the default's surface
    (FairnessRule.spread_mu 1.5 x 300 above 70 degrees), and sp600t70 differs."""
    import gerbs_core
    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    S = importlib.import_module("shape.proto.sharp_mu")
    from shape import methods
    V, F = suzanne
    # all without the fairing (mesh.fairing), which the prototype predates: its optimisation
    # would carry the round-off of the equal constructions up to ~1e-4
    import gerbs_core.mesh.surface as su
    monkeypatch.setattr(su, "faired", lambda model, *args: (model, None))
    ref = methods.gerbs_samples(V, F, 2, exact=False,
                                fairness=gerbs_core.FairnessRule(mu=450.0, spread_mu=1.0))
    const = S.variant_of(S.patched, mu_smooth=450.0, mu_sharp=450.0)(V, F, 2, exact=False)
    assert np.abs(const["points"] - ref["points"]).max() < 1e-10
    base = methods.gerbs_samples(V, F, 2, exact=False)["points"]
    assert np.abs(S.sp450t70(V, F, 2, exact=False)["points"] - base).max() < 1e-10
    assert np.abs(S.sp600t70(V, F, 2, exact=False)["points"] - base).max() > 1e-4


def test_ngon_fan_prototype_passes_through_the_vertices_and_the_face_points(monkeypatch):
    """scripts/shape/proto/ngon_fan.py (docs/design.md, "Known limits"): a 16-sided
    cylinder's caps fanned about their corners' mean; the surface passes through every
    cage vertex and both face points."""
    from scipy.spatial import cKDTree

    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    fan = importlib.import_module("shape.proto.ngon_fan")
    n = 16
    t = 2 * np.pi * np.arange(n) / n
    ring = np.c_[np.cos(t), np.sin(t)]
    V = np.r_[np.c_[ring, -np.ones(n)], np.c_[ring, np.ones(n)]]
    F = [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    F += [list(range(n))[::-1], list(range(n, 2 * n))]
    V2, F2 = fan.fanned(V, F)
    assert len(V2) == 2 * n + 2 and len(F2) == n + 2 * n
    assert np.allclose(V2[-2:], [[0, 0, -1], [0, 0, 1]])
    P = fan.variant(V, F, 2, exact=False)["points"]
    d, _ = cKDTree(P).query(V2)
    assert d.max() < 1e-12
    assert max(len(f) for f in F2) == 4
