"""One build of a surface through gerbs_core, and writing it into a result object.

:func:`surface_arguments`, :func:`make_model` and :func:`evaluate` run the core on a
:class:`mesh_io.MeshInput` (engine._rebuild calls them in turn) and return a
:class:`Built`: the output points, the lattice (its polygons are the output faces:
quads in quad faces, triangles elsewhere), the stencil (``points = stencil.apply(X)``,
the fast path of later edits; None with Hermite normals, whose surface is not
``W @ X``) and the map of vertex values used to carry vertex attributes (the same
stencil; with Hermite normals one assembled from the surface's own partition and
fits, made on first use). :func:`write_geometry` and :func:`write_carried` put it
into the result mesh (mesh_io, transfer, carry_write, snapshot).

The surface's model (layouts, charts, cover, fits, the fairing: most of a build's cost)
depends only on the ``BlendingSurface`` constructor's arguments, the output resolution
only on ``stencil`` / ``tessellate``. A build is therefore two steps: :func:`make_model`
(the surface, and :func:`model_key`, a digest of exactly the arguments it was constructed
with) and :func:`evaluate` (its output at one resolution). ``make_model`` reuses a held
:class:`Model` whose key is equal -- equal arguments give the same surface bit for bit --
and constructs a new one otherwise (:data:`counts` counts both, for tests).
"""
from __future__ import annotations

import time

import hashlib
import numbers
from collections import Counter
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


@dataclass(frozen=True, eq=False)
class Model:
    """A constructed ``BlendingSurface`` and :func:`model_key` of its arguments (None: an
    argument the key cannot digest; such a model is never reused)."""

    key: str | None
    surface: object
    seconds: float = 0.0  # what constructing the surface took (a reuse takes none)


counts: Counter = Counter()  # "built": BlendingSurfaces constructed, "reused": held ones reused


class _Undigestable(TypeError):
    pass


def _feed(h, value) -> None:
    """Feed `value` into hash `h`, typed and delimited, so that unequal values (or equal
    values of another type, dtype or shape) feed different bytes."""
    from .core import module

    if value is None:
        h.update(b"N;")
    elif isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        h.update(f"A{a.dtype.str}{a.shape};".encode())
        h.update(a.tobytes())
    elif isinstance(value, (bool, np.bool_)):
        h.update(b"B1;" if value else b"B0;")
    elif isinstance(value, numbers.Integral):
        h.update(f"I{type(value).__name__}:{int(value)};".encode())
    elif isinstance(value, numbers.Real):
        h.update(f"F{type(value).__name__}:{float(value).hex()};".encode())
    elif isinstance(value, str):
        data = value.encode()
        h.update(f"S{len(data)}:".encode() + data)
    elif isinstance(value, (list, tuple)):
        h.update(f"{'L' if isinstance(value, list) else 'T'}{len(value)}(".encode())
        for item in value:
            _feed(h, item)
        h.update(b")")
    elif isinstance(value, dict):
        h.update(f"D{len(value)}(".encode())
        for key in sorted(value):
            _feed(h, key)
            _feed(h, value[key])
        h.update(b")")
    elif isinstance(value, module("kernels").Kernel):
        # kernels are immutable value objects identified by type and parameters (their
        # own == and hash)
        kind = type(value)
        h.update(f"K{kind.__module__}.{kind.__qualname__}".encode())
        _feed(h, tuple(value._params()))
    else:
        raise _Undigestable(type(value).__name__)


def model_key(arguments: dict) -> str | None:
    """A digest of `arguments`, the ``BlendingSurface`` keyword arguments: arrays by dtype,
    shape and bytes, scalars, strings and kernels by type and value. Equal keys, equal
    arguments; None if an argument is of a type it does not know (never reused)."""
    h = hashlib.blake2b(digest_size=20)
    try:
        _feed(h, arguments)
    except _Undigestable:
        return None
    return h.hexdigest()


def surface_arguments(settings: dict, inp, creases=None, rest=None) -> dict:
    """Every argument of the ``BlendingSurface`` of `inp` with `settings` (keywords):
    `creases`: :class:`blender_addon.creases.Creases` (None: none); `rest`: (V, 3) the rest
    shape it is bound to (Rest Shape Bound, rest.py; None: `inp`'s positions)."""
    args = settings_mod.core_arguments(settings)
    normals = None if inp.normals is None else inp.normals.astype(np.float64)
    crease_args = creases.core_arguments() if creases is not None else {}  # creases.py
    return dict(vertices=inp.positions.astype(np.float64), faces=inp.faces(),
                kernel=args.kernel, normals=normals, rest_positions=rest, **args.surface,
                **crease_args)


def make_model(arguments: dict, held=()) -> Model:
    """The surface of `arguments` (:func:`surface_arguments`): the first of the `held`
    models (:class:`Model` or None) with an equal key, else a new one (raises GERBSError)."""
    from .core import module, scipy_problem
    from .errors import MissingDependencyError

    key = model_key(arguments)
    if key is not None:
        for model in held:
            if model is not None and model.key == key:
                counts["reused"] += 1
                return model
    if problem := scipy_problem():  # a message in the panel and status bar, not a traceback
        raise MissingDependencyError(problem)
    t0 = time.perf_counter()
    surface = module("mesh.surface").BlendingSurface(**arguments)
    counts["built"] += 1
    return Model(key, surface, time.perf_counter() - t0)


def evaluate(model: Model, arguments: dict, resolution: int, progress) -> Built:
    """The output of `model`'s surface (made from `arguments`) at `resolution` (raises
    GERBSError, e.g. a resolution over the memory budget)."""
    surface, X = model.surface, arguments["vertices"]
    if arguments["normals"] is not None:  # Hermite normals: not W @ X (no stencil)
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
