"""The modifier's settings: one validator, and the one mapping to gerbs_core.

Every route that sets or reads settings -- :mod:`api`, the operators, the
command line and the sync step reading a modifier -- goes through
:func:`validate`, so a bad value is refused when it is set (and a value that
reached a modifier some other way, e.g. a driver, is refused when it is read)
with an :class:`~gerbs_core.errors.InvalidParameterError` naming the setting.
:func:`core_arguments` is the only place that knows how settings become core
arguments (kernel object, ``BlendingSurface`` keywords, resolution): a change
of the core's options is a change here.

Values, as in ``api.add_surface(**settings)``: menus as lower-case keys (either
case accepted), ints as ``int`` (not bool, not float), floats as finite reals
(returned rounded to float32, as the modifier stores them), ``use_normals`` as
bool, ``memory_budget`` in bytes. Ranges are the sockets' (``ids.SETTINGS``).
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from . import ids

_SPECS = {s.key: s for s in ids.SETTINGS}


def _error(key: str, message: str):
    from .core import module

    return module("errors").InvalidParameterError(key, message)


def _menu(spec, value):
    if isinstance(value, str) and value.lower() in spec.items:
        return value.lower()
    raise _error(spec.key, f"expected one of {list(spec.items)}, got {value!r}")


def _range(spec) -> tuple[float, float]:
    return spec.min * spec.scale, spec.max * spec.scale


def _integer(spec, value):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise _error(spec.key, f"must be an integer, got {value!r}")
    lo, hi = _range(spec)
    if not lo <= int(value) <= hi:
        raise _error(spec.key, f"must be in [{lo:g}, {hi:g}], got {int(value)}")
    return int(value)


def _real(spec, value):
    """The value as the float socket stores it (float32, in socket units), checked
    against the socket's float32 range: what is validated is what is read back."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise _error(spec.key, f"must be a real number, got {value!r}")
    value = float(value)
    lo, hi = _range(spec)
    with np.errstate(over="ignore"):
        stored = np.float32(value / spec.scale)
    if not (math.isfinite(value) and np.isfinite(stored)
            and np.float32(spec.min) <= stored <= np.float32(spec.max)):
        raise _error(spec.key, f"must be finite and in [{lo:g}, {hi:g}], got {value}")
    return float(stored) * spec.scale


def _boolean(spec, value):
    if not isinstance(value, (bool, np.bool_)):
        raise _error(spec.key, f"must be True or False, got {value!r}")
    return bool(value)


_CHECKS = {"NodeSocketMenu": _menu, "NodeSocketInt": _integer, "NodeSocketFloat": _real,
           "NodeSocketBool": _boolean}


def validate(settings: dict) -> dict:
    """Checked and normalized copy of `settings` (any subset of ``ids.SETTING_KEYS``).

    Raises InvalidParameterError naming the first bad setting (unknown keys
    included) and its accepted values.
    """
    unknown = sorted(set(settings) - set(_SPECS))
    if unknown:
        raise _error(unknown[0], f"unknown GERBS setting; expected one of {list(_SPECS)}")
    return {key: _CHECKS[_SPECS[key].socket_type](_SPECS[key], value)
            for key, value in settings.items()}


def settings_key(settings: dict) -> tuple:
    """A hashable, order-independent key of a full settings dict."""
    return tuple(sorted(settings.items()))


@dataclass(frozen=True)
class CoreArguments:
    """What the core needs for one build: ``BlendingSurface(X, F, kernel=kernel,
    **surface)`` then ``.stencil(resolution)`` / ``.tessellate(resolution)``."""

    kernel: object
    surface: dict
    resolution: int


def core_arguments(settings: dict) -> CoreArguments:
    """The one mapping from (validated, full) add-on settings to gerbs_core arguments."""
    from .core import module

    kernels = module("kernels")
    name = settings["kernel"]
    keys = zip(kernels.KERNELS[name].parameters, ids.KERNEL_PARAMETERS[name])
    kernel = kernels.make_kernel(name, **{p: settings[key] for p, key in keys})
    surface = {"boundary": settings["boundary"], "memory_budget": settings["memory_budget"],
               "merge_distance": settings["merge_distance"] if settings["merge"] else None}
    return CoreArguments(kernel, surface, settings["resolution"])
