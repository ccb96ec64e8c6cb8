"""The assembly's face classes (gerbs_core.mesh.face_classes): faces equal in every bit of
their rows' inputs are evaluated once and their rows copied; the stencil must be the same
bit for bit as evaluating every sample in its own face."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.mesh import assembly
from gerbs_core.mesh.assembly import _sorted_corners
from gerbs_core.mesh.face_classes import face_classes
from gerbs_core.mesh.surface import BlendingSurface

MESHES = {
    "quad_grid": lambda: P.grid(8, 8),
    "tri_grid": lambda: P.grid(6, 6, kind="tri"),
    "mixed_bent": lambda: P.mixed_mesh(bend=0.5),       # triangles, quads, n-gons
    "cylinder": lambda: P.cylinder(12),                  # n-gon caps
    "icosphere": lambda: P.icosphere(1),
}


def _stencil(V, F, fraction, monkeypatch, r, **kw):
    monkeypatch.setattr(assembly, "SHARED_FRACTION", fraction)
    return BlendingSurface(V, F, **kw).stencil(r)


def _same(a, b):
    for m, n in ((a.base, b.base), (a.mono, b.mono)):
        assert np.array_equal(m.indptr, n.indptr)
        assert np.array_equal(m.indices, n.indices)
        assert np.array_equal(m.data, n.data)          # bit for bit, not to rounding


@pytest.mark.parametrize("r", [3, 8])
@pytest.mark.parametrize("name", sorted(MESHES))
def test_shared_rows_equal_every_sample_evaluated(name, r, monkeypatch):
    V, F = MESHES[name]()
    _same(_stencil(V, F, -1.0, monkeypatch, r), _stencil(V, F, np.inf, monkeypatch, r))


def test_shared_rows_with_creases(monkeypatch):
    # the crease surface assembles on the cut mesh (vertex copies, their own charts)
    V, F = P.grid(6, 6)
    s = BlendingSurface(V, F)
    T = s.topology
    e = np.asarray(T.edges)[:8]
    kw = dict(creases=(e, np.ones(len(e))))
    _same(_stencil(V, F, -1.0, monkeypatch, 4, **kw), _stencil(V, F, np.inf, monkeypatch, 4, **kw))


def test_a_regular_grid_has_few_classes_and_jitter_makes_every_face_its_own():
    V, F = P.grid(16, 16)
    s = BlendingSurface(V, F)
    lat = s.lattice(4)
    n = sum(len(r) for r in face_classes(s.model, lat, _sorted_corners(s.model.topology)).rep)
    assert n < s.topology.n_faces / 4
    Vj = V + np.random.default_rng(0).uniform(-0.01, 0.01, V.shape) * [1, 1, 0]
    sj = BlendingSurface(Vj, F)
    cj = face_classes(sj.model, sj.lattice(4), _sorted_corners(sj.model.topology))
    assert sum(len(r) for r in cj.rep) == s.topology.n_faces
    # every face of a class has the same bits as its representative
    c = face_classes(s.model, lat, _sorted_corners(s.model.topology))
    fo = s.topology.face_offsets
    for (fk, _, _, n_), cls, rep in zip(lat.size_classes, c.cls, c.rep):
        corners = s.layouts.corners
        assert np.array_equal(corners[fo[fk][:, None] + np.arange(n_)],
                              corners[fo[rep[cls]][:, None] + np.arange(n_)])
