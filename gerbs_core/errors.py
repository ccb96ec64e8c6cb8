"""Exception hierarchy of :mod:`gerbs_core`.

Every error raised for bad input is a :class:`GERBSValueError` (a
``ValueError``), so ``except ValueError`` keeps working for callers that do not
care about the details. Subclasses carry the offending indices so that a GUI
(the Blender add-on) can point at the problem.
"""
from __future__ import annotations

from typing import Sequence

__all__ = [
    "GERBSError",
    "GERBSValueError",
    "InvalidParameterError",
    "InvalidPointSetError",
    "InvalidMeshError",
    "ResourceLimitError",
]


def _short(indices: Sequence[int] | None, limit: int = 10) -> str:
    if indices is None:
        return ""
    idx = [int(i) for i in indices]
    shown = ", ".join(str(i) for i in idx[:limit])
    more = f", ... ({len(idx)} in all)" if len(idx) > limit else ""
    return f" [{shown}{more}]"


def _rebuilt(cls, args, state):
    err = cls.__new__(cls)
    err.args = args
    err.__dict__.update(state)
    return err


class GERBSError(Exception):
    """Base class of every error raised by gerbs_core."""

    def __reduce__(self):
        # pickle and deepcopy call cls(*self.args), but the subclasses' arguments are not
        # their formatted message (found by a review: an InvalidMeshError raised in a worker
        # process broke the pool instead of reaching the caller): rebuilt from the message
        # and the attributes
        return _rebuilt, (type(self), self.args, dict(self.__dict__))


class GERBSValueError(GERBSError, ValueError):
    """Bad input. ``indices`` (tuple of int) names the offending elements, if any."""

    def __init__(self, message: str, indices: Sequence[int] | None = None):
        self.indices = tuple(int(i) for i in indices) if indices is not None else ()
        super().__init__(message + _short(indices))


class InvalidParameterError(GERBSValueError):
    """A scalar parameter (kernel parameter, degree, resolution, ...) is out of range.

    ``name`` is the parameter's name as spelled in the signature.
    """

    def __init__(self, name: str, message: str):
        self.name = name
        super().__init__(f"{name}: {message}")


class InvalidPointSetError(GERBSValueError):
    """Scattered points are duplicated, non-finite, too few, degenerate, ..."""


class InvalidMeshError(GERBSValueError):
    """A polygon mesh cannot carry a blending surface.

    ``problem`` is a short machine-readable tag, one of ``"non_manifold_edge"``,
    ``"inconsistent_orientation"``, ``"non_manifold_vertex"``, ``"degenerate_face"``, ``"duplicate_face"``,
    ``"repeated_index"``, ``"index_out_of_range"``, ``"unused_vertex"``,
    ``"non_finite"``, ``"empty"``, ``"outlier_vertex"``, ``"zero_length_edge"``,
    ``"bad_shape"``;
    ``element`` says what ``indices`` count (``"vertex"``, ``"edge"``, ``"face"``).
    Edge problems (non-manifold, inconsistent orientation, zero length) report
    the edges' end points with ``element="vertex"``, since the caller's edge
    numbering is unknown to the core; the validator may attach ``edges`` and
    ``faces`` attributes with the (a, b) pairs and the faces involved.
    """

    def __init__(self, problem: str, message: str, indices: Sequence[int] | None = None,
                 element: str = "face"):
        self.problem = problem
        self.element = element
        super().__init__(message, indices)


class ResourceLimitError(GERBSValueError):
    """A request would exceed a memory budget; the message states the estimate."""
