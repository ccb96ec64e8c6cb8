"""Progress reporting: Blender's progress API in the UI, callbacks for scripts.

A build calls ``progress(fraction, message)`` at a few stages (reading the
mesh, building the surface, the stencil, writing the result). ``Progress``
fans that out to the window manager's progress indicator (``wm.progress_begin
/ progress_update / progress_end``; harmless in background mode) and to an
optional callback, e.g. :func:`text_bar` for the command line.
"""
from __future__ import annotations

import sys
import time


class Progress:
    """Callable ``progress(fraction in [0, 1], message)``; use as a context manager."""

    def __init__(self, callback=None, window_manager=None):
        self.callback = callback
        self.wm = window_manager
        self._inside = False
        self._begun = False

    def __enter__(self):
        self._inside = True
        return self

    def __call__(self, fraction: float, message: str = "") -> None:
        fraction = min(max(float(fraction), 0.0), 1.0)
        if self.wm is not None and self._inside:
            if not self._begun:  # begin lazily: W @ X updates never touch the cursor
                self.wm.progress_begin(0, 1000)
                self._begun = True
            self.wm.progress_update(int(1000 * fraction))
        if self.callback is not None:
            self.callback(fraction, message)

    def __exit__(self, *exc):
        if self._begun:
            self.wm.progress_end()
        self._inside = self._begun = False
        return False


def silent(fraction: float, message: str = "") -> None:
    """A progress callback that does nothing."""


def text_bar(stream=None, width: int = 30):
    """Return a callback drawing ``[#####-----]  50%  message`` on `stream` (stderr)."""
    stream = stream if stream is not None else sys.stderr
    start = time.perf_counter()

    def draw(fraction: float, message: str = "") -> None:
        filled = int(round(width * fraction))
        bar = "#" * filled + "-" * (width - filled)
        end = "\n" if fraction >= 1.0 else ""
        stream.write(f"\r[{bar}] {100 * fraction:5.1f}%  {time.perf_counter() - start:6.2f}s  "
                     f"{message:<40.40}{end}")
        stream.flush()

    return draw
