"""The type stubs describe the module as it is (mypy's stubtest)."""

import subprocess
import sys


def test_the_stubs_match_the_native_module(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "drapery._drapery"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stdout + r.stderr
