"""Truncated Taylor-series arithmetic on arrays (automatic differentiation).

A series is a list ``[a_0, a_1, ..., a_n]`` of equally shaped arrays holding
the Taylor coefficients a_k = f^(k)(t) / k! at every point t. The recurrences
below are exact (no differencing); they turn closed-form inner derivatives into
closed-form derivatives of exp(E), 1/(1 + exp(g)), products, powers.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["exp_series", "logistic_series", "to_derivatives"]


def exp_series(E, w0=None):
    """Taylor coefficients of w = exp(E), from w' = E' w.

    w_k = (1/k) sum_{j=1..k} j E_j w_{k-j}. ``w0`` may be passed if exp(E_0)
    is already known.
    """
    n = len(E) - 1
    w = [np.exp(E[0]) if w0 is None else w0]
    for k in range(1, n + 1):
        acc = E[1] * w[k - 1]
        for j in range(2, k + 1):
            acc = acc + (j * E[j]) * w[k - j]
        w.append(acc / k)
    return w


def logistic_series(g, F0, G0):
    """Taylor coefficients of F = 1 / (1 + exp(g)), from F' = -g' F (1 - F).

    ``F0`` = F(t) and ``G0`` = 1 - F(t) must both be given accurately (the
    latter computed as 1 / (1 + exp(-g)), not as 1 - F0, to keep relative
    accuracy where F is close to 1).
    """
    n = len(g) - 1
    F = [F0]
    G = [G0]                           # series of 1 - F: G_0 = 1 - F_0, G_i = -F_i
    H = [F0 * G0]                      # series of F (1 - F)
    for k in range(1, n + 1):
        acc = g[1] * H[k - 1]
        for j in range(2, k + 1):
            acc = acc + (j * g[j]) * H[k - j]
        Fk = -acc / k
        F.append(Fk)
        G.append(-Fk)
        if k < n:
            Hk = F[0] * G[k]
            for i in range(1, k + 1):
                Hk = Hk + F[i] * G[k - i]
            H.append(Hk)
    return F


def to_derivatives(series):
    """The derivatives k! * series[k], stacked (len(series), ...)."""
    return np.stack([math.factorial(k) * s for k, s in enumerate(series)])
