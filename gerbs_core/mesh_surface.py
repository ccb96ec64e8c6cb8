"""C-infinity GERBS blending surfaces through the vertices of a polygon mesh (DESIGN 5).

    S(p) = sum_v Psi_v(p) l_v(zeta_v(p)),   Psi_v = psi_v / sum_u psi_u   (eq. (73), B = Psi)

summed over the corners u of the face containing p (the other size functions
vanish there: supp psi_v lies compactly inside v's open star). psi_v = b(g_v)
with the smooth star gauge g_v = r / rho~_v(theta) in v's unfolded polar
coordinates (eq. (62) with the smooth envelope of DESIGN section 4; r/rho~ is
the same function as |y| / rho~(phi / s_v) in the angle-scaled chart y = zeta_v),
l_v the local polynomial of :mod:`gerbs_core.local_fit` in chart coordinates.
Near every vertex Psi_v = 1, so S = l_v there and S(v) = X_v.

Evaluation is vectorized over samples: samples are grouped by face size and
padded per face, every quantity is computed per corner slot for all faces of a
size class at once; envelopes are evaluated with one call per distinct star
envelope. Mode "regular" stencils go further (see BlendingSurface). The Python
loops over vertices are in the set-up only (local fits, star envelopes), with
equal star shapes sharing one solve / one envelope.

Exact: everything is closed form up to round-off, except that the kernel's F is
tabulated to ~1e-13 (gerbs_core.kernels). Uncovered points (eps0 = 0) would give
0/0; the adaptive envelope guarantees rho~ >= kappa * shrink * rho, measured
eps0 >= 0.10 on every test mesh.
"""
from __future__ import annotations

import numpy as np

from .charts import build_envelopes, eval_envelopes, vertex_charts
from .errors import InvalidParameterError, ResourceLimitError
from .face_shapes import face_shapes
from .local_fit import fit_local_functions, monomials
from .mesh_topology import MeshTopology, validate_geometry
from .stencil import Stencil, assemble_csr

__all__ = ["BlendingSurface"]

# memory model of a tessellation / stencil, calibrated on tracemalloc peaks (Suzanne,
# icosphere(3), UV sphere, mixed mesh; 10k..1M points; scripts/measure_memory.py):
# peak ~ P (~450 B + 12 B per non-zero of W) + the chunked working set (~20 MB)
_BYTES_PER_SAMPLE = 700  # points, normals, lattice and per-sample arrays (with margin)
_BYTES_PER_NNZ = 12  # W: float64 data + int32 index
_CHUNK_BYTES = 48e6  # working arrays of one chunk (~200000 sample x corner terms)


def _points(name, a, V=None):
    x = np.array(a, dtype=np.float64, copy=True)  # never alias the caller's array
    if x.ndim != 2 or x.shape[1] != 3 or (V is not None and len(x) != V):
        raise InvalidParameterError(name, f"must be a ({'V' if V is None else V}, 3) array, "
                                    f"got shape {x.shape}")
    return x


def _first_and_inverse(*keys):
    """Distinct tuples of equally long key arrays (compared exactly): (first (D,) the
    index of each distinct tuple's first occurrence; inv (N,) the distinct tuple of
    each i). A stable lexsort (np.unique(axis=0) is ~10x slower for small blocks)."""
    order = np.lexsort(keys[::-1])  # first key primary; stable: first occurrence first
    same = np.ones(max(len(order) - 1, 0), dtype=bool)
    for k in keys:
        sk = np.asarray(k)[order]
        same &= sk[1:] == sk[:-1]
    new = np.ones(len(order), dtype=bool)
    new[1:] = ~same
    inv = np.empty(len(order), dtype=np.int64)
    inv[order] = np.cumsum(new) - 1
    return order[new], inv


