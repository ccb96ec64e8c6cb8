"""Matplotlib figures (Agg): kernels, a partition of unity on a Delaunay star-1 cover, convergence.

Each figure function takes (out_dir, (width, height) in pixels, quick=bool) and
returns (path, info dict). Sizes follow the render size so the test can make
tiny images; the README images are rendered at 800x600 and up.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

DPI = 100


def _figure(size, ncols=1, nrows=1, scale=1.0, **kw):
    w, h = size
    fig, axes = plt.subplots(nrows, ncols, figsize=(scale * w / DPI, h / DPI), dpi=DPI, **kw)
    return fig, axes


def _small(size) -> bool:
    return size[0] < 300


def _save(fig, path: Path, size):
    if _small(size):
        # the test renders at 64x48: tick labels would not fit; keep the curves
        for ax in fig.axes:
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title("")
            ax.set_xlabel("")
            ax.set_ylabel("")
            legend = ax.get_legend()
            if legend is not None:
                legend.remove()
        fig.subplots_adjust(0.02, 0.02, 0.98, 0.98, 0.05, 0.05)
    else:
        fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


# ---------------------------------------------------------------- kernels


def kernel_set():
    """(label, kernel, style) of the kernels drawn in kernels.png."""
    from gerbs_core.kernels import BFBS, ERBS, Affine, LogisticStep, Step

    blues = plt.get_cmap("Blues")
    return [
        ("ERBS() (default)", ERBS(), dict(color=blues(0.95), lw=2.4)),
        ("ERBS(alpha=3)", ERBS(alpha=3.0), dict(color=blues(0.75), lw=1.6)),
        ("ERBS(beta=0.2)", ERBS(beta=0.2), dict(color=blues(0.6), lw=1.6)),
        ("ERBS(lam=0.25, gamma=2)", ERBS(lam=0.25, gamma=2.0), dict(color=blues(0.45), lw=1.6)),
        ("BFBS(2, 2)", BFBS(2, 2), dict(color="tab:orange", lw=1.6, ls="--")),
        ("BFBS(1, 4)", BFBS(1, 4), dict(color="tab:red", lw=1.4, ls="--")),
        ("LogisticStep()", LogisticStep(), dict(color="tab:green", lw=1.6, ls="-.")),
        ("Affine()", Affine(), dict(color="0.35", lw=1.4, ls=":")),
        ("Step()", Step(), dict(color="k", lw=1.2, ls=(0, (1, 3)))),
    ]


def kernels(out: Path, size, quick=False):
    """F on [0, 1] (left) and the bump b(t) = 1 - F(|t|) (right), eq. (2) and Definition 2."""
    fig, (a0, a1) = _figure((size[0] * 1.25, size[1] * 0.7), ncols=2)
    t = np.linspace(-0.15, 1.15, 300 if quick else 1301)
    s = np.linspace(-1.15, 1.15, 300 if quick else 2301)
    items = kernel_set()
    for label, k, style in items:
        a0.plot(t, k.cdf(t), label=label, **style)
        a1.plot(s, k.bump(s), **style)
    a0.set_title("F (cumulative kernel)")
    a1.set_title("b(t) = 1 - F(|t|)  (supp b = [-1, 1])")
    for ax in (a0, a1):
        ax.set_xlabel("t")
        ax.grid(alpha=0.3)
        ax.set_ylim(-0.05, 1.05)
    a0.legend(fontsize=7, loc="lower right", frameon=True)
    return _save(fig, out / "kernels.png", size), {"kernels": len(items)}


FIGURES = {"kernels": kernels}


# ---------------------------------------------------------------- partition of unity


def _colouring(tri, n, ncolours):
    """Greedy colouring of the Delaunay graph: neighbours get different colours."""
    indptr, indices = tri.vertex_neighbor_vertices
    colour = -np.ones(n, dtype=int)
    for i in np.argsort(-(indptr[1:] - indptr[:-1]), kind="stable"):
        taken = set(colour[indices[indptr[i]:indptr[i + 1]]])
        colour[i] = next(c for c in range(ncolours) if c not in taken)
    return colour


def basis_functions(points, x):
    """All B_i = Psi_i (eq. (73), the default minimal basis) of the Delaunay star-1 cover
    at x (..., 2) -> (..., N), from the interpolator's dense basis matrix."""
    from gerbs_core.scattered.hermite import GERBSInterpolator

    x = np.asarray(x, dtype=np.float64)
    interp = GERBSInterpolator(points, np.zeros(len(points)), cover="delaunay")
    return interp.basis_matrix(x.reshape(-1, 2)).reshape(x.shape[:-1] + (len(points),))


