"""The bench_shape table (plain markdown) and the acceptance verdicts of issue 11.

``results``: {(input name, method label): figures of measure.measure}; missing
entries (a method that failed on an input) print as "fail".
"""
from __future__ import annotations

import math

import numpy as np

COLUMNS = ["input", "method", "V", "P", "dist max", "dist rms", "n° max", "nx° max", "H rms",
           "H max", "H min", "H p5-95", "Hx rms", "Hx max", "Hx min", "zebra", "box x/y/z",
           ">60/>90/max°"]
KEYS = ["dmax", "drms", "nmax", "nxmax", "Hrms", "Hmax", "Hmin", "Hspread", "Hxrms", "Hxmax",
        "Hxmin"]


def num(x) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return f"{x:.3g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.1e}"


def _line(cells):
    return "| " + " | ".join(cells) + " |"


def table(cases, methods, results, orders, ratios):
    """Markdown lines: one row per (input, method), then one row per refinement
    sequence and method with the observed order of each figure."""
    out = [_line(COLUMNS), _line(["---"] * len(COLUMNS))]
    for c in cases:
        for m in methods:
            r = results.get((c.name, m))
            if r is None:
                continue
            folds = f"{r['f60']}/{r['f90']}/{r['fmax']:.0f}"
            if (c.name, m) in ratios:
                folds += f" (x{ratios[(c.name, m)]:.2f})"
            box = "/".join(num(b) for b in r["box"])
            zebra = f"{num(r['zebra'])}/{num(r['zebra_fine'])}"
            out.append(_line([c.name, m, str(len(c.V)), str(r["P"])] + [num(r[k]) for k in KEYS]
                             + [zebra, box, folds]))
    for seq, per_method in orders.items():
        for m, o in per_method.items():
            cells = {"dmax": o["dmax"], "drms": o["drms"], "nmax": o["nmax"],
                     "nxmax": o["nxmax"], "Hrms": o["Hrms"], "Hmax": o["Hmax"],
                     "Hxrms": o["Hxrms"], "Hxmax": o["Hxmax"]}
            out.append(_line([f"order {seq}", m, "", ""] + [num(cells.get(k, np.nan)) for k in KEYS]
                             + ["", "", ""]))
    return out


