"""Scattered-point Hermite interpolation in R^n (paper sections 2-5): metrics, radii, the
partitions of unity of eqs. (27)-(36), Taylor data and :class:`GERBSInterpolator`."""
from .diagnostics import cover_report
from .hermite import GERBSInterpolator

__all__ = ["GERBSInterpolator", "cover_report"]
