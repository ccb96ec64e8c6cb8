"""Prototype: the flipped triangulation of obtuse triangles (gerbs_core.mesh.lattice_templates
``FLIP_ANGLE``, ``flipped_triangles``) at other thresholds, as bench_shape variants
(``--variant scripts/shape/proto/flip.py:off,...``; ``off`` = no face flipped, the former
output), and the fold counts side by side on one build per mesh:

    OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/shape/proto/flip.py [cow suzanne ...] [--r 16]

prints, per mesh and threshold, the output pairs above 60 / 90 degrees, the largest, the
faces flipped and the largest output triangle angle (3D)."""
import sys
from contextlib import contextmanager
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.lattice_templates as lt  # noqa: E402

THRESHOLDS = (180.0, 135.0, 120.0, 110.0)


@contextmanager
def flip_at(angle: float):
    """FLIP_ANGLE = angle (degrees) while the block runs (180: nothing flipped)."""
    with patching({}, {}, [(lt, "FLIP_ANGLE", angle)]):
        yield


def _variant(angle):
    def f(V, F, r, exact=True):
        return run_variant(lambda: flip_at(angle), V, F, r, exact=exact)
    return f


off, flip110, flip120, flip135 = (_variant(a) for a in (180.0, 110.0, 120.0, 135.0))


def largest_angles(P, T):
    """(T,) the largest angle (degrees) of every output triangle in 3D."""
    p = P[T]
    out = []
    for k in range(3):
        a, b = p[:, (k + 1) % 3] - p[:, k], p[:, (k + 2) % 3] - p[:, k]
        c = np.einsum("ij,ij->i", a, b) / np.maximum(
            np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
        out.append(np.degrees(np.arccos(np.clip(c, -1, 1))))
    return np.max(out, axis=0)


def main(names, r=8):
    from gerbs_core import BlendingSurface
    from shape.folds import fold_sites, load
    for name in names:
        V, F = load(name)
        s = BlendingSurface(V, F)
        for t in THRESHOLDS:
            with flip_at(t):
                sites = fold_sites(s, r, 60.0)
                lat = s.lattice(r)
                P, T, _ = s.tessellate(r)
            a = np.array([x[0] for x in sites] or [0.0])
            print(f"{name} r={r} flip>{t:.0f}: pairs>60 {len(sites)}, >90 {int((a > 90).sum())}, "
                  f"largest {a.max():.1f}; faces flipped {int((lat.flip >= 0).sum())} of "
                  f"{len(lat.flip)}; output angle max {largest_angles(P, T).max():.1f}",
                  flush=True)


if __name__ == "__main__":
    args = sys.argv[1:]
    r = int(args.pop(args.index("--r") + 1)) if "--r" in args else 8
    main([a for a in args if a != "--r"] or ["suzanne", "cow"], r)