class Verdicts:
    """Acceptance lines of issue 11 for one GERBS method label ``g``."""

    def __init__(self, results, orders, ratios, g):
        self.R, self.O, self.ratios, self.g = results, orders, ratios, g
        self.lines = []

    def get(self, case, method, key):
        r = self.R.get((case, method))
        return np.nan if r is None else r[key]

    def add(self, ok, text):
        ok = bool(ok)
        self.lines.append(f"- {'PASS' if ok else 'FAIL'} {text}")

    def missing(self, text, names, methods):
        gone = [n for n in names if any((n, m) not in self.R for m in methods)]
        self.lines.append(f"- n/a  {text} (not measured: {', '.join(gone) or 'see notes'})")

    def have(self, names, methods):
        return all((n, m) in self.R for n in names for m in methods)

    def sphere(self):
        g, lv = self.g, ["ico1", "ico2", "ico3", "ico4"]
        if not self.have(lv, [g, "loop", "butterfly"]):
            return self.missing("sphere", lv, [g, "loop", "butterfly"])
        H = [self.get(n, g, "Hrms") for n in lv]
        Hx = [self.get(n, g, "Hxrms") for n in lv]
        Lp = [self.get(n, "loop", "Hrms") for n in lv]
        f = lambda xs: " / ".join(num(x) for x in xs)  # noqa: E731
        self.add(all(a <= b for a, b in zip(H, Lp)),
                 f"sphere H rms (cotangent) <= Loop's at levels 1-4: {f(H)} vs {f(Lp)} "
                 f"(exact-derivative H rms {f(Hx)})")
        o = self.O["ico L2-4"][g]["Hrms"]
        dec = all(a > b for a, b in zip(H[1:], H[2:]))
        og = self.O["ico L2-4"][g]
        self.add(dec and o >= 1.5, f"sphere H rms decreasing L2-4 with order >= 1.5: "
                 f"{'decreasing' if dec else 'not decreasing'}, order {num(o)} (L3-4 alone "
                 f"{num(og['Hrms@last'])}; exact-derivative {num(og['Hxrms'])})")
        mn = [self.get(n, g, "Hmin") for n in lv]
        mx = [self.get(n, g, "Hxmin") for n in lv]
        both = [np.nanmin([a, b]) for a, b in zip(mn, mx)]
        self.add(all(b > 0 for b in both), f"sphere min H > 0 at every level: cotangent "
                 f"{f(mn)}, exact-derivative {f(mx)}")
        nm = [self.get(n, g, "nmax") for n in lv]
        nb = [self.get(n, "butterfly", "nmax") for n in lv]
        self.add(all(a <= b for a, b in zip(nm, nb)),
                 f"sphere largest normal error (vertex normals of the output) <= Butterfly's: "
                 f"{f(nm)} vs {f(nb)} deg (exact normals: "
                 f"{f([self.get(n, g, 'nxmax') for n in lv])})")

    def torus(self):
        g, ts = self.g, ["torus12x8", "torus24x16", "torus48x32"]
        if not self.have(ts, [g, "butterfly"]):
            return self.missing("torus", ts, [g, "butterfly"])
        f = lambda xs: " / ".join(num(x) for x in xs)  # noqa: E731
        H = [self.get(n, g, "Hrms") for n in ts]
        B = [self.get(n, "butterfly", "Hrms") for n in ts]
        og = self.O["torus 12-48"][g]
        o = og["Hrms"]
        self.add(all(a <= b for a, b in zip(H, B)) and o >= 1.5,
                 f"torus H rms (cotangent) <= Butterfly's at every size, order >= 1.5: {f(H)} vs "
                 f"{f(B)}, order {num(o)} (24-48 alone {num(og['Hrms@last'])}; exact-derivative "
                 f"{f([self.get(n, g, 'Hxrms') for n in ts])}, order {num(og['Hxrms'])})")
        d = [self.get(n, g, "dmax") for n in ts]
        db = [self.get(n, "butterfly", "dmax") for n in ts]
        self.add(all(a <= b for a, b in zip(d, db)),
                 f"torus largest distance <= Butterfly's: {f(d)} vs {f(db)}")

    def cylinder_cone_cube(self):
        g = self.g
        for name, lim in (("cylinder", 1.2), ("cone", 1.2), ("cube", 1.45)):
            if not self.have([name], [g]):
                self.missing(name, [name], [g])
                continue
            box = self.get(name, g, "box")
            self.add(np.all(box <= lim), f"{name} box <= {lim}x the cage's: "
                     f"{'/'.join(num(b) for b in box)}")
        for name in ("cylinder", "cone"):
            if not self.have([name, name + "@16"], [g]):
                self.missing(f"{name} r=16 / r=8", [name, name + "@16"], [g])
                continue
            a8, a16 = self.get(name, g, "fmax"), self.get(name + "@16", g, "fmax")
            self.add(a16 <= 0.6 * a8, f"{name} largest dihedral r=16 <= 0.6x r=8: "
                     f"{num(a16)} vs {num(a8)} deg (x{num(a16 / a8)})")
        if self.have(["cylinder"], [g]):
            a8 = self.get("cylinder", g, "fmax")
            self.add(a8 <= 20, f"cylinder largest dihedral <= 20 deg (r=8): {num(a8)}")

    def real(self):
        g, ok, parts, names = self.g, True, [], []
        for n in ("suzanne", "cow", "airplane", "bone", "bunny10k"):
            if not self.have([n], [g, "catmull-clark L2"]):
                continue
            names.append(n)
            a60, a90 = self.get(n, g, "f60"), self.get(n, g, "f90")
            c60 = self.get(n, "catmull-clark L2", "f60")
            good = a90 == 0 and a60 <= 2 * c60
            ok &= good if n == "suzanne" else True
            parts.append((n, good, f"{n} {a60}/{a90} vs CC L2 {c60}/"
                          f"{self.get(n, 'catmull-clark L2', 'f90')}"))
        if "suzanne" not in names or len(names) < 3:
            return self.missing("Suzanne + 2 real meshes", ["suzanne", "cow", "airplane", "bone"],
                                [g, "catmull-clark L2"])
        n_good = sum(p[1] for p in parts if p[0] != "suzanne")
        self.add(ok and n_good >= 2, "real meshes: no pair > 90 deg, > 60 deg at most 2x Subdivision "
                 "Surface level 2 (Suzanne and at least two more), pairs >60/>90: "
                 + "; ".join(p[2] for p in parts))

    def zebra(self):
        """Issue 11's "zebra on Suzanne and the torus at least as regular as Butterfly's", as
        the stripes' visible pieces per direction (measure.py's ``zebra`` and ``zebra_fine``:
        pieces of at least 1e-3 and 1e-4 of the area; fewer is fairer): at both sizes."""
        g, names = self.g, ["suzanne", "torus12x8", "torus24x16", "torus48x32"]
        if not self.have(names[:1], [g, "butterfly"]):
            return self.missing("zebra", names[:1], [g, "butterfly"])
        names = [n for n in names if self.have([n], [g, "butterfly"])]
        z = lambda n, m: f"{num(self.get(n, m, 'zebra'))}/{num(self.get(n, m, 'zebra_fine'))}"  # noqa: E731
        ok = all(self.get(n, g, k) <= self.get(n, "butterfly", k)
                 for n in names for k in ("zebra", "zebra_fine"))
        parts = [f"{n} {z(n, g)} vs {z(n, 'butterfly')}" for n in names]
        peers = ", ".join(f"{m} {z('suzanne', m)}" for m in ("loop", "catmull-clark"))
        self.add(ok, "zebra stripes in no more visible pieces than Butterfly's (per direction, "
                 "pieces of >= 1e-3 / >= 1e-4 of the area): " + "; ".join(parts)
                 + f" (Suzanne: {peers})")

    def all(self):
        self.sphere()
        self.torus()
        self.cylinder_cone_cube()
        self.real()
        self.zebra()
        self.lines.append("- n/a  zebra figures (README, looked at), 'what holds today' (tests, "
                          "bench_surface, bench_blender), the closing note: not measured here")
        return self.lines
