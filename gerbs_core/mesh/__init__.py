"""Blending surfaces over polygon meshes (paper sections 4-5 on a 2-manifold domain).

Stage by stage (docs/design.md): :mod:`.repair`, :mod:`.topology`, :mod:`.validation`,
:mod:`.layout`, :mod:`.charts`, :mod:`.cover`, :mod:`.rings`, :mod:`.fits`,
:mod:`.agreement`, :mod:`.evaluate`, :mod:`.lattice`, :mod:`.assembly`,
:mod:`.stencil`, :mod:`.surface`.
"""
from .agreement import FairnessRule
from .lattice import Lattice, output_counts
from .stencil import Stencil
from .surface import BlendingSurface
from .topology import MeshTopology
from .validation import validate_geometry

__all__ = ["BlendingSurface", "FairnessRule", "Lattice", "MeshTopology", "Stencil",
           "output_counts", "validate_geometry"]
