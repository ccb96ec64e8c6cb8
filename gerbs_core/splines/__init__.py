"""Univariate GERBS splines: the basis of eq. (3) and curves c = sum_j G_j l_j (Lemma 3)."""
from .curves import GERBSBasis, GERBSCurve

__all__ = ["GERBSBasis", "GERBSCurve"]
