"""Scattered-point Hermite interpolation by GERBS: f(x) = sum_i B_i(x) T_i(x).

B_i is a GERBS partition of unity over a cover (paper sections 2.4, 5), T_i the
Taylor polynomial of the data at x_i (section 2.6, item 1); see
:class:`GERBSInterpolator`.
"""
from __future__ import annotations

import contextlib

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InvalidParameterError
from ..immutable import Immutable
from ..inputs import integer
from ..kernels.base import check_order
from ..kernels.names import as_kernel
from . import budget as _budget
from . import covers as _covers
from .balls import BallCover
from .candidates import StarCandidates, delaunay_candidates
from .hermite_data import hermite_data
from .local_sums import interpolant_sum
from .metric_forms import as_metric
from .metrics import Euclidean
from .partition import disjoint_basis, general_basis, minimal_basis
from .radii import MARGIN, check_points, nearest_distances
from .star_nd import DelaunayStarCover
from .taylor import averaged_taylor, coefficient_tables, estimate_derivatives

__all__ = ["GERBSInterpolator"]


class GERBSInterpolator(Immutable):
    """Smooth Hermite interpolant of scattered data in R^n (scipy style).

    Parameters
    ----------
    points : (N, n) scattered points, distinct and finite, of extent (the longest side
        of their bounding box) in [1e-100, 1e100] (:data:`~.radii.EXTENT_RANGE`;
        narrower, [10^(-280/p), 10^(280/p)], for l_p metrics with p > 2.8), anywhere
        (the Delaunay triangulation is computed on centred coordinates,
        :mod:`~gerbs_core.scattered.triangulation`); else InvalidPointSetError.
    values : (N, ...) data values, any trailing shape.
    gradients : (N, ..., n), optional. Hessians : (N, ..., n, n), optional; a Hessian
        that is not symmetric is replaced by its symmetric part (H + H^T) / 2 (all
        that the Taylor polynomial sees of it).
        Derivatives not given (up to ``degree``) are estimated by local weighted
        least squares (see :mod:`gerbs_core.scattered.taylor`): a polynomial of degree
        ``fit_degree`` (default ``min(degree + 1, 3)``) through f(x_i) fitted to
        the ~1.8 M + 2 nearest neighbours (M unknown coefficients), weights
        (1 - (r/1.2 h)^2)^2.
    cover : "delaunay" (default for n >= 2), "voronoi" (n = 2), "balls" (default for
        n = 1) or a list of N polygons (K_i, 2), each counter-clockwise and
        star-shaped w.r.t. its point (n = 2).
        * "delaunay": star-1 neighbourhoods of the Delaunay vertices with a smooth
          star gauge (DESIGN 4; in n >= 3 the gauge on S^(n-1) of
          :mod:`gerbs_core.scattered.star_nd`); domain = convex hull of the points.
          Values are accurate in every n, but in n >= 3 the certified gauge has steep
          transitions near sliver simplices, so second (and in R^4 first) derivatives
          are far off at a small fraction of points: 800 random points in R^3, f =
          sin(2 x_0) exp(sum x / 2) (|Hessian| <= 11), 20000 queries in the middle
          half: max |Hessian error| 2.4e3 with "delaunay" against 0.78 with "balls"
          (99 % quantile 6.9 against 0.16; with exact gradients and Hessians as data
          667 against 0.67). For derivatives in n >= 3, cover="balls" is the better
          choice.
        * "voronoi": Voronoi cells clipped to ``domain`` (convex polygon; default the
          bounding box enlarged by 5 %), enlarged 2x about their sites; domain = ``domain``.
        * "balls": the general construction, psi_i = b(d(x, x_i)/R_i),
          phi_i = b(d(x, x_i)/rho_i) (39) in ``metric``; radii from the local point
          spacing with a certified cover of the hull (:mod:`gerbs_core.scattered.radii`)
          unless given; domain = union of the supports (contains the convex hull).
    basis : "minimal" (B = Psi, (73); default for star covers), "maximal" (phi = psi,
        (67)) or "general" ((32) with phi_i balls of radius rho_i; default
        for "balls", evaluated as (35) when the phi supports are disjoint (34)).
        On balls only "general" interpolates: "minimal" is a Shepard-type partition
        without the Hermite property, and "maximal" does not interpolate either (its
        phi = psi is not 0 at the neighbouring points: the automatic R_i exceed the
        nearest-point distance). 300 random points in the unit square: node errors
        1.6e-4 "minimal", 2.0e-4 "maximal", 0 "general".
    degree : Taylor degree m of the local functions (0..3, default 3). Orders above
        the given data are estimated (e.g. with exact gradients and Hessians and
        degree 3, only the third derivatives are estimated). Degree 3 gives O(h^4)
        in the interior and keeps the Taylor extrapolation error small in long thin
        hull simplices (the dominant error of degree 2 near the boundary).
    kernel : GERBS kernel (default ERBS()) or its name ("erbs", "bfbs", "logistic",
        "affine": default parameters; :func:`gerbs_core.kernels.as_kernel`).
    metric : for cover="balls": a :class:`gerbs_core.scattered.metrics.Metric` or any
        form of :func:`gerbs_core.scattered.metric_forms.as_metric` ("euclidean", "l1",
        "linf", ("lp", 3), ("bounded", base), weighted forms, ...). Derivatives
        nu <= metric.max_nu (2 for Euclidean, l_p p >= 2, l_inf, l_1, bounded; 1 for
        1 < p < 2; 0 for quasi-norms).
    rho, R : radii for the general construction (scalar or (N,)), validated
        against (16), (17).
    regularized : optional callable ``f_jet(y (..., n)) -> [f (..., V), grad (..., V, n),
        Hess (..., V, n, n)]``: use the regularized Taylor coefficients of Lemma 5
        averaged over B(x_i, r_i), r_i = rho_i (Theorem 3 (iii); quasi-interpolation,
        values at x_i are then reproduced only up to O(r^(m+1))); needs degree <= 2.
        Quadrature: see :func:`gerbs_core.scattered.taylor.averaged_taylor`.
    fill_value : returned outside the domain (no support covers x), for the values and
        for every entry of the derivatives (nu = 1, 2) alike; default NaN. A query
        inside the domain where every size function psi_i vanishes (a kernel whose
        1 - F(t) is 0 before t = 1, e.g. ERBS(gamma=7.4, lam=0, sigma=0) or Step(), see
        :attr:`cover_guaranteed`) is refused with InvalidParameterError("kernel", "...
        leaves holes in the cover"), as BlendingSurface does, rather than filled.
    kappa, shrink : star gauge parameters (rho~ >= kappa shrink rho, rho~ <= shrink rho);
        kappa default 0.8 in the plane, :func:`~gerbs_core.scattered.star_nd.default_kappa`
        in n >= 3.
    exact_gauge : use the kinked exact polygon radius (tests only).
    chunk_size : queries per evaluation block (rows are further split so that one
        block's working arrays stay within the working memory).
    memory_budget : bytes one call may use (default 1e9): the output, the query
        ordering and one chunk's working arrays (``min(256 MB, budget / 4)``). A call
        that would exceed it raises ResourceLimitError before allocating; fitting
        uses the same working memory for the derivative estimation.

    Calling ``interp(x, nu=0|1|2)`` with x (..., n) returns values (..., *vshape),
    gradients (..., *vshape, n) or Hessians (..., *vshape, n, n); nu <= :attr:`max_order`
    (2, less for kernels without derivatives and for metrics with C^0 / C^1 bumps). All
    formulas are exact algebra; estimated derivatives are the only approximation.
    """

    def __init__(self, points, values, gradients=None, hessians=None, *, cover=None, kernel=None,
                 metric=None, basis=None, degree=3, fit_degree=None, n_neighbors=None, rho=None,
                 R=None, regularized=None, domain=None, fill_value=np.nan, exact_gauge=False,
                 kappa=None, shrink=0.95, chunk_size=20000, memory_budget=1e9):
        pts, tree = check_points(points, "points", min_points=1, return_tree=True)
        tree = cKDTree(pts) if tree is None else tree     # the one tree of the points
        N, n = pts.shape
        pts.flags.writeable = False                       # a copy: the caller's is untouched
        self.points, self.n, self._tree = pts, n, tree
        self._points_t = np.ascontiguousarray(pts.T)     # coordinate-major, for gathers
        self.kernel = as_kernel(kernel)
        if isinstance(fill_value, (bool, np.bool_)) or not isinstance(
                fill_value, (int, float, np.integer, np.floating)):
            raise InvalidParameterError("fill_value", f"must be a real number (NaN by "
                                        f"default), got {fill_value!r}")
        self.fill_value = float(fill_value)
        self.chunk_size = integer("chunk_size", chunk_size, 1)
        self.memory_budget = float(memory_budget)
        if not self.memory_budget > 0:
            raise InvalidParameterError("memory_budget", f"must be > 0 bytes, got {memory_budget!r}")
        self._work = min(256e6, 0.25 * self.memory_budget)
        if not (isinstance(degree, (int, np.integer)) and 0 <= degree <= 3):
            raise InvalidParameterError("degree", f"Taylor degree must be 0..3, got {degree!r}")
        self.degree = int(degree)
        D, self.vshape, self._V = hermite_data(values, gradients, hessians, N, n)
        self._setup_cover(cover, basis, metric, rho, R, domain,
                          dict(kappa=kappa, shrink=shrink, exact=exact_gauge))
        # ---- local functions -------------------------------------------
        if regularized is not None:
            if self.degree > 2:
                raise InvalidParameterError("degree", "regularized Taylor coefficients need degree <= 2")
            D = averaged_taylor(regularized, pts, self.rho, self.degree)
            D = [d.reshape((N, self._V) + (n,) * k) for k, d in enumerate(D)]
        else:
            known = len(D) - 1
            if known < self.degree:
                fd = min(3, self.degree + 1) if fit_degree is None else int(fit_degree)
                if fd < self.degree:
                    raise InvalidParameterError("fit_degree", f"must be >= degree ({self.degree}), got {fd}")
                est = estimate_derivatives(pts, D, fd, n_neighbors=n_neighbors, tree=self._tree,
                                           work_bytes=self._work)
                D = D + [est[k] for k in range(known + 1, self.degree + 1)]
            D = D[: self.degree + 1]
        self.D = D
        # T_i as monomial coefficients (gathered per query); those of its derivatives
        # are added on the first call with nu >= 1 (:meth:`_coefs`)
        self._coef = coefficient_tables(D, n, 0)
        # scalar data: T_i's coefficients also as (Q, N, 1) rows, for the values' sum
        self._coef_t = (np.ascontiguousarray(self._coef[0].transpose(2, 0, 1))
                        if self._V == 1 else None)
        self._freeze()

    # ------------------------------------------------------------------
    def _setup_cover(self, cover, basis, metric, rho, R, domain, gauge_kw):
        n = self.n
        if cover is None:
            cover = "balls" if n == 1 else "delaunay"
        if not isinstance(cover, str):
            self.cover_kind = "polygons"
        elif cover in ("delaunay", "voronoi", "balls"):
            self.cover_kind = cover
        else:
            raise InvalidParameterError("cover", f"unknown cover {cover!r}")
        if basis is None:
            basis = "general" if self.cover_kind == "balls" else "minimal"
        if basis not in ("minimal", "maximal", "general"):
            raise InvalidParameterError("basis", f"unknown basis {basis!r}")
        self.basis_kind = basis
        self.domain = None
        self._planar = False
        if self.cover_kind == "balls":
            self.metric = as_metric(metric, n)
            self.cover = BallCover(self.points, self.metric, self.kernel, R=R, rho=rho, tree=self._tree)
            return
        if metric is not None and not isinstance(as_metric(metric, n), Euclidean):
            raise InvalidParameterError(
                "metric", "star covers use the Euclidean gauge; metric applies to cover='balls'")
        for name, value in (("rho", rho), ("R", R)):
            if value is not None:       # was ignored silently
                raise InvalidParameterError(
                    name, f"ball radii apply to cover='balls', not {self.cover_kind!r}")
        if domain is not None and self.cover_kind != "voronoi":
            raise InvalidParameterError("domain", f"applies to cover='voronoi' (the clipping "
                                        f"polygon), not {self.cover_kind!r}")
        if self.cover_kind != "delaunay" and n != 2:
            raise InvalidParameterError("cover", f"{self.cover_kind} covers are planar: points must have n = 2")
        if n == 1:
            raise InvalidParameterError("cover", "star covers need n >= 2; use cover='balls' in R^1")
        if n == 2:
            self._planar = True
            gauge_kw["kappa"] = 0.8 if gauge_kw["kappa"] is None else gauge_kw["kappa"]
            if self.cover_kind == "delaunay":
                self.cover, self.tri, self.simplices = _covers.delaunay_cover(self.points, self.kernel, **gauge_kw)
            elif self.cover_kind == "voronoi":
                self.cover, self.domain = _covers.voronoi_cover(self.points, self.kernel, domain=domain, **gauge_kw)
            else:
                self.cover = _covers.polygon_cover(self.points, list(cover), self.kernel, **gauge_kw)
            self._star_candidates = None
        else:
            self.cover = DelaunayStarCover(self.points, self.kernel, tree=self._tree, **gauge_kw)
            self.tri, self.simplices = self.cover.tri, self.cover.simplices
        self._rho = None

    @property
    def R(self):
        """(N,) the radius of a ball about x_i containing supp psi_i: for cover="balls"
        the size radii R_i themselves (in ``metric``: psi_i = b(d(x, x_i) / R_i)); for the
        star covers the Euclidean bound shrink times the distance from x_i to the
        farthest corner of its star polygon (Delaunay star, Voronoi cell, user polygon)."""
        if self.cover_kind == "balls":
            return self.cover.R
        return self.cover.support_radius

    @property
    def rho(self):
        """Non-degeneracy radii rho_i (N,): the phi balls of the general basis (for star
        covers inside the support, halved: Remark 6; computed on first use)."""
        if self.cover_kind == "balls":
            return self.cover.rho
        if self._rho is None:
            self._cache("_rho", 0.5 * np.minimum(self.cover.min_radius, self._nearest_d()))
        return self._rho

    @property
    def cover_guaranteed(self) -> bool:
        """True if every point of the domain provably has some psi_i(x) >= b(t) > 0: the
        cover has a certified gauge bound t < 1 there (``cover.max_gauge``) and the kernel
        does not vanish at t. The bounds: t = 0.9 on the convex hull for the automatic
        ball radii (:func:`~gerbs_core.scattered.radii.auto_R`; more for the bounded
        metric); t = n / ((n+1) kappa shrink) on the hull for "delaunay" (0.877 in the
        plane); t = 1 / (2 kappa shrink) on the domain polygon for "voronoi" (0.658).
        False for user radii R and user polygons (no certificate), and for a kernel with
        b(t) = 1 - F(t) = 0 (holes: ERBS(gamma=7.4, lam=0, sigma=0), Step(0.5))."""
        t = self.cover.max_gauge
        return bool(t < 1.0 and self.kernel.bump(t) > 0.0)

    @property
    def max_order(self) -> int:
        """Highest derivative order ``nu`` of a call: 2, or less when the kernel has fewer
        derivatives (``kernel.max_order``) or the metric's bumps are only C^0 / C^1."""
        m = min(2, self.kernel.max_order)
        return min(m, self.metric.max_nu) if self.cover_kind == "balls" else m

    def _check_nu(self, nu) -> int:
        """``nu`` checked against :attr:`max_order`, the error saying what limits it."""
        k = self.kernel.max_order
        why = f"(its kernel, {type(self.kernel).__name__}, has max_order = {k})" if k < 2 else ""
        nu = check_order(nu, min(2, k), owner="the interpolator", why=why)
        if self.cover_kind == "balls":
            self.metric.check_nu(nu)
        return nu

    def _nearest_d(self):
        return nearest_distances(self.points, Euclidean(self.n), self._tree)

    # ------------------------------------------------------------------
    def _candidates(self, x):
        """Padded candidate indices (M, K) (-1 empty) and planar star edges (or None)."""
        if self.cover_kind == "balls" or not self._planar:
            return self.cover.candidates(x), None
        if self.cover_kind == "delaunay":
            return delaunay_candidates(self.tri, self.simplices, x)
        if self._star_candidates is None:
            self._cache("_star_candidates", StarCandidates(self.points, self._tree,
                                                           self.cover.support_radius))
        idx = self._star_candidates(x)
        if self.domain is not None:
            inside = _covers.in_convex_polygon(x, self.domain)
            idx[~inside] = -1
        return idx, None

    def _jets(self, x, idx, edge, nu):
        """psi and phi jets (M, K, ...) of the candidates."""
        want_phi = self.basis_kind == "general"
        if self.cover_kind == "balls":
            return self.cover.jets(x, idx, nu, want_phi)
        if self._planar:
            psi = self.cover.psi_jet(x, idx, edge, nu)
        else:
            psi = self.cover.psi_jet(x, idx, nu)
        phi = None
        if want_phi:
            valid = idx >= 0
            j = np.maximum(idx, 0)
            y = x[:, None, :] - self.points[j]
            phi = list(Euclidean(self.n).bump_jet(y, self.rho[j], self.kernel, nu))
            phi[0] = np.where(valid, phi[0], 0.0)
            if nu >= 1:
                phi[1] = np.where(valid[..., None], phi[1], 0.0)
            if nu >= 2:
                phi[2] = np.where(valid[..., None, None], phi[2], 0.0)
        return psi, phi

    def basis(self, x, nu=0):
        """The nonzero basis functions at x (M, n): (idx (M, K) with -1 = empty slot,
        B (M, K), grad B (M, K, n) or None, Hess B (M, K, n, n) or None), derivatives up to
        ``nu`` <= :attr:`max_order` (as a call). Rows outside the domain have NaN B; a hole
        of the cover inside it is refused (see ``fill_value``)."""
        nu = self._check_nu(nu)
        x = self._check_x(x).reshape(-1, self.n)
        out = self._basis(x, *self._candidates(x), nu)
        self._refuse_holes(x, out[0], ~np.isfinite(out[1]).all(axis=1))
        return out

    def _refuse_holes(self, x, idx, bad):
        """Raise where the cover has a hole: rows of x (M, n) with candidates idx (M, K)
        whose basis is undefined (``bad`` (M,): every psi_i(x) = 0) although x lies where
        the cover is thick for any kernel positive before t = 1 -- in the domain of a
        "delaunay" or "voronoi" cover (every point there has some gauge <= max_gauge < 1),
        or well inside a support (gauge <= 0.9: a ball, or a star polygon's inner disc).
        The rule is BlendingSurface's (:func:`gerbs_core.mesh.cover.require_cover`)."""
        rows = np.flatnonzero(bad & (idx >= 0).any(axis=1))
        if not rows.size:
            return
        if self.cover_kind in ("delaunay", "voronoi") and self.cover.max_gauge < 1.0:
            hole = True
        elif self.cover_kind == "balls":
            hole = self.cover.well_inside(x[rows], idx[rows], MARGIN).any()
        else:
            j = np.maximum(idx[rows], 0)
            r = np.linalg.norm(x[rows, None, :] - self.points[j], axis=-1)
            hole = ((idx[rows] >= 0) & (r <= MARGIN * self.cover.min_radius[j])).any()
        if hole:
            from ..mesh.cover import require_cover    # (the mesh package only on this path)
            require_cover(0.0, self.kernel)

    def _basis(self, x, idx, edge, nu):
        disjoint = self.cover_kind == "balls" and self.cover.disjoint_phi
        if self.basis_kind != "minimal" and not disjoint:
            # (29) multiplies over j < i: sort candidates by global index, empties last
            key = np.where(idx >= 0, idx, np.iinfo(np.int64).max)
            o = np.argsort(key, axis=1, kind="stable")
            idx = np.take_along_axis(idx, o, 1)
            if edge is not None:
                edge = np.take_along_axis(edge, o, 1)
        psi, phi = self._jets(x, idx, edge, nu)
        if self.basis_kind == "minimal":
            B = minimal_basis(tuple(psi), nu)
        elif self.basis_kind == "maximal":
            B = general_basis(tuple(psi), tuple(psi), nu)
        elif disjoint:
            B = disjoint_basis(tuple(phi), tuple(psi), nu)
        else:
            B = general_basis(tuple(phi), tuple(psi), nu)
        return (idx,) + tuple(B)

    def basis_matrix(self, x):
        """Dense (M, N) matrix of B_i(x) (small problems and tests)."""
        idx, B, _, _ = self.basis(x)
        out = np.zeros((idx.shape[0], self.points.shape[0]))
        rows, cols = np.nonzero(idx >= 0)
        out[rows, idx[rows, cols]] = B[rows, cols]
        out[~np.isfinite(B).all(axis=1)] = np.nan
        return out

    def _check_x(self, x):
        x = np.asarray(x, dtype=float)
        if self.n == 1 and x.ndim <= 1:
            x = x[..., None]          # in R^1: a scalar, or (M,) points, as interp1d's
        if x.ndim == 0 or x.shape[-1] != self.n:
            raise InvalidParameterError("x", f"last axis must have length n={self.n}, got shape {x.shape}")
        return x

    def _coefs(self, nu):
        """[C0, C1, C2][: nu + 1] of :func:`~gerbs_core.scattered.taylor.coefficient_tables`."""
        if len(self._coef) <= nu:
            self._cache("_coef", coefficient_tables(self.D, self.n, 2))
        return self._coef[: nu + 1]

    # ------------------------------------------------------------------ evaluation
    def memory_estimate(self, M, nu=0):
        """Bytes a call with M query points needs at peak (an upper bound): the output,
        the query ordering and one chunk of working arrays."""
        M = integer("M", M, 0, " (query points)")
        nu = self._check_nu(nu)
        return _budget.call_estimate(M, self.n, self._V, nu, self._work)

    def __call__(self, x, nu=0):
        nu = self._check_nu(nu)
        x = self._check_x(x)
        lead = x.shape[:-1]
        xf = x.reshape(-1, self.n)
        M = xf.shape[0]
        n, V = self.n, self._V
        _budget.check_budget(M, n, V, nu, self._work, self.memory_budget)
        out = np.empty((M, V) + (n,) * nu)
        order = self._spatial_order(xf)
        block = self.chunk_size
        if self.cover_kind == "balls":       # the candidate search itself within the work
            block = int(max(1, min(block, self._work // self.cover.search_bytes_per_query())))
        # NaN / infinite queries get the fill value; their arithmetic on the way is expected
        quiet = np.errstate(invalid="ignore", divide="ignore") \
            if not np.isfinite(xf).all() else contextlib.nullcontext()
        with quiet:
            for s in range(0, M, block):
                e = min(M, s + block)
                sel = order[s:e] if order is not None else slice(s, e)
                out[sel] = self._eval_block(xf[sel], nu)
        return out.reshape(lead + self.vshape + (n,) * nu)

    def _spatial_order(self, x):
        """The visiting order of large queries (None when one chunk holds them)."""
        if x.shape[0] <= self.chunk_size or self.n == 1:
            return None
        return _budget.spatial_order(x, max(int((x.shape[0] / 4) ** (1.0 / self.n)), 1))

    def _eval_block(self, x, nu):
        """One block: candidates once, then rows split so the working arrays fit."""
        idx, edge = self._candidates(x)
        pairs = 0
        if isinstance(self.cover, DelaunayStarCover):
            deg = np.diff(self.cover.star_ptr)
            pairs = int(deg[np.maximum(idx, 0)].sum(axis=1).max()) if idx.size else 0
        coefs = sum(c[0, 0].size for c in self._coefs(nu))
        rb = _budget.row_bytes(idx.shape[1], self.n, self._V, nu, coefs, pairs)
        step = _budget.rows_per_step(self._work, rb)
        if step >= len(x):
            return self._eval_chunk(x, idx, edge, nu)
        out = np.empty((len(x), self._V) + (self.n,) * nu)
        for s in range(0, len(x), step):
            sl = slice(s, s + step)
            out[sl] = self._eval_chunk(x[sl], idx[sl], None if edge is None else edge[sl], nu)
        return out

    def _eval_chunk(self, x, idx, edge, nu):
        idx, Bv, Bg, Bh = self._basis(x, idx, edge, nu)
        out, bad = interpolant_sum(nu, x, self._points_t, idx, Bv, Bg, Bh, self._coefs(nu),
                                   self._coef_t, self.degree)
        if bad.any():
            self._refuse_holes(x, idx, bad)
            out[bad] = self.fill_value
        return out

    def __repr__(self) -> str:
        N, n = self.points.shape
        metric = f", metric={self.metric!r}" if self.cover_kind == "balls" else ""
        return (f"GERBSInterpolator(N={N}, n={n}, values={self.vshape}, "
                f"cover={self.cover_kind!r}{metric}, basis={self.basis_kind!r}, "
                f"degree={self.degree}, kernel={self.kernel!r})")
