"""Package-level invariants: the core stays headless."""
import subprocess
import sys


def test_import_gerbs_core_does_not_import_bpy():
    code = (
        "import sys, gerbs_core\n"
        "for name in gerbs_core.__all__: getattr(gerbs_core, name)\n"
        "assert 'bpy' not in sys.modules, 'gerbs_core imported bpy'\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_unknown_attribute_raises_attribute_error():
    import gerbs_core
    import pytest

    with pytest.raises(AttributeError, match="no_such_thing"):
        gerbs_core.no_such_thing
