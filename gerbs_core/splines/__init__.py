"""Univariate GERBS splines: the basis of eq. (3), curves c = sum_j G_j l_j (Lemma 3), and
the one spline evaluator every caller uses (:mod:`.evaluate`)."""
from .curves import GERBSBasis, GERBSCurve

__all__ = ["GERBSBasis", "GERBSCurve"]
