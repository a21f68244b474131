"""The extension's type stubs match the compiled module."""

from __future__ import annotations

import subprocess
import sys


def test_core_stubs_match_the_extension():
    done = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "dream._core"], capture_output=True, text=True, timeout=300, check=False
    )
    assert done.returncode == 0, done.stdout + done.stderr
