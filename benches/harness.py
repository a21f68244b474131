"""Timing helpers for the benchmarks: medians of repeated calls, printed side by side.

Every bench starts with :func:`machine` (CPU, cores, load, date) so that its figures can be
judged, and times with :func:`median_seconds` (at least :data:`REPEAT` samples).
"""

from __future__ import annotations

import datetime
import importlib.util
import os
import platform
import statistics
import time
from collections.abc import Callable, Sequence
from types import ModuleType

#: Fewest samples a median is taken over.
REPEAT = 7


def median_seconds(call: Callable[[], object], repeat: int = REPEAT, min_time: float = 0.05) -> float:
    """Median wall time (s) of one ``call()`` over ``repeat`` samples (at least :data:`REPEAT`).

    Each sample loops until ``min_time`` seconds have passed and divides by the loop count, so
    fast calls are not lost in the timer's resolution; one warm-up call comes first.
    """
    call()
    samples = []
    for _ in range(max(repeat, REPEAT)):
        loops, start = 0, time.perf_counter()
        while True:
            call()
            loops += 1
            elapsed = time.perf_counter() - start
            if elapsed >= min_time:
                break
        samples.append(elapsed / loops)
    return statistics.median(samples)


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo, or what :mod:`platform` knows."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            for line in info:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> str:
    """One line saying where and when the figures were measured: CPU, cores, load, date."""
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"
    now = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
    return f"machine: {cpu_model()}, {os.cpu_count()} cores, load average {load} (1/5/15 min), {now}"


def show(seconds: float) -> str:
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if seconds >= scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds / 1e-9:.3g} ns"


def table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A Markdown table (pasted as is into docs/benchmarks.md)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def extension(path: str) -> ModuleType:
    """The ``dream._core`` build at ``path`` (an older one, say), loaded as a module of its own
    beside the installed one."""
    spec = importlib.util.spec_from_file_location("_core", path)
    if spec is None or spec.loader is None:
        raise SystemExit(f"cannot load an extension module from {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
