"""Benchmark: GERBS scattered-point Hermite interpolation vs scipy, side by side in one run.

Parts (``--parts``, default all):

  2d       Franke's six test functions on [0, 1]^2 (methods below), N = 100 ... 100,000
  metrics  n = 2, Franke F1, cover="balls" in the metrics of paper section 2.5.1
           (Euclidean, l1, l_inf, l_p p=3, bounded), N = 500 ... 32,000
  3d, 4d   values only, points uniform in [0,1]^n, a smooth function (Franke's in R^n)
           and one with a steep feature (tanh front of width 0.04), 20,000 queries in
           [0.1, 0.9]^n: GERBSInterpolator (cover "delaunay" = the n-D Delaunay star cover,
           and "balls"), LinearNDInterpolator, RBFInterpolator(neighbors=50); RMS, order
           in h = N^(-1/n), fit / eval time (median of repeats), tracemalloc peak
  million  n = 3, N = 32,000, 10^6 queries, fresh process: time, tracemalloc and RSS peak
  cold     n = 2, first call (fit + 200 x 200 grid) in a fresh process, N = 4,004
           clustered points and N = 100,000, against Clough-Tocher

Methods of part 2d
  GERBS-v    GERBSInterpolator(points, values)   (defaults: Delaunay star cover,
             B = Psi (73), Taylor degree 3, derivatives from local cubic LSQ)
  GERBS-v2   same, Taylor degree 2
  GERBS-H    GERBSInterpolator(points, values, exact gradients, exact Hessians)
             (default degree 3: third derivatives estimated by local LSQ from the
             neighbours' values and exact gradients)
  GERBS-H2   same data, Taylor degree 2 (exactly the given data, nothing estimated)
  CT         scipy.interpolate.CloughTocher2DInterpolator (values only)
  Linear     scipy.interpolate.LinearNDInterpolator
  RBF50      scipy.interpolate.RBFInterpolator(neighbors=50) (thin-plate spline)

Points: uniform random, seeded. 2d errors on the 300 x 300 grid points inside the convex
hull. Observed order: least-squares slope of log RMS vs log h.

Usage:  python scripts/bench_scattered.py [--parts 2d,metrics,3d,4d,million,cold]
        [--max-n 100000] [--repeats 3] [--quick] [--scaling]
        --quick   smaller N everywhere, 1 repeat (a development smoke run)
        --scaling also runs GERBS-H for N = 10^4, 10^5, 10^6 (fit + 10^6 evaluations,
        chunked) and reports time / (N log N) and peak RSS.
"""
import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"

import argparse  # noqa: E402
import resource  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.interpolate import CloughTocher2DInterpolator, LinearNDInterpolator, RBFInterpolator  # noqa: E402
from scipy.spatial import Delaunay  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_scattered_nd as nd  # noqa: E402
from gerbs_core.datasets.franke import franke  # noqa: E402
from gerbs_core.scattered.hermite import GERBSInterpolator  # noqa: E402


def methods(P, k):
    f = franke(k, P)
    g, H = franke(k, P, 1), franke(k, P, 2)
    return {
        "GERBS-v": lambda: GERBSInterpolator(P, f),
        "GERBS-v2": lambda: GERBSInterpolator(P, f, degree=2),
        "GERBS-H": lambda: GERBSInterpolator(P, f, g, H),
        "GERBS-H2": lambda: GERBSInterpolator(P, f, g, H, degree=2),
        "CT": lambda: CloughTocher2DInterpolator(P, f),
        "Linear": lambda: LinearNDInterpolator(P, f),
        "RBF50": lambda: RBFInterpolator(P, f, neighbors=50),
    }


timed = nd.timed


def grid_inside(P, m=300):
    g = np.linspace(0.0, 1.0, m)
    X = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    return X[Delaunay(P).find_simplex(X) >= 0]


def run_table(Ns, ks, repeats, timing_k=1):
    rows = []
    for k in ks:
        for N in Ns:
            rng = np.random.default_rng(1000 + N)
            P = rng.random((N, 2))
            X = grid_inside(P)
            fe = franke(k, X)
            rep = repeats if k == timing_k else 1
            for name, make in methods(P, k).items():
                interp, tfit = timed(make, rep)
                vals, teval = timed(lambda: interp(X), rep)
                err = vals - fe
                rows.append(dict(k=k, N=N, method=name, fit=tfit, eval=teval,
                                 max=float(np.nanmax(np.abs(err))),
                                 rms=float(np.sqrt(np.nanmean(err ** 2))),
                                 nan=int(np.isnan(vals).sum())))
                print(f"  F{k} N={N:>6} {name:8s} fit {tfit:7.3f}s eval {teval:7.3f}s "
                      f"max {rows[-1]['max']:.3e} rms {rows[-1]['rms']:.3e}", flush=True)
    return rows


def orders(rows, k, method, Ns):
    sel = [(r["N"], r["rms"]) for r in rows if r["k"] == k and r["method"] == method and r["N"] in Ns]
    if len(sel) < 2:
        return float("nan")
    N, e = np.array(sel, float).T
    h = N ** -0.5
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])


