"""gerbs_core: generalized expo-rational B-splines (GERBS), headless.

numpy + scipy only; never imports bpy. Equation numbers in docstrings refer to
Dechevsky, "Smooth convex resolution of unity and/or scattered-point Hermite
interpolation by generalized expo-rational B-splines, II: star-shaped covers",
Int. J. Pure Appl. Math. 65(4), 2010, 413-460.

The public names below are imported lazily, so that ``import gerbs_core`` is
cheap and a submodule is loaded only when one of its names is used.
"""
from __future__ import annotations

import importlib

from .errors import (  # noqa: F401  (re-exported)
    GERBSError,
    GERBSValueError,
    InvalidMeshError,
    InvalidParameterError,
    InvalidPointSetError,
    ResourceLimitError,
)

__version__ = "0.1.0"

# public name -> submodule that defines it
_LAZY = {
    # kernels (DESIGN section 1)
    "Kernel": "kernels",
    "ERBS": "kernels",
    "BFBS": "kernels",
    "LogisticStep": "kernels",
    "Affine": "kernels",
    "Step": "kernels",
    "CustomCDF": "kernels",
    # univariate GERBS splines (DESIGN section 2)
    "GERBSBasis": "splines",
    "GERBSCurve": "splines",
    # smooth star gauge (DESIGN section 4)
    "RadialEnvelope": "gauge",
    "StarGauge": "gauge",
    # scattered points in R^n (DESIGN sections 3-4)
    "GERBSInterpolator": "scattered",
    "cover_report": "scattered",
    # polygon-mesh blending surfaces (DESIGN section 5)
    "MeshTopology": "mesh",
    "validate_geometry": "mesh",
    "Lattice": "mesh",
    "output_counts": "mesh",
    "BlendingSurface": "mesh",
    "FairnessRule": "mesh",
    "Stencil": "mesh",
}

__all__ = sorted(
    list(_LAZY)
    + [
        "GERBSError",
        "GERBSValueError",
        "InvalidMeshError",
        "InvalidParameterError",
        "InvalidPointSetError",
        "ResourceLimitError",
    ]
)


def __getattr__(name: str):
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'gerbs_core' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
