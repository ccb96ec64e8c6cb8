"""Benchmark and accuracy report of the GERBS kernels (issue 2 acceptance).

Run:  OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/bench_kernels.py [--n 1000000]
      [--repeats 21] [--no-accuracy]

Timing: the same n uniform random points in (0, 1) for every entry, median of
``repeats`` runs after one warm-up, in one process. Anchors measured in the
same run: ``numpy.exp`` and the elementary C-infinity step
s(t) = 1 / (1 + exp(1/t - 1/(1-t))) written plainly in numpy.

Accuracy (unless --no-accuracy): max |F - F_ref| of ERBS values against
scipy.integrate.quad (per point, epsabs 1e-17, epsrel 1e-15) and max errors of
F', ..., F'''' against Cauchy-integral derivatives of the closed-form density
(integer sigma) or 8th-order differences of the next lower order (otherwise),
for the default and four non-default parameter sets.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from gerbs_core.kernels import BFBS, ERBS, LogisticStep  # noqa: E402

SETS = [
    (1.0, 1.0, 1.0, 0.5, 1.0),
    (1.0, 1.0, 1.0, 0.3, 1.0),
    (1.0, 2.0, 1.0, 0.5, 2.0),
    (0.5, 2.0, 1.5, 0.4, 2.0),
    (2.0, 1.0, 1.0, 0.6, 1.5),
]


def step_numpy(t):
    """The anchor s(t) = 1 / (1 + exp(1/t - 1/(1-t))), plain numpy."""
    return 1.0 / (1.0 + np.exp(1.0 / t - 1.0 / (1.0 - t)))


def median_ms(fn, repeats):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def timing(n, repeats):
    rng = np.random.default_rng(12345)
    t = rng.random(n)
    erbs, bfbs, logi = ERBS(), BFBS(2, 2), LogisticStep()
    erbs.cdf(0.5)                                   # build the table outside the timing
    with np.errstate(over="ignore", divide="ignore"):
        rows = [
            ("numpy.exp(t)", lambda: np.exp(t)),
            ("s(t) elementary step, numpy", lambda: step_numpy(t)),
            ("ERBS() values", lambda: erbs.cdf(t)),
            ("ERBS() value + 3 derivatives", lambda: erbs.cdf_derivs(t, 3)),
            ("ERBS() value + 4 derivatives", lambda: erbs.cdf_derivs(t, 4)),
            ("BFBS(2, 2) values", lambda: bfbs.cdf(t)),
            ("BFBS(2, 2) value + 3 derivatives", lambda: bfbs.cdf_derivs(t, 3)),
            ("LogisticStep() values", lambda: logi.cdf(t)),
        ]
        res = [(name, median_ms(fn, repeats)) for name, fn in rows]
    t_exp, t_s = res[0][1], res[1][1]
    print(f"timing: n = {n}, median of {repeats} repeats, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")
    print(f"{'':34s} {'ms':>8s} {'/ s(t)':>8s} {'/ exp':>8s}")
    for name, ms in res:
        print(f"{name:34s} {ms:8.2f} {ms / t_s:8.2f} {ms / t_exp:8.2f}")
    r_val, r_der = res[2][1] / t_s, res[3][1] / t_s
    print(f"targets: ERBS values <= 2x s(t): {r_val:.2f}x "
          f"[{'PASS' if r_val <= 2 else 'FAIL'}];  value + 3 derivatives <= 6x s(t): "
          f"{r_der:.2f}x [{'PASS' if r_der <= 6 else 'FAIL'}]")


def _phi(p, s):
    a, b, g, lam, sig = p
    if not 0.0 < s < 1.0:
        return 0.0
    return math.exp(-b * abs(s - lam) ** (2 * sig) / (s * (1 - s) ** g) ** a)


def accuracy():
    from scipy.integrate import IntegrationWarning, quad
    warnings.simplefilter("ignore", IntegrationWarning)

    def q(f, lo, hi, lam):
        pts = [lam] if lo < lam < hi else None
        return quad(f, lo, hi, points=pts, epsabs=1e-17, epsrel=1e-15, limit=400)[0]

    print("\naccuracy of ERBS (absolute; derivatives also relative to max |F^(k)| on the sample)")
    print(f"{'(alpha, beta, gamma, lam, sigma)':34s} {'F':>9s} {'F1':>9s} {'F2':>9s} "
          f"{'F3':>9s} {'F4':>9s}  deriv. reference")
    rng = np.random.default_rng(1)
    for p in SETS:
        k = ERBS(*p)
        f = lambda s, p=p: _phi(p, s)  # noqa: E731
        lam = p[3]
        Z = q(f, 0, lam, lam) + q(f, lam, 1, lam)
        x = np.concatenate([np.linspace(0, 1, 401), rng.random(200)])
        ref = np.array([q(f, 0, xi, lam) / Z if xi <= lam else 1 - q(f, xi, 1, lam) / Z
                        for xi in x])
        cols = [f"{np.abs(k.cdf(x) - ref).max():9.1e}"]
        xs = np.linspace(0.03, 0.97, 95)
        xs = xs[np.abs(xs - lam) > 0.02]
        D = k.cdf_derivs(xs, 4)
        if p[4] == int(p[4]):
            how = "Cauchy integral"
            for m in range(1, 5):
                refm = np.array([_cauchy(p, k.Z, xi, m) for xi in xs])
                e = np.abs(D[m] - refm).max()
                cols.append(f"{e:9.1e}")
        else:
            how = "8th-order FD of F^(k-1)"
            h = 1e-3
            w = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
            offs = np.arange(-4, 5) * h
            for m in range(1, 5):
                fd = k.cdf(xs[:, None] + offs, m - 1) @ w / h
                cols.append(f"{np.abs(D[m] - fd).max():9.1e}")
        rel = "  rel: " + " ".join(f"{float(c) / np.abs(D[m]).max():.0e}"
                                   for m, c in enumerate(cols[1:], start=1))
        print(f"{str(p):34s} " + " ".join(cols) + f"  {how}{rel}")
    D = ERBS().cdf_derivs(np.array([0.0, 1.0]), 4)
    print(f"defaults: max |F^(k)(0 or 1)|, k = 1..4: {np.abs(D[1:]).max():.1e}")


def _cauchy(p, Z, x, m, nodes=128):
    a, b, g, lam, sig = p
    r = min(x, 1 - x) / 2
    dz = r * np.exp(2j * np.pi * np.arange(nodes) / nodes)
    z = x + dz
    phi = np.exp(-b * (z - lam) ** int(2 * sig) * z ** (-a) * (1 - z) ** (-a * g))
    return (math.factorial(m - 1) * np.mean(phi * dz ** (1 - m))).real / Z


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--no-accuracy", action="store_true")
    args = ap.parse_args()
    timing(args.n, args.repeats)
    if not args.no_accuracy:
        accuracy()


if __name__ == "__main__":
    main()
