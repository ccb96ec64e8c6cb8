"""Parts of scripts/bench_scattered.py: scattered data in R^3 and R^4, ball covers in
every metric (R^2), the memory of 10^6 queries, and cold first calls in fresh processes.

Every comparison is side by side in one run; times are medians of ``repeats``; peak
memory is the tracemalloc peak of fit + evaluation (numpy buffers are traced), in a
separate untimed run.
"""
import os
import subprocess
import sys
import time
import tracemalloc

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


# ---------------------------------------------------------------- test functions
def franke_nd(x):
    """Franke's function generalized to R^n (the R^3 form of the RBF literature)."""
    n = x.shape[-1]
    y = 9.0 * x
    a = np.array([7.0, 3.0] + [5.0] * (n - 2))[:n]
    b = np.array([4.0, 7.0] + [5.0] * (n - 2))[:n]
    return (0.75 * np.exp(-np.sum((y - 2) ** 2, -1) / 4)
            + 0.75 * np.exp(-(y[..., 0] + 1) ** 2 / 49 - np.sum(y[..., 1:] + 1, -1) / 10)
            + 0.5 * np.exp(-np.sum((y - a) ** 2, -1) / 4)
            - 0.2 * np.exp(-np.sum((y - b) ** 2, -1)))


def steep_nd(x):
    """A steep spherical front: tanh(25 (|x - c| - 0.35)), width ~0.04, c = (0.45, ...)."""
    return np.tanh(25.0 * (np.linalg.norm(x - 0.45, axis=-1) - 0.35))


FUNCTIONS = {"franke": franke_nd, "steep": steep_nd}


# ------------------------------------------------------------------- methods
def nd_methods(P, f, covers=("delaunay", "balls")):
    from scipy.interpolate import LinearNDInterpolator, RBFInterpolator
    from gerbs_core import GERBSInterpolator
    out = {f"GERBS-{c}": (lambda c=c: GERBSInterpolator(P, f, cover=c)) for c in covers}
    out["Linear"] = lambda: LinearNDInterpolator(P, f)
    out["RBF50"] = lambda: RBFInterpolator(P, f, neighbors=50)
    return out


def timed(fn, repeats):
    ts, out = [], None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return out, float(np.median(ts))


def traced_peak(fn):
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = fn()
        return out, (tracemalloc.get_traced_memory()[1] - base) / 1e6
    finally:
        tracemalloc.stop()


def order(Ns, errs, n):
    N, e = np.asarray(Ns, float), np.asarray(errs, float)
    ok = np.isfinite(e) & (e > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(N[ok] ** (-1.0 / n)), np.log(e[ok]), 1)[0])


def run_nd(n, Ns, repeats, n_query=20_000, funcs=("franke", "steep"), timing="franke"):
    """Rows dict(fn, N, method, rms, max, fit, eval, peak) for points uniform in [0,1]^n
    and queries uniform in [0.1, 0.9]^n."""
    rows = []
    X = np.random.default_rng(7).random((n_query, n)) * 0.8 + 0.1
    for fname in funcs:
        func = FUNCTIONS[fname]
        fx = func(X)
        for N in Ns:
            P = np.random.default_rng(1000 + N).random((N, n))
            fp = func(P)
            rep = repeats if fname == timing else 1
            for name, make in nd_methods(P, fp).items():
                interp, tfit = timed(make, rep)
                vals, teval = timed(lambda: interp(X), rep)
                peak = float("nan")
                if fname == timing:
                    _, peak = traced_peak(lambda: make()(X))
                err = vals - fx
                row = dict(fn=fname, N=N, method=name, fit=tfit, eval=teval, peak=peak,
                           rms=float(np.sqrt(np.nanmean(err ** 2))), max=float(np.nanmax(np.abs(err))),
                           nan=int(np.isnan(vals).sum()))
                rows.append(row)
                print(f"  n={n} {fname:6s} N={N:>6} {name:15s} fit {tfit:7.3f}s eval {teval:7.3f}s "
                      f"peak {peak:7.1f} MB rms {row['rms']:.3e} nan {row['nan']}", flush=True)
                del interp, vals
    return rows


