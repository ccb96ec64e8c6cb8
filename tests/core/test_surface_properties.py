"""Property-based tests (hypothesis) of BlendingSurface on random VALID meshes (issue 7 item 1).

Random meshes: Delaunay patches of random points (square corners kept, or a
random disc-like outline: irregular boundary with hull slivers), jittered
Delaunay grids, quad-dominant jittered grids with random triangle splits and
holes, n-gons (5..9) ringed by quads/triangles, open triangle fans and closed
bipyramids (valence 3..12), the mixed mesh and noisy icospheres / UV spheres;
then a random bend z += b x^2, random z-noise and a random rigid motion.
Random settings: kernel ERBS (alpha, beta, gamma, lam, sigma in the guaranteed
box of docs/robustness.md), LogisticStep, BFBS (integer and real exponents
0..6), boundary keep / straighten, resolution 1..3.

Properties checked on every case:

* tessellate(): points, normals finite, normals unit; S(v) = X_v at every mesh
  vertex (interpolation, to 1e-12 of the mesh size);
* stencil(): finite W, W @ X = tessellated points, W @ 1 = 1 (rows sum to one:
  affine invariance, from sum Psi = 1 and l_v reproducing constants);
* partition(): at random points of random faces Psi_v >= 0, sum Psi_v = 1,
  sum dPsi_v = 0, the unnormalised psi finite and max psi > 0 (covered);
* evaluate() with nu = 1, 2 finite at the same points; eps0 > 0.

Case counts are fixed by ``max_examples`` (and printed with -s): 360 + 120
generated cases here, on top of the 4,000 of test_mesh_validation_properties.
"""
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, event, given, settings
from hypothesis import strategies as st

from gerbs_core import BlendingSurface, InvalidParameterError
from gerbs_core.datasets import primitives
from gerbs_core.kernels import BFBS, ERBS, LogisticStep

