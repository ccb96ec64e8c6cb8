"""Radial envelope of a star-shaped polygon and its smooth GERBS lower envelope.

DESIGN sections 4-5 ("Size functions"); paper section 5.1 and eq. (62).

A region star-shaped with respect to its centre (the origin) whose boundary is
made of straight edges has the exact radial function

    rho(theta) = p_k / cos(theta - n_k),   theta in [theta_k, theta_{k+1}],

on piece k (p_k > 0 the distance of the edge's line from the centre, n_k the
direction of its outward normal). rho has kinks at the corner directions, so
eq. (62) with the exact radius gives a size function with kinks along those
rays. :class:`RadialEnvelope` replaces it by a C-infinity lower envelope
rho~ that is a GERBS spline (eq. (3)) in theta, blended in the reciprocal
u = 1/rho:

    u~(theta) = sum_j G_j(theta) u_j(theta),   u_j = a_j cos(theta - m_j) + b_j,

i.e. on the knot interval [t_j, t_{j+1}] (w = (theta - t_j) / (t_{j+1} - t_j))

    u~ = (1 - F(w)) u_j + F(w) u_{j+1}.                                   (*)

(evaluated by :mod:`gerbs_core.gauge.envelope_spline` through the package's one GERBS
spline evaluator).

A local function is a straight line (b = 0, a = 1/q: its gauge |y| u_j is
LINEAR in y) or a constant radius (a = 0). Three certified constructions
(:mod:`gerbs_core.gauge.blend`, :mod:`gerbs_core.gauge.fallbacks`); the first that exists
is kept (``method``):

* ``"blend"`` (default): the edges' own lines, pulled in by c in [kappa, 1],
  blended DIRECTLY across each corner by one GERBS transition as wide as the
  certified bound allows (up to half of each adjacent edge; collinear edges
  merged). Widest transitions: on the test meshes max |U + U''|/U 3.7-12 where
  the fillets gave 4.7-80. Certified by rigorous bounds
  (:func:`~gerbs_core.gauge.blend.closed_form_fit`,
  :func:`~gerbs_core.gauge.blend.blend_check`), not by the argument below;
* ``"fillet"``: exact edge lines, each corner rounded by an inscribed arc
  (knots on the rays of arc points; chords / tangents as local lines);
* ``"constant"``: DESIGN's rule (knots at the corners, bisection while
  min rho / max rho < sqrt(kappa), coefficient = min rho over the two
  intervals beside a knot); the fallback for slivers.

Guarantee of "fillet" and "constant" (proved, and certified numerically at
construction): every local function satisfies kappa * rho <= 1/u_j <= rho on
the knot intervals where it is used (checked where the ratio can be extremal:
the ratio of two line radii is monotone, a constant over p/cos(theta - n) is
extremal only at the ends or at theta = n); (*) is a convex combination, so

    kappa * shrink * rho <= rho~ <= shrink * rho     everywhere.

``min_ratio`` is the certified lower bound of rho~/rho (>= kappa * shrink).
Curvature is not bounded a priori; it is MEASURED (:meth:`curvature_stats`).
"""
from __future__ import annotations

import math

import numpy as np

from .blend_ragged import build_blend
from .envelope_spline import envelope_u, reciprocal_derivs
from .fallbacks import build_constant, build_fillet, interval_ratios
from ..errors import InvalidParameterError, InvalidPointSetError
from ..immutable import ReadOnlyArrays
from ..kernels.base import check_order

__all__ = ["RadialEnvelope"]

TWO_PI = 2.0 * math.pi


def _check_unit_interval(name, value, closed_right):
    v = float(value)
    ok = 0.0 < v < 1.0 or (closed_right and v == 1.0)
    if not (math.isfinite(v) and ok):
        rng = "(0, 1]" if closed_right else "(0, 1)"
        raise InvalidParameterError(name, f"must lie in {rng}, got {value!r}")
    return v


