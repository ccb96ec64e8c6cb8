"""Exact reference surfaces: signed distance, unit normal, mean curvature.

Each surface answers ``closest(p)`` for points p (N, 3): ``(d (N,), n (N, 3),
H (N,))`` with d the signed distance of p (positive on the side n points to),
n the unit normal and H the mean curvature at the closest point of the surface
(sign convention of :mod:`gerbs_core.testing`: H > 0 where the surface bends
away from n). Sphere and torus are closed form; the height field projects by
Newton's method (converged to ~1e-13 for points near the surface).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["UnitSphere", "Torus", "HeightField"]


def _pts(p):
    p = np.asarray(p, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {p.shape}")
    return p


@dataclass(frozen=True)
class UnitSphere:
    """The unit sphere about the origin, outward normals: d = |p| - 1, H = 1."""

    def closest(self, p):
        p = _pts(p)
        r = np.linalg.norm(p, axis=1)
        n = p / np.where(r > 0, r, 1.0)[:, None]
        n[r == 0] = (0.0, 0.0, 1.0)  # every direction is closest: pick one
        return r - 1.0, n, np.ones(len(p))

    def signed_distance(self, p):
        return self.closest(p)[0]


@dataclass(frozen=True)
class Torus:
    """Torus about the z axis: major radius R (to the tube's centre circle), minor
    radius r (the tube's), R > r > 0, outward normals. At the closest point, at
    distance rho from the axis, the principal curvatures are 1/r and
    (rho - R)/(r rho), so H = (2 rho - R) / (2 r rho)."""

    R: float = 1.0
    r: float = 0.4

    def __post_init__(self):
        if not (self.R > self.r > 0):
            raise ValueError(f"need R > r > 0, got R={self.R}, r={self.r}")

    def closest(self, p):
        p = _pts(p)
        rho = np.hypot(p[:, 0], p[:, 1])
        safe = np.where(rho > 0, rho, 1.0)
        axis_dir = np.where((rho > 0)[:, None], p[:, :2] / safe[:, None], [1.0, 0.0])
        c = np.concatenate([self.R * axis_dir, np.zeros((len(p), 1))], axis=1)  # tube centre
        v = p - c
        dist_c = np.linalg.norm(v, axis=1)
        n = v / np.where(dist_c > 0, dist_c, 1.0)[:, None]
        n[dist_c == 0] = np.concatenate([axis_dir, np.zeros((len(p), 1))], axis=1)[dist_c == 0]
        rho_q = self.R + self.r * np.einsum("ij,ij->i", n[:, :2], axis_dir)
        H = (2.0 * rho_q - self.R) / (2.0 * self.r * rho_q)
        return dist_c - self.r, n, H

    def signed_distance(self, p):
        return self.closest(p)[0]

    def sample(self, n_major: int, n_minor: int, phase: float = 0.0):
        """Quad mesh with vertices on the torus: (vertices (n_major n_minor, 3),
        faces (n_major n_minor, 4)), counter-clockwise seen from outside."""
        u = 2.0 * np.pi * np.arange(n_major) / n_major
        v = 2.0 * np.pi * (np.arange(n_minor) + phase) / n_minor
        uu, vv = np.meshgrid(u, v, indexing="ij")
        rr = self.R + self.r * np.cos(vv)
        X = np.stack([rr * np.cos(uu), rr * np.sin(uu), self.r * np.sin(vv)], -1).reshape(-1, 3)
        i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
        idx = lambda a, b: (a % n_major) * n_minor + (b % n_minor)  # noqa: E731
        F = np.stack([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)], -1)
        return X, F.reshape(-1, 4)


@dataclass(frozen=True)
class HeightField:
    """The graph z = f(x, y), normal n = (-f_x, -f_y, 1) / W (upward), W = sqrt(1 +
    |grad f|^2), H = -((1 + f_y^2) f_xx - 2 f_x f_y f_xy + (1 + f_x^2) f_yy) / (2 W^3).

    ``jet(x, y)`` returns (f, f_x, f_y, f_xx, f_xy, f_yy), arrays of x's shape.
    """

    jet: Callable
    newton_steps: int = 30

    @staticmethod
    def wave(a: float = 0.3, kx: float = 2.0, ky: float = 1.5, b: float = 0.15):
        """f = a sin(kx x) cos(ky y) + b x y: smooth, both signs of curvature."""
        def jet(x, y):
            s, c = np.sin(kx * x), np.cos(kx * x)
            sy, cy = np.sin(ky * y), np.cos(ky * y)
            return (a * s * cy + b * x * y, a * kx * c * cy + b * y, -a * ky * s * sy + b * x,
                    -a * kx * kx * s * cy, -a * kx * ky * c * sy + b, -a * ky * ky * s * cy)
        return HeightField(jet)

    def height(self, x, y):
        return self.jet(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))[0]

    def _project(self, p):
        """(x, y) of the closest graph point, Newton on |(x, y, f) - p|^2 / 2 from p's (x, y)."""
        x, y = p[:, 0].copy(), p[:, 1].copy()
        for _ in range(self.newton_steps):
            f, fx, fy, fxx, fxy, fyy = self.jet(x, y)
            dz = f - p[:, 2]
            gx, gy = x - p[:, 0] + dz * fx, y - p[:, 1] + dz * fy
            a, b, c = 1 + fx * fx + dz * fxx, fx * fy + dz * fxy, 1 + fy * fy + dz * fyy
            det = a * c - b * b
            ok = det > 1e-12  # far from the surface the Hessian may be indefinite: gradient step
            sx = np.where(ok, (c * gx - b * gy) / np.where(ok, det, 1.0), 0.5 * gx)
            sy = np.where(ok, (a * gy - b * gx) / np.where(ok, det, 1.0), 0.5 * gy)
            x, y = x - sx, y - sy
            if max(np.abs(sx).max(initial=0.0), np.abs(sy).max(initial=0.0)) < 1e-14:
                break
        return x, y

    def closest(self, p):
        p = _pts(p)
        x, y = self._project(p)
        f, fx, fy, fxx, fxy, fyy = self.jet(x, y)
        W = np.sqrt(1.0 + fx * fx + fy * fy)
        n = np.stack([-fx, -fy, np.ones_like(fx)], -1) / W[:, None]
        d = np.einsum("ij,ij->i", p - np.stack([x, y, f], -1), n)
        H = -((1 + fy * fy) * fxx - 2 * fx * fy * fxy + (1 + fx * fx) * fyy) / (2 * W ** 3)
        return d, n, H

    def signed_distance(self, p):
        return self.closest(p)[0]