class BlendingSurface:
    """GERBS blending surface of a polygon mesh (triangles, quads, n-gons; boundaries).

    Parameters: vertices (V,3); faces (list of int sequences or (F,k) array, or a
    MeshTopology); degree 0..3 of the local functions; kernel (default ERBS());
    mode "regular" (unit edges: W depends only on topology) or "metric" (edge
    lengths of rest_positions, default the vertices); boundary "keep" or
    "straighten"; normals (V,3): optional vertex normals as Hermite data
    (dl_v(0) orthogonal to n_v); kappa, shrink: envelope parameters (DESIGN 5);
    exact_gauge: use the exact (kinked) polygon radius -- a deliberately
    non-smooth variant for tests; max_condition: enlargement threshold of the
    local fits; memory_budget: bytes a tessellation/stencil may use
    (ResourceLimitError beyond, stating the estimate); eps0_resolution: lattice
    resolution of the eps0 check.

    Performance: in mode "regular" all faces of one size share their reference
    polygon, so stencils evaluate size functions and monomials once per distinct
    (corner slot, star envelope, sector) and gather (:meth:`_corner_terms_shared`).

    Attributes: topology, eps0 (min over a check lattice of max_v psi_v > 0: the
    cover is thick), degree, mode, boundary, charts, shapes, fits.
    Raises InvalidMeshError (from the topology/geometry validation) or
    InvalidParameterError; the caller's arrays are never modified.
    """

    def __init__(self, vertices, faces, degree: int = 2, kernel=None, mode: str = "regular",
                 rest_positions=None, boundary: str = "keep", normals=None, kappa: float = 0.8,
                 shrink: float = 0.95, exact_gauge: bool = False, max_condition: float = 100.0,
                 memory_budget: float = 2.0e9, eps0_resolution: int = 6):
        X = _points("vertices", vertices)
        if normals is not None:
            nrm = _points("normals", normals, len(X))
            ln = np.linalg.norm(nrm, axis=1)
            if not np.all(np.isfinite(ln)) or np.any(ln == 0):
                raise InvalidParameterError("normals", "must be finite and non-zero")
            normals = nrm / ln[:, None]
        topo = faces if isinstance(faces, MeshTopology) else MeshTopology(faces, len(X))
        validate_geometry(X, topo)
        rest = X if rest_positions is None else _points("rest_positions", rest_positions, len(X))
        if rest_positions is not None:
            validate_geometry(rest, topo)
        if kernel is None:
            from .kernels import ERBS
            kernel = ERBS()
        if not (0.0 < shrink <= 1.0):
            raise InvalidParameterError("shrink", f"must be in (0, 1], got {shrink}")
        if not (0.0 < kappa < 1.0):
            raise InvalidParameterError("kappa", f"must be in (0, 1), got {kappa}")
        self.topology = topo
        self.kernel = kernel
        self.mode, self.boundary = mode, boundary
        self.memory_budget = float(memory_budget)
        self.shapes = face_shapes(topo.face_offsets, topo.face_vertices, mode, rest)
        self.charts = vertex_charts(topo.face_offsets, topo.face_vertices, self.shapes.corners,
                                    self.shapes.angles, topo.star_offsets, topo.star_corners,
                                    topo.vertex_is_boundary, boundary)
        self.fits = fit_local_functions(topo, self.charts, self.shapes.corners, degree,
                                        max_condition=max_condition,
                                        flat=normals is not None)
        self.degree = self.fits.degree
        self._envelopes, self._corner_env, self._env_offset = build_envelopes(
            topo, self.charts, self.shapes.corners, kappa=kappa, shrink=shrink,
            exact=exact_gauge, kernel=kernel)
        self._X = X
        self._normals = normals
        self._coef = self.fits.coefficients(X, normals)  # (V, M, 3)
        self._eps0_resolution = eps0_resolution
        self._eps0 = None
        self._last_eps0 = float("nan")

    # ------------------------------------------------------------------ data
    @property
    def eps0(self) -> float:
        """min over a check lattice (every lattice point of every face, resolution
        ``eps0_resolution``) of max_v psi_v: the thickness of the cover, > 0 means no
        point is left uncovered (computed on first access). ``last_eps0``: the same
        over the samples of the latest evaluation/tessellation/stencil."""
        if self._eps0 is None:
            self._eps0 = self._check_cover(self._eps0_resolution)
        return self._eps0

    @property
    def last_eps0(self) -> float:
        return self._last_eps0

    @property
    def vertices(self) -> np.ndarray:
        return self._X.copy()

    def with_positions(self, vertices) -> "BlendingSurface":
        """A copy evaluating new positions with the same charts (rest binding kept)."""
        new = object.__new__(BlendingSurface)
        new.__dict__.update(self.__dict__)
        new._X = _points("vertices", vertices, len(self._X))
        new._coef = self.fits.coefficients(new._X, self._normals)
        return new

    # ------------------------------------------------------------- machinery
    def _groups(self, face_ids, x):
        """Group samples by face size, padded per face: yields (n, faces, sel, xb)."""
        topo = self.topology
        order = np.argsort(face_ids, kind="stable")
        fs = face_ids[order]
        uf, start, counts = np.unique(fs, return_index=True, return_counts=True)
        sizes = topo.face_sizes[uf]
        for n in np.unique(sizes):
            kk = np.flatnonzero(sizes == n)
            P = int(counts[kk].max())
            faces = uf[kk]
            rank = np.arange(P)[None, :]
            valid = rank < counts[kk][:, None]
            sel = np.where(valid, order[np.minimum(start[kk][:, None] + rank, len(order) - 1)], -1)
            xb = np.where(valid[..., None], x[np.maximum(sel, 0)],
                          self._centroids()[faces][:, None, :])
            # chunks keep the working memory bounded
            per = max(1, int(200000 // (P * n)))
            for a in range(0, len(faces), per):
                yield int(n), faces[a:a + per], sel[a:a + per], xb[a:a + per]

    def _centroids(self):
        c = getattr(self, "_centroid_cache", None)
        if c is None:
            topo = self.topology
            c = np.add.reduceat(self.shapes.corners, topo.face_offsets[:-1], axis=0)
            c = c / topo.face_sizes[:, None]
            self._centroid_cache = c
        return c

    def _corner_terms(self, n, faces, xb, nu):
        """Per corner slot k: (u (F,), Psi [..], mono [..]) with derivatives to order nu.

        Psi_k (F,P), dPsi (F,P,2), HPsi (F,P,2,2); mono (F,P,M), (F,P,M,2), (F,P,M,2,2),
        all w.r.t. face coordinates.
        """
        ch = self.charts
        off = self.topology.face_offsets
        corners = off[faces][None, :] + np.arange(n)[:, None]  # (n, F)
        cb = np.broadcast_to(corners[:, :, None], (n,) + xb.shape[:2])
        pol = ch.polar(cb, xb[None], nu)
        r, th = pol[0]
        u = self.topology.face_vertices[corners]
        # gauge g = r u~(theta), u~ = 1/rho~ (eq. (62) with the smooth envelope)
        uu = eval_envelopes(self._envelopes, self._corner_env, self._env_offset, corners, th, nu)
        g = r * uu[0]
        dF = self.kernel.cdf_derivs(g, nu)
        psi = [1.0 - dF[0]]
        o = lambda a, b: a[..., :, None] * b[..., None, :]  # noqa: E731
        if nu >= 1:
            dr, dt = pol[1]
            dg = uu[0][..., None] * dr + (r * uu[1])[..., None] * dt
            psi.append(-dF[1][..., None] * dg)
        if nu >= 2:
            Hr, Ht = pol[2]
            Hg = (uu[0][..., None, None] * Hr + uu[1][..., None, None] * (o(dr, dt) + o(dt, dr))
                  + (r * uu[2])[..., None, None] * o(dt, dt) + (r * uu[1])[..., None, None] * Ht)
            psi.append(-dF[2][..., None, None] * o(dg, dg) - dF[1][..., None, None] * Hg)
        S0 = psi[0].sum(axis=0)
        with np.errstate(invalid="ignore"):  # 0/0 only in holes of the cover: refused later
            Psi = [psi[0] / S0]
        if nu >= 1:
            S1 = psi[1].sum(axis=0)
            Psi.append((psi[1] - Psi[0][..., None] * S1) / S0[..., None])
        if nu >= 2:
            S2 = psi[2].sum(axis=0)
            Psi.append((psi[2] - o(Psi[1], S1) - o(S1, Psi[1]) - Psi[0][..., None, None] * S2)
                       / S0[..., None, None])
        # local-function monomials in chart coordinates, chained to face coordinates
        if self.degree == 0:
            mono = [np.zeros(th.shape + (0,)), np.zeros(th.shape + (0, 2)),
                    np.zeros(th.shape + (0, 2, 2))][:nu + 1]
        else:
            yy = ch.to_chart(cb, xb[None], nu, pol=pol)
            mm = monomials(yy[0], self.degree, nu)
            mono = [mm[0]]
            if nu >= 1:
                mono.append(np.einsum("...mi,...ij->...mj", mm[1], yy[1]))
            if nu >= 2:
                J = yy[1]
                mono.append(np.einsum("...mik,...ij,...kl->...mjl", mm[2], J, J)
                            + np.einsum("...mi,...ijk->...mjk", mm[1], yy[2]))
        return u, Psi, mono, psi[0].max(axis=0)

    def _shared_tables(self, n, faces, xt, parts=None):
        """The distinct corner terms of faces that all have the same reference polygon
        and samples xt (P, 2) (mode "regular", lattice template).

        Then r and the in-face angle depend only on the corner slot k, psi only on
        (slot, envelope, sector start) and the monomials only on (slot, angle scale,
        sector start): each distinct combination is evaluated once, for all faces
        of the size class in one envelope/kernel evaluation per slot. ``parts``
        (slices of ``faces``, default one): the blocks the stencil is built in;
        combinations (rounded) are told apart per block, represented by their first
        corner in the block, and representatives with equal exact inputs share the
        evaluation of the first block having them (the block's first face is the
        reference of the in-face angle) -- the values a per-block evaluation with a
        memo of exact inputs gives.
        Returns (corners (n, F), [(psi table (D, P), inv (F,), mono table (D', M, P)
        or None, inv' (F,)) per slot]).
        """
        ch = self.charts
        off = self.topology.face_offsets
        corners = off[faces][None, :] + np.arange(n)[:, None]  # (n, F)
        P = len(xt)
        M = self.fits.coef.shape[1]
        parts = [slice(0, len(faces))] if parts is None else parts
        bid = np.repeat(np.arange(len(parts)), [p.stop - p.start for p in parts])
        starts = np.array([p.start for p in parts])
        tabs = []
        for k in range(n):
            ck = corners[k]
            # r and in-face angle a of the template points, per block (its first face)
            (r, th), = ch.polar(np.broadcast_to(ck[starts][:, None], (len(parts), P)),
                                xt[None], 0)
            a = th - ch.theta0[ck[starts]][:, None]
            shift = np.round(ch.theta0[ck] - self._env_offset[ck], 11)
            first, inv = _first_and_inverse(bid, self._corner_env[ck], shift)
            rep = ck[first]  # one representative corner per distinct combination
            # the exact inputs of the representatives: equal ones (from different
            # blocks) are evaluated once, in the first block that has them
            f2, inv2 = _first_and_inverse(self._corner_env[rep], ch.theta0[rep],
                                          self._env_offset[rep])
            rep, b, inv = rep[f2], bid[first[f2]], inv2[inv]
            uu = eval_envelopes(self._envelopes, self._corner_env, self._env_offset, rep,
                                ch.theta0[rep][:, None] + a[b], 0)[0]
            psi_tab = 1.0 - self.kernel.cdf_derivs(r[b] * uu, 0)[0]
            mono_tab = mono_inv = None
            if M:
                s = ch.scale[ch.corner_vertex[ck]]
                fm, mono_inv = _first_and_inverse(bid, np.round(s, 12),
                                                  np.round(ch.theta0[ck], 11))
                f2, inv2 = _first_and_inverse(s[fm], ch.theta0[ck[fm]])
                fm, mono_inv = fm[f2], inv2[mono_inv]
                b = bid[fm]
                phi = s[fm][:, None] * (ch.theta0[ck[fm]][:, None] + a[b])
                y = np.stack([r[b] * np.cos(phi), r[b] * np.sin(phi)], axis=-1)
                # stored transposed (M, P): the layout the stencil assembly multiplies
                mono_tab = np.ascontiguousarray(monomials(y, self.degree, 0)[0].transpose(0, 2, 1))
            tabs.append((psi_tab, inv, mono_tab, mono_inv))
        return corners, tabs

    def _corner_terms_shared(self, n, faces, xt, tables=None, part=slice(None)):
        """:meth:`_corner_terms` (nu = 0) from :meth:`_shared_tables`: ``tables`` made
        for a superset of faces (default: for ``faces``), ``part`` the slice of it
        that is ``faces``. The monomials are returned shared, not gathered: a list over
        the corner slots k of (table (D, M, P), inv (F,)) with mono_k of face f =
        table[inv[f]].T (the form :func:`gerbs_core.stencil.assemble_csr` takes).
        """
        corners, tabs = self._shared_tables(n, faces, xt) if tables is None else tables
        corners = corners[:, part]
        F, P = corners.shape[1], len(xt)
        psi = np.empty((n, F, P))
        mono = []  # per slot k: (table (D, M, P), inv (F,)), mono_k[f] = table[inv[f]].T
        for k, (psi_tab, inv, mono_tab, mono_inv) in enumerate(tabs):
            psi[k] = psi_tab[inv[part]]
            if mono_tab is not None:
                mono.append((mono_tab, mono_inv[part]))
        S0 = psi.sum(axis=0)
        with np.errstate(invalid="ignore"):  # 0/0 only in holes of the cover: refused later
            Psi = psi / S0
        return self.topology.face_vertices[corners], [Psi], [mono], psi.max(axis=0)

    def _template_blocks(self, lat):
        """Yield (n, faces, sel, xt, class_faces, part, per) per block of faces of one
        size: all lattice points of each face in template order (shared points once
        per face; sel = -1 where another face owns the sample), the block's slice
        ``part`` of all faces of its size and the block length ``per`` -- for
        :meth:`_shared_tables` / :meth:`_corner_terms_shared`."""
        topo = self.topology
        lo = lat.local_offsets
        for n in np.unique(topo.face_sizes).tolist():
            fk = np.flatnonzero(topo.face_sizes == n)
            P = int(lo[fk[0] + 1] - lo[fk[0]])
            xt = self._template_points(lat, fk[0])
            per = max(1, int(200000 // (P * n)))
            for a in range(0, len(fk), per):
                faces = fk[a:a + per]
                idx = lo[faces][:, None] + np.arange(P)[None, :]
                smp = lat.local_sample[idx]
                sel = np.where(lat.face[smp] == faces[:, None], smp, -1)
                yield n, faces, sel, xt, fk, slice(a, a + len(faces)), per

    def _template_points(self, lat, f):
        """Face-local coordinates of face f's lattice points in template order (the
        formulas of Lattice.map_to_polygon, for one face only)."""
        topo = self.topology
        X = self.shapes.corners[topo.face_offsets[f]:topo.face_offsets[f + 1]]
        uv, fan = lat.template_params(len(X))  # = lat.local_uv/local_fan of face f
        n = len(X)
        s, t = uv[:, :1], uv[:, 1:]
        if n == 3:
            return (1 - s - t) * X[0] + s * X[1] + t * X[2]
        if n == 4:
            return (1 - s) * (1 - t) * X[0] + s * (1 - t) * X[1] + s * t * X[2] + (1 - s) * t * X[3]
        return (1 - s - t) * X.mean(axis=0) + s * X[fan] + t * X[(fan + 1) % n]

    def _evaluate_flat(self, face_ids, x, nu):
        """S and derivatives at samples (face_ids (N,), x (N,2)); list up to order nu."""
        N = len(face_ids)
        out = [np.zeros((N, 3)), np.zeros((N, 3, 2)), np.zeros((N, 3, 2, 2))][:nu + 1]
        eps = np.inf
        X, C = self._X, self._coef
        for n, faces, sel, xb in self._groups(face_ids, x):
            u, Psi, mono, mx = self._corner_terms(n, faces, xb, nu)
            valid = sel >= 0
            eps = min(eps, float(mx[valid].min()))
            Cu = C[u]  # (n, F, M, 3)
            lval = X[u][:, :, None, :] + np.einsum("kfpm,kfmc->kfpc", mono[0], Cu)
            res = [np.einsum("kfp,kfpc->fpc", Psi[0], lval)]
            if nu >= 1:
                dl = np.einsum("kfpmj,kfmc->kfpcj", mono[1], Cu)
                res.append(np.einsum("kfpj,kfpc->fpcj", Psi[1], lval)
                           + np.einsum("kfp,kfpcj->fpcj", Psi[0], dl))
            if nu >= 2:
                Hl = np.einsum("kfpmjl,kfmc->kfpcjl", mono[2], Cu)
                res.append(np.einsum("kfpjl,kfpc->fpcjl", Psi[2], lval)
                           + np.einsum("kfpj,kfpcl->fpcjl", Psi[1], dl)
                           + np.einsum("kfpcj,kfpl->fpcjl", dl, Psi[1])
                           + np.einsum("kfp,kfpcjl->fpcjl", Psi[0], Hl))
            for o, rr in zip(out, res):
                o[sel[valid]] = rr[valid]
        self._last_eps0 = eps
        return out

    def _check_cover(self, resolution):
        from .tessellation import Lattice
        lat = Lattice(self.topology, resolution)
        x = lat.map_to_polygon(self.shapes.corners, local=True)
        self._evaluate_flat(lat.local_face, x, 0)
        return self._last_eps0

    def _require_cover(self, eps: float) -> None:
        """Refuse to return a surface with holes: where every psi_v underflows to 0
        the rational form Psi = psi / sum psi is 0/0 (NaN). Happens for kernels whose
        1 - F(t) underflows well before t = 1 (e.g. ERBS(gamma=7.389, lam=0, sigma=0))."""
        if not eps > 0.0:
            raise InvalidParameterError(
                "kernel", f"{self.kernel!r} leaves holes in the cover: every size function "
                f"psi_v = 1 - F(g_v) is 0 at some samples (1 - F(t) underflows for t < 1); "
                f"use a kernel whose F reaches 1 only near t = 1")

    def _nnz_estimate(self) -> float:
        """Non-zeros per row of W, an upper bound on average: the corners of a face
        times (1 + fit data per vertex), no sharing counted (measured 1.8-2.6x the
        real count on Suzanne, spheres, the mixed mesh)."""
        n = float(np.mean(self.topology.face_sizes))
        return n * (1.0 + float(np.mean((self.fits.ids >= 0).sum(axis=1))))

    def memory_estimate(self, resolution: int) -> int:
        """Bytes a tessellation or stencil at `resolution` is expected to need at peak
        (an upper bound: measured peaks are 0.4-0.7x of it from 10k to 1M points)."""
        from .tessellation import output_counts
        P, _ = output_counts(self.topology, resolution)
        return int(P * (_BYTES_PER_SAMPLE + _BYTES_PER_NNZ * self._nnz_estimate()) + _CHUNK_BYTES)

    def lattice(self, resolution: int):
        """The sample lattice at `resolution` (checked against the memory budget)."""
        from .tessellation import Lattice, output_counts
        P, T = output_counts(self.topology, resolution)
        est = self.memory_estimate(resolution)
        if est > self.memory_budget:
            raise ResourceLimitError(f"resolution {resolution}: {P} points, estimated memory "
                                     f"{est / 1e6:.0f} MB exceeds the budget "
                                     f"{self.memory_budget / 1e6:.0f} MB (memory_budget)")
        return Lattice(self.topology, resolution)

    # ---------------------------------------------------------------- public
    def evaluate(self, face_index, local_coords, nu: int = 0):
        """S or its nu-th derivative at points of faces, in face-local coordinates of D_f.

        face_index int or int array broadcastable against local_coords[..., 0];
        local_coords (..., 2) in the frame of :mod:`gerbs_core.face_shapes`.
        Returns (..., 3) for nu=0, dS_i/dx_j (..., 3, 2) for nu=1, (..., 3, 2, 2)
        for nu=2. Exact up to round-off (closed-form derivatives).
        """
        if nu not in (0, 1, 2):
            raise InvalidParameterError("nu", f"must be 0, 1 or 2, got {nu!r}")
        x = np.asarray(local_coords, dtype=np.float64)
        if x.shape[-1:] != (2,):
            raise InvalidParameterError("local_coords", f"must have shape (..., 2), got {x.shape}")
        f = np.broadcast_to(np.asarray(face_index), x.shape[:-1]).astype(np.int64).ravel()
        if np.any((f < 0) | (f >= self.topology.n_faces)):
            raise InvalidParameterError("face_index", "out of range")
        out = self._evaluate_flat(f, x.reshape(-1, 2), nu)[nu]
        self._require_cover(self._last_eps0)
        return out.reshape(x.shape[:-1] + out.shape[1:])

    def partition(self, face_index, local_coords, nu: int = 0):
        """The partition of unity Psi_v (eq. (73)) at face points.

        face_index (N,), local_coords (N,2). Returns (vertices (N, n), Psi (N, n),
        psi (N, n)) with n the largest face size (padding: vertex -1, values 0): the
        corners' vertices, Psi_v and the unnormalised size functions psi_v; with
        nu=1 also dPsi (N, n, 2) w.r.t. face coordinates.
        """
        x = np.asarray(local_coords, dtype=np.float64).reshape(-1, 2)
        f = np.broadcast_to(np.asarray(face_index), x.shape[:1]).astype(np.int64)
        nmax = int(self.topology.face_sizes.max())
        verts = np.full((len(f), nmax), -1, dtype=np.int64)
        Ps, ps = np.zeros((len(f), nmax)), np.zeros((len(f), nmax))
        dP = np.zeros((len(f), nmax, 2))
        for n, faces, sel, xb in self._groups(f, x):
            u, Psi, _, _ = self._corner_terms(n, faces, xb, max(nu, 0))
            pol = self.charts.polar(self.topology.face_offsets[faces][None, :, None]
                                    + np.arange(n)[:, None, None], xb[None], 0)
            valid = sel >= 0
            s = sel[valid]
            cb = self.topology.face_offsets[faces][None, :] + np.arange(n)[:, None]
            uu = eval_envelopes(self._envelopes, self._corner_env, self._env_offset, cb,
                                pol[0][1], 0)
            psi = 1.0 - self.kernel.cdf_derivs(pol[0][0] * uu[0], 0)[0]
            for k in range(n):
                verts[s, k] = np.broadcast_to(u[k][:, None], valid.shape)[valid]
                Ps[s, k] = Psi[0][k][valid]
                ps[s, k] = psi[k][valid]
                if nu >= 1:
                    dP[s, k] = Psi[1][k][valid]
        return (verts, Ps, ps, dP) if nu >= 1 else (verts, Ps, ps)

    def evaluate_all(self, face_index, local_coords, nu: int = 0):
        """[S, dS, d2S] up to order nu (shapes as in :meth:`evaluate`)."""
        x = np.asarray(local_coords, dtype=np.float64)
        f = np.broadcast_to(np.asarray(face_index), x.shape[:-1]).astype(np.int64).ravel()
        out = self._evaluate_flat(f, x.reshape(-1, 2), nu)
        return [o.reshape(x.shape[:-1] + o.shape[1:]) for o in out]

    def chart_evaluate(self, v: int, y, nu: int = 0, corner=None):
        """S o zeta_v^{-1} and its derivatives w.r.t. chart coordinates y (N, 2) of vertex v.

        corner: force the face (a corner of v's star) used for every point (one-sided
        derivatives on a spoke); default: the sector containing each point.
        Returns [S (N,3), dS/dy (N,3,2), d2S/dy2 (N,3,2,2)] up to nu.
        """
        y = np.atleast_2d(np.asarray(y, dtype=np.float64))
        topo = self.topology
        star = topo.star_corners[topo.star_offsets[v]:topo.star_offsets[v + 1]]
        c, x = self.charts.from_chart(v, y, star)
        if corner is not None:
            c = np.full(len(y), int(corner))
            s = self.charts.scale[v]
            mid = self.charts.theta0[c] + 0.5 * self.charts.alpha[c]
            phi = np.arctan2(y[:, 1], y[:, 0])
            phi = s * mid + np.angle(np.exp(1j * (phi - s * mid)))  # branch nearest the sector
            a = phi / s - self.charts.theta0[c] + self.charts.beta[c]
            r = np.hypot(y[:, 0], y[:, 1])
            x = self.charts.origin[c] + r[:, None] * np.stack([np.cos(a), np.sin(a)], -1)
        f = topo.corner_face[c]
        out = self._evaluate_flat(f, x, nu)
        if nu == 0:
            return out
        yy = self.charts.to_chart(c, x, nu, clamp=False)
        Jinv = np.linalg.inv(yy[1])  # dx/dy
        res = [out[0], np.einsum("pcj,pji->pci", out[1], Jinv)]
        if nu >= 2:
            # d2S/dy2 = Jinv^T (H_x S - sum_i dS/dy_i H_x y_i) Jinv
            Hc = out[2] - np.einsum("pci,pijk->pcjk", res[1], yy[2])
            res.append(np.einsum("pcjk,pja,pkb->pcab", Hc, Jinv, Jinv))
        return res

    def local_function(self, v: int, y, nu: int = 0):
        """l_v and its derivatives at chart points y (N,2): [(N,3), (N,3,2), (N,3,2,2)]."""
        y = np.atleast_2d(np.asarray(y, dtype=np.float64))
        if self.degree == 0:
            z = [np.broadcast_to(self._X[v], (len(y), 3)).copy(), np.zeros((len(y), 3, 2)),
                 np.zeros((len(y), 3, 2, 2))]
            return z[:nu + 1]
        mm = monomials(y, self.degree, nu)
        C = self._coef[v]
        out = [self._X[v] + mm[0] @ C]
        if nu >= 1:
            out.append(np.einsum("pmj,mc->pcj", mm[1], C))
        if nu >= 2:
            out.append(np.einsum("pmjk,mc->pcjk", mm[2], C))
        return out

    def tessellate(self, resolution: int):
        """(points (P,3), triangles (T,3) int, normals (P,3)) at `resolution` segments per edge.

        Crack-free (shared edge samples once, :class:`gerbs_core.tessellation.Lattice`);
        normals from the analytic derivatives dS/dx1 x dS/dx2 (at mesh vertices from
        the linear part of l_v; where that vanishes, e.g. degree 0, the mesh normal).
        """
        lat = self.lattice(resolution)
        x = lat.map_to_polygon(self.shapes.corners)
        S, dS = self._evaluate_flat(lat.face, x, 1)
        self._require_cover(self._last_eps0)
        nrm = np.cross(dS[..., 0], dS[..., 1])
        vs = lat.vertex_sample
        if self.degree >= 1:
            nrm[vs] = np.cross(self._coef[:, 0, :], self._coef[:, 1, :])
        ln = np.linalg.norm(nrm, axis=1)
        bad = ln <= 1e-14 * max(1.0, float(np.max(ln, initial=0.0)))
        if np.any(bad):
            fb = self._mesh_normals_at(lat, np.flatnonzero(bad))
            nrm[bad] = fb
            ln[bad] = np.linalg.norm(fb, axis=1)
        nrm /= np.where(ln > 0, ln, 1.0)[:, None]
        return S, np.array(lat.triangles), nrm

    def _mesh_normals_at(self, lat, idx):
        """Fallback normals: Newell normal of the evaluating face (vertex: sum over its star)."""
        topo, X = self.topology, self._X
        fv, nx, cf = topo.face_vertices, topo.corner_next, topo.corner_face
        fn = np.zeros((topo.n_faces, 3))
        np.add.at(fn, cf, np.cross(X[fv], X[fv[nx]]))
        vn = np.zeros((topo.n_vertices, 3))
        np.add.at(vn, fv, fn[cf])
        out = fn[lat.face[idx]]
        isv = idx < topo.n_vertices
        out[isv] = vn[idx[isv]]
        return out

    def stencil(self, resolution: int) -> Stencil:
        """Sparse W (P, V) with W @ X = tessellate(resolution)[0] for the bound charts.

        Mode "regular": W depends only on topology and settings; "metric": on the
        rest positions too. See :mod:`gerbs_core.stencil` for locality. Not available
        with vertex normals (the Hermite constraint couples the coordinates).
        """
        if self._normals is not None:
            raise InvalidParameterError("normals", "stencils need normals=None (with Hermite "
                                        "normals the surface is not W @ X)")
        lat = self.lattice(resolution)
        blocks = []
        eps = np.inf
        ids, coef = self.fits.ids, self.fits.coef
        if self.mode == "regular":  # identical reference polygons: shared template
            tables = {}  # per face size: the distinct corner terms of all its faces

            def shared(n, f, xt, fk, part, per):
                if n not in tables:
                    tables[n] = self._shared_tables(
                        n, fk, xt, [slice(a, min(a + per, len(fk))) for a in range(0, len(fk), per)])
                return self._corner_terms_shared(n, f, xt, tables[n], part)

            groups = ((n, f, sel, xt, shared(n, f, xt, fk, part, per))
                      for n, f, sel, xt, fk, part, per in self._template_blocks(lat))
        else:
            x = lat.map_to_polygon(self.shapes.corners)
            groups = ((n, f, sel, xb, self._corner_terms(n, f, xb, 0))
                      for n, f, sel, xb in self._groups(lat.face, x))
        for n, faces, sel, _, (u, Psi, mono, mx) in groups:
            eps = min(eps, float(mx[sel >= 0].min()))
            blocks.append((faces, sel, u, Psi[0], mono[0]))
        self._last_eps0 = eps
        self._require_cover(eps)
        W = assemble_csr(blocks, ids, coef, lat.n_points, self.topology.n_vertices)
        return Stencil(W, lat.triangles, lat.vertex_sample, lat)  # read-only, not copied
