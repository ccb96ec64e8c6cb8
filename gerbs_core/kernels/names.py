"""Kernels by name: the one lookup behind every ``kernel=`` argument of gerbs_core.

``KERNEL_NAMES`` are the names the Blender add-on and the CLI (``--kernel``) use, each
the kernel with its default parameters; :func:`as_kernel` turns None, a
:class:`~gerbs_core.kernels.base.Kernel` or one of those names into a kernel and refuses
anything else with an :class:`~gerbs_core.errors.InvalidParameterError` naming the
argument and listing what is accepted.
"""
from __future__ import annotations

from ..errors import InvalidParameterError
from .base import Kernel
from .bfbs import BFBS
from .elementary import Affine
from .erbs import ERBS
from .logistic import LogisticStep

__all__ = ["KERNEL_NAMES", "as_kernel"]

# name -> the kernel class, made with its default parameters
KERNEL_NAMES = {"erbs": ERBS, "bfbs": BFBS, "logistic": LogisticStep, "affine": Affine}


def as_kernel(kernel, name: str = "kernel") -> Kernel:
    """None -> ``ERBS()``; a Kernel -> itself; a name of :data:`KERNEL_NAMES` -> that
    kernel with its default parameters; anything else: InvalidParameterError(``name``)
    listing the accepted names."""
    if kernel is None:
        return ERBS()
    if isinstance(kernel, Kernel):
        return kernel
    if isinstance(kernel, str) and kernel in KERNEL_NAMES:
        return KERNEL_NAMES[kernel]()
    names = ", ".join(repr(n) for n in KERNEL_NAMES)
    got = repr(kernel) if isinstance(kernel, (str, int, float)) else type(kernel).__name__
    raise InvalidParameterError(name, f"must be a gerbs_core.kernels.Kernel or one of {names}, "
                                f"got {got}")
