"""Many star envelopes at once: built and evaluated in ragged / padded arrays.

:func:`envelope_table` builds the smooth envelopes (:mod:`gerbs_core.gauge.envelope`) of S
stars given as ragged polar vertex lists with array operations over all stars (validation,
the pieces' lines, :func:`gerbs_core.gauge.blend_ragged.build_blend_ragged`); only stars whose
blend cannot be certified (none on the test and benchmark meshes) take the per-star
fallbacks of :class:`~gerbs_core.gauge.envelope.RadialEnvelope`. :class:`EnvelopeTable`
evaluates u~ = 1/rho~ of any envelope at any angle in one vectorized pass and gives the
per-star :class:`RadialEnvelope` objects on demand.
"""
from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..errors import InvalidParameterError, InvalidPointSetError
from .blend_ragged import _segments, build_blend_ragged
from .envelope_spline import pieces_u
from .fallbacks import line_through

__all__ = ["EnvelopeTable", "envelope_table", "polar_pieces", "validate_stars"]

_RTOL = 1e-12        # rounding slack in the certified bounds


def _star_error(S, i, text):
    return text if S == 1 else f"star {i}: {text}"


def validate_stars(theta, radius, ptr, closed) -> None:
    """Raise InvalidPointSetError (naming the first bad star and its vertex indices) unless
    every star is a valid polar polygon: finite, radii > 0, angle steps in (0, pi), closed
    stars repeating their first vertex at the end."""
    S = len(ptr) - 1
    n = np.diff(ptr)
    if np.any(n < 2):
        raise InvalidParameterError("theta", "need at least 2 boundary vertices (K+1 >= 2)")
    few = np.flatnonzero(closed & (n < 3))
    if few.size:
        raise InvalidPointSetError(_star_error(
            S, few[0], "a closed star needs at least 2 edges (K+1 >= 3 vertices)"))
    star, rank = _segments(ptr)

    def fail(bad, text, pad=False):
        i = int(star[bad[0]])
        loc = rank[bad[star[bad] == i]]
        if pad:
            loc = np.unique(np.concatenate([loc, loc + 1]))
        raise InvalidPointSetError(_star_error(S, i, text), loc)

    bad = np.flatnonzero(~(np.isfinite(theta) & np.isfinite(radius)))
    if bad.size:
        fail(bad, "non-finite boundary vertex at indices")
    bad = np.flatnonzero(~(radius > 0))
    if bad.size:
        fail(bad, "boundary vertex radius must be > 0 at indices")
    step = np.flatnonzero(rank < n[star] - 1)          # vertex k -> k+1 within a star
    d = theta[step + 1] - theta[step]
    bad = step[~((d > 0) & (d < math.pi))]
    if bad.size:
        fail(bad, "not star-shaped w.r.t. the centre: each edge must subtend an angle in "
                  "(0, pi); vertex indices", pad=True)
    first, last = ptr[:-1], ptr[1:] - 1
    bad = np.flatnonzero(closed & (np.abs(radius[last] - radius[first]) > 1e-9 * radius[first]))
    if bad.size:
        i = int(bad[0])
        raise InvalidPointSetError(_star_error(
            S, i, "closed star: the last vertex must repeat the first (radius differs)"),
            [0, int(n[i]) - 1])


def polar_pieces(theta, radius, ptr):
    """(normal, dist) (N - S,) of the stars' edges: edge k of a star runs from its vertex k
    to k+1, its line at distance dist from the centre with outward normal angle normal.
    Raises InvalidPointSetError when the centre lies on an edge's line."""
    S = len(ptr) - 1
    star, rank = _segments(ptr)
    i0 = np.flatnonzero(rank < np.diff(ptr)[star] - 1)
    d = theta[i0 + 1] - theta[i0]
    r0, r1 = radius[i0], radius[i0 + 1]
    m_loc, q = line_through(r0, 0.0 * r0, r1 * np.cos(d), r1 * np.sin(d))
    bad = np.flatnonzero(~(q > _RTOL * np.maximum(r0, r1)))
    if bad.size:
        i = int(star[i0[bad[0]]])
        loc = rank[i0[bad]][star[i0[bad]] == i]
        raise InvalidPointSetError(_star_error(
            S, i, "the centre lies on (the line of) a boundary edge; ring indices"),
            np.unique(np.concatenate([loc, loc + 1])))
    return theta[i0] + m_loc, q