def print_tables(rows, Ns, ks):
    names = list(dict.fromkeys(r["method"] for r in rows))
    print("\n### RMS error on the 300x300 grid inside the hull (max error in parentheses)\n")
    for k in ks:
        print(f"F{k}: | N | " + " | ".join(names) + " |")
        print("|---|" + "---|" * len(names))
        for N in Ns:
            cells = []
            for m in names:
                r = [x for x in rows if x["k"] == k and x["N"] == N and x["method"] == m][0]
                cells.append(f"{r['rms']:.2e} ({r['max']:.1e})")
            print(f"| {N} | " + " | ".join(cells) + " |")
        big = [N for N in Ns if N >= 1000]
        print("| order | " + " | ".join(f"{orders(rows, k, m, big):.2f}" for m in names) + " |\n")
    if 1 not in ks:
        return
    print("### Timings F1 (median of repeats): fit / eval seconds\n")
    print("| N | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for N in Ns:
        cells = []
        for m in names:
            r = [x for x in rows if x["k"] == 1 and x["N"] == N and x["method"] == m][0]
            cells.append(f"{r['fit']:.3f} / {r['eval']:.3f}")
        print(f"| {N} | " + " | ".join(cells) + " |")


def targets(rows, Ns):
    def get(N, m):
        return [x for x in rows if x["k"] == 1 and x["N"] == N and x["method"] == m][0]

    print("\n### Targets (F1)\n")
    if 10000 in Ns:
        ct, gv, gh = get(10000, "CT"), get(10000, "GERBS-v"), get(10000, "GERBS-H")
        gh2 = get(10000, "GERBS-H2")
        print(f"- (degree 2, nothing estimated) GERBS-H2 RMS {gh2['rms']:.3e} -> ratio {gh2['rms'] / ct['rms']:.2f}")
        print(f"- values only, N=10000: GERBS-v RMS {gv['rms']:.3e} vs CT {ct['rms']:.3e} "
              f"-> ratio {gv['rms'] / ct['rms']:.2f} (target <= 1): {'PASS' if gv['rms'] <= ct['rms'] else 'FAIL'}")
        print(f"- exact gradients+Hessians, N=10000: GERBS-H RMS {gh['rms']:.3e} -> ratio "
              f"{gh['rms'] / ct['rms']:.2f} (target <= 0.5): {'PASS' if gh['rms'] <= 0.5 * ct['rms'] else 'FAIL'}")
    big = [N for N in Ns if N >= 1000]
    for m in ("GERBS-H", "GERBS-H2"):
        o = orders(rows, 1, m, big)
        print(f"- observed order {m} (N in {big}): {o:.2f} (target >= 2.8): {'PASS' if o >= 2.8 else 'FAIL'}")
    if 100000 in Ns:
        ct, gv, gh = get(100000, "CT"), get(100000, "GERBS-v"), get(100000, "GERBS-H")
        tct = ct["fit"] + ct["eval"]
        for g in (gv, gh, get(100000, "GERBS-H2")):
            t = g["fit"] + g["eval"]
            print(f"- fit+eval N=100000 {g['method']}: {t:.3f}s vs CT {tct:.3f}s -> ratio {t / tct:.2f} "
                  f"(target <= 3): {'PASS' if t <= 3 * tct else 'FAIL'}")


def scaling(Ns=(10_000, 100_000, 1_000_000), n_eval=1_000_000):
    print("\n### Scaling, GERBS-H on F1 (fit; evaluation at 10^6 random points, chunked)\n")
    print("| N | fit s | eval s (10^6 pts) | fit / (N log N) [us] | peak RSS MB |")
    print("|---|---|---|---|---|")
    rng = np.random.default_rng(5)
    X = rng.random((n_eval, 2)) * 0.98 + 0.01
    for N in Ns:
        P = np.random.default_rng(N).random((N, 2))
        f, g, H = franke(1, P), franke(1, P, 1), franke(1, P, 2)
        t = time.perf_counter()
        interp = GERBSInterpolator(P, f, g, H)
        tf = time.perf_counter() - t
        t = time.perf_counter()
        v = interp(X)
        te = time.perf_counter() - t
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        err = np.sqrt(np.nanmean((v - franke(1, X)) ** 2))
        print(f"| {N} | {tf:.2f} | {te:.2f} | {1e6 * tf / (N * np.log(N)):.3f} | {rss:.0f} |  (rms {err:.2e})",
              flush=True)
        del interp, v


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--parts", type=str, default="2d,metrics,3d,4d,million,cold")
    ap.add_argument("--max-n", type=int, default=100_000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--functions", type=str, default="1,2,3,4,5,6")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--scaling", action="store_true")
    a = ap.parse_args()
    parts = a.parts.split(",")
    if a.quick:
        a.max_n, a.repeats = min(a.max_n, 10_000), 1
    print(f"# bench_scattered: parts {parts}, repeats {a.repeats}, "
          f"OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}")
    if "2d" in parts:
        Ns = [N for N in (100, 1000, 10_000, 100_000) if N <= a.max_n]
        ks = [int(s) for s in a.functions.split(",")]
        rows = run_table(Ns, ks, a.repeats)
        print_tables(rows, Ns, ks)
        if 1 in ks:
            targets(rows, Ns)
    if "metrics" in parts:
        nd.run_metrics((500, 2000, 8000) if a.quick else (500, 2000, 8000, 32_000))
    for n, Ns in ((3, (1000, 2000, 4000, 8000, 16_000, 32_000)), (4, (1000, 2000, 4000, 8000, 16_000))):
        if f"{n}d" not in parts:
            continue
        Ns = [N for N in Ns if N <= (4000 if a.quick else 10 ** 9)]
        rows = nd.run_nd(n, Ns, a.repeats)
        nd.print_nd(rows, n, Ns, 20_000)
        nd.verdicts_nd(rows, n, Ns)
    if "million" in parts:
        nd.million(N=8000 if a.quick else 32_000, M=200_000 if a.quick else 1_000_000)
    if "cold" in parts:
        nd.cold(repeats=1 if a.quick else 3)
    if a.scaling:
        scaling()


if __name__ == "__main__":
    main()
