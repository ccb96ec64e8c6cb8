"""The ``metric`` argument of the general construction: every form names a metric of
paper section 2.5.1 (:mod:`gerbs_core.scattered.metrics`), see :func:`as_metric`."""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from .metrics import L1, Bounded, Euclidean, LInf, Lp, Metric, QuasiNorm

__all__ = ["as_metric"]


_NAMES = {
    "euclidean": "l2", "l2": "l2", "linf": "linf", "chebyshev": "linf", "inf": "linf",
    "l1": "l1", "manhattan": "l1", "lp": "lp", "quasi": "quasi", "bounded": "bounded",
    "d/(1+d)": "bounded",
}


def _from_p(p, n, weights=None):
    p = float(p)
    if p == 2:
        return Euclidean(n, weights)
    if p == 1:
        return L1(n, weights)
    if p == np.inf:
        return LInf(n, weights)
    if not p > 0:
        raise InvalidParameterError("metric", f"l_p needs p > 0, got {p}")
    return Lp(n, p, weights) if p > 1 else QuasiNorm(n, p, weights)


def as_metric(metric, n):
    """Normalize the ``metric`` argument to a :class:`Metric` for points in R^n.

    Accepted forms (names case-insensitive; ``w`` = weights, a scalar or (n,) > 0):

    * a Metric (its ``n`` must match), None, "euclidean"/"l2", ("euclidean", w);
    * "linf"/"chebyshev"/"inf", ("linf", w); "l1"/"manhattan", ("l1", w)  (eq. (41));
    * a number p > 0 (2, 1, inf map to the classes above; 1 < p < inf: :class:`Lp`;
      0 < p < 1: :class:`QuasiNorm`), ("lp", p), ("lp", p, w), ("quasi", p), ("quasi", p, w);
    * "bounded" (d/(1+d) of the Euclidean norm, eq. (38)), ("bounded", base) with
      ``base`` any of the forms above.
    """
    if metric is None:
        return Euclidean(n)
    if isinstance(metric, Metric):
        if metric.n != n:
            raise InvalidParameterError("metric", f"metric is for n={metric.n}, points have n={n}")
        return metric
    if isinstance(metric, str):
        metric = (metric,)
    if isinstance(metric, (int, float, np.integer, np.floating)) and not isinstance(metric, bool):
        return _from_p(metric, n)
    if not isinstance(metric, (tuple, list)) or not metric or not isinstance(metric[0], str):
        raise InvalidParameterError("metric", f"unknown metric {metric!r}")
    key = _NAMES.get(metric[0].lower())
    args = tuple(metric[1:])
    try:
        if key == "bounded":
            if len(args) > 1:
                raise TypeError
            base = as_metric(args[0] if args else None, n)
            if isinstance(base, Bounded):
                raise InvalidParameterError("metric", "the base of a bounded metric is itself bounded")
            return Bounded(base)
        if key in ("lp", "quasi"):
            if not 1 <= len(args) <= 2:
                raise TypeError
            p = float(args[0])
            if key == "quasi" and not 0 < p < 1:
                raise InvalidParameterError("p", f"QuasiNorm needs 0 < p < 1, got {p}")
            return _from_p(p, n, *args[1:])
        cls = {"l2": Euclidean, "linf": LInf, "l1": L1}.get(key)
        if cls is not None and len(args) <= 1:
            return cls(n, *args)
    except TypeError:
        pass
    raise InvalidParameterError("metric", f"unknown metric {metric!r} (see as_metric for the forms)")
