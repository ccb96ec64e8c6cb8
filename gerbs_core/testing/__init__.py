"""Measuring instruments for tests and benchmarks (numpy + scipy only, never bpy).

:mod:`gerbs_core.testing.fairness`: shape metrics of triangle meshes (dihedral
angles, folds, discrete normals, cotangent mean curvature, bounding boxes,
observed orders) and the mean curvature of a parametrization from its exact
derivatives. :mod:`gerbs_core.testing.exact`: exact reference surfaces (unit
sphere, torus, height field) with signed distance, unit normal and mean
curvature at the closest point. :mod:`gerbs_core.testing.zebra`: zebra stripes as a
number (how many pieces the reflection-line bands break into).

Sign convention everywhere: the mean curvature H = (k1 + k2) / 2 is positive
where the surface bends away from its normal, so the unit sphere with outward
normals has H = +1 (the mean-curvature normal -Laplace(x) = 2 H n).
"""
from __future__ import annotations

from .exact import HeightField, Torus, UnitSphere
from .fairness import (
    box_ratio,
    cotangent_mean_curvature,
    dihedral_angles,
    edge_adjacency,
    fold_counts,
    mean_curvature_from_derivatives,
    mixed_areas,
    observed_order,
    orientation_defects,
    triangle_normals,
    vertex_normals,
)
from .zebra import sphere_directions, stripe_components

__all__ = [
    "HeightField", "Torus", "UnitSphere", "box_ratio", "cotangent_mean_curvature",
    "dihedral_angles", "edge_adjacency", "fold_counts", "mean_curvature_from_derivatives", "mixed_areas",
    "observed_order", "orientation_defects", "sphere_directions", "stripe_components",
    "triangle_normals", "vertex_normals",
]
