"""GERBS kernels (DESIGN section 1; paper Definitions 1, 2 and 4).

Every kernel is an immutable object with ``cdf(t, nu=0)``, ``bump(t, nu=0)``,
``cdf_derivs(t, nmax)``, ``bump_derivs(t, nmax)``, ``max_order`` and
``smoothness``; see :class:`Kernel` for the shared conventions. Every ``kernel=``
argument also takes a name of ``KERNELS``, the one table of kernel names (:func:`as_kernel`,
:func:`make_kernel`).
"""
from .base import Kernel
from .bfbs import BFBS
from .custom import CustomCDF
from .elementary import Affine, Step
from .erbs import ERBS
from .logistic import LogisticStep
from .names import KERNEL_NAMES, KERNELS, KernelEntry, as_kernel, make_kernel

__all__ = ["Kernel", "ERBS", "BFBS", "LogisticStep", "Affine", "Step", "CustomCDF",
           "KERNELS", "KernelEntry", "KERNEL_NAMES", "as_kernel", "make_kernel"]
