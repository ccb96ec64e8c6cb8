"""Prototype: an affine-covariant surface by binding the model to the whitened rest shape.

The layouts, charts, cover and fits are built on Y = (X - m) A, A = Sigma^(-1/2) of the
cage surface's area-weighted second moment (eigenvalues floored at FLOOR^2 x the largest),
and the resulting linear map is applied to the true positions X. Because the map is
linear with rows summing to 1 and the construction is similarity invariant, the surface
of an affine image of a cage is the affine image of its surface (as for subdivision).
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.methods import gerbs_samples  # noqa: E402

FLOOR = 0.0


def moment(V, F):
    V = np.asarray(V, float)
    tris = np.array([[f[0], f[k], f[k + 1]] for f in F for k in range(1, len(f) - 1)])
    a, b, c = V[tris[:, 0]], V[tris[:, 1]], V[tris[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    m = (area[:, None] * (a + b + c) / 3).sum(0) / area.sum()
    a, b, c = a - m, b - m, c - m
    # exact second moment of a triangle: A/12 (sum x x^T + s s^T), s = a + b + c
    s = a + b + c
    M = (area[:, None, None] / 12 * (np.einsum("ti,tj->tij", a, a) + np.einsum("ti,tj->tij", b, b)
                                     + np.einsum("ti,tj->tij", c, c) + np.einsum("ti,tj->tij", s, s))).sum(0)
    return m, M / area.sum()


def vertex_moment(V, F):
    V = np.asarray(V, float)
    m = V.mean(0)
    return m, (V - m).T @ (V - m) / len(V)


MOMENT = {"area": moment, "vertex": vertex_moment}


def whitened(V, F, floor=None, power=1.0, kind="vertex"):
    floor = FLOOR if floor is None else floor
    m, M = MOMENT[kind](V, F)
    w, Q = np.linalg.eigh(M)
    w = np.maximum(w, (floor ** 2) * w.max())
    w = np.maximum(w, 1e-30 * w.max())
    A = Q @ np.diag((w / w.max()) ** (-0.5 * power)) @ Q.T
    return (np.asarray(V, float) - m) @ A


def variant(V, F, r, exact=True):
    return gerbs_samples(V, F, r, exact=exact, rest_positions=whitened(V, F, 0.05))


def floor10(V, F, r, exact=True):
    return gerbs_samples(V, F, r, exact=exact, rest_positions=whitened(V, F, 0.10))


def half(V, F, r, exact=True):
    return gerbs_samples(V, F, r, exact=exact, rest_positions=whitened(V, F, 0.05, 0.5))
