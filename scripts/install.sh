#!/usr/bin/env bash
# Install everything the main job and the whole test suite need (idempotent):
#   .venv           bpy 5.0.1 (the newest supported Blender, pins numpy<2), the core, pytest
#   .venvs/bpy42    bpy 4.2.0 (Blender 4.2 LTS, the oldest supported) and
#   .venvs/bpy45    bpy 4.5.15 (4.5 LTS): tests/blender/test_versions.py runs the README
#                   snippet and a compat subset in their interpreters
#   .cache/wheels   the scipy wheels every extension zip carries (all platforms, Python
#                   3.11 and 3.13), fetched from the package index here, so
#                   tests/blender/test_extension.py builds the zips offline
# Used by the README's first command and by .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
    python3.11 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -e ".[blender,test]"
for spec in "bpy42 bpy==4.2.0" "bpy45 bpy==4.5.15"; do
    set -- $spec
    if [ ! -x ".venvs/$1/bin/python" ]; then
        python3.11 -m venv ".venvs/$1"
    fi
    ".venvs/$1/bin/python" -m pip install --quiet "$2" "numpy<2" "scipy==1.17.1"
done
.venv/bin/python scripts/build_extension.py fetch
