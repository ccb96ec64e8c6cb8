"""C-infinity GERBS blending surfaces through the vertices of a polygon mesh.

    S(p) = sum_v Psi_v(p) l_v(zeta_v(p)),   Psi_v = psi_v / sum_u psi_u   (eq. (27), B = Psi by eq. (73))

The stages, each its own module of :mod:`gerbs_core.mesh`: topology and
geometry checks -> face layouts with the rest edge lengths (:mod:`.layout`) ->
vertex charts (:mod:`.charts`) -> the star cover of smooth size functions
(:mod:`.cover`) -> data rings and candidate fits (:mod:`.rings`, :mod:`.fits`)
-> the choice and coupling that make neighbouring local functions agree
(:mod:`.agreement`) -> the fairing that bounds how sharply the surface turns
(:mod:`.fairing`) -> evaluation (:mod:`.evaluate`), tessellation
(:mod:`.lattice`) and stencils (:mod:`.stencil`). docs/design.md describes the
design and the measurements behind it.

Exact: everything is closed form up to round-off, except the kernel's F (tabulated to
~1e-13, :mod:`gerbs_core.kernels`) and the fairing's weights (where its optimiser stops,
:mod:`.fairing`; the output is still exactly linear in X). Near every vertex Psi_v = 1,
so S = l_v there and S(v) = X_v.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import InvalidParameterError, ResourceLimitError
from ..immutable import Immutable
from ..inputs import check_index, is_integer
from ..kernels.base import check_order
from ..kernels.names import as_kernel
from .agreement import MMAX, FairnessRule, fair_fits
from .charts import vertex_charts
from .coupling import SelectedFits
from .cover import require_cover, star_cover
from .crease_surface import build_model, crease_input, first_occurrence, merge_tessellation
from .evaluate import evaluate, partition_at
from .fairing import FairedFits, FairingSkipped, ring1_pairs, turn_correction
from .lattice import Lattice, output_counts
from .lattice_templates import obtuse_flips
from .layout import face_layouts
from .memory import (BUILD_MIN_BUDGET, assembly_chunk, check_build, evaluation_chunk,
                     fairing_estimate, megabytes, memory_estimate)
from .monomials import monomials
from .repair import MeshWarning, repair_mesh
from .rings import data_rings
from .stencil import Stencil
from .surface_inputs import (chart_points, check_settings, face_points, points, positive,
                             unit_normals)
from .self_crossing import self_crossing_warning, surface_crossings
from .thin_parts import thin_part_samples, thin_part_warning
from .topology import MeshTopology
from .validation import check_finite

__all__ = ["BlendingSurface", "SurfaceModel"]


@dataclass(frozen=True)
class SurfaceModel:
    """Everything of a surface that is fixed by the topology, the rest shape and the
    settings (built once; shared by every surface made with :meth:`BlendingSurface.with_positions`).

    degrees (V,) the local functions' degrees; fits their coefficients as a linear map of
    the positions (:class:`gerbs_core.mesh.coupling.CoupledFits`: ``fits(X)``, and the
    explicit ``operator`` (V MMAX, V), made on first use). With creases
    (:class:`gerbs_core.mesh.creases.CreaseCut` ``crease``) ``topology`` is the cut mesh and
    the per-vertex arrays index its vertex copies (``crease.copy_of``).
    """

    topology: MeshTopology
    layouts: object
    charts: object
    cover: object
    degrees: np.ndarray
    fits: object
    boundary: str
    crease: object = None
    fairing_points: int = 0     # the lattice points the fairing looked at (memory estimates)

    @property
    def operator(self):
        """The coefficients' operator (V MMAX, V) (csr; made on first use)."""
        return self.fits.operator

    @property
    def max_degree(self) -> int:
        return int(self.degrees.max())


