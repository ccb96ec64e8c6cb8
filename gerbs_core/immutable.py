"""Immutable objects: instances that refuse attribute writes once constructed.

The package's interpolators, surfaces and stencils are values, as scipy's interpolators
are meant to be used: ``obj.kernel = ...`` after construction would change what the
object reports without changing what it computes (the kernel is baked into its cover),
so it raises instead. Lazy caches (a transposed matrix made on first use, a memo) are
written by the class itself through :meth:`Immutable._cache`; ``functools.cached_property``
writes the instance dictionary directly and needs nothing.
"""
from __future__ import annotations

__all__ = ["Immutable"]


class Immutable:
    """Mixin: after :meth:`_freeze` (the constructor's last step) ``setattr`` and
    ``delattr`` raise AttributeError naming the class and the attribute."""

    __slots__ = ()

    def __setattr__(self, name, value):
        if self.__dict__.get("_frozen", False):
            raise AttributeError(f"{type(self).__name__} objects are immutable: cannot set "
                                 f"{name!r} (make a new one)")
        object.__setattr__(self, name, value)

    def __delattr__(self, name):
        if self.__dict__.get("_frozen", False):
            raise AttributeError(f"{type(self).__name__} objects are immutable: cannot "
                                 f"delete {name!r}")
        object.__delattr__(self, name)

    def _freeze(self) -> None:
        object.__setattr__(self, "_frozen", True)

    def _cache(self, name: str, value):
        """Write the lazy cache `name` (the class's own, never a public attribute)."""
        object.__setattr__(self, name, value)
        return value
