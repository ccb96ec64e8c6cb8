"""The real GERBS code behind the figures (gerbs_core only; no bpy here)."""
from __future__ import annotations

import numpy as np


def output_count(faces, n_vertices: int, resolution: int) -> int:
    """Number of tessellation samples (points) at `resolution` (exact, from the lattice)."""
    from gerbs_core.mesh.topology import MeshTopology
    from gerbs_core.mesh.lattice import output_counts

    return output_counts(MeshTopology(faces, n_vertices), int(resolution))[0]


def blending_surface(vertices, faces, *, kinked: bool = False, **options):
    """`BlendingSurface` of the mesh; `kinked=True` asks for the exact (kinked) polygon gauge.

    The kinked variant is the deliberately non-smooth control of DESIGN section 6:
    the exact star radius rho has corners in the directions of the star's
    corners, so the size functions psi_v = b(|y| / rho) have creases along the
    rays from each vertex to its star's corners (the mesh edges, and the
    diagonals of quads and n-gons).
    """
    from gerbs_core.mesh.surface import BlendingSurface

    return BlendingSurface(np.asarray(vertices, dtype=np.float64), faces,
                           exact_gauge=bool(kinked), **options)


def tessellate(vertices, faces, resolution: int, *, kinked: bool = False, **options):
    """(points (P,3), triangles (T,3), normals (P,3)) of the GERBS blending surface."""
    surf = blending_surface(vertices, faces, kinked=kinked, **options)
    return surf.tessellate(int(resolution))


def tessellate_split(vertices, faces, resolution: int, *, kinked: bool = False, **options):
    """Tessellation with the normal of every triangle corner taken from the triangle's own face.

    A shared edge sample gets one normal per incident face, each from the
    analytic derivatives of that face's evaluation. A smooth surface gives the
    same normal from both sides; a crease shows as a jump, which a zebra render
    then displays as broken stripes (instead of a smeared ramp). Returns
    (points (P,3), triangles (T,3), corner normals (T,3,3), point normals (P,3) as
    from tessellate(), max angle in degrees between the normals one sample gets
    from its different faces, edge curves (E, r+1): the sample indices along
    each mesh edge's image on the surface, vertex to vertex).
    """
    surf = blending_surface(vertices, faces, kinked=kinked, **options)
    pts, tris, nrm = surf.tessellate(int(resolution))
    lat = surf.lattice(int(resolution))
    if not np.array_equal(lat.triangles, tris):
        raise RuntimeError("tessellate() no longer returns the lattice's triangles")
    x = lat.map_to_polygon(surf.layouts.corners, local=True)
    dS = surf.evaluate_all(lat.local_face, x, nu=1)[1]
    n = np.cross(dS[..., 0], dS[..., 1])
    length = np.linalg.norm(n, axis=1)
    bad = length <= 1e-12 * max(1.0, float(length.max(initial=0.0)))
    n[bad] = nrm[lat.local_sample[bad]]  # degenerate derivatives: fall back to the sample normal
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    P = len(pts)
    key = lat.local_face * P + lat.local_sample
    order = np.argsort(key)
    tri_key = lat.triangle_face[:, None] * P + tris
    idx = order[np.searchsorted(key[order], tri_key)]
    if not np.array_equal(key[idx], tri_key):
        raise RuntimeError("a triangle corner is missing from the lattice's local table")
    corner_normals = n[idx]
    # largest angle between the normals one sample gets from its different faces
    dots = np.einsum("ij,ij->i", n, nrm[lat.local_sample])
    jump = float(np.degrees(np.arccos(np.clip(dots, -1.0, 1.0))).max())
    ends = lat.topology.edges
    curves = np.concatenate([ends[:, :1], lat.edge_samples, ends[:, 1:]], axis=1)
    return pts, tris, corner_normals, nrm, jump, curves