SETTINGS = dict(deadline=None, derandomize=True, database=None,
                phases=(Phase.explicit, Phase.reuse, Phase.generate, Phase.shrink),  # no "explain"
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
N_SURFACE_CASES = 360
N_KERNEL_CASES = 120
N_WIDE_CASES = 60

# ERBS parameters drawn from the guaranteed box (docs/robustness.md). Outside it, a
# kernel either works, is refused at construction (untabulable), or -- where
# 1 - F(t) underflows to 0 long before t = 1 -- leaves holes in the cover, which
# BlendingSurface refuses with InvalidParameterError("kernel") (it returned NaN
# points before): test_wide_erbs_parameters_work_or_raise_the_specific_error.
ERBS_BOX = dict(alpha=(0.1, 1.0), beta=(0.01, 10.0), gamma=(0.1, 1.0), sigma=(0.0, 10.0))


# ----------------------------------------------------------------- meshes
def _disc_patch(rng, n):
    """Delaunay triangulation of random points in a random star-shaped outline."""
    t = np.sort(rng.uniform(0, 2 * np.pi, max(5, n // 2)))
    r = rng.uniform(0.6, 1.0, len(t))
    outline = np.stack([r * np.cos(t), r * np.sin(t)], 1)
    inner = rng.uniform(-0.5, 0.5, (n, 2))
    return primitives.delaunay_patch(points=np.concatenate([outline, inner]))


def _closed(rng, kind):
    if kind == "icosphere":
        v, f = primitives.icosphere(1)
    else:
        v, f = primitives.uv_sphere(int(rng.integers(4, 9)), int(rng.integers(3, 6)))
    return v * rng.uniform(0.9, 1.1, (len(v), 1)), f


@st.composite
def valid_meshes(draw):
    """(kind, vertices (V,3), faces): a random valid mesh, bent, noisy and moved."""
    kind = draw(st.sampled_from(["delaunay", "disc", "jittered", "quads", "ngon", "fan",
                                 "bipyramid", "mixed", "icosphere", "uv_sphere"]))
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    if kind == "delaunay":
        v, f = primitives.delaunay_patch(draw(st.integers(5, 24)), seed)
    elif kind == "disc":
        v, f = _disc_patch(rng, draw(st.integers(0, 14)))
    elif kind == "jittered":
        v, f = primitives.jittered_patch(draw(st.integers(3, 5)), seed,
                                         draw(st.floats(0.0, 0.45)))
    elif kind == "quads":
        v, f = primitives.quad_patch(draw(st.integers(1, 5)), draw(st.integers(1, 4)), seed,
                                     split=draw(st.floats(0.0, 1.0)),
                                     jitter=draw(st.floats(0.0, 0.3)),
                                     holes=draw(st.floats(0.0, 1.0)))
    elif kind == "ngon":
        v, f = primitives.ngon_ring(draw(st.integers(5, 9)), seed, draw(st.floats(0.0, 1.0)))
    elif kind in ("fan", "bipyramid"):
        # apex heights away from 0: a bipyramid with both apices at the rim's centre
        # is a doubly covered disc (faces cancel, no normal exists)
        h = draw(st.floats(0.2, 1.0)) * draw(st.sampled_from([-1.0, 1.0]))
        v, f = primitives.fan(draw(st.integers(3, 12)),
                              h if kind == "bipyramid" else draw(st.sampled_from([0.0, h])),
                              closed=kind == "bipyramid")
    elif kind == "mixed":
        v, f = primitives.mixed_mesh(draw(st.floats(-2.0, 2.0)))
    else:
        v, f = _closed(rng, kind)
    v = np.array(v, dtype=np.float64)
    if kind not in ("icosphere", "uv_sphere", "bipyramid"):
        span = np.ptp(v[:, :2], axis=0).max()
        v[:, 2] += draw(st.floats(-1.0, 1.0)) * (v[:, 0] / span) ** 2 * span
    v[:, 2] += rng.normal(0.0, draw(st.sampled_from([0.0, 0.01, 0.05])), len(v)) * np.ptp(v, 0).max()
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # random rigid motion
    v = v @ q.T + rng.uniform(-5, 5, 3)
    event(f"mesh: {kind}")
    return kind, v, f


ERBS_WIDE = dict(alpha=(0.1, 10.0), beta=(0.01, 100.0), gamma=(0.1, 10.0), sigma=(0.0, 10.0))


def erbs_params(box=ERBS_BOX):
    logu = lambda lo, hi: st.floats(np.log(lo), np.log(hi)).map(  # noqa: E731
        lambda x: float(np.round(np.exp(x), 3)))
    return st.tuples(logu(*box["alpha"]), logu(*box["beta"]), logu(*box["gamma"]),
                     st.floats(0.0, 1.0).map(lambda x: round(x, 3)),
                     st.floats(*box["sigma"]).map(lambda x: round(x, 3)))


def erbs_kernels():
    return erbs_params().map(lambda p: ERBS(alpha=p[0], beta=p[1], gamma=p[2], lam=p[3],
                                            sigma=p[4]))


def kernels():
    ints = st.integers(0, 6)
    reals = st.floats(0.0, 6.0).map(lambda x: round(x, 2))
    return st.one_of(erbs_kernels(), st.just(LogisticStep()), st.just(ERBS()),
                     st.builds(BFBS, ints, ints), st.builds(BFBS, reals, reals))


# ---------------------------------------------------------------- checks
def _random_face_points(surface, rng, k):
    """k random points (face ids (k,), local coords (k, 2)) inside random faces:
    Dirichlet-weighted corner combinations (the reference polygons are convex)."""
    topo = surface.topology
    faces = rng.integers(0, topo.n_faces, k)
    x = np.empty((k, 2))
    for i, f in enumerate(faces):
        C = surface.layouts.corners[topo.face_offsets[f]:topo.face_offsets[f + 1]]
        x[i] = rng.dirichlet(np.full(len(C), 0.7)) @ C
    return faces, x


def check_surface(surface, X, resolution, rng):
    diam = float(np.linalg.norm(np.ptp(X, axis=0)))
    P, T, N = surface.tessellate(resolution)
    assert np.all(np.isfinite(P)) and np.all(np.isfinite(N))
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-12)
    assert T.min() >= 0 and T.max() < len(P)
    # interpolation: vertex samples are the first V points
    assert np.abs(P[:len(X)] - X).max() <= 1e-12 * diam
    W = surface.stencil(resolution)
    for M in (W.base, W.mono, W.operator):
        assert np.all(np.isfinite(M.data))
    # round-off only, amplified by the fits' conditioning (the normal matrices are
    # truncated at RCOND = 1e-8 relative, i.e. a design condition of 1e4)
    assert np.abs(W.apply(X) - P).max() <= 1e-10 * (diam + np.abs(X).max())
    assert np.abs(W.apply(np.ones(len(X))) - 1.0).max() <= 1e-10
    faces, x = _random_face_points(surface, rng, 24)
    verts, Psi, psi, dPsi = surface.partition(faces, x, nu=1)
    assert np.all(np.isfinite(Psi)) and np.all(np.isfinite(psi)) and np.all(np.isfinite(dPsi))
    assert Psi.min() >= -1e-15
    assert np.abs(Psi.sum(axis=1) - 1.0).max() <= 1e-12
    assert np.abs(dPsi.sum(axis=1)).max() <= 1e-9 * max(1.0, np.abs(dPsi).max())
    assert np.all(psi.max(axis=1) > 0.0)  # every point is covered
    for nu in (1, 2):
        assert np.all(np.isfinite(surface.evaluate(faces, x, nu=nu)))
    assert surface.eps0 > 0.0


@settings(max_examples=N_SURFACE_CASES, **SETTINGS)
@given(valid_meshes(), kernels(), st.sampled_from(["keep", "straighten"]), st.integers(1, 3),
       st.integers(0, 2**31 - 1))
def test_random_surfaces_interpolate_partition_and_stay_finite(mesh, kernel, boundary,
                                                               resolution, seed):
    kind, X, faces = mesh
    event(f"kernel: {type(kernel).__name__}")
    surface = BlendingSurface(X, faces, kernel=kernel, boundary=boundary)
    check_surface(surface, X, resolution, np.random.default_rng(seed))


@settings(max_examples=N_KERNEL_CASES, **SETTINGS)
@given(erbs_kernels(), st.integers(0, 2**31 - 1))
def test_random_erbs_parameters_on_the_mixed_mesh(kernel, seed):
    """Every ERBS parameter set of the guaranteed box, on the mesh with all face sizes."""
    X, faces = primitives.mixed_mesh(0.7)
    surface = BlendingSurface(X, faces, kernel=kernel)
    check_surface(surface, np.asarray(X, float), 2, np.random.default_rng(seed))


@settings(max_examples=N_WIDE_CASES, **SETTINGS)
@given(erbs_params(ERBS_WIDE), st.integers(0, 2**31 - 1))
def test_wide_erbs_parameters_work_or_raise_the_specific_error(params, seed):
    """Outside the guaranteed box every ERBS parameter set either gives a valid
    surface (all checks) or raises InvalidParameterError naming the parameter
    (untabulable set) or the kernel (holes in the cover) -- never NaN points."""
    X, faces = primitives.mixed_mesh(0.7)
    try:
        kernel = ERBS(*params)
    except InvalidParameterError as e:
        event("refused by ERBS")
        assert e.name in ("alpha", "beta", "gamma", "lam", "sigma")
        return
    try:
        surface = BlendingSurface(X, faces, kernel=kernel)
    except InvalidParameterError as e:  # the fits' energies sample the cover too
        event("holes in the cover: refused at construction")
        assert e.name == "kernel" and "holes in the cover" in str(e)
        return
    if not surface.eps0 > 0.0:
        # holes between the samples of a coarse tessellation: eps0 reports them, and
        # a tessellation that samples them (the check lattice's resolution) refuses
        event("holes in the cover: eps0 = 0, refused where sampled")
        with pytest.raises(InvalidParameterError, match="holes in the cover"):
            surface.tessellate(surface.eps0_resolution)
        return
    try:
        check_surface(surface, np.asarray(X, float), 2, np.random.default_rng(seed))
    except InvalidParameterError as e:
        event("holes in the cover: refused")
        assert e.name == "kernel" and "holes in the cover" in str(e)
        return
    event("valid surface")


def test_a_kernel_leaving_holes_is_refused_not_nan():
    """The reproducer of the former silent-NaN bug: the construction (whose fits sample
    the cover) refuses it."""
    X, faces = primitives.mixed_mesh(0.7)
    with pytest.raises(InvalidParameterError, match="holes in the cover"):
        BlendingSurface(X, faces, kernel=ERBS(gamma=7.389, lam=0.0, sigma=0.0))


def test_the_checks_catch_a_broken_surface():
    """check_surface is not vacuous: a surface whose local function misses its vertex
    (coefficients shifted) fails interpolation."""
    X, faces = primitives.mixed_mesh(0.3)
    surface = BlendingSurface(X, faces)
    broken = surface.with_positions(X)
    broken._cache("_X", broken._X + np.array([0.0, 0.0, 1e-6]))  # l_v(0) != X_v
    try:
        check_surface(broken, X, 2, np.random.default_rng(0))
    except AssertionError:
        return
    raise AssertionError("check_surface accepted a non-interpolating surface")