def print_nd(rows, n, Ns, n_query):
    names = list(dict.fromkeys(r["method"] for r in rows))
    get = {(r["fn"], r["N"], r["method"]): r for r in rows}
    for fname in dict.fromkeys(r["fn"] for r in rows):
        print(f"\n### n = {n}, {fname}: RMS on {n_query} random queries in [0.1, 0.9]^{n}\n")
        print("| N | " + " | ".join(names) + " |")
        print("|---|" + "---|" * len(names))
        for N in Ns:
            print(f"| {N:,} | " + " | ".join(f"{get[fname, N, m]['rms']:.2e}" for m in names) + " |")
        print("| order in h | " + " | ".join(
            f"{order(Ns, [get[fname, N, m]['rms'] for N in Ns], n):.2f}" for m in names) + " |")
    fname = rows[0]["fn"]
    print(f"\n### n = {n}, {fname}: fit / evaluation s (median) and tracemalloc peak MB\n")
    print("| N | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for N in Ns:
        cells = [f"{get[fname, N, m]['fit']:.2f} / {get[fname, N, m]['eval']:.2f}, "
                 f"{get[fname, N, m]['peak']:.0f} MB" for m in names]
        print(f"| {N:,} | " + " | ".join(cells) + " |")


def verdicts_nd(rows, n, Ns, default="GERBS-delaunay"):
    get = {(r["fn"], r["N"], r["method"]): r for r in rows}
    fname = rows[0]["fn"]
    print(f"\n### Verdicts, n = {n} ({default}, values only)\n")
    for fn in dict.fromkeys(r["fn"] for r in rows):
        o = order(Ns, [get[fn, N, default]["rms"] for N in Ns], n)
        want = 2.0 if n == 3 else 1.5
        print(f"- {fn}: observed order {o:.2f} (target >= {want}): {'PASS' if o >= want else 'FAIL'}")
    if n != 3:
        return
    for N in [N for N in Ns if N >= 8000]:
        g, r = get[fname, N, default], get[fname, N, "RBF50"]
        print(f"- {fname} N={N}: RMS {g['rms']:.2e} vs RBF50 {r['rms']:.2e}: "
              f"{'PASS' if g['rms'] <= r['rms'] else 'FAIL'}")
    for N in Ns:
        g, r = get[fname, N, default], get[fname, N, "RBF50"]
        tg, tr = g["fit"] + g["eval"], r["fit"] + r["eval"]
        print(f"- N={N}: fit+eval {tg:.2f}s vs RBF50 {tr:.2f}s -> {tg / tr:.2f}x (target <= 2): "
              f"{'PASS' if tg <= 2 * tr else 'FAIL'}")


# ------------------------------------------------------------ ball covers, R^2
def run_metrics(Ns, metrics=("euclidean", "l1", "linf", ("lp", 3), "bounded")):
    """Franke F1 with cover='balls' in every metric: RMS on an 80x80 grid of [0.1, 0.9]^2,
    fit + eval time and tracemalloc peak."""
    from gerbs_core import GERBSInterpolator
    from gerbs_core.datasets.franke import franke
    g = np.linspace(0.1, 0.9, 80)
    X = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    fx = franke(1, X)
    print("\n### n = 2, Franke F1, cover='balls': RMS (80 x 80 grid in [0.1, 0.9]^2), "
          "fit + eval s, peak MB\n")
    labels = [m if isinstance(m, str) else f"{m[0]} p={m[1]}" for m in metrics]
    print("| N | " + " | ".join(labels) + " |")
    print("|---|" + "---|" * len(metrics))
    errs = {m: [] for m in labels}
    for N in Ns:
        P = np.random.default_rng(N).random((N, 2))
        cells = []
        for m, lab in zip(metrics, labels):
            t = time.perf_counter()
            v, peak = traced_peak(lambda: GERBSInterpolator(P, franke(1, P), cover="balls", metric=m)(X))
            dt = time.perf_counter() - t
            e = float(np.sqrt(np.nanmean((v - fx) ** 2)))
            errs[lab].append(e)
            cells.append(f"{e:.2e}, {dt:.2f} s, {peak:.0f} MB")
        print(f"| {N:,} | " + " | ".join(cells) + " |", flush=True)
    ords = [order(Ns, errs[lab], 2) for lab in labels]
    print("| order in h | " + " | ".join(f"{o:.2f}" for o in ords) + " |")
    print("\n- ball covers converge (order >= 1.5 on F1): "
          + ("PASS" if min(ords) >= 1.5 else "FAIL") + f" (min {min(ords):.2f})")


# ------------------------------------------------------------ 10^6 queries
_MILLION = r"""
import os, sys, time, tracemalloc
os.environ["OPENBLAS_NUM_THREADS"] = "1"
sys.path.insert(0, {root!r})
import numpy as np
sys.path.insert(0, {here!r})
from bench_scattered_nd import franke_nd
from gerbs_core import GERBSInterpolator
n, N, M, cover = {n}, {N}, {M}, {cover!r}
P = np.random.default_rng(1000 + N).random((N, n))
X = np.random.default_rng(5).random((M, n)) * 0.8 + 0.1
tracemalloc.start()
t = time.perf_counter()
interp = GERBSInterpolator(P, franke_nd(P), cover=cover)
v = interp(X)
dt = time.perf_counter() - t
peak = tracemalloc.get_traced_memory()[1] / 1e6
tracemalloc.stop()
# VmHWM: this process's own peak RSS (ru_maxrss would include the parent's image,
# inherited across fork/exec)
rss = [float(l.split()[1]) / 1024 for l in open("/proc/self/status") if l.startswith("VmHWM")][0]
rms = float(np.sqrt(np.nanmean((v - franke_nd(X)) ** 2)))
print(f"{{dt:.2f}} {{peak:.0f}} {{rss:.0f}} {{rms:.3e}}")
"""


def million(n=3, N=32_000, M=1_000_000, covers=("delaunay", "balls")):
    print(f"\n### n = {n}, N = {N:,}, {M:,} queries (fresh process each)\n")
    print("| cover | fit + eval s | tracemalloc peak MB | peak RSS MB | RMS | <= 1 GB |")
    print("|---|---|---|---|---|---|")
    for cover in covers:
        code = _MILLION.format(root=ROOT, here=os.path.dirname(os.path.abspath(__file__)),
                               n=n, N=N, M=M, cover=cover)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        dt, peak, rss, rms = out.stdout.split()
        ok = float(rss) <= 1024 and float(peak) <= 1000
        print(f"| {cover} | {dt} | {peak} | {rss} | {rms} | {'PASS' if ok else 'FAIL'} |", flush=True)


# ------------------------------------------------------------ cold first calls
_COLD = r"""
import os, sys, time
os.environ["OPENBLAS_NUM_THREADS"] = "1"
sys.path.insert(0, {root!r})
import numpy as np
import scipy.spatial
N = {N}
rng = np.random.default_rng(3)
if N == 4004:       # clustered: 3 Gaussian clusters + uniform background + the corners
    parts = [rng.random((1000, 2))] + [np.clip(c + 0.05 * rng.normal(size=(1000, 2)), 0, 1)
                                      for c in ((0.3, 0.3), (0.7, 0.4), (0.5, 0.75))]
    P = np.concatenate(parts + [np.array([[0, 0], [1, 0], [0, 1], [1, 1.0]])])
else:
    P = rng.random((N, 2))
f = np.sin(4 * P[:, 0]) * np.cos(3 * P[:, 1])
g = np.linspace(0, 1, 200)
X = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
if {method!r} == "GERBS":
    from gerbs_core import GERBSInterpolator as make
else:
    from scipy.interpolate import CloughTocher2DInterpolator as make
ts, cs = [], []
for _ in range(4):
    t, c = time.perf_counter(), time.process_time()
    make(P, f)(X)
    ts.append(time.perf_counter() - t)
    cs.append(time.process_time() - c)
print(ts[0], float(np.median(ts[1:])), cs[0], float(np.median(cs[1:])))
"""


def cold(repeats=3):
    """First call (fit + 200 x 200 grid) in fresh processes, GERBS and Clough-Tocher
    alternating process by process (both see the same load); wall and CPU seconds."""
    print("\n### First call in a fresh process (n = 2, 200 x 200 grid): cold / warm s, "
          "median of fresh processes, GERBS and CT alternating; ratios by wall (CPU) time\n")
    print("| N | GERBS cold | GERBS warm | CT cold | CT warm | cold x | warm x |")
    print("|---|---|---|---|---|---|---|")
    for N in (4004, 100_000):
        runs = {"GERBS": [], "CT": []}
        for _ in range(repeats):
            for method in ("GERBS", "CT"):
                code = _COLD.format(root=ROOT, N=N, method=method)
                out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                     check=True)
                runs[method].append([float(a) for a in out.stdout.split()])
        gc, gw, gcc, gwc = np.median(np.array(runs["GERBS"]), axis=0)
        cc, cw, ccc, cwc = np.median(np.array(runs["CT"]), axis=0)
        print(f"| {N:,} | {gc:.3f} | {gw:.3f} | {cc:.3f} | {cw:.3f} | {gc / cc:.2f} ({gcc / ccc:.2f}) "
              f"| {gw / cw:.2f} ({gwc / cwc:.2f}) |", flush=True)
