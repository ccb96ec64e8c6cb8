"""Smooth star gauge and size function psi = b(g) (DESIGN sections 4-5, eq. (62)).

For a region star-shaped with respect to its centre, with smooth lower
envelope rho~ of its radial function (:class:`~gerbs_core.gauge.envelope.RadialEnvelope`),

    g(y) = |y| / rho~(theta(y)),        psi(y) = b(g(y)) = 1 - F(g(y))  (g < 1),

in chart coordinates y (the centre at the origin). This is eq. (62) with the
exact boundary parametrization Gamma_i replaced by the smooth envelope (DESIGN
section 4 explains why). Chart angles may be scaled (mesh vertex charts,
DESIGN section 5): the chart polar angle of the envelope direction theta is
phi = scale * theta (so theta = phi / scale).

g is positively homogeneous of degree 1, g(y) = r U(phi) with U(phi) =
1/rho~(phi/scale), so (exactly, in polar form)

    grad g = U e_r + U' e_phi,        Hess g = (U + U'') / r  e_phi e_phi^T,

and psi is C-infinity wherever b o g is: away from y = 0 because rho~ and the
kernel are smooth, and at y = 0 because F is flat at 0 (ERBS, LogisticStep),
so every derivative of psi vanishes there (computed as exactly 0 where F'
and F'' underflow).
"""
from __future__ import annotations

import math

import numpy as np

from .envelope import TWO_PI, RadialEnvelope
from .jet import bump_jet, polar_jet, star_gauge_jet
from ..errors import InvalidParameterError
from ..immutable import ReadOnlyArrays
from ..kernels.base import check_order

__all__ = ["StarGauge", "RadialEnvelope"]

_SECTOR_TOL = 1e-10   # angular slack (radians, chart) on the rays of an open sector


def _check_nu(nu):
    return check_order(nu, 2, owner="the gauge")


