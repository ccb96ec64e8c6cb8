"""Where the add-on finds gerbs_core: one import rule for a checkout and for the extension.

The extension zip carries the core as the add-on's own subpackage
(``<add-on>.gerbs_core``, copied from the repository's ``gerbs_core/`` by
``scripts/build_extension.py``); a checkout uses the repository's top-level
``gerbs_core``. Add-on modules import the core only through :func:`module`, so
both layouts run the same code and an installed extension never depends on
what else is on ``sys.path``.

scipy is the core's one dependency Blender does not bundle (numpy it does). The
extension carries scipy wheels for its platform and Python 3.11 / 3.13; where
Blender found none that fits, :func:`scipy_problem` says so in one sentence.
"""
from __future__ import annotations

import importlib
import importlib.util
import platform
import sys


def _package() -> str:
    bundled = f"{__package__}.gerbs_core"
    return bundled if importlib.util.find_spec(bundled) is not None else "gerbs_core"


PACKAGE = _package()  # "gerbs_core" (checkout) or "<add-on>.gerbs_core" (extension)


def module(name: str = ""):
    """The core's submodule `name` (e.g. ``"errors"``, ``"mesh.surface"``), imported
    on first use; ``module()`` is the package itself."""
    return importlib.import_module(f"{PACKAGE}.{name}" if name else PACKAGE)


def scipy_problem() -> str:
    """"" when scipy imports in this Blender's Python, else what is wrong and what to do."""
    try:
        importlib.import_module("scipy.sparse")
    except ImportError as exc:
        python = f"{sys.version_info.major}.{sys.version_info.minor}"
        system = f"{platform.system()} {platform.machine()}"
        return (f"scipy is not available to this Blender (Python {python}, {system}): {exc}. "
                f"Install the GERBS extension zip built for this platform (it carries scipy "
                f"for Python 3.11 and 3.13); the base mesh is left as is")
    return ""
