"""Scan a grid of ERBS parameters: refused / works / leaves holes in a surface's cover.

    OPENBLAS_NUM_THREADS=1 python scripts/scan_erbs_parameters.py [--quick]

For every (alpha, beta, gamma, lam, sigma) of the grid: ``refused`` if ERBS(...)
raises InvalidParameterError (it cannot be tabulated, docs/robustness.md);
``ok`` if the kernel is finite and monotone on 2049 points and the
surface of the mixed mesh (all face sizes 3..6) at resolution 2 is finite with
eps0 > 0; ``holes`` if that surface is not finite or eps0 = 0 (the kernel's
1 - F(t) underflows long before t = 1); anything else is printed as a failure.
Prints the counts and the largest sub-box (contiguous value ranges, all lam) in
which every grid point is ``ok``. Takes ~8 min on 2 cores (``--quick``: ~30 s).
"""
from __future__ import annotations

import argparse
import itertools
import sys
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this checkout's gerbs_core


def classify(params, X, faces, grid):
    from gerbs_core import BlendingSurface
    from gerbs_core.errors import InvalidParameterError
    from gerbs_core.kernels import ERBS

    try:
        kernel = ERBS(**params)
    except InvalidParameterError:
        return "refused"
    d = kernel.cdf_derivs(grid[grid != params["lam"]], 1)
    if not (np.all(np.isfinite(d)) and np.all(np.diff(d[0]) >= -1e-14) and np.all(d[1] >= 0)):
        return "kernel-bad"
    surface = BlendingSurface(X, faces, kernel=kernel)
    P, _, N = surface.tessellate(2)
    if not (np.all(np.isfinite(P)) and np.all(np.isfinite(N))) or not surface.eps0 > 0:
        return "holes"
    return "ok"


def main() -> None:
    from gerbs_core.datasets import primitives

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 values per parameter")
    args = ap.parse_args()
    warnings.simplefilter("ignore", RuntimeWarning)  # NaN surfaces are counted, not shown
    vals = dict(alpha=[0.1, 0.3, 1, 3, 10], beta=[0.01, 0.1, 1, 10, 100],
                gamma=[0.1, 0.3, 1, 3, 10], lam=[0, 0.25, 0.5, 0.75, 1], sigma=[0, 0.5, 1, 3, 10])
    if args.quick:
        vals = {k: v[::2] for k, v in vals.items()}
    X, faces = primitives.mixed_mesh(0.7)
    grid = np.linspace(0.0, 1.0, 2049)
    t0 = time.perf_counter()
    status = {}
    for combo in itertools.product(*vals.values()):
        p = dict(zip(vals, combo))
        status[combo] = classify(p, X, faces, grid)
        if status[combo] not in ("ok", "refused", "holes"):
            print("FAILURE", p, status[combo])
    print(dict(Counter(status.values())), f"{len(status)} parameter sets, "
          f"{time.perf_counter() - t0:.0f} s")

    def ranges(v):
        return [v[i:j + 1] for i in range(len(v)) for j in range(i, len(v))]

    best = max(((a, b, g, s) for a in ranges(vals["alpha"]) for b in ranges(vals["beta"])
                for g in ranges(vals["gamma"]) for s in ranges(vals["sigma"])
                if all(status[(x, y, z, l_, w)] == "ok" for x in a for y in b for z in g
                       for l_ in vals["lam"] for w in s)),
               key=lambda box: np.prod([len(r) for r in box]), default=None)
    if best:
        names = ("alpha", "beta", "gamma", "sigma")
        print("largest all-ok box (every lam in [0, 1]): "
              + ", ".join(f"{n} in [{r[0]}, {r[-1]}]" for n, r in zip(names, best)))


if __name__ == "__main__":
    main()
