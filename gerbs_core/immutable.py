"""Immutable objects: instances that refuse attribute writes once constructed.

The package's interpolators, surfaces and stencils are values, as scipy's interpolators
are meant to be used: ``obj.kernel = ...`` after construction would change what the
object reports without changing what it computes (the kernel is baked into its cover),
so it raises instead. Lazy caches (a transposed matrix made on first use, a memo) are
written by the class itself through :meth:`Immutable._cache`; ``functools.cached_property``
writes the instance dictionary directly and needs nothing.

Pickling and ``copy.deepcopy`` keep the read-only arrays read-only: numpy restores every
array writeable, so the state carries the list of the arrays that were not (pickle and
deepcopy restore shared objects once, so the list names the restored arrays themselves).
Found by a review: an unpickled curve's ``local_curves[...] = 7`` changed what it computed.
"""
from __future__ import annotations

import numpy as np

__all__ = ["Immutable", "ReadOnlyArrays"]

_READ_ONLY = "_read_only_arrays"


def _read_only_arrays(state: dict) -> list:
    """The non-writeable numpy arrays reachable from `state` through containers and the
    package's own objects (each once)."""
    out, seen, todo = [], set(), list(state.values())
    while todo:
        x = todo.pop()
        if id(x) in seen:
            continue
        seen.add(id(x))
        if isinstance(x, np.ndarray):
            if not x.flags.writeable and x.dtype != object:
                out.append(x)
        elif isinstance(x, dict):
            todo.extend(x.values())
        elif isinstance(x, (list, tuple, set, frozenset)):
            todo.extend(x)
        elif type(x).__module__.startswith("gerbs_core.") and not isinstance(x, type):
            todo.extend(getattr(x, "__dict__", {}).values())
            for name in getattr(type(x), "__slots__", ()):
                todo.append(getattr(x, name, None))
    return out


class ReadOnlyArrays:
    """Mixin: pickling and ``copy.deepcopy`` restore the object's read-only numpy arrays
    (its own and those of the package's objects it holds) read-only (module doc). Also for
    the package's mutable-looking but never-written objects (topologies, lattices, gauges:
    a review found an unpickled envelope's ``line_a`` writable, and writing it changed its
    star gauge's values)."""

    __slots__ = ()

    def __getstate__(self):
        return {**self.__dict__, _READ_ONLY: _read_only_arrays(self.__dict__)}

    def __setstate__(self, state: dict) -> None:
        state = dict(state)
        for a in state.pop(_READ_ONLY, ()):
            a.setflags(write=False)
        self.__dict__.update(state)


class Immutable(ReadOnlyArrays):
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