class EnvelopeTable:
    """S star envelopes in ragged arrays, padded for vectorized evaluation (immutable).

    Ragged (per star i, ``knot_ptr`` (S+1,)): ``knots``, ``line_m``, ``line_a``, ``line_b``
    (local functions u_j = a_j cos(theta - m_j) + b_j, shrink included). Per star:
    ``closed``, ``span``, ``first`` / ``last`` (the sector's end angles: open envelopes are
    evaluated inside them), ``method``, ``min_ratio``. ``theta``, ``radius``, ``ptr``: the
    stars' polar vertices (for :meth:`envelope`). ``kappa``, ``shrink``, ``exact``,
    ``kernel`` are shared.
    """

    def __init__(self, knot_ptr, knots, line_m, line_a, line_b, closed, theta, radius, ptr,
                 method, min_ratio, kappa, shrink, exact, kernel):
        self.knot_ptr, self.knots = np.asarray(knot_ptr), np.asarray(knots, float)
        self.line_m, self.line_a, self.line_b = (np.asarray(a, float)
                                                 for a in (line_m, line_a, line_b))
        self.closed = np.asarray(closed, dtype=bool)
        self.theta, self.radius, self.ptr = theta, radius, np.asarray(ptr)
        self.first, self.last = theta[self.ptr[:-1]], theta[self.ptr[1:] - 1]
        self.span = self.last - self.first
        self.method, self.min_ratio = np.asarray(method), np.asarray(min_ratio, float)
        self.kappa, self.shrink, self.exact, self.kernel = kappa, shrink, bool(exact), kernel
        S = len(self.knot_ptr) - 1
        self.n_knots = np.diff(self.knot_ptr)
        star, rank = _segments(self.knot_ptr)
        width = int(self.n_knots.max()) if S else 1
        self._pad = {}
        for name in ("knots", "line_m", "line_a", "line_b"):
            arr = np.full((S, width), np.inf if name == "knots" else 0.0)
            arr[star, rank] = getattr(self, name)
            arr.setflags(write=False)
            self._pad[name] = arr
        for a in ("knot_ptr", "knots", "line_m", "line_a", "line_b", "closed", "theta",
                  "radius", "ptr", "first", "last", "span", "method", "min_ratio", "n_knots"):
            getattr(self, a).setflags(write=False)

    def __len__(self) -> int:
        return len(self.knot_ptr) - 1

    def envelope(self, i: int):
        """Envelope i as a :class:`~gerbs_core.gauge.envelope.RadialEnvelope`."""
        from .envelope import RadialEnvelope
        a, b = self.ptr[i], self.ptr[i + 1]
        ka, kb = self.knot_ptr[i], self.knot_ptr[i + 1]
        return RadialEnvelope._adopt(
            self.theta[a:b], self.radius[a:b], bool(self.closed[i]), self.knots[ka:kb],
            self.line_m[ka:kb], self.line_a[ka:kb], self.line_b[ka:kb], str(self.method[i]),
            float(self.min_ratio[i]), self.kappa, self.shrink, self.exact, self.kernel)

    def u_derivs(self, env, theta, nmax=2):
        """u~ and its derivatives (nmax+1, *theta.shape) of envelope ``env[i]`` at
        ``theta[i]`` (env an int array broadcastable to theta): the same numbers as each
        envelope's :meth:`RadialEnvelope.u_derivs`. Closed envelopes are periodic; open
        ones are evaluated at theta clipped to their sector (round-off of the unfolded
        angle must not extrapolate the end lines)."""
        theta = np.asarray(theta, dtype=np.float64)
        env = np.broadcast_to(np.asarray(env, dtype=np.int64), theta.shape).ravel()
        x = self._reduce(env, theta.ravel())
        at = self._interval(env, x)                 # flat index of knot j in the padding
        at1 = at + 1
        pad = self._flat
        out = pieces_u(x, pad["knots"][at], pad["knots"][at1],
                           pad["line_m"][at], pad["line_m"][at1],
                           pad["line_a"][at], pad["line_a"][at1],
                           pad["line_b"][at], pad["line_b"][at1],
                           self.kernel, nmax, self.exact)
        return out.reshape((nmax + 1,) + theta.shape)

    @property
    def _flat(self):
        """The padded (S, width) tables raveled: entry (i, j) at i * width + j."""
        return {k: v.reshape(-1) for k, v in self._pad.items()}

    def _reduce(self, env, x):
        """Angles x (N,) brought into envelope env's domain: closed periodic from its first
        knot, open clipped to the sector (only the branch some star needs is computed)."""
        closed = self.closed[env]
        if closed.all():
            t0 = self._pad["knots"][env, 0]
            return t0 + np.mod(x - t0, self.span[env])
        if not closed.any():
            return np.clip(x, self.first[env], self.last[env])
        t0 = self._pad["knots"][env, 0]
        return np.where(closed, t0 + np.mod(x - t0, self.span[env]),
                        np.clip(x, self.first[env], self.last[env]))

    def _interval(self, env, x):
        """Flat padded index of the knot interval [t_j, t_j+1] holding x (N,) in envelope
        env (N,): j = #(knots <= x) - 1 clipped to [0, n_knots - 2]. The count comes from
        a branchless binary search over the row of ``_search`` (the knots padded with inf
        to 2^L - 1 columns): L gathers instead of a (N, width) compare."""
        table = self._search
        width = table.shape[1]
        flat = table.reshape(-1)
        base = env * width
        count = np.zeros(len(x), dtype=np.int64)
        step = (width + 1) >> 1
        while step:
            count += (flat[base + count + (step - 1)] <= x) * step
            step >>= 1
        j = np.clip(count - 1, 0, self.n_knots[env] - 2)
        return env * self._pad["knots"].shape[1] + j

    @cached_property
    def _search(self):
        kn = self._pad["knots"]
        out = np.full((kn.shape[0], (1 << kn.shape[1].bit_length()) - 1), np.inf)
        out[:, :kn.shape[1]] = kn
        out.setflags(write=False)
        return out


