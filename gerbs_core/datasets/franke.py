"""Franke's six test functions on [0, 1]^2 (R. Franke, "Scattered data
interpolation: tests of some methods", Math. Comp. 38 (1982) 181-200), with
exact gradients and Hessians (closed form).

``franke(k, p, nu=0)``: k = 1..6, p (..., 2); returns value (...), gradient
(..., 2) or Hessian (..., 2, 2).
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["franke", "FRANKE_NAMES"]

FRANKE_NAMES = {1: "exponentials", 2: "cliff", 3: "saddle", 4: "gentle", 5: "steep", 6: "sphere"}


def _expq(a, c, p, nu):
    """a * exp(q(p)) with q = c0 + c1 x + c2 y + c11 x^2 + c22 y^2 (c = (c0, c1, c2, c11, c22))."""
    x, y = p[..., 0], p[..., 1]
    c0, c1, c2, c11, c22 = c
    e = a * np.exp(c0 + c1 * x + c2 * y + c11 * x * x + c22 * y * y)
    if nu == 0:
        return e
    gq = np.stack([c1 + 2 * c11 * x, c2 + 2 * c22 * y], -1)
    if nu == 1:
        return e[..., None] * gq
    Hq = np.zeros(p.shape[:-1] + (2, 2))
    Hq[..., 0, 0] = 2 * c11
    Hq[..., 1, 1] = 2 * c22
    return e[..., None, None] * (gq[..., :, None] * gq[..., None, :] + Hq)


def _sq(a, b, s):
    """Coefficients of -(a x + b)^2 / s as (c0, c1, c11) for one variable."""
    return -(b * b) / s, -2 * a * b / s, -(a * a) / s


def _gauss(a, ax, bx, sx, ay, by, sy):
    """a exp(-(ax x + bx)^2/sx - (ay y + by)^2/sy) coefficients."""
    x0, x1, x11 = _sq(ax, bx, sx)
    y0, y1, y11 = _sq(ay, by, sy)
    return a, (x0 + y0, x1, y1, x11, y11)


def franke(k, p, nu=0):
    """Franke's function F_k (k = 1..6) at p (..., 2), derivative order nu (0, 1, 2)."""
    p = np.asarray(p, dtype=float)
    if p.shape[-1] != 2:
        raise InvalidParameterError("p", f"need points of shape (..., 2), got {p.shape}")
    if nu not in (0, 1, 2):
        raise InvalidParameterError("nu", f"0, 1 or 2, got {nu}")
    x, y = p[..., 0], p[..., 1]
    if k == 1:
        terms = [_gauss(0.75, 9, -2, 4, 9, -2, 4),
                 (0.75, (-1 / 49 - 1 / 10, -18 / 49, -9 / 10, -81 / 49, 0.0)),
                 _gauss(0.5, 9, -7, 4, 9, -3, 4),
                 _gauss(-0.2, 9, -4, 1, 9, -7, 1)]
        return sum(_expq(a, c, p, nu) for a, c in terms)
    if k in (4, 5):
        s = 16 / 81 if k == 4 else 4 / 81
        a, c = _gauss(1 / 3, 1, -0.5, s, 1, -0.5, s)
        return _expq(a, c, p, nu)
    if k == 2:
        t = np.tanh(9 * y - 9 * x)
        if nu == 0:
            return (t + 1) / 9
        d1 = (1 - t * t) / 9
        gs = np.array([-9.0, 9.0])
        if nu == 1:
            return d1[..., None] * gs
        d2 = -2 * t * (1 - t * t) / 9
        return d2[..., None, None] * np.outer(gs, gs)
    if k == 3:
        u = (1.25 + np.cos(5.4 * y)) / 6
        w = 1 + (3 * x - 1) ** 2
        v = 1 / w
        if nu == 0:
            return u * v
        du = -5.4 * np.sin(5.4 * y) / 6
        dv = -6 * (3 * x - 1) / w ** 2
        if nu == 1:
            return np.stack([u * dv, du * v], -1)
        ddu = -5.4 ** 2 * np.cos(5.4 * y) / 6
        ddv = -18 / w ** 2 + 72 * (3 * x - 1) ** 2 / w ** 3
        H = np.empty(p.shape[:-1] + (2, 2))
        H[..., 0, 0] = u * ddv
        H[..., 1, 1] = ddu * v
        H[..., 0, 1] = H[..., 1, 0] = du * dv
        return H
    if k == 6:
        X, Y = x - 0.5, y - 0.5
        w = 64 - 81 * (X * X + Y * Y)
        r = np.sqrt(w)
        if nu == 0:
            return r / 9 - 0.5
        gw = np.stack([-162 * X, -162 * Y], -1)
        if nu == 1:
            return gw / (18 * r)[..., None]
        Hw = -162 * np.eye(2)
        return Hw / (18 * r)[..., None, None] - gw[..., :, None] * gw[..., None, :] / (36 * r ** 3)[..., None, None]
    raise InvalidParameterError("k", f"Franke functions are numbered 1..6, got {k}")
