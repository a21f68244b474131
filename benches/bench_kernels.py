"""Rust kernels against their NumPy reference, measured side by side in one run.

    python benches/bench_kernels.py            # all tables (a few minutes: the references are slow)
    python benches/bench_kernels.py --quick    # smaller sizes only

Swarms are uniform in a square sized for ~10 neighbours per robot within the query radius.
References that would take minutes (O(n^2) or Python loops at the largest sizes) are not run:
their cell says so.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from harness import median_seconds, show, table
from original_hrvo import original_style_hrvo

from dream import _core, _reference, backends, kernels
from dream.specs import RPS, ArenaSpec

WHEELS = dict(diameter=RPS.diameter, wheel_radius=RPS.wheel_radius, base_length=RPS.base_length, max_wheel=RPS.max_wheel)
NEIGHBOURS = 10


def swarm(n: int, radius: float, seed: int = 0) -> np.ndarray:
    """Positions ``(n, 2)`` with about NEIGHBOURS robots within ``radius`` of each."""
    side = math.sqrt(n * math.pi * radius**2 / NEIGHBOURS)
    return np.random.default_rng(seed).uniform(0, side, (n, 2))


def row(name: str, fast_call, slow_call, run_slow: bool, repeat: int = 5) -> list[object]:
    fast = median_seconds(fast_call, repeat=repeat)
    if not run_slow:
        return [name, show(fast), "not run", "-"]
    slow = median_seconds(slow_call, repeat=3, min_time=0.0)
    return [name, show(fast), show(slow), f"{slow / fast:,.0f}x"]


def dynamics_rows(sizes) -> list[list[object]]:
    """One Fast-backend tick: rps validation (grid collision search) plus the Euler step."""
    rows = []
    for n in sizes:
        arena = ArenaSpec.centred(3.2 * math.sqrt(n / 10), 2.0 * math.sqrt(n / 10))
        poses = backends.initial_poses(n, np.random.default_rng(0), arena)
        commands = np.random.default_rng(1).uniform(-0.3, 0.3, (2, n))

        def rust() -> None:
            _core.validate(poses, commands, arena.bounds, **WHEELS)
            _core.unicycle_step(poses, commands, RPS.time_step)

        def numpy() -> None:
            _reference.validate(poses, commands, arena.bounds, **WHEELS)
            _reference.unicycle_step(poses, commands, RPS.time_step)

        rows.append(row(f"dynamics/n={n}", rust, numpy, n <= 4_000))
    return rows


def neighbour_rows(sizes) -> list[list[object]]:
    rows = []
    for n in sizes:
        p = swarm(n, 0.5)
        rows.append(row(f"neighbours/n={n}", lambda: _core.neighbours(p, 0.5), lambda: _reference.neighbours(p, 0.5), n <= 10_000))
    return rows


def hrvo_rows(sizes) -> list[list[object]]:
    """Whole-swarm HRVO with the neighbour search (radius 0.5) included."""
    rows = []
    grid = _reference.candidate_grid(0.2)
    for n in sizes:
        p = swarm(n, 0.5)
        rng = np.random.default_rng(2)
        v = rng.uniform(-0.14, 0.14, (n, 2))
        angle = rng.uniform(-np.pi, np.pi, n)
        pref = 0.2 * np.column_stack((np.cos(angle), np.sin(angle)))

        def rust() -> None:
            _core.hrvo(p, v, pref, None, None, radius=0.5, safety=0.24, v_max=0.2, bounds=None, candidates=grid, include_preferred=True)

        rows.append(row(f"hrvo/n={n}", rust, lambda: _reference.hrvo(p, v, pref, radius=0.5), n <= 10_000))
    return rows


def voronoi_rows(sizes) -> list[list[object]]:
    """Cells of radius 0.5 (the disc polygon has 64 vertices) in an arena that fits the swarm."""
    rows = []
    for n in sizes:
        p = swarm(n, 0.5)
        side = float(p.max()) + 0.01
        box = (0.0, side, 0.0, side)
        rows.append(row(
            f"voronoi/n={n}",
            lambda: _core.voronoi_cells(p, radius=0.5, bounds=box),
            lambda: _reference.voronoi_cells(p, radius=0.5, bounds=box),
            n <= 1_000,
        ))
    return rows


def per_robot_rows() -> list[list[object]]:
    """One robot's HRVO call with 9 neighbours: DREAM's per-robot API against the prototype's loops."""
    rng = np.random.default_rng(3)
    detections = np.column_stack((rng.uniform(0.2, 1.0, 9), rng.uniform(-np.pi, np.pi, 9), rng.uniform(-0.2, 0.2, (9, 2))))
    velocity, desired, position = np.array([0.1, 0.05]), np.array([0.2, 0.0]), np.array([0.3, -0.2])
    bounds = (-1.545, 1.545, -0.945, 0.945)
    planner = kernels.HrvoPlanner(bounds=bounds)
    fast = median_seconds(lambda: planner.velocity(detections, velocity, desired, position))
    slow = median_seconds(lambda: original_style_hrvo(detections, velocity, desired, position, bounds), repeat=3)
    return [["hrvo per robot, 9 neighbours", show(fast), show(slow), f"{slow / fast:,.0f}x"]]


HEADER = ["kernel", "Rust (median)", "NumPy reference (median)", "speed-up"]

if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes only")
    quick = parser.parse_args().quick
    print(f"kernels: {kernels.IMPLEMENTATION}, {_core.__version__}\n")
    print(table(HEADER, dynamics_rows((100, 1_000) if quick else (100, 1_000, 10_000))), "\n")
    print(table(HEADER, neighbour_rows((1_000,) if quick else (1_000, 10_000, 100_000))), "\n")
    print(table(HEADER, hrvo_rows((100,) if quick else (100, 1_000, 10_000))), "\n")
    print(table(HEADER, voronoi_rows((100,) if quick else (100, 1_000, 10_000))), "\n")
    print(table(["call", "DREAM (median)", "prototype-style Python (median)", "speed-up"], per_robot_rows()))
