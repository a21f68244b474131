"""Rust kernels against their NumPy reference, measured side by side in one run.

    python benches/bench_kernels.py
"""

from __future__ import annotations

import numpy as np
from harness import median_seconds, show, table

from dream import _core, _reference, backends
from dream.specs import RPS, ArenaSpec

WHEELS = dict(diameter=RPS.diameter, wheel_radius=RPS.wheel_radius, base_length=RPS.base_length, max_wheel=RPS.max_wheel)


def dynamics_rows() -> list[list[object]]:
    """One Fast-backend tick: Euler step plus rps validation (collisions included)."""
    rows = []
    for n in (100, 1_000, 4_000):
        arena = ArenaSpec.centred(3.2 * np.sqrt(n / 10), 2.0 * np.sqrt(n / 10))
        poses = backends.initial_poses(n, np.random.default_rng(0), arena)
        commands = np.random.default_rng(1).uniform(-0.3, 0.3, (2, n))

        def rust() -> None:
            _core.validate(poses, commands, arena.bounds, **WHEELS)
            _core.unicycle_step(poses, commands, RPS.time_step)

        def numpy() -> None:
            _reference.validate(poses, commands, arena.bounds, **WHEELS)
            _reference.unicycle_step(poses, commands, RPS.time_step)

        fast, slow = median_seconds(rust), median_seconds(numpy)
        rows.append([f"dynamics/n={n}", show(fast), show(slow), f"{slow / fast:.0f}x"])
    return rows


if __name__ == "__main__":
    print(table(["kernel", "Rust (median)", "NumPy reference (median)", "speed-up"], dynamics_rows()))