def partition(out: Path, size, quick=False):
    """Colour map of the Psi_i on a Delaunay star-1 cover, and the Psi_i along a line."""
    from matplotlib.colors import to_rgb
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(7)
    n = 14 if quick else 30
    pts = np.concatenate([[[0, 0], [1, 0], [1, 1], [0, 1]], rng.uniform(0.04, 0.96, (n - 4, 2))])
    tri = Delaunay(pts)
    m = 80 if quick else 400
    g = np.linspace(0.0, 1.0, m)
    X, Y = np.meshgrid(g, g)
    B = basis_functions(pts, np.stack([X, Y], -1))  # (m, m, N)
    palette = np.array([to_rgb(c) for c in plt.get_cmap("tab10").colors])
    colour = _colouring(tri, len(pts), len(palette))
    img = np.clip(B @ palette[colour], 0.0, 1.0)
    fig, (a0, a1) = _figure((size[0] * 1.25, size[1] * 0.75), ncols=2,
                            gridspec_kw={"width_ratios": [1, 1.35]})
    a0.imshow(img, origin="lower", extent=(0, 1, 0, 1), interpolation="bilinear")
    a0.triplot(pts[:, 0], pts[:, 1], tri.simplices, color="k", lw=0.6, alpha=0.7)
    a0.plot(pts[:, 0], pts[:, 1], "o", ms=3, color="k")
    y0 = 0.5
    a0.axhline(y0, color="w", lw=1.0, ls="--")
    a0.set_aspect("equal")
    a0.set_title("Psi_i blended with one colour per point")
    line = np.stack([g, np.full_like(g, y0)], -1)
    Bl = basis_functions(pts, line)
    for i in np.flatnonzero(Bl.max(axis=0) > 1e-9):
        a1.plot(g, Bl[:, i], color=palette[colour[i]], lw=1.6)
    total = Bl.sum(axis=1)
    a1.plot(g, total, color="k", lw=1.2, ls="--", label="sum of all Psi_i")
    a1.set_ylim(-0.03, 1.08)
    a1.set_xlabel(f"x   (on the line y = {y0})")
    a1.set_title("Psi_i along the dashed line")
    a1.grid(alpha=0.3)
    a1.legend(loc="lower right", fontsize=8)
    info = {"points": len(pts), "max |sum - 1|": float(np.abs(B.sum(-1) - 1.0).max())}
    return _save(fig, out / "partition.png", size), info


FIGURES["partition"] = partition


# ---------------------------------------------------------------- convergence

def convergence_data(quick=False):
    """Rows of the scattered-data benchmark (scripts/bench_scattered.py) on Franke's F1.

    The same methods, seeded points and 300 x 300 error grid as the benchmark,
    one repeat, N up to 10^4 (quick: 100 and 400). Each row: method, N, rms, max, nan.
    """
    import bench_scattered  # scripts/ is on sys.path (render_figures.py puts it there)

    ns = [100, 400] if quick else [100, 1000, 10_000]
    return bench_scattered.run_table(ns, [1], 1), ns


STYLES = {  # by the benchmark's method names; unknown names get matplotlib's defaults
    "GERBS-v": dict(color="tab:blue", marker="o", ls="-"),
    "GERBS-v2": dict(color="deepskyblue", marker="D", ls="-"),
    "GERBS-H": dict(color="navy", marker="s", ls="-"),
    "GERBS-H2": dict(color="purple", marker="X", ls="-"),
    "CT": dict(color="tab:orange", marker="^", ls="--"),
    "Linear": dict(color="0.5", marker="v", ls=":"),
    "RBF50": dict(color="tab:green", marker="P", ls="-."),
}


def _order(h, e):
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])


def convergence(out: Path, size, quick=False):
    """Log-log RMS error vs N of the benchmark's methods, fitted orders in h = N^(-1/2)."""
    rows, ns = convergence_data(quick=quick)
    fig, ax = _figure((size[0], size[1] * 0.85))
    info = {}
    for method in dict.fromkeys(r["method"] for r in rows):
        rr = sorted((r for r in rows if r["method"] == method), key=lambda r: r["N"])
        N = np.array([r["N"] for r in rr], dtype=np.float64)
        e = np.array([r["rms"] for r in rr])
        p = _order(N ** -0.5, e)
        info[method] = round(p, 2)
        # a NaN means a grid point no cover element reaches (a hole): say so, never hide it
        holes = sum(int(r.get("nan", 0)) for r in rr)
        note = f", {holes} NaN grid points left out" if holes else ""
        if holes:
            info[method + " NaN"] = holes
        ax.loglog(N, e, label=f"{method}  (order {p:.2f}{note})", **STYLES.get(method, {"marker": "o"}))
    ax.set_xticks(ns, [str(n) for n in ns])
    ax.minorticks_off()
    ax.set_xlabel("N scattered points in [0, 1]^2 (uniform random, seeded)")
    ax.set_ylabel("RMS error, 300 x 300 grid")
    ax.set_title("Franke's F1 (scripts/bench_scattered.py); order = slope in h = N^(-1/2)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, title="method (as named in the benchmark)", title_fontsize=8)
    return _save(fig, out / "convergence.png", size), info


FIGURES["convergence"] = convergence
