"""Swapping steps of the core for the duration of a build: the one mechanism of the
prototypes in scripts/shape/proto (bench_shape variants that change the rule without
changing the core)."""
from __future__ import annotations

from contextlib import contextmanager


@contextmanager
def patching(options: dict, opts: dict, replacements):
    """``options.update(opts)`` and ``setattr(module, name, value)`` for each (module, name,
    value) of ``replacements`` while the block runs; both restored afterwards."""
    saved_opts = dict(options)
    saved = [(m, n, getattr(m, n)) for m, n, _ in replacements]
    options.update(opts)
    for m, n, v in replacements:
        setattr(m, n, v)
    try:
        yield
    finally:
        for m, n, v in saved:
            setattr(m, n, v)
        options.clear()
        options.update(saved_opts)


def run_variant(patched, V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface built inside ``patched(**opts)``."""
    from shape import methods

    with patched(**opts):
        return methods.gerbs_samples(V, F, r, exact=exact)


def variant_of(patched, **opts):
    """A bench_shape variant function (V, F, r, exact) -> samples: the default surface
    built inside ``patched(**opts)``."""
    def variant(V, F, r, exact=True):
        return run_variant(patched, V, F, r, exact=exact, **opts)
    return variant
