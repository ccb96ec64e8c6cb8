"""scripts/install.sh refuses an option it does not know before installing anything
(a typo such as --main_only must not start the full 4 GB install)."""
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_unknown_option_is_refused_before_any_work(tmp_path):
    out = subprocess.run(["bash", str(ROOT / "scripts" / "install.sh"), "--main_only"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert out.returncode == 2
    assert "unknown option '--main_only'" in out.stderr and "--main-only" in out.stderr
    assert out.stdout == "" and not any(tmp_path.iterdir())