def faired(model: SurfaceModel, rest, h, rule: FairnessRule, budget: float):
    """(``model`` with its fits corrected where its surface turns too sharply on the rest
    shape (:mod:`gerbs_core.mesh.fairing`), the same model where it nowhere does; a
    ``fairing_skipped`` warning or None)."""
    from dataclasses import replace

    from .spread_fits import star_spread

    try:
        corr, points = turn_correction(model, rest, h, ring1_pairs(model.topology), rule,
                                       star_spread(model.topology, rest), budget)
    except FairingSkipped as skip:
        return model, MeshWarning(
            "fairing_skipped", f"the surface is not faired: the {skip.points} lattice points "
            f"of its sharply turning faces would need about {megabytes(fairing_estimate(skip.points))}, "
            f"over the build's limit (memory_budget, at least {megabytes(BUILD_MIN_BUDGET)})",
            (), "face")
    if corr is not None:
        model = replace(model, fits=FairedFits(model.fits, corr))
    return replace(model, fairing_points=points), None


class BlendingSurface(Immutable):
    """GERBS blending surface of a polygon mesh (triangles, quads, n-gons; boundaries).

    Parameters
    ----------
    vertices : (V, 3) positions. faces : list of int sequences, (F, k) array or a
        :class:`~gerbs_core.mesh.topology.MeshTopology`.
    kernel : the GERBS kernel of the size functions (default ``ERBS()``), or its name
        (``"erbs"``, ``"bfbs"``, ``"logistic"``, ``"affine"``: default parameters;
        :func:`gerbs_core.kernels.as_kernel`).
    rest_positions : (V, 3) the rest shape the layouts and fits are bound to
        (default: ``vertices``); the output is a fixed sparse linear function of the
        positions for a fixed topology and rest shape (:meth:`stencil`).
    boundary : ``"keep"`` (boundary vertices keep their angles: a flat mesh stays
        in its plane; a mesh one face wide bulges in it, a single square by 0.6%) or ``"straighten"`` (the border passes smoothly through
        boundary vertices; mesh corners get rounded).
    normals : optional (V, 3) vertex normals as Hermite data: the tangent plane of l_v
        is orthogonal to n_v (the surface is then not W @ X: no stencil). Finite at
        the vertices the repair keeps; a zero row means no normal at that vertex (a
        ``zero_normal`` warning names it).
    fairness : :class:`~gerbs_core.mesh.agreement.FairnessRule` (the measured default).
    kappa, shrink : envelope parameters of the star cover (:mod:`gerbs_core.gauge.envelope`).
    exact_gauge : the exact (kinked) star radius: a deliberately non-smooth variant,
        the control of the smoothness tests.
    memory_budget : bytes a tessellation or stencil may use (ResourceLimitError beyond).
        The construction itself is checked against the larger of it and 2 GB before it
        allocates (:func:`gerbs_core.mesh.memory.check_build`: faces of many corners cost
        memory as the cube of their size; a 512-gon is refused, not run into the
        machine's memory).
    eps0_resolution : lattice resolution of the cover-thickness check :attr:`eps0`.
    merge_distance : None (default) or a distance: weld vertices closer than it first.
    creases : optional edge crease weights in [0, 1] (Blender's ``crease_edge``) on INPUT
        vertex pairs: a mapping {(i, j): w} or a pair (edges (K, 2) int, weights (K,)).
        A weight of 1 cuts the surface along the edge: a crease curve through its vertices,
        C0 with a normal jump; chains of such edges give smooth crease curves, their ends
        and vertices with >= 3 of them are corners. Partial weights make the surface near
        the edge proportionally tighter (still C-infinity). :mod:`gerbs_core.mesh.creases`.
    corners : optional (V,) input vertex crease weights in [0, 1] (``crease_vert``): 1 makes
        a crease chain through the vertex a corner; any weight tightens the surface there.
        Both map through the repair (``vertex_map``; :mod:`gerbs_core.mesh.crease_surface`).

    Any mesh is first repaired into an oriented 2-manifold (:mod:`gerbs_core.mesh.repair`:
    bow-ties, non-manifold edges, loose, degenerate and duplicate elements); the surface
    is that of the repaired mesh: :attr:`vertices` (V', 3), :attr:`topology`, the output's
    first V' samples are its vertices, :attr:`vertex_map` / :attr:`face_map` lead back to
    the input and :attr:`warnings` say what was repaired. Positions passed in
    (``vertices``, ``rest_positions``, ``normals``, :meth:`with_positions`,
    ``stencil().apply``) are the input's (V, 3).

    With creases the per-vertex arrays (:attr:`degrees`, :attr:`coefficients`,
    :attr:`charts`, :meth:`local_function`, :meth:`chart_evaluate`) index the vertex
    copies of the cut mesh (``model.crease.copy_of`` maps them to repaired vertices);
    outputs (:meth:`tessellate`, :meth:`stencil`, :meth:`lattice`) are on the repaired mesh.

    Raises InvalidMeshError (what no surface can come from: NaN, empty, ...) or
    InvalidParameterError; the caller's arrays are never modified. Immutable.
    """

    def __init__(self, vertices, faces, kernel=None, rest_positions=None, boundary: str = "keep",
                 normals=None, *, fairness: FairnessRule | None = None, kappa: float = 0.8,
                 shrink: float = 0.95, exact_gauge: bool = False, memory_budget: float = 2.0e9,
                 eps0_resolution: int = 6, merge_distance: float | None = None,
                 creases=None, corners=None):
        X = points("vertices", vertices)
        rest = None if rest_positions is None else points("rest_positions", rest_positions, len(X))
        self.repair = repair_mesh(X, faces, merge_distance=merge_distance, rest_positions=rest)
        X, topo = np.array(self.repair.vertices), self.repair.topology
        rest = X if rest is None else np.array(self.repair.rest)
        kernel = as_kernel(kernel)
        fairness = check_settings(boundary, kappa, shrink, fairness)
        self.memory_budget = positive("memory_budget", memory_budget)
        self.eps0_resolution = positive("eps0_resolution", eps0_resolution, integer=True, lo=1,
                                        closed=True)
        self.kernel = kernel
        self._normals, normal_warning = (None, None) if normals is None else \
            unit_normals(normals, len(self.repair.representative), self.repair.vertex_map)
        self._warnings = self.repair.warnings + ((normal_warning,) if normal_warning else ())
        check_build(topo.face_sizes, self.memory_budget)
        cut = crease_input(self.repair, faces, creases, corners)
        if cut is None:
            layouts = face_layouts(topo, rest)
            charts = vertex_charts(topo, layouts.corners, layouts.angles, boundary)
            cover = star_cover(topo, charts, layouts.corners, kernel, kappa, shrink, exact_gauge)
            rings = data_rings(topo, charts, layouts.corners)
            check_build(topo.face_sizes, self.memory_budget, len(rings.ids))
            degrees, fits = fair_fits(topo, charts, layouts.corners, cover, rings, rest, fairness)
            degrees.flags.writeable = False
            model = SurfaceModel(topo, layouts, charts, cover, degrees, fits, boundary)
            self.model, skipped = faired(model, rest, rings.h, fairness, self.memory_budget)
            if skipped is not None:
                self._warnings += (skipped,)
        else:
            parts = build_model(topo, rest, cut, kernel, boundary, fairness, kappa, shrink,
                                exact_gauge, self.memory_budget)
            self.model = SurfaceModel(cut.topology, *parts, boundary, cut)
        self._X = X
        self._X.flags.writeable = False
        self._coef = self._coefficients(X)
        self._freeze()

    # ------------------------------------------------------------------ data
    @property
    def _Xm(self):
        """Positions of the model's vertices (the copies of the cut mesh with creases)."""
        cut = self.model.crease
        return self._X if cut is None else cut.positions(self._X)

    def _coefficients(self, X):
        """(V, MMAX, 3) coefficients of the local functions for positions X; with Hermite
        normals the linear part is projected onto the planes orthogonal to them."""
        cut = self.model.crease
        C = self.model.fits(X if cut is None else cut.positions(X)).reshape(-1, MMAX, 3)
        if self._normals is not None:
            n = self._normals if cut is None else self._normals[cut.copy_of]
            C[:, :2] -= np.einsum("vmk,vk->vm", C[:, :2], n)[..., None] * n[:, None, :]
        C.flags.writeable = False
        return C

    @property
    def topology(self) -> MeshTopology:
        """The repaired mesh's topology (with creases: before the cut)."""
        cut = self.model.crease
        return self.model.topology if cut is None else cut.original

    @property
    def layouts(self):
        """Face layouts (:class:`gerbs_core.mesh.layout.FaceLayouts`)."""
        return self.model.layouts

    @property
    def charts(self):
        return self.model.charts

    @property
    def degrees(self) -> np.ndarray:
        """(V,) degree of each vertex's local function (chosen, :mod:`.agreement`)."""
        return self.model.degrees

    @property
    def boundary(self) -> str:
        return self.model.boundary

    def __repr__(self) -> str:
        T = self.topology
        return (f"BlendingSurface(vertices={T.n_vertices}, faces={T.n_faces}, "
                f"kernel={self.kernel!r}, boundary={self.boundary!r})")

    @property
    def vertices(self) -> np.ndarray:
        """(V', 3) positions of the repaired mesh's vertices (= input[vertex_map])."""
        return self._X.copy()

    @property
    def vertex_map(self) -> np.ndarray:
        """(V',) the input vertex of each vertex of the surface (and output vertex sample)."""
        return self.repair.vertex_map

    @property
    def face_map(self) -> np.ndarray:
        """(F',) the input face of each face of :attr:`topology`."""
        return self.repair.face_map

    @property
    def warnings(self) -> tuple:
        """What the repair changed (:class:`gerbs_core.mesh.repair.MeshWarning`, ordered),
        then the kept vertices given a zero normal (tag ``zero_normal``, no Hermite normal
        there), a skipped fairing (``fairing_skipped``), a surface bulging far beyond its
        cage (``thin_part``, :mod:`gerbs_core.mesh.thin_parts`) and one passing through
        itself where the cage does not (``self_crossing``, naming the input faces:
        :mod:`gerbs_core.mesh.self_crossing`); the last two read on first access from the
        surface at resolution 4, or 2 on a large mesh."""
        return self._warnings + self._surface_warnings

    @cached_property
    def _surface_warnings(self) -> tuple:
        """The warnings about the surface itself, read on one lattice: ``thin_part`` and
        ``self_crossing`` (:mod:`gerbs_core.mesh.self_crossing`, naming input faces)."""
        lat, S = thin_part_samples(self)
        out = [thin_part_warning(self._X, S)]
        if lat is not None:
            pairs = surface_crossings(self.topology, self._X, S, lat.triangles,
                                      lat.triangle_face)
            out.append(self_crossing_warning(pairs, np.asarray(self.face_map)[
                np.asarray(lat.triangle_face)]))
        return tuple(w for w in out if w is not None)

    @property
    def coefficients(self) -> np.ndarray:
        """(V, M, 3) read-only coefficients of the local functions (graded monomials)."""
        return self._coef

    def with_positions(self, vertices) -> "BlendingSurface":
        """The surface of new input positions (V, 3) with the same binding (model shared).
        Refused as the constructor refuses them: InvalidParameterError (shape),
        InvalidMeshError ``non_finite`` naming the rows with NaN or infinite coordinates."""
        new = object.__new__(BlendingSurface)
        new.__dict__.update({k: v for k, v in self.__dict__.items()
                             if k not in ("eps0", "_surface_warnings")})
        X = points("vertices", vertices, len(self.repair.representative))
        check_finite(X, "vertices")
        new._cache("_X", self.repair.positions(X))
        new._X.flags.writeable = False
        new._cache("_coef", new._coefficients(new._X))
        return new

    # ------------------------------------------------------------ the cover
    @cached_property
    def eps0(self) -> float:
        """min over a check lattice (every lattice point of every face, resolution
        ``eps0_resolution``) of max_v psi_v: the thickness of the cover (Definition 11);
        > 0 means no point is left uncovered."""
        lat = Lattice(self.model.topology, self.eps0_resolution)
        x = lat.map_to_polygon(self.layouts.corners, local=True)
        return self._evaluate(lat.local_face, x, 0)[1]

    def _require_cover(self, eps: float) -> None:
        require_cover(eps, self.kernel)

    def _evaluate(self, f, x, nu):
        return evaluate(self.model, self._Xm, self._coef, f, x, nu,
                        evaluation_chunk(self.memory_budget, nu))

    # ---------------------------------------------------------------- public
    def evaluate_all(self, face_index, local_coords, nu: int = 0):
        """[S (..., 3), dS (..., 3, 2), d2S (..., 3, 2, 2)] up to nu at points of faces, in
        face layout coordinates (:mod:`gerbs_core.mesh.layout`); exact to round-off."""
        nu = check_order(nu, 2, owner="the surface")
        f, x, shape = self._face_points(face_index, local_coords)
        return self._evaluate_at(f, x, nu, shape)

    def _evaluate_at(self, f, x, nu, shape):
        """:meth:`evaluate_all` at checked points: faces f (N,), their points x (N, 2) (the
        package's own lattices and charts, known to lie in their faces)."""
        out, eps = self._evaluate(f, x, nu)
        self._require_cover(eps)
        return [o.reshape(tuple(shape) + o.shape[1:]) for o in out]

    def evaluate(self, face_index, local_coords, nu: int = 0):
        """S (nu = 0, (..., 3)) or its nu-th derivative w.r.t. the layout coordinates."""
        return self.evaluate_all(face_index, local_coords, nu)[nu]

    def partition(self, face_index, local_coords, nu: int = 0):
        """The partition of unity (eq. (73)) at face points: (vertices (N, n), Psi (N, n),
        psi (N, n)) with n the largest face size (padding: vertex -1, values 0); with
        nu = 1 also dPsi (N, n, 2)."""
        nu = check_order(nu, 1, owner="the partition")
        f, x, _ = self._face_points(face_index, local_coords)
        return partition_at(self.model, f, x, nu)

    def _face_points(self, face_index, local_coords):
        """(faces (N,), points (N, 2), leading shape): checked, every point in its face's
        layout polygon (:func:`surface_inputs.face_points`)."""
        topo = self.model.topology
        return face_points(face_index, local_coords, topo.n_faces,
                           (self.layouts.corners, topo.face_offsets))

    def local_function(self, v: int, y, nu: int = 0):
        """l_v and its derivatives at chart points y (N, 2): [(N,3), (N,3,2), (N,3,2,2)]."""
        v = check_index("v", v, len(self.degrees))
        nu = check_order(nu, 2, owner="a local function")
        y = chart_points(y)
        d = int(self.degrees[v])
        mm = monomials(y, d, nu)
        C = self._coef[v, :mm[0].shape[-1]]
        out = [self._Xm[v] + mm[0] @ C]
        if nu >= 1:
            out.append(np.einsum("pmj,mc->pcj", mm[1], C))
        if nu >= 2:
            out.append(np.einsum("pmjk,mc->pcjk", mm[2], C))
        return out

    def chart_evaluate(self, v: int, y, nu: int = 0, corner=None):
        """S o zeta_v^{-1} and its derivatives w.r.t. chart coordinates y (N, 2) of vertex v.

        corner: force the face (a corner of v's star) used for every point (one-sided
        derivatives on a spoke); default: the sector containing each point.
        """
        from .chart_eval import chart_evaluate
        topo = self.model.topology
        v = check_index("v", v, topo.n_vertices)
        nu = check_order(nu, 2, owner="the surface")
        if corner is not None:
            star = topo.star_corners[topo.star_offsets[v]:topo.star_offsets[v + 1]]
            if not is_integer(corner) or int(corner) not in set(star.tolist()):
                raise InvalidParameterError("corner", f"must be a corner of vertex {v}'s star "
                                            f"{sorted(star.tolist())}, got {corner!r}")
        return chart_evaluate(self, v, chart_points(y), nu, corner)

    # ---------------------------------------------------------- tessellation
    def memory_estimate(self, resolution: int) -> int:
        """Bytes a tessellation or stencil at `resolution` is expected to need at peak (its
        steps sized for :attr:`memory_budget`, :mod:`gerbs_core.mesh.memory`)."""
        return memory_estimate(self.model, resolution, self.memory_budget)

    def lattice(self, resolution: int):
        """The sample lattice at `resolution` (checked against the memory budget); triangles
        with a layout corner above ``lattice_templates.FLIP_ANGLE`` triangulated for it."""
        P, _ = output_counts(self.topology, resolution)
        est = self.memory_estimate(resolution)
        if est > self.memory_budget:
            raise ResourceLimitError(f"resolution {resolution}: {P} points, estimated memory "
                                     f"{megabytes(est)} exceeds the budget "
                                     f"{megabytes(self.memory_budget)} (memory_budget)")
        return Lattice(self.topology, resolution,
                       flip=obtuse_flips(self.topology, self.layouts.angles))

    def tessellate(self, resolution: int):
        """(points (P,3), triangles (T,3) int, normals (P,3)) at `resolution` segments per edge.

        Crack-free (shared edge samples once); normals from the analytic derivatives
        dS/dx1 x dS/dx2 (at mesh vertices from the linear part of l_v). With full creases
        the two sides of a cut edge are evaluated separately and their samples merged (the
        same points to rounding); the normals there are the mean of the two sides'.
        """
        lat = self.lattice(resolution)
        cut = self.model.crease
        mlat = lat if cut is None else Lattice(self.model.topology, resolution)
        x = mlat.map_to_polygon(self.layouts.corners)
        (S, dS), eps = self._evaluate(mlat.face, x, 1)
        self._require_cover(eps)
        nrm = np.cross(dS[..., 0], dS[..., 1])
        nrm[mlat.vertex_sample] = np.cross(self._coef[:, 0, :], self._coef[:, 1, :])
        ln = np.linalg.norm(nrm, axis=1)
        nrm /= np.where(ln > 0, ln, 1.0)[:, None]
        if mlat is not lat:
            S, nrm = merge_tessellation(cut, mlat, lat, S, nrm)
        return S, np.array(lat.triangles), nrm

    def stencil(self, resolution: int) -> Stencil:
        """The output points at `resolution` as a linear map of the input positions X (V, 3)
        (:class:`gerbs_core.mesh.stencil.Stencil`): ``stencil.apply(X) ==
        tessellate(resolution)[0]``. Not available with Hermite normals."""
        if self._normals is not None:
            raise InvalidParameterError("normals", "stencils need normals=None (with Hermite "
                                        "normals the surface is not a linear map of X)")
        return self.value_stencil(resolution)

    def value_stencil(self, resolution: int) -> Stencil:
        """The same linear map without the Hermite normals' projection (with normals=None
        exactly :meth:`stencil`): carries vertex values (V, k) to the output points,
        equal at the vertices, through the surface's own partition and fits."""
        from .assembly import assemble
        lat = self.lattice(resolution)
        cut = self.model.crease
        chunk = assembly_chunk(self.memory_budget, int(self.model.topology.face_sizes.max()))
        if cut is None:
            base, mono, eps = assemble(self.model, lat, chunk)
            fits = self.model.fits
        else:
            mlat = Lattice(self.model.topology, resolution)
            base, mono, eps = assemble(self.model, mlat, chunk)
            rows = first_occurrence(cut.sample_map(mlat), lat.n_points)
            # merged crease samples: one row each; the columns of a vertex's copies summed
            base, mono = base[rows] @ cut.copy_matrix, mono[rows]
            fits = SelectedFits(self.model.fits, cut.copy_of, cut.original.n_vertices)
        self._require_cover(eps)
        return Stencil(self.repair.to_input(base), mono, self.repair.fits_of_input(fits), lat)