class RadialEnvelope(ReadOnlyArrays):
    """Exact radius rho(theta) of a polygonal star and its smooth lower envelope.

    Parameters
    ----------
    theta : (K+1,) float
        Polar angles of the boundary vertices, strictly increasing, each step
        in (0, pi). Closed star: vertex K is vertex 0 again at
        theta_0 + T (T = total span: 2*pi in the plane; in an unfolded mesh
        vertex chart the sum of the corner angles). Open star (a sector, the
        centre on the domain boundary): the chain from one boundary
        neighbour to the other; in a mesh vertex chart its unfolded span
        theta_K - theta_0 may exceed 2*pi (the chart compresses the angle).
    radius : (K+1,) float
        Distances of the vertices from the centre (> 0). Consecutive
        vertices are joined by straight edges (in the isometric unfolding).
    closed : bool
    kappa : float in (0, 1)
        Guaranteed lower bound rho~ >= kappa * shrink * rho.
    shrink : float in (0, 1]
        rho~ <= shrink * rho (supports compactly inside the open star).
    kernel : Kernel, its name (:func:`~gerbs_core.kernels.as_kernel`) or None (-> ERBS())
        Blending kernel F of the GERBS spline (*).
    exact : bool
        If True, rho~ = shrink * rho exactly (kinked: for tests that must
        detect kinks).
    fixed_ends : (bool, bool)
        Open stars: the first / last line's pull-in scale is fixed
        (:data:`~gerbs_core.gauge.blend.CREASE_SCALE`) instead of adaptive, so
        rho~ on that end ray depends only on its length (crease rays).

    Attributes: ``theta``, ``radius``, ``normal`` (K,), ``dist`` (K,),
    ``span``, ``closed``, ``kappa``, ``shrink``, ``exact``, ``kernel``,
    ``knots`` (n+1,), ``line_m``, ``line_a``, ``line_b`` (n+1,) (local
    functions, shrink included), ``method`` ("blend", "fillet", "constant" or
    "exact"), ``min_ratio`` (certified min of rho~/rho).
    """

    def __init__(self, theta, radius, closed=True, kappa=0.8, shrink=0.95, kernel=None,
                 exact=False, fixed_ends=(False, False)):
        self._setup(theta, radius, closed, kappa, shrink, kernel, exact)
        fixed = (bool(fixed_ends[0]), bool(fixed_ends[1]))
        if self.exact:
            self._finish_exact()
        else:
            self._finish_smooth(build_blend(self.theta, self.normal, self.dist, self.closed,
                                            self.span, self.kappa, self.kernel,
                                            fixed if any(fixed) else None))

    @classmethod
    def _adopt(cls, theta, radius, closed, knots, line_m, line_a, line_b, method, min_ratio,
               kappa, shrink, exact, kernel):
        """An envelope from already built parts (:meth:`EnvelopeTable.envelope`)."""
        from .envelope_table import polar_pieces
        env = cls.__new__(cls)
        env.closed, env.kappa, env.shrink, env.exact, env.kernel = (closed, kappa, shrink,
                                                                    exact, kernel)
        env.theta, env.radius = theta, radius
        env.span = float(theta[-1] - theta[0])
        env.normal, env.dist = polar_pieces(theta, radius, np.array([0, len(theta)]))
        env.knots, env.line_m, env.line_a, env.line_b = knots, line_m, line_a, line_b
        env.method, env.min_ratio, env._curv = method, min_ratio, None
        env._freeze()
        return env

    def _setup(self, theta, radius, closed, kappa, shrink, kernel, exact):
        """Validation and the exact radius's pieces (normal, dist)."""
        theta = np.array(theta, dtype=np.float64).reshape(-1)
        radius = np.array(radius, dtype=np.float64).reshape(-1)
        if theta.shape != radius.shape:
            raise InvalidParameterError(
                "radius", f"shape {radius.shape} does not match theta {theta.shape}")
        self.closed = bool(closed)
        self.kappa = _check_unit_interval("kappa", kappa, closed_right=False)
        self.shrink = _check_unit_interval("shrink", shrink, closed_right=True)
        self.exact = bool(exact)
        from ..kernels.names import as_kernel
        self.kernel = as_kernel(kernel)
        from .envelope_table import polar_pieces, validate_stars
        one = np.array([0, len(theta)])
        validate_stars(theta, radius, one, np.array([self.closed]))
        self.theta, self.radius = theta, radius
        self.theta.setflags(write=False)
        self.radius.setflags(write=False)
        self.span = float(theta[-1] - theta[0])
        # pieces: edge k from vertex k to vertex k+1
        self.normal, self.dist = polar_pieces(theta, radius, one)
        self._curv = None

    def _freeze(self):
        for a in ("knots", "line_m", "line_a", "line_b", "normal", "dist"):
            getattr(self, a).setflags(write=False)

    def _finish_exact(self):
        self.knots = self.theta.copy()
        self.line_m = np.append(self.normal, self.normal[-1])
        self.line_a = 1.0 / (np.append(self.dist, self.dist[-1]) * self.shrink)
        self.line_b = np.zeros_like(self.line_a)
        self.min_ratio = self.shrink
        self.method = "exact"
        self._freeze()

    # ------------------------------------------------------------------ build
    @classmethod
    def from_ring(cls, ring, closed=True, **kwargs):
        """Envelope from boundary vertices (K,2) (or (K+1,2), first repeated) in
        counter-clockwise polar order about the origin.

        Closed: the whole ring (K >= 3). Open: the chain from one boundary
        neighbour to the other (K >= 2 points). Raises InvalidPointSetError
        naming ring indices when the ring is not star-shaped w.r.t. the origin.
        """
        theta, r = _ring_polar(ring, closed)
        return cls(theta, r, closed=closed, **kwargs)

    def _finish_smooth(self, bl):
        """Keep the certified construction ``bl`` of :mod:`.blend` (the widest
        transitions) if it exists, else the better of the fallbacks of
        :mod:`.fallbacks` (smaller max |U + U''| / U, measured on 16 samples per knot
        interval)."""
        if bl is not None:
            kn, m, a, b, rmin, rmax = bl
            if 1.0 / rmin <= 1.0 + 1e-9 and 1.0 / rmax >= self.kappa * (1.0 - 1e-9):
                self.method, self.knots, self.line_m = "blend", kn, m
                self.line_a, self.line_b = a / self.shrink, b / self.shrink
                self.min_ratio = self.shrink / rmax
                self._freeze()
                return
        period = self.span if self.closed else None
        cands = []
        fil = build_fillet(self.theta, self.radius, self.normal, self.dist, self.closed,
                           self.span, self.kappa)
        if fil is not None:
            cands.append(("fillet", fil))
        cands.append(("constant", build_constant(self.theta, self.normal, self.dist,
                                                 self.closed, self.kappa)))
        best = None
        for name, (kn, m, a, b) in cands:
            ratio = interval_ratios(kn, m, a, b, self.theta, self.normal, self.dist, period)
            if np.any(ratio > 1.0 + 1e-9) or np.any(ratio < self.kappa * (1.0 - 1e-9)):
                continue      # not certified: never used
            w = (np.arange(16) + 0.5) / 16
            x = (kn[:-1, None] + np.diff(kn)[:, None] * w).ravel()
            u = envelope_u(x, kn, m, a, b, self.kernel, 2, False)
            score = float(np.max(np.abs(u[0] + u[2]) / u[0]))
            if best is None or score < best[0]:
                best = (score, name, kn, m, a, b, float(ratio.min()))
        if best is None:
            # "constant" is certified by proof; only rounding on a degenerate star fails it
            raise InvalidPointSetError(
                "no certified smooth envelope (kappa * rho <= rho~ <= rho) for this star")
        _, self.method, self.knots, self.line_m, a, b, worst = best
        self.line_a = a / self.shrink
        self.line_b = b / self.shrink
        self.min_ratio = self.shrink * worst
        self._freeze()

    # ------------------------------------------------------------- evaluation
    def _reduce(self, theta, start=None):
        """theta mapped into [start, start + span) (closed; start defaults to
        the first knot, which may lie after theta_0); open: unchanged."""
        theta = np.asarray(theta, dtype=np.float64)
        if self.closed:
            t0 = self.knots[0] if start is None else start
            return t0 + np.mod(theta - t0, self.span)
        return theta

    def _exact_u(self, theta, piece_at=None):
        """1/rho on the piece containing ``piece_at`` (default theta itself)."""
        loc = theta if piece_at is None else piece_at
        k = np.clip(np.searchsorted(self.theta, loc, side="right") - 1, 0, len(self.dist) - 1)
        return np.cos(theta - self.normal[k]) / self.dist[k]

    def exact_radius(self, theta):
        """The exact (kinked) radius rho(theta); nan outside an open sector."""
        x = self._reduce(theta, start=self.theta[0])
        u = self._exact_u(x)
        out = 1.0 / u
        if not self.closed:
            out = np.where((x >= self.theta[0]) & (x <= self.theta[-1]), out, np.nan)
        return out

    def u_derivs(self, theta, nmax=2):
        """u~ = 1/rho~ and its theta-derivatives: array (nmax+1, *theta.shape).

        Exact to rounding (closed-form lines, kernel derivatives). Closed:
        periodic with period ``span``; open: values outside the sector are
        those of the end lines (callers mask them out).
        """
        x = self._reduce(theta)
        return envelope_u(x, self.knots, self.line_m, self.line_a, self.line_b, self.kernel,
                          nmax, self.exact)

    def derivs(self, theta, nmax=2):
        """rho~ and its theta-derivatives (order <= 3): array (nmax+1, *theta.shape)."""
        if not 0 <= int(nmax) <= 3:
            raise InvalidParameterError("nmax", f"must be 0..3, got {nmax!r}")
        return reciprocal_derivs(self.u_derivs(theta, nmax))

    def __call__(self, theta, nu=0):
        """rho~^(nu)(theta), nu = 0..3 (scipy style)."""
        nu = check_order(nu, 3, owner="the envelope")
        return self.derivs(theta, nu)[nu]

    # ------------------------------------------------------------ diagnostics
    def curvature_stats(self, scale=1.0, samples=64):
        """Measured (dense sampling, ``samples`` per knot interval) curvature.

        Returns dict with ``geometric`` = max |curvature| * rho~ of the curve
        r = rho~(phi/scale) in the chart (dimensionless; 1 for a circle, 0
        for a straight edge), ``second`` = max |d^2 rho~/dphi^2| / rho~,
        ``gauge_hessian`` = max |U + U''| / U with U = 1/rho~ (= |y| times the
        norm of the Hessian of g, over g: what psi's Hessian sees; 0 on
        straight edges, 1 for a circle), and
        ``second_exact`` = the same for the exact radius on its pieces (for
        comparison: large on nearly radial edges even though they are
        straight).
        """
        t = self.knots
        w = (np.arange(samples) + 0.5) / samples
        x = (t[:-1, None] + np.diff(t)[:, None] * w[None, :]).ravel()
        u = self.u_derivs(x, 2)
        hess = np.abs(u[0] + u[2] / scale ** 2) / u[0]
        r = reciprocal_derivs(u)
        r0, r1, r2 = r[0], r[1] * (1.0 / scale), r[2] * (1.0 / scale) ** 2
        geo = np.abs(r0 ** 2 + 2 * r1 ** 2 - r0 * r2) / (r0 ** 2 + r1 ** 2) ** 1.5 * r0
        xe = self._reduce(x, start=self.theta[0])
        k = np.clip(np.searchsorted(self.theta, xe, side="right") - 1, 0, len(self.dist) - 1)
        tn = np.tan(xe - self.normal[k])
        sec_exact = np.abs(1 + 2 * tn ** 2) / scale ** 2
        return {"geometric": float(geo.max()), "second": float(np.max(np.abs(r2) / r0)),
                "gauge_hessian": float(hess.max()),
                "second_exact": float(sec_exact.max())}

    @property
    def max_curvature(self):
        """max |curvature| * rho~ of the envelope curve (scale 1), measured."""
        if self._curv is None:
            self._curv = self.curvature_stats()
        return self._curv["geometric"]

    def __repr__(self):
        kind = "closed" if self.closed else "open"
        return (f"RadialEnvelope({kind}, pieces={len(self.dist)}, knots={len(self.knots)}, "
                f"span={self.span:.6g}, exact={self.exact}, min_ratio={self.min_ratio:.4g})")


