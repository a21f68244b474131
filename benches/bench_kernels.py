"""Rust kernels against their NumPy reference, measured side by side in one run.

    python benches/bench_kernels.py            # all tables (a few minutes: the references are slow)
    python benches/bench_kernels.py --quick    # smaller sizes only

The swarm is a jittered square lattice (spacing 0.56 m, jitter +-0.14 m, so robots stay
0.28 m apart) with ~10 robots within 1 m of each: the sensing range of the experiments.
Neighbours and HRVO query within 1 m; Voronoi cells have radius 0.5 m (clipped by the robots
within 1 m). References that would take minutes (O(n^2) or Python loops at the largest sizes)
are not run: their cell says so.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from harness import median_seconds, show, table
from original_hrvo import original_style_hrvo

from dream import _core, _reference, backends, kernels
from dream.specs import RPS, ArenaSpec

WHEELS = dict(
    diameter=RPS.diameter, wheel_radius=RPS.wheel_radius, base_length=RPS.base_length, max_wheel=RPS.max_wheel
)
RANGE = 1.0  #: sensing range (m)
SPACING = RANGE * math.sqrt(math.pi / 10)  #: lattice spacing for ~10 robots within RANGE


def swarm(n: int, seed: int = 0) -> np.ndarray:
    """Positions ``(n, 2)`` on a jittered lattice, ~10 robots within RANGE of each."""
    columns = math.ceil(math.sqrt(n))
    lattice = np.column_stack(np.divmod(np.arange(n), columns)).astype(np.float64) * SPACING
    return lattice + np.random.default_rng(seed).uniform(-SPACING / 4, SPACING / 4, (n, 2))


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
        p = swarm(n)
        rows.append(
            row(
                f"neighbours/n={n}",
                lambda: _core.neighbours(p, RANGE),
                lambda: _reference.neighbours(p, RANGE),
                n <= 10_000,
            )
        )
    return rows


def hrvo_rows(sizes) -> list[list[object]]:
    """Whole-swarm HRVO with the neighbour search included; random velocities and goals."""
    rows = []
    grid = _reference.candidate_grid(0.2)
    for n in sizes:
        p = swarm(n)
        rng = np.random.default_rng(2)
        v = rng.uniform(-0.14, 0.14, (n, 2))
        angle = rng.uniform(-np.pi, np.pi, n)
        pref = 0.2 * np.column_stack((np.cos(angle), np.sin(angle)))

        def rust() -> None:
            _core.hrvo(
                p,
                v,
                pref,
                None,
                None,
                radius=RANGE,
                safety=0.24,
                v_max=0.2,
                bounds=None,
                candidates=grid,
                include_preferred=True,
            )

        rows.append(row(f"hrvo/n={n}", rust, lambda: _reference.hrvo(p, v, pref, radius=RANGE), n <= 10_000))
    return rows


def voronoi_rows(sizes) -> list[list[object]]:
    """Cells of radius 0.5 (the disc polygon has 64 vertices) in an arena that fits the swarm."""
    rows = []
    for n in sizes:
        p = swarm(n)
        box = (
            float(p[:, 0].min()) - 0.2,
            float(p[:, 0].max()) + 0.2,
            float(p[:, 1].min()) - 0.2,
            float(p[:, 1].max()) + 0.2,
        )
        rows.append(
            row(
                f"voronoi/n={n}",
                lambda: _core.voronoi_cells(p, radius=0.5, bounds=box),
                lambda: _reference.voronoi_cells(p, radius=0.5, bounds=box),
                n <= 1_000,
            )
        )
    return rows


def per_robot_rows() -> list[list[object]]:
    """One robot's HRVO call with 9 neighbours: DREAM's per-robot API against the prototype's loops."""
    rng = np.random.default_rng(3)
    detections = np.column_stack(
        (rng.uniform(0.2, 1.0, 9), rng.uniform(-np.pi, np.pi, 9), rng.uniform(-0.2, 0.2, (9, 2)))
    )
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
