"""A kernel whose buffers cannot be allocated raises MemoryError (Rust and NumPy alike), never aborts."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import dream

# The child imports the dream this suite tests (an installed wheel, or a checkout on PYTHONPATH).
PYTHON = Path(dream.__file__).parents[1]

# Run in a child under an address-space limit of its size at start plus 512 MiB: 20,000 robots
# at one point, each in range of all the others, make 4e8 neighbour pairs (6.4 GB).
CHILD = textwrap.dedent(
    """
    import resource, sys
    import numpy as np
    from dream import kernels
    from dream.kernels import _dispatch
    if sys.argv[1] == "rust":
        from dream import _core
        _dispatch._core = _core
    else:
        _dispatch._core = None
    size = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmSize"))
    resource.setrlimit(resource.RLIMIT_AS, (size * 1024 + 2**29, resource.RLIM_INFINITY))
    crowd, headings = np.zeros((20_000, 2)), np.zeros(20_000)
    for name, call in [
        ("neighbours", lambda: kernels.neighbours(crowd, 1.0)),
        ("perceive", lambda: kernels.perceive(crowd, headings, np.arange(len(crowd)), sight=(1.0, 7.0, 0.0))),
    ]:
        try:
            call()
        except MemoryError as err:
            print(name, "MemoryError", err)
        else:
            print(name, "no error")
    """
)


@pytest.mark.parametrize("implementation", ["rust", "numpy"])
def test_a_query_too_large_for_memory_raises_memory_error(implementation):
    done = subprocess.run(
        [sys.executable, "-c", CHILD, implementation],
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(PYTHON), "RAYON_NUM_THREADS": "2"},
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]  # an abort would be -6 (SIGABRT)
    lines = done.stdout.splitlines()
    assert [line.split()[:2] for line in lines] == [["neighbours", "MemoryError"], ["perceive", "MemoryError"]]
    if implementation == "rust":
        assert "out of memory: neighbour" in lines[0]