def _ring_polar(ring, closed):
    """(theta, radius) (K+1,) of boundary vertices (K, 2) about the origin, checked to
    form a star (the rules of :meth:`RadialEnvelope.from_ring`)."""
    ring = np.array(ring, dtype=np.float64)
    if ring.ndim != 2 or ring.shape[1] != 2:
        raise InvalidParameterError("ring", f"expected shape (K, 2), got {ring.shape}")
    nonfinite = np.flatnonzero(~np.isfinite(ring).all(axis=1))
    if nonfinite.size:
        raise InvalidPointSetError("ring has non-finite coordinates at indices", nonfinite)
    if closed and len(ring) >= 2 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    need = 3 if closed else 2
    if len(ring) < need:
        raise InvalidPointSetError(
            f"a {'closed' if closed else 'open'} star needs at least {need} ring "
            f"vertices, got {len(ring)}")
    r = np.hypot(ring[:, 0], ring[:, 1])
    at0 = np.flatnonzero(r <= 0.0)
    if at0.size:
        raise InvalidPointSetError("ring vertices coincide with the centre at indices", at0)
    nxt = np.roll(ring, -1, axis=0) if closed else ring[1:]
    cur = ring if closed else ring[:-1]
    cross = cur[:, 0] * nxt[:, 1] - cur[:, 1] * nxt[:, 0]
    dot = (cur * nxt).sum(axis=1)
    k = np.arange(len(cur))
    j = (k + 1) % len(ring)
    scale = np.hypot(cur[:, 0], cur[:, 1]) * np.hypot(nxt[:, 0], nxt[:, 1])
    on_edge = (np.abs(cross) <= 1e-12 * scale) & (dot < 0)
    if on_edge.any():
        e = np.flatnonzero(on_edge)
        raise InvalidPointSetError(
            "the centre lies on a boundary edge; ring indices",
            np.unique(np.concatenate([k[e], j[e]])))
    nonpos = cross <= 1e-12 * scale
    if nonpos.any():
        e = np.flatnonzero(nonpos)
        raise InvalidPointSetError(
            "ring is not star-shaped w.r.t. the centre (edges seen at a non-positive "
            "angle, i.e. not counter-clockwise); ring indices",
            np.unique(np.concatenate([k[e], j[e]])))
    dth = np.arctan2(cross, dot)
    total = dth.sum()
    if closed and abs(total - TWO_PI) > 1e-9:
        first = int(np.searchsorted(np.cumsum(dth), TWO_PI + 1e-9))
        raise InvalidPointSetError(
            f"ring winds {total / TWO_PI:.3g} times around the centre (not star-shaped); "
            "it overlaps itself from ring index", [min(first, len(ring) - 1)])
    if not closed and total >= TWO_PI:
        raise InvalidPointSetError("open ring spans >= 2*pi around the centre")
    th0 = math.atan2(ring[0, 1], ring[0, 0])
    theta = th0 + np.concatenate([[0.0], np.cumsum(dth)])
    if closed:
        theta[-1] = th0 + TWO_PI
        r = np.append(r, r[0])
    return theta, r
