"""What a run of ``n`` robots needs in memory, checked before anything is allocated.

A run's arrays grow linearly with its robots (poses, commands, the neighbour lists of a
bounded density, each robot's decision state). :data:`PER_ROBOT` is the least a robot costs:
hrvo-circle in swarm mode, the leanest path, peaked at 0.6-1.6 KiB a robot above a 10-robot
run from 10,000 to 1,000,000 robots (docs/benchmarks.md, "Memory"); robot-by-robot runs cost
more (a Python object a robot). The check refuses only what cannot fit in any mode: a run it
lets through may still run out, and then fails with ``MemoryError``.
"""

from __future__ import annotations

import os

FIXED = 200 * 2**20  #: bytes: the interpreter, NumPy and the extension, whatever the count
PER_ROBOT = 512  #: bytes a robot needs at least (see the module docs)


def estimate(n: int) -> int:
    """Bytes a run of ``n`` robots needs at least."""
    return FIXED + PER_ROBOT * n


def machine_memory() -> int:
    """This machine's physical memory (bytes)."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def check_fits(n: int) -> None:
    """Refuse, before any allocation, ``n`` robots whose arrays cannot fit in this machine's memory.

    Raises
    ------
    ValueError
        If :func:`estimate` exceeds :func:`machine_memory`, naming both.
    """
    need, have = estimate(n), machine_memory()
    if need > have:
        raise ValueError(
            f"n={n:,} robots need about {_size(need)} of memory ({PER_ROBOT} bytes a robot over "
            f"{_size(FIXED)}), more than this machine's {_size(have)}: run at most {(have - FIXED) // PER_ROBOT:,}"
        )


def _size(size: int) -> str:
    """``size`` bytes in the largest binary unit that keeps it at 1 or more (``"15.7 GiB"``)."""
    value, unit = float(size), "B"
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if value < 1024 or unit == "PiB":
            break
        value /= 1024
    return f"{value:.1f} {unit}"
