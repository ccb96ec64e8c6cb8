"""A warning where the surface bulges far beyond its cage (a thin part: a board, a plank, a
coin).

The local functions are polynomials over each vertex's star. Where a part of the cage is
much thinner than its faces are long (Blender's Cube scaled to a 2 x 2 x 0.2 board, the
Cylinder as a 0.2 thick coin), no such polynomial turns through 90 degrees within the
star, and the surface swells to 2.4-3.3x the part's thickness (docs/design.md, "Known
limits"). That is a limit of the construction, not of the input, so the surface is built
and the user is told what to do: a bevel of 2-3 segments on the edges keeps a board within
1.6x (the bevelled box's faces become fillet sides, :mod:`gerbs_core.mesh.fillets`).

The check reads the surface on its lattice at resolution 4 (the add-on's default; 20 ms
on Suzanne, 0.12-0.2 s on the cow, bunny10k and the airplane, 3-9% of their builds), at 2
where that would exceed ``MAX_POINTS`` samples: the faces' centroids alone miss bulges
that peak elsewhere (a board with two top corners raised: 2.14x at r = 4, 1.81x at r = 2).
"""
from __future__ import annotations

import numpy as np

from .lattice import output_counts
from .repair import MeshWarning

__all__ = ["BULGE", "SIGNIFICANT", "MAX_POINTS", "thin_part_samples", "thin_part_warning"]

BULGE = 2.0         # warn where the surface's extent exceeds BULGE x the cage's on an axis
SIGNIFICANT = 0.05  # ... by more than SIGNIFICANT x the cage's largest extent (not a sheet)
MAX_POINTS = 100_000  # the most samples read at resolution 4 (else at 2)


def thin_part_samples(surface) -> tuple:
    """(lattice, (N, 3) its points) of a :class:`gerbs_core.mesh.surface.BlendingSurface` at
    resolution 4, or 2 where that has more than MAX_POINTS points or exceeds the surface's
    memory budget; (None, (0, 3)) where 2 exceeds it too (nothing is read: no warning). The
    self-crossing check (:mod:`gerbs_core.mesh.self_crossing`) reads the same samples."""
    for r in (4, 2):
        if (r == 2 or output_counts(surface.topology, r)[0] <= MAX_POINTS) \
                and surface.memory_estimate(r) <= surface.memory_budget:
            lat = surface.lattice(r)
            # the lattice's own points (in their faces: no check needed)
            return lat, surface._evaluate_at(lat.face, lat.map_to_polygon(
                surface.layouts.corners), 0, (lat.n_points,))[0]
    return None, np.empty((0, 3))


def thin_part_warning(cage, surface_points):
    """A ``thin_part`` :class:`gerbs_core.mesh.repair.MeshWarning` (no indices) or None.

    cage (V, 3) the positions; surface_points (N, 3) points of the surface
    (:func:`thin_part_samples`). Warns where on some axis the points' extent (with the
    cage's) exceeds ``BULGE`` times the cage's and the excess is more than ``SIGNIFICANT``
    of the cage's largest extent (a slightly wavy sheet, whose cage is flat but for a small
    height, does not warn)."""
    C = np.asarray(cage, dtype=np.float64)
    S = np.concatenate([C, np.asarray(surface_points, dtype=np.float64).reshape(-1, 3)])
    cage_ext, ext = np.ptp(C, axis=0), np.ptp(S, axis=0)
    big = cage_ext.max()
    excess = ext - cage_ext
    bad = np.flatnonzero((ext > BULGE * cage_ext) & (excess > SIGNIFICANT * big))
    if not len(bad) or not np.isfinite(ext).all():
        return None
    k = int(bad[np.argmax(ext[bad] / np.maximum(cage_ext[bad], 1e-300))])
    ratio = ext[k] / cage_ext[k] if cage_ext[k] > 0 else np.inf
    return MeshWarning(
        "thin_part",
        f"the surface reaches {ratio:.1f}x the cage's extent along {'xyz'[k]} (the mesh's "
        f"own axes): where faces "
        f"are much longer than the part is thick (a board, a coin, a tower), the local "
        f"functions cannot turn 90 degrees within them; bevelling the edges (2-3 segments; in "
        f"Blender a Bevel modifier above this one in the stack) keeps the surface near the "
        f"cage",
        (), "face")
