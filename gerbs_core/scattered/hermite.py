"""Scattered-point Hermite interpolation by GERBS: f(x) = sum_i B_i(x) T_i(x).

B_i is a GERBS partition of unity over a cover (paper sections 2.4, 5), T_i the
Taylor polynomial of the data at x_i (section 2.6, item 1); see
:class:`GERBSInterpolator`.
"""
from __future__ import annotations


import numpy as np
from scipy.spatial import cKDTree

from ..errors import InvalidParameterError, InvalidPointSetError
from .metrics import Euclidean, as_metric
from .partition import general_basis, minimal_basis
from .radii import auto_R, check_points, nearest_distances, validate_radii
from .taylor import averaged_taylor, estimate_derivatives, taylor_jet
from . import covers as _covers

__all__ = ["GERBSInterpolator"]


def _default_kernel():
    from ..kernels import ERBS
    return ERBS()


class GERBSInterpolator:
    """Smooth Hermite interpolant of scattered data in R^n (scipy style).

    Parameters
    ----------
    points : (N, n) scattered points, distinct and finite.
    values : (N, ...) data values, any trailing shape.
    gradients : (N, ..., n), optional. Hessians : (N, ..., n, n), optional.
        Derivatives not given (up to ``degree``) are estimated by local weighted
        least squares (see :mod:`gerbs_core.scattered.taylor`): a polynomial of degree
        ``fit_degree`` (default ``min(degree + 1, 3)``) through f(x_i) fitted to
        the ~1.8 M + 2 nearest neighbours (M unknown coefficients), weights
        (1 - (r/1.2 h)^2)^2.
    cover : "delaunay" (default for n = 2), "voronoi", "balls" (default otherwise)
        or a list of N polygons (K_i, 2), each counter-clockwise and star-shaped w.r.t.
        its point.
        * "delaunay": star-1 neighbourhoods of the Delaunay vertices with the smooth
          gauge (DESIGN 4); domain = convex hull of the points.
        * "voronoi": Voronoi cells clipped to ``domain`` (convex polygon; default the
          bounding box enlarged by 5 %), enlarged 2x about their sites; domain = ``domain``.
        * "balls": the general construction, psi_i = b(d(x, x_i)/R_i),
          phi_i = b(d(x, x_i)/rho_i) (39) in ``metric``; radii from
          :mod:`gerbs_core.scattered.radii` unless given; domain = union of the supports
          (contains the convex hull).
    basis : "minimal" (B = Psi, (73); default for star covers), "maximal" (phi = psi,
        (67)) or "general" ((32) with phi_i Euclidean balls of radius rho_i; default
        for "balls"). "minimal" on balls is a Shepard-type partition without the
        Hermite property.
    degree : Taylor degree m of the local functions (0..3, default 3). Orders above
        the given data are estimated (e.g. with exact gradients and Hessians and
        degree 3, only the third derivatives are estimated). Degree 3 gives O(h^4)
        in the interior and keeps the Taylor extrapolation error small in long thin
        hull triangles (the dominant error of degree 2 near the boundary).
    kernel : GERBS kernel (default ERBS()).
    metric : for cover="balls": a :class:`gerbs_core.scattered.metrics.Metric` or a shorthand
        ("euclidean", "linf", "l1", "bounded", p). Derivatives nu <= metric.max_nu
        (2 for Euclidean, l_p p >= 2, l_inf, l_1, bounded; 1 for 1 < p < 2; 0 for
        quasi-norms).
    rho, R : radii for the general construction (scalar or (N,)), validated
        against (16), (17).
    regularized : optional callable ``f_jet(y (..., n)) -> [f (..., V), grad (..., V, n),
        Hess (..., V, n, n)]``: use the regularized Taylor coefficients of Lemma 5
        averaged over B(x_i, r_i), r_i = rho_i (Theorem 3 (iii); quasi-interpolation,
        values at x_i are then reproduced only up to O(r^(m+1))); needs degree <= 2.
        Quadrature: see :func:`gerbs_core.scattered.taylor.averaged_taylor`.
    fill_value : returned outside the domain (no support covers x); default NaN.
    kappa, shrink : star gauge parameters (rho~ >= kappa shrink rho, rho~ <= shrink rho).
    exact_gauge : use the kinked exact polygon radius (tests only).
    chunk_size : evaluation chunk (bounded memory).

    Calling ``interp(x, nu=0|1|2)`` with x (..., n) returns values (..., *vshape),
    gradients (..., *vshape, n) or Hessians (..., *vshape, n, n). All formulas are
    exact algebra; estimated derivatives are the only approximation.
    """

    def __init__(self, points, values, gradients=None, hessians=None, *, cover=None, kernel=None,
                 metric=None, basis=None, degree=3, fit_degree=None, n_neighbors=None, rho=None,
                 R=None, regularized=None, domain=None, fill_value=np.nan, exact_gauge=False,
                 kappa=0.8, shrink=0.95, chunk_size=20000):
        pts = check_points(points, "points", min_points=1)
        N, n = pts.shape
        self.points, self.n = pts, n
        self.kernel = _default_kernel() if kernel is None else kernel
        self.fill_value = fill_value
        self.chunk_size = int(chunk_size)
        if not (isinstance(degree, (int, np.integer)) and 0 <= degree <= 3):
            raise InvalidParameterError("degree", f"Taylor degree must be 0..3, got {degree!r}")
        self.degree = int(degree)
        D = self._data(values, gradients, hessians, N, n)
        # ---- cover --------------------------------------------------------
        if cover is None:
            cover = "delaunay" if n == 2 else "balls"
        if not isinstance(cover, str):
            self.cover_kind = "polygons"
            self._polygons = list(cover)
        else:
            if cover not in ("delaunay", "voronoi", "balls"):
                raise InvalidParameterError("cover", f"unknown cover {cover!r}")
            self.cover_kind = cover
        if basis is None:
            basis = "general" if self.cover_kind == "balls" else "minimal"
        if basis not in ("minimal", "maximal", "general"):
            raise InvalidParameterError("basis", f"unknown basis {basis!r}")
        self.basis_kind = basis
        gauge_kw = dict(kappa=kappa, shrink=shrink, exact=exact_gauge)
        self._nearest = None
        if self.cover_kind == "balls":
            self._setup_balls(metric, rho, R)
        else:
            if metric is not None and not isinstance(metric, Euclidean):
                raise InvalidParameterError("metric", "star covers use the Euclidean gauge; metric applies to cover='balls'")
            if self.cover_kind == "delaunay":
                self.cover, self.tri, self.simplices = _covers.delaunay_cover(pts, self.kernel, **gauge_kw)
                self.domain = None
            elif self.cover_kind == "voronoi":
                if n != 2:
                    raise InvalidParameterError("cover", "star covers are planar: points must have n = 2")
                self.cover, self.domain = _covers.voronoi_cover(pts, self.kernel, domain=domain, **gauge_kw)
            else:
                if n != 2:
                    raise InvalidParameterError("cover", "star covers are planar: points must have n = 2")
                self.cover = _covers.polygon_cover(pts, self._polygons, self.kernel, **gauge_kw)
                self.domain = None
            self._centre_tree = None
            # phi radii for the general basis: (64)/(68) inside the support, halved (Remark 6)
            if self.basis_kind == "general" or regularized is not None:
                self.rho = 0.5 * np.minimum(self.cover.min_radius, self._nearest_d())
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
                est = estimate_derivatives(pts, D, fd, n_neighbors=n_neighbors)
                D = D + [est[k] for k in range(known + 1, self.degree + 1)]
            D = D[: self.degree + 1]
        self.D = D

    # ------------------------------------------------------------------
    def _data(self, values, gradients, hessians, N, n):
        vals = np.array(values, dtype=float, copy=True)
        if vals.ndim == 0 or vals.shape[0] != N:
            raise InvalidParameterError("values", f"expected shape (N={N}, ...), got {np.shape(values)}")
        self.vshape = vals.shape[1:]
        V = int(np.prod(self.vshape)) if self.vshape else 1
        self._V = V
        bad = np.flatnonzero(~np.all(np.isfinite(vals.reshape(N, -1)), axis=1))
        if bad.size:
            raise InvalidPointSetError("values: non-finite (NaN or inf) at indices", bad)
        D = [vals.reshape(N, V)]
        if hessians is not None and gradients is None:
            raise InvalidParameterError("hessians", "Hessians need gradients too")
        for name, arr, k in (("gradients", gradients, 1), ("hessians", hessians, 2)):
            if arr is None:
                break
            a = np.array(arr, dtype=float, copy=True)
            want = (N,) + self.vshape + (n,) * k
            if a.shape != want:
                raise InvalidParameterError(name, f"expected shape {want}, got {a.shape}")
            bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(N, -1)), axis=1))
            if bad.size:
                raise InvalidPointSetError(f"{name}: non-finite (NaN or inf) at indices", bad)
            a = a.reshape((N, V) + (n,) * k)
            if k == 2:
                a = 0.5 * (a + np.swapaxes(a, -1, -2))
            D.append(a)
        return D

    def _nearest_d(self):
        if self._nearest is None:
            m = getattr(self, "metric", None) or Euclidean(self.n)
            self._nearest = nearest_distances(self.points, m)
        return self._nearest

    def _setup_balls(self, metric, rho, R):
        N = self.points.shape[0]
        self.metric = as_metric(metric, self.n)
        self.domain = None
        if R is None:
            if N < 2:
                raise InvalidPointSetError("points: cover='balls' needs R when N < 2")
            self.R, self.cover_guaranteed = auto_R(self.points, self.metric)
        else:
            self.R = np.broadcast_to(np.asarray(R, float), (N,)).copy()
            self.cover_guaranteed = False
        nearest = self._nearest_d()
        if rho is None:
            self.rho = np.minimum(0.5 * nearest, self.R)
        else:
            self.rho = np.broadcast_to(np.asarray(rho, float), (N,)).copy()
        validate_radii(self.rho, self.R, nearest)
        self._tree = cKDTree(self.metric.tree_coords(self.points))
        bound = self.metric.coord_bound(self.R) * self.metric.w      # in tree coordinates
        self._qr = float(bound.max())

    # ------------------------------------------------------------------
    def _candidates(self, x):
        """Padded candidate indices (M, K) (-1 empty) and star edges (or None)."""
        if self.cover_kind == "balls":
            z = self.metric.tree_coords(x)
            idx = _covers.padded_ball_query(self._tree, z, self._qr * (1 + 1e-12), p=np.inf)
            return idx, None
        if self.cover_kind == "delaunay":
            # small tolerance: points on the hull boundary belong to the domain
            simp = self.tri.find_simplex(x, tol=1e-12)
            ok = simp >= 0
            idx = np.where(ok[:, None], self.simplices[np.maximum(simp, 0)], -1)
            edge = np.where(ok[:, None], 3 * np.maximum(simp, 0)[:, None] + np.arange(3), -1)
            return idx, edge
        idx = self._star_candidates(x)
        if self.domain is not None:
            inside = _covers.in_convex_polygon(x, self.domain)
            idx[~inside] = -1
        return idx, None

    def _star_candidates(self, x):
        """Stars whose support radius reaches x. Typical stars through a KD-tree ball
        query with radius r = the 99 % quantile of the support radii; the few larger ones (cells at
        the domain boundary) by a direct distance check, so the query stays local."""
        R = self.cover.support_radius
        if self._centre_tree is None:
            self._centre_tree = cKDTree(self.points)
            self._r_typ = float(np.quantile(R, 0.99))
            self._big = np.flatnonzero(R > self._r_typ)
        idx = _covers.padded_ball_query(self._centre_tree, x, self._r_typ * (1 + 1e-12))
        j = np.maximum(idx, 0)
        d = np.linalg.norm(x[:, None, :] - self.points[j], axis=-1)
        idx = np.where((idx >= 0) & (d < R[j]) & (R[j] <= self._r_typ), idx, -1)
        if self._big.size:
            db = np.linalg.norm(x[:, None, :] - self.points[self._big], axis=-1)
            idx = np.concatenate([idx, np.where(db < R[self._big], self._big, -1)], axis=1)
        # compact: valid entries first, drop all-empty columns
        o = np.argsort(idx < 0, axis=1, kind="stable")
        idx = np.take_along_axis(idx, o, 1)
        width = max(int((idx >= 0).sum(1).max()) if idx.size else 0, 1)
        return idx[:, :width]

    def _jets(self, x, idx, edge, nu):
        """psi and phi jets (M, K, ...) of the candidates."""
        valid = idx >= 0
        j = np.maximum(idx, 0)
        if self.cover_kind == "balls":
            y = x[:, None, :] - self.points[j]
            psi = list(self.metric.bump_jet(y, self.R[j], self.kernel, nu))
            phi = list(self.metric.bump_jet(y, self.rho[j], self.kernel, nu)) \
                if self.basis_kind == "general" else None
            for jet in (psi, phi):
                if jet is None:
                    continue
                jet[0] = np.where(valid, jet[0], 0.0)
                if nu >= 1:
                    jet[1] = np.where(valid[..., None], jet[1], 0.0)
                if nu >= 2:
                    jet[2] = np.where(valid[..., None, None], jet[2], 0.0)
            return psi, phi
        psi = self.cover.psi_jet(x, idx, edge, nu)
        phi = None
        if self.basis_kind == "general":
            y = x[:, None, :] - self.points[j]
            phi = list(Euclidean(2).bump_jet(y, self.rho[j], self.kernel, nu))
            phi[0] = np.where(valid, phi[0], 0.0)
            if nu >= 1:
                phi[1] = np.where(valid[..., None], phi[1], 0.0)
            if nu >= 2:
                phi[2] = np.where(valid[..., None, None], phi[2], 0.0)
        return psi, phi

    def basis(self, x, nu=0):
        """The nonzero basis functions at x (M, n): (idx (M, K) with -1 = empty slot,
        B (M, K), grad B (M, K, n) or None, Hess B (M, K, n, n) or None).
        Rows outside the domain have NaN B."""
        x = self._check_x(x).reshape(-1, self.n)
        idx, edge = self._candidates(x)
        if self.basis_kind != "minimal":
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
        if x.ndim == 0 or x.shape[-1] != self.n:
            raise InvalidParameterError("x", f"last axis must have length n={self.n}, got shape {x.shape}")
        return x

    def __call__(self, x, nu=0):
        if nu not in (0, 1, 2):
            raise InvalidParameterError("nu", f"derivative order must be 0, 1 or 2, got {nu!r}")
        if self.cover_kind == "balls":
            self.metric.check_nu(nu)
        x = self._check_x(x)
        lead = x.shape[:-1]
        xf = x.reshape(-1, self.n)
        M = xf.shape[0]
        n, V = self.n, self._V
        out = np.empty((M, V) + (n,) * nu)
        order = self._spatial_order(xf)
        for s in range(0, M, self.chunk_size):
            e = min(M, s + self.chunk_size)
            sel = order[s:e] if order is not None else slice(s, e)
            out[sel] = self._eval_chunk(xf[sel], nu)
        return out.reshape(lead + self.vshape + (n,) * nu)

    def _spatial_order(self, x):
        """Visit large queries cell by cell (rows of a ~sqrt(M) grid, boustrophedon):
        the Delaunay walk of ``find_simplex`` and the neighbour gathers then stay
        local, so the cost per point does not grow with N for unordered queries."""
        M = x.shape[0]
        if M <= self.chunk_size or self.n == 1:
            return None
        lo, hi = x.min(0), x.max(0)
        k = max(int(np.sqrt(M / 4)), 1)
        c = np.clip(((x[:, :2] - lo[:2]) / np.maximum(hi[:2] - lo[:2], 1e-300) * k).astype(np.int64), 0, k - 1)
        row, col = c[:, 1], c[:, 0]
        col = np.where(row % 2 == 1, k - 1 - col, col)
        return np.argsort(row * k + col, kind="stable")

    def _eval_chunk(self, x, nu):
        idx, Bv, Bg, Bh = self.basis(x, nu)
        j = np.maximum(idx, 0)
        d = x[:, None, :] - self.points[j]
        Tv, Tg, Th = taylor_jet([Dk[j] for Dk in self.D], d, nu)      # (M, K, V, ...)
        bad = ~np.all(np.isfinite(Bv), axis=1)
        Bv = np.where(np.isfinite(Bv), Bv, 0.0)
        if nu == 0:
            out = np.einsum("mk,mkv->mv", Bv, Tv)
        elif nu == 1:
            out = np.einsum("mki,mkv->mvi", Bg, Tv) + np.einsum("mk,mkvi->mvi", Bv, Tg)
        else:
            out = (np.einsum("mkij,mkv->mvij", Bh, Tv) + np.einsum("mki,mkvj->mvij", Bg, Tg)
                   + np.einsum("mkj,mkvi->mvij", Bg, Tg) + np.einsum("mk,mkvij->mvij", Bv, Th))
        out[bad] = self.fill_value
        return out
