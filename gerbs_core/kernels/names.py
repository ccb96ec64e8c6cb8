"""Kernels by name: the one table of kernel names, and the lookup behind every
``kernel=`` argument of gerbs_core.

:data:`KERNELS` is the one list of the names the Blender add-on (its Kernel menu, in this
order and with these labels) and the CLI (``--kernel``) use: for each, the kernel class,
its label and the keyword parameters its constructor takes. :func:`make_kernel` builds a
named kernel from parameters (what the add-on's settings become);
:func:`as_kernel` turns None, a :class:`~gerbs_core.kernels.base.Kernel` or a name into
a kernel (default parameters) and refuses anything else with an
:class:`~gerbs_core.errors.InvalidParameterError` naming the argument and listing what
is accepted. ``KERNEL_NAMES`` (name -> class) is a view of the same table.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import InvalidParameterError
from .base import Kernel
from .bfbs import BFBS
from .elementary import Affine
from .erbs import ERBS
from .logistic import LogisticStep

__all__ = ["KernelEntry", "KERNELS", "KERNEL_NAMES", "make_kernel", "as_kernel"]


@dataclass(frozen=True)
class KernelEntry:
    """One named kernel: ``kernel(**{p: value for p in parameters})`` builds it."""

    kernel: type  # the Kernel subclass
    label: str  # its name in a menu
    parameters: tuple = ()  # keyword parameters of the constructor, in the paper's order


KERNELS = {
    "erbs": KernelEntry(ERBS, "ERBS", ("alpha", "beta", "gamma", "lam", "sigma")),
    "bfbs": KernelEntry(BFBS, "BFBS", ("i_left", "i_right")),
    "logistic": KernelEntry(LogisticStep, "Logistic"),
    "affine": KernelEntry(Affine, "Affine"),
}
# name -> the kernel class, made with its default parameters
KERNEL_NAMES = {name: entry.kernel for name, entry in KERNELS.items()}


def _refuse(kernel, name: str):
    names = ", ".join(repr(n) for n in KERNELS)
    got = repr(kernel) if isinstance(kernel, (str, int, float)) else type(kernel).__name__
    return InvalidParameterError(name, f"must be a gerbs_core.kernels.Kernel or one of {names}, "
                                 f"got {got}")


def make_kernel(kernel: str, **parameters) -> Kernel:
    """The kernel named `kernel` (a key of :data:`KERNELS`) with `parameters` (any subset
    of its entry's ``parameters``; the others keep their defaults). An unknown name
    raises InvalidParameterError("kernel"), a parameter the kernel does not take
    InvalidParameterError(that parameter), a bad value the kernel's own error."""
    if not isinstance(kernel, str) or kernel not in KERNELS:
        raise _refuse(kernel, "kernel")
    entry = KERNELS[kernel]
    for key in parameters:
        if key not in entry.parameters:
            raise InvalidParameterError(key, f"not a parameter of the {entry.label} kernel; "
                                        f"it takes {list(entry.parameters)}")
    return entry.kernel(**parameters)


def as_kernel(kernel, name: str = "kernel") -> Kernel:
    """None -> ``ERBS()``; a Kernel -> itself; a name of :data:`KERNELS` -> that
    kernel with its default parameters; anything else: InvalidParameterError(``name``)
    listing the accepted names."""
    if kernel is None:
        return ERBS()
    if isinstance(kernel, Kernel):
        return kernel
    if isinstance(kernel, str) and kernel in KERNELS:
        return KERNELS[kernel].kernel()
    raise _refuse(kernel, name)