class StarGauge(ReadOnlyArrays):
    """Gauge g and size function psi = b(g) of one star (eq. (62), DESIGN 4-5).

    Parameters
    ----------
    envelope : RadialEnvelope
    scale : float or None
        Chart angle scale s (phi = s * theta). None -> 2*pi/span for a closed
        envelope (1 in the plane), 1 for an open one. A closed envelope needs
        s * span = 2*pi; an open one s * span < 2*pi.
    kernel : Kernel, its name (:func:`~gerbs_core.kernels.as_kernel`) or None (-> ERBS())
        Kernel of b (the envelope has its own blending kernel).
    center : (2,) array or None
        The centre in the caller's coordinates; evaluation points y are
        taken relative to it (default: the origin).

    Evaluation: ``g(y, nu)`` and ``psi(y, nu)`` for y of shape (..., 2) give
    the value (...), gradient (..., 2) or Hessian (..., 2, 2);
    ``g_derivs`` / ``psi_derivs`` return all three at once. Exact to rounding
    (closed forms + kernel derivatives). Outside an open sector: g = inf,
    psi = 0 (derivatives of g: nan; of psi: 0). At y = centre g is not
    differentiable: its gradient and Hessian are nan there (psi's are 0).
    """

    def __init__(self, envelope, scale=None, kernel=None, center=None):
        if not isinstance(envelope, RadialEnvelope):
            raise InvalidParameterError("envelope", "expected a RadialEnvelope")
        self.envelope = envelope
        span = envelope.span
        if scale is None:
            scale = TWO_PI / span if envelope.closed else 1.0
        scale = float(scale)
        if not (math.isfinite(scale) and scale > 0):
            raise InvalidParameterError("scale", f"must be finite and > 0, got {scale!r}")
        if envelope.closed and abs(scale * span - TWO_PI) > 1e-9 * TWO_PI:
            raise InvalidParameterError(
                "scale", f"a closed star needs scale * span = 2*pi (span = {span!r}, "
                f"so scale = {TWO_PI / span!r}), got {scale!r}")
        if not envelope.closed and scale * span >= TWO_PI:
            raise InvalidParameterError(
                "scale", f"an open sector must span < 2*pi in the chart; scale * span = "
                f"{scale * span!r}")
        self.scale = scale
        from ..kernels.names import as_kernel
        self.kernel = as_kernel(kernel)
        c = np.zeros(2) if center is None else np.array(center, dtype=np.float64).reshape(-1)
        if c.shape != (2,) or not np.isfinite(c).all():
            raise InvalidParameterError("center", f"expected 2 finite numbers, got {center!r}")
        c.setflags(write=False)
        self.center = c

    @classmethod
    def from_polygon(cls, center, ring, closed=True, kappa=0.8, shrink=0.95, kernel=None,
                     exact=False):
        """Gauge of a planar polygon star-shaped w.r.t. ``center``.

        ring : (K,2) boundary vertices counter-clockwise (closed), or the chain
        from one boundary neighbour to the other, counter-clockwise (open: the
        centre lies on the domain boundary). Works in the polygon's
        coordinates (the centre is subtracted on evaluation).
        """
        c = np.array(center, dtype=np.float64).reshape(-1)
        if c.shape != (2,) or not np.isfinite(c).all():
            raise InvalidParameterError("center", f"expected 2 finite numbers, got {center!r}")
        ring = np.asarray(ring, dtype=np.float64)
        env = RadialEnvelope.from_ring(ring - c, closed=closed, kappa=kappa, shrink=shrink,
                                       kernel=kernel, exact=exact)
        return cls(env, scale=1.0, kernel=kernel, center=c)

    @classmethod
    def from_polar(cls, theta, radius, closed=True, scale=None, kappa=0.8, shrink=0.95,
                   kernel=None, exact=False):
        """Gauge of a star given by its boundary vertices in (unscaled) polar form.

        For mesh vertex charts: theta (K+1,) cumulative unfolded angles (closed:
        the last vertex repeats the first at theta_0 + T), radius (K+1,); see
        :class:`RadialEnvelope`. ``scale`` None -> 2*pi/T (closed), 1 (open).
        """
        env = RadialEnvelope(theta, radius, closed=closed, kappa=kappa, shrink=shrink,
                             kernel=kernel, exact=exact)
        return cls(env, scale=scale, kernel=kernel)

    # ------------------------------------------------------------ geometry
    @property
    def min_ratio(self):
        """Certified min of rho~/rho (>= kappa * shrink)."""
        return self.envelope.min_ratio

    @property
    def max_curvature(self):
        """Measured max |curvature| * rho~ of the support boundary in the chart."""
        return self.curvature_stats()["geometric"]

    def curvature_stats(self, samples=64):
        """See :meth:`RadialEnvelope.curvature_stats` (in chart angles)."""
        return self.envelope.curvature_stats(scale=self.scale, samples=samples)

    def _polar(self, y):
        """r, phi (chart), theta (envelope), inside-sector mask for y (..., 2)."""
        y = np.asarray(y, dtype=np.float64)
        if y.shape[-1:] != (2,):
            raise InvalidParameterError("y", f"expected shape (..., 2), got {y.shape}")
        d = y - self.center
        x0, x1 = d[..., 0], d[..., 1]
        r = np.hypot(x0, x1)
        phi = np.arctan2(x1, x0)
        env, s = self.envelope, self.scale
        phi0 = s * env.theta[0]
        if env.closed:
            rel = np.mod(phi - phi0, TWO_PI)
            inside = np.ones(r.shape, bool)
        else:
            width = s * env.span
            half_gap = 0.5 * (TWO_PI - width)
            rel = np.mod(phi - phi0 + half_gap, TWO_PI) - half_gap
            inside = (rel >= -_SECTOR_TOL) & (rel <= width + _SECTOR_TOL)
            rel = np.clip(rel, 0.0, width)
        inside |= r == 0.0          # the centre belongs to every star
        return r, phi, env.theta[0] + rel / s, inside

    def _chart_u(self, theta, nmax):
        """U(phi) = 1/rho~(phi/s) and its phi-derivatives (nmax+1, ...)."""
        u = self.envelope.u_derivs(theta, nmax)
        for i in range(1, nmax + 1):
            u[i] *= self.scale ** (-i)
        return u

    def rho(self, y):
        """rho~ along the ray through y (chart radius of the support boundary)."""
        r, phi, theta, inside = self._polar(y)
        u = self._chart_u(theta, 0)[0]
        return np.where(inside, 1.0 / u, 0.0)

    # ---------------------------------------------------------------- gauge
    def g_derivs(self, y, nmax=2):
        """(g, grad g, Hess g) up to order nmax (a tuple of nmax+1 arrays)."""
        if nmax not in (0, 1, 2):
            raise InvalidParameterError("nmax", f"must be 0, 1 or 2, got {nmax!r}")
        jet, inside, r = self._gauge_jet(y, nmax)
        out = [np.where(inside, jet[0], np.inf)]
        bad = ~inside | (r == 0.0)
        for i in range(1, nmax + 1):
            out.append(np.where(bad.reshape(bad.shape + (1,) * i), np.nan, jet[i]))
        return tuple(out)

    def _gauge_jet(self, y, nmax):
        """The jet of g = r U(phi) (:func:`gerbs_core.gauge.jet.star_gauge_jet`), the
        inside-sector mask and r."""
        r, phi, theta, inside = self._polar(y)
        r_jet, t_jet = polar_jet(np.asarray(y, dtype=np.float64) - self.center, nmax)
        return star_gauge_jet(r_jet, t_jet, self._chart_u(theta, nmax), nmax), inside, r

    def g(self, y, nu=0):
        """g(y) (nu=0), gradient (..., 2) (nu=1) or Hessian (..., 2, 2) (nu=2)."""
        nu = _check_nu(nu)
        return self.g_derivs(y, nu)[nu]

    # ---------------------------------------------------------- size function
    def psi_derivs(self, y, nmax=2):
        """(psi, grad psi, Hess psi) up to order nmax; psi = b(g) (eq. (62)).

        psi = 1 - F(g) for g < 1, 0 for g >= 1 and outside an open sector.
        Derivatives by the chain rule: grad psi = -F'(g) grad g,
        Hess psi = -F''(g) grad g grad g^T - F'(g) Hess g; terms whose kernel
        factor is exactly 0 (beyond the support, or underflow near the
        centre where F is flat) are exactly 0.
        """
        if nmax not in (0, 1, 2):
            raise InvalidParameterError("nmax", f"must be 0, 1 or 2, got {nmax!r}")
        g_jet, inside, r = self._gauge_jet(y, nmax)
        g_jet[0] = np.where(inside, g_jet[0], np.inf)
        jet = bump_jet(self.kernel, g_jet, nmax)
        live = inside & (r > 0.0)      # (beyond g = 1 the bump's derivatives are exactly 0)
        out = [jet[0]]
        for i in range(1, nmax + 1):
            out.append(np.where(live.reshape(live.shape + (1,) * i), jet[i], 0.0))
        return tuple(out)

    def psi(self, y, nu=0):
        """psi(y) (nu=0), gradient (..., 2) (nu=1) or Hessian (..., 2, 2) (nu=2)."""
        nu = _check_nu(nu)
        return self.psi_derivs(y, nu)[nu]

    __call__ = psi

    def support_contains(self, y):
        """True where psi(y) > 0 (y strictly inside the support, g < 1)."""
        r, phi, theta, inside = self._polar(y)
        return inside & (r * self._chart_u(theta, 0)[0] < 1.0)

    def __repr__(self):
        return f"StarGauge({self.envelope!r}, scale={self.scale:.6g}, kernel={self.kernel!r})"

