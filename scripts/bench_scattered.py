"""Benchmark: GERBS scattered-point Hermite interpolation vs scipy, on Franke's six
test functions on [0, 1]^2 (one run, same machine state for every method).

Methods
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

Points: uniform random in [0,1]^2, seeded. Errors on the 300 x 300 grid points
inside the convex hull of the points. Timings: median of ``--repeats`` runs
(fit = construction, eval = the grid). Observed order: least-squares slope of
log RMS vs log h, h = N^(-1/2), over N >= 1000.

Usage:  python scripts/bench_scattered.py [--max-n 100000] [--repeats 3] [--scaling]
        --quick  (N <= 10000, 1 repeat)
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


def timed(fn, repeats):
    ts, out = [], None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return out, float(np.median(ts))


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
    ap.add_argument("--max-n", type=int, default=100_000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--functions", type=str, default="1,2,3,4,5,6")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--scaling", action="store_true")
    a = ap.parse_args()
    if a.quick:
        a.max_n, a.repeats = min(a.max_n, 10_000), 1
    Ns = [N for N in (100, 1000, 10_000, 100_000) if N <= a.max_n]
    ks = [int(s) for s in a.functions.split(",")]
    print(f"# bench_scattered: N = {Ns}, functions {ks}, repeats {a.repeats}, "
          f"OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}")
    rows = run_table(Ns, ks, a.repeats)
    print_tables(rows, Ns, ks)
    if 1 in ks:
        targets(rows, Ns)
    if a.scaling:
        scaling()


if __name__ == "__main__":
    main()
