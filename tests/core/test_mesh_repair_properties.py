"""Property tests (hypothesis) of the mesh repair (issue 14) on random corruptions of
random valid meshes (the generators of test_mesh_validation_properties.py):

* every corruption is either repaired -- a valid MeshTopology, the warning of the
  corruption naming the corrupted index, every remaining face an input face up to the
  documented changes -- or refused with one of the errors for what no surface can come
  from (``empty``, ``bad_shape``, ``index_out_of_range``, ``non_finite``);
* on a smaller sample the whole surface is built: every corner of every face
  interpolated to 1e-12, nothing NaN.
"""
import numpy as np
from hypothesis import event, given, settings
from hypothesis import strategies as st

from gerbs_core.errors import InvalidMeshError
from gerbs_core.mesh import BlendingSurface
from gerbs_core.mesh.repair import repair_mesh

from .test_mesh_validation_properties import (GEOMETRY_CORRUPTIONS, SETTINGS,
                                              TOPOLOGY_CORRUPTIONS, _corrupt, valid_meshes)

REFUSED = {"empty", "bad_shape", "index_out_of_range", "non_finite"}
# the warning each repaired corruption must carry (and the attribute naming the index)
EXPECTED = {
    "non_manifold_edge": ("non_manifold_edge", "indices"),
    "inconsistent_orientation": ("inconsistent_orientation", "indices"),
    "non_manifold_vertex": ("non_manifold_vertex", "indices"),
    "duplicate_face": ("duplicate_face", None),
    "repeated_index": ("repeated_index", "indices"),
    "degenerate_face": (("loose_edge", "degenerate_face"), "indices"),
    "unused_vertex": ("unused_vertex", "indices"),
    "zero_length_edge": ("zero_length_edge", "indices"),
}


def _corrupted(kind, rng, v, faces):
    if kind in GEOMETRY_CORRUPTIONS:
        x = v.copy()
        T = repair_mesh(v, faces).topology
        if kind == "non_finite":
            i = int(rng.integers(len(x)))
            x[i, int(rng.integers(3))] = [np.nan, np.inf, -np.inf][int(rng.integers(3))]
            return x, faces, i
        if kind == "zero_length_edge":
            a, b = T.edges[int(rng.integers(T.n_edges))]
            x[a] = x[b]
            return x, faces, int(min(a, b))
        f = int(rng.integers(T.n_faces))
        c = T.face(f)
        x[c] = x[c[0]] + np.linspace(0.0, 1.0, len(c))[:, None] * rng.normal(size=3)
        return x, faces, f
    v2, bad, nv, index, _ = _corrupt(kind, rng, v, faces)
    if nv > len(v2):  # unused vertices: give them positions
        v2 = np.concatenate([v2, rng.normal(size=(nv - len(v2), 3)) + 7.0])
    return v2[:nv], bad, index


def _check_repaired(r, kind, index, n_input_faces):
    T = r.topology
    assert T.n_vertices == len(r.vertex_map) == len(r.vertices)
    assert np.all(np.diff(r.vertex_map) >= 0)
    assert np.all((r.face_map >= 0) & (r.face_map < n_input_faces))
    tags = {w.tag: w for w in r.warnings}
    want, attr = EXPECTED.get(kind, (None, None))
    if kind == "degenerate_face" and index is not None and kind in GEOMETRY_CORRUPTIONS:
        want = ("zero_area_face", "degenerate_face")
    if want is None:
        return
    want = (want,) if isinstance(want, str) else want
    hit = [tags[t] for t in want if t in tags]
    assert hit, (kind, [w.tag for w in r.warnings])
    if attr is not None and index is not None:
        named = any(index in w.indices for w in hit)
        # a tie (one face of two flipped): flipping either side is the documented rule
        tie = kind == "inconsistent_orientation" and 2 * len(hit[0].indices) == n_input_faces
        assert named or tie, (kind, index, [w.message for w in hit])


@settings(max_examples=700, **SETTINGS)
@given(valid_meshes(), st.sampled_from(TOPOLOGY_CORRUPTIONS + GEOMETRY_CORRUPTIONS),
       st.integers(0, 2**32 - 1))
def test_random_corruptions_are_repaired_or_refused_specifically(mesh, kind, seed):
    v, faces, *_ = mesh
    if kind in GEOMETRY_CORRUPTIONS and not mesh[4]:  # flat meshes only, as in validation
        kind = "zero_length_edge"
    event(f"corruption: {kind}")
    rng = np.random.default_rng(seed)
    x, bad, index = _corrupted(kind, rng, v, faces)
    frozen = x.copy()
    try:
        r = repair_mesh(x, bad)
    except InvalidMeshError as err:
        event(f"refused: {err.problem}")
        assert err.problem in REFUSED, (kind, str(err))
        # or nothing left: every face of a tiny mesh collapsed by the corruption
        assert kind in REFUSED or (err.problem == "empty" and kind in (
            "degenerate_face", "zero_length_edge", "repeated_index") and len(faces) <= 4), \
            (kind, str(err))
        return
    event("repaired")
    assert kind not in ("index_out_of_range", "empty", "bad_shape", "non_finite")
    _check_repaired(r, kind, index, len(bad))
    assert np.array_equal(x, frozen, equal_nan=True)


@settings(max_examples=200, **SETTINGS)
@given(valid_meshes(), st.sampled_from(["non_manifold_edge", "inconsistent_orientation",
                                        "non_manifold_vertex", "duplicate_face",
                                        "repeated_index", "degenerate_face", "unused_vertex"]),
       st.integers(0, 2**32 - 1))
def test_random_corruptions_build_interpolating_surfaces(mesh, kind, seed):
    v, faces, *_ = mesh
    rng = np.random.default_rng(seed)
    x, bad, index = _corrupted(kind, rng, v, faces)
    try:
        s = BlendingSurface(x, bad)
    except InvalidMeshError as err:  # only a mesh left with nothing (a 1-face input)
        assert err.problem == "empty", str(err)
        return
    T = s.topology
    S = s.evaluate(T.corner_face, s.layouts.corners)
    assert np.abs(S - x[s.vertex_map[T.face_vertices]]).max() <= 1e-12
    pts = s.tessellate(2)[0]
    assert np.all(np.isfinite(pts))
    assert np.abs(pts[:T.n_vertices] - x[s.vertex_map]).max() <= 1e-12
