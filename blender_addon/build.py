"""One build of a surface through gerbs_core, and writing it into a result object.

:func:`build_surface` runs the core on a :class:`mesh_io.MeshInput` and returns a
:class:`Built`: the output points, the lattice (its polygons are the output faces:
quads in quad faces, triangles elsewhere), the stencil (``points = stencil.apply(X)``,
the fast path of later edits; None with Hermite normals, whose surface is not
``W @ X``) and the map of vertex values used to carry vertex attributes (the same
stencil; with Hermite normals one assembled from the surface's own partition and
fits, made on first use). :func:`write_geometry` and :func:`write_carried` put it
into the result mesh (mesh_io, transfer, carry_write, snapshot).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import carry_write, mesh_io, snapshot
from . import geometry_nodes as gn
from . import settings as settings_mod
from .transfer import Transfer


class _LazyValues:
    """The surface's linear map of vertex values when the points themselves are not one
    (Hermite normals): ``BlendingSurface.value_stencil``, made on first use."""

    def __init__(self, surface, lattice):
        self.surface, self.lattice, self._stencil = surface, lattice, None

    def apply(self, values):
        if self._stencil is None:
            self._stencil = self.surface.value_stencil(self.lattice.resolution)
        return self._stencil.apply(values)


@dataclass
class Built:
    points: np.ndarray  # (P, 3) float64
    lattice: object  # gerbs_core.mesh.lattice.Lattice (of the repaired mesh)
    stencil: object  # Stencil or None (Hermite normals)
    values: object  # .apply(values (V, k) of the input's vertices) -> (P, k)
    surface: object  # the BlendingSurface (its repair maps output elements to the input's)


def build_surface(settings: dict, inp, resolution: int, progress, creases=None,
                  rest=None) -> Built:
    """The surface of `inp` with `settings` at `resolution` (raises GERBSError);
    `creases`: :class:`blender_addon.creases.Creases` (None: none); `rest`: (V, 3) the rest
    shape it is bound to (Rest Shape Bound, rest.py; None: `inp`'s positions)."""
    from .core import module, scipy_problem
    from .errors import MissingDependencyError

    if problem := scipy_problem():  # a message in the panel and status bar, not a traceback
        raise MissingDependencyError(problem)
    BlendingSurface = module("mesh.surface").BlendingSurface

    args = settings_mod.core_arguments(settings)
    X = inp.positions.astype(np.float64)
    normals = None if inp.normals is None else inp.normals.astype(np.float64)
    progress(0.05, "building surface")
    crease_args = creases.core_arguments() if creases is not None else {}
    surface = BlendingSurface(X, inp.faces(), kernel=args.kernel, normals=normals,
                              rest_positions=rest, **args.surface,
                              **crease_args)  # creases: creases.py
    if normals is not None:  # Hermite normals: not W @ X (the core refuses a stencil)
        progress(0.35, "evaluating surface")
        P = surface.tessellate(resolution)[0]
        lattice = surface.lattice(resolution)
        return Built(P, lattice, None, _LazyValues(surface, lattice), surface)
    progress(0.35, "building stencil")
    stencil = surface.stencil(resolution)
    return Built(stencil.apply(X), stencil.lattice, stencil, stencil, surface)


def write_geometry(mesh, built: Built, previous: Transfer | None, inp) -> Transfer:
    """Points and faces of the result mesh (only the points when `previous`, the maps of
    the last build into this mesh, has the same faces); returns the new maps."""
    if previous is not None and np.array_equal(previous.corners, built.lattice.polygons()[1]) \
            and len(mesh.vertices) == len(built.points):
        mesh_io.write_positions(mesh, built.points)  # e.g. a new kernel: same output faces
        out_edges = previous.out_edges
    else:
        offsets, corners, _, _ = built.lattice.polygons(quads=True)
        edges = built.lattice.edges(quads=True)  # None: Blender computes them, no edge map
        mesh_io.write_surface(mesh, built.points, offsets, corners, edges=edges)
        out_edges = len(edges[0]) if edges is not None else None
    return Transfer(built.lattice, True, built.values, inp, out_edges, built.surface.repair)


def write_carried(res, mod, transfer: Transfer, inp, record) -> str:
    """The carried layers of `inp` on result object `res`, its record and the names;
    returns the record's stamp (snapshot.stamp)."""
    carried = inp.carried
    carry_write.write_layers(res, [transfer.layer(layer) for layer in carried.layers], carried)
    stamp = snapshot.write_snapshot(res.data, inp, record)
    if gn.set_names(mod, snapshot.layer_table(carried)[0]):
        # writing the modifier's property tags nothing: without the tag the depsgraph's
        # second pass re-evaluates the object (its result changed) with the old names in
        # its evaluated copy of the modifier, finds the new record's layers unnamed and
        # shows the input (a layer added with a move in Edit Mode did until the next edit)
        mod.id_data.update_tag()
    res.data.update()
    return stamp
