"""Parametrize ids that are the same in every process.

pytest-xdist's workers must collect identical test ids; a CustomCDF's repr holds its
functions' addresses, which differ from process to process."""
from gerbs_core.kernels import CustomCDF


def kernel_id(kernel) -> str:
    """The kernel's repr, or "CustomCDF" for a custom kernel (its functions have no
    stable repr)."""
    return "CustomCDF" if isinstance(kernel, CustomCDF) else repr(kernel)