def envelope_table(theta, radius, ptr, closed, kappa=0.8, shrink=0.95, kernel=None,
                   exact=False, fixed=None) -> EnvelopeTable:
    """The envelopes of S stars (star i: polar vertices theta[ptr[i]:ptr[i+1]],
    radius[...]; ``closed`` (S,); ``fixed`` (S, 2) optional: the ``fixed_ends`` of open
    stars), as :class:`~gerbs_core.gauge.envelope.RadialEnvelope` would build each (same
    parameters), in one vectorized pass."""
    from .envelope import RadialEnvelope, _check_unit_interval
    theta = np.asarray(theta, dtype=np.float64)
    radius = np.asarray(radius, dtype=np.float64)
    ptr = np.asarray(ptr, dtype=np.int64)
    closed = np.broadcast_to(np.asarray(closed, dtype=bool), (len(ptr) - 1,))
    kappa = _check_unit_interval("kappa", kappa, closed_right=False)
    shrink = _check_unit_interval("shrink", shrink, closed_right=True)
    from ..kernels.names import as_kernel
    kernel = as_kernel(kernel)
    validate_stars(theta, radius, ptr, closed)
    normal, dist = polar_pieces(theta, radius, ptr)
    S = len(ptr) - 1
    span = theta[ptr[1:] - 1] - theta[ptr[:-1]]
    pptr = ptr - np.arange(S + 1)
    if exact:
        # knots at the vertices, the exact lines (the last one repeated)
        star, rank = _segments(ptr)
        piece = pptr[:-1][star] + np.minimum(rank, np.diff(ptr)[star] - 2)
        m, a = normal[piece], 1.0 / (dist[piece] * shrink)
        return EnvelopeTable(ptr, theta, m, a, np.zeros_like(a), closed, theta, radius, ptr,
                             np.full(S, "exact"), np.full(S, shrink), kappa, shrink, True,
                             kernel)
    rb = build_blend_ragged(theta, normal, dist, ptr, closed, span, kappa, kernel, fixed)
    good = rb.ok & (1.0 / rb.rmin <= 1.0 + 1e-9) & (1.0 / rb.rmax >= kappa * (1.0 - 1e-9))
    method = np.where(good, "blend", "").astype(object)  # the fallbacks' longer names fit
    min_ratio = shrink / rb.rmax
    if good.all():
        kptr, knots, line_m = rb.knot_ptr, rb.knots, rb.line_m
        line_a = rb.line_inv / shrink
        line_b = np.zeros_like(line_a)
    else:
        # stars whose blend is not certified take the per-star fallbacks (rare: slivers);
        # the ragged arrays are then assembled star by star
        fb = {i: RadialEnvelope(theta[ptr[i]:ptr[i + 1]], radius[ptr[i]:ptr[i + 1]],
                                closed=bool(closed[i]), kappa=kappa, shrink=shrink,
                                kernel=kernel,
                                fixed_ends=(False, False) if fixed is None else fixed[i])
              for i in np.flatnonzero(~good).tolist()}
        kp = rb.knot_ptr
        cols = {"knots": [], "line_m": [], "line_a": [], "line_b": []}
        for i in range(S):
            if i in fb:
                env = fb[i]
                method[i], min_ratio[i] = env.method, env.min_ratio
                for k in cols:
                    cols[k].append(getattr(env, k))
                continue
            sl = slice(kp[i], kp[i + 1])
            cols["knots"].append(rb.knots[sl])
            cols["line_m"].append(rb.line_m[sl])
            cols["line_a"].append(rb.line_inv[sl] / shrink)
            cols["line_b"].append(np.zeros(kp[i + 1] - kp[i]))
        kptr = np.concatenate([[0], np.cumsum([len(x) for x in cols["knots"]])])
        knots, line_m, line_a, line_b = (np.concatenate(cols[k]) for k in cols)
    return EnvelopeTable(kptr, knots, line_m, line_a, line_b, closed, theta, radius, ptr,
                         method.astype(str), min_ratio, kappa, shrink, False, kernel)
