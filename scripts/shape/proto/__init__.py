"""Prototypes of changes to the fair-shape rule, measured with bench_shape without changing
the core: ``--variant scripts/shape/proto/<module>.py:variant`` (each module's ``patched``
context manager swaps one step of gerbs_core.mesh.agreement for the duration of a build).
None is the default; their numbers are in docs/design.md ("Folds" table)."""
