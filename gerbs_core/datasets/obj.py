"""Minimal Wavefront OBJ reader/writer for polygon meshes.

Only geometry is handled: ``v x y z`` lines and ``f`` lines whose entries may
be ``a``, ``a/b``, ``a//c`` or ``a/b/c`` (texture and normal indices are
ignored), with any number of corners (n-gons) and negative (relative)
indices. Every other statement (``o``, ``g``, ``s``, ``vt``, ``vn``,
``usemtl``, comments, ...) is skipped. Faces are returned 0-based.
"""
from __future__ import annotations

import os
from typing import Iterable, Sequence

import numpy as np

from ..errors import InvalidMeshError

__all__ = ["read_obj", "write_obj", "parse_obj"]


def parse_obj(text: str) -> tuple[np.ndarray, list[tuple[int, ...]]]:
    """Parse OBJ text. Returns ``(vertices (V,3) float64, faces list of tuples)``.

    Raises :class:`InvalidMeshError` (``bad_shape``) for a malformed ``v`` or
    ``f`` statement, naming the 1-based line number.
    """
    verts: list[tuple[float, float, float]] = []
    faces: list[tuple[int, ...]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tok = line.split()
        if tok[0] == "v":
            try:
                xyz = tuple(float(t) for t in tok[1:4])
            except ValueError:
                xyz = ()
            if len(xyz) != 3:
                raise InvalidMeshError("bad_shape", f"OBJ line {lineno}: malformed vertex {raw!r}",
                                       [lineno], "line")
            verts.append(xyz)  # an optional 4th (w) or colour components are ignored
        elif tok[0] == "f":
            idx = []
            for t in tok[1:]:
                try:
                    i = int(t.split("/", 1)[0])
                except ValueError:
                    i = 0
                if i == 0:
                    raise InvalidMeshError("bad_shape", f"OBJ line {lineno}: malformed face {raw!r}",
                                           [lineno], "line")
                # negative indices count back from the vertices read so far
                idx.append(i - 1 if i > 0 else len(verts) + i)
            faces.append(tuple(idx))
    vertices = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    return vertices, faces


def read_obj(path: str | os.PathLike) -> tuple[np.ndarray, list[tuple[int, ...]]]:
    """Read an OBJ file. Returns ``(vertices (V,3) float64, faces list of 0-based tuples)``."""
    with open(path, "r", encoding="utf-8", errors="replace") as fh:
        return parse_obj(fh.read())


def write_obj(path: str | os.PathLike, vertices, faces: Iterable[Sequence[int]] | np.ndarray,
              name: str | None = None) -> None:
    """Write ``vertices (V,3)`` and 0-based ``faces`` (list of sequences or (F,k) array) as OBJ.

    Coordinates are written with 17 significant digits, so a read back is exact.
    """
    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 3:
        raise InvalidMeshError("bad_shape", f"vertices must have shape (V, 3), got {v.shape}",
                               None, "vertex")
    lines = []
    if name:
        lines.append(f"o {name}")
    lines.extend("v %.17g %.17g %.17g" % tuple(p) for p in v.tolist())
    for f in (faces.tolist() if isinstance(faces, np.ndarray) else faces):
        lines.append("f " + " ".join(str(int(i) + 1) for i in f))
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines) + "\n")
