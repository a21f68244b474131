"""Rust kernels against their NumPy reference, measured side by side in one run.

    python benches/bench_kernels.py            # all tables (a few minutes: the references are slow)
    python benches/bench_kernels.py --quick    # smaller sizes only
    python benches/bench_kernels.py --baseline OLD/_core.so   # also time another build of the kernels

The scenes (``scenes.py``) have ~10 robots within 1 m of each, the sensing range of the
experiments: the easy jittered lattice and the hard ones (uniform random with overlaps, a dense
antipodal crossing, a crowd whose preferred velocities are all blocked), and hrvo-circle's ring,
~5 within 1 m but spread thin over an arena hundreds of metres wide. Neighbours and HRVO
query within 1 m (HRVO's neighbour search is included in its time); Voronoi cells have radius
0.5 m. The NumPy reference is timed at the same size when that takes seconds, otherwise at a
smaller size (the cell says which) and the speed-up compares the time per robot.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from types import ModuleType

import numpy as np

from dream import _core, _reference, backends, kernels
from dream._csr import spans
from dream.experiments.hrvo_circle import circle_layout
from dream.kernels import _dispatch
from dream.specs import RPS, ArenaSpec
from harness import extension, machine, median_seconds, show, table
from original_hrvo import original_style_hrvo
from scenes import RANGE, SCENES, lattice

WHEELS = {
    "diameter": RPS.diameter,
    "wheel_radius": RPS.wheel_radius,
    "base_length": RPS.base_length,
    "max_wheel": RPS.max_wheel,
}
#: Another build of ``dream._core`` to time beside this one (``--baseline``), or None.
BASELINE: ModuleType | None = None


def on_baseline(call: Callable[[], object]) -> Callable[[], object]:
    """``call`` with ``dream.kernels`` dispatching to the baseline build instead of this one."""

    def swapped() -> object:
        _dispatch._core = BASELINE
        try:
            return call()
        finally:
            _dispatch._core = _core

    return swapped


def row(
    name: str,
    n: int,
    fast: Callable[[int], Callable[[], object]],
    slow: Callable[[int], Callable[[], object]],
    limit: int,
) -> list[object]:
    """Timings of ``fast(n)()`` and of the reference ``slow(m)()`` with ``m = min(n, limit)``.

    ``fast`` and ``slow`` build the call for a size (building is not timed); with ``m < n`` the
    speed-up is per robot.
    """
    call = fast(n)
    fast_s = median_seconds(call)
    cells: list[object] = [name, show(fast_s), show(fast_s / n) if n else "-"]
    if BASELINE is not None:
        base_s = median_seconds(on_baseline(call))
        cells += [show(base_s), f"{base_s / fast_s:.2f}x"]
    m = min(n, limit)
    slow_s = median_seconds(slow(m), min_time=0.0)
    at = "" if m == n else f" (at n={m})"
    cells += [show(slow_s) + at, f"{(slow_s / m) / (fast_s / n):,.0f}x"]
    return cells


def header(what: str = "Rust") -> list[str]:
    cells = ["kernel", f"{what} (median)", "per robot"]
    if BASELINE is not None:
        cells += ["baseline build (median)", "baseline / this"]
    return cells + ["NumPy reference (median)", "speed-up"]


def dynamics_rows(sizes) -> list[list[object]]:
    """One Fast-backend tick: rps validation (grid collision search) plus the Euler step, on
    rps's random grid start in an arena grown with n, and on hrvo-circle's ring (spread thin)."""

    def tick(step: Callable, check: Callable, ring: bool) -> Callable[[int], Callable[[], object]]:
        def build(n: int) -> Callable[[], object]:
            if ring:
                arena = circle_layout(n).arena
                headings = np.random.default_rng(0).uniform(-np.pi, np.pi, n)
                poses = np.vstack((SCENES["ring"](n).positions.T, headings))
            else:
                arena = ArenaSpec.centred(3.2 * math.sqrt(n / 10), 2.0 * math.sqrt(n / 10))
                poses = backends.initial_poses(n, np.random.default_rng(0), arena)
            commands = np.random.default_rng(1).uniform(-0.3, 0.3, (2, n))
            return lambda: (check(poses, commands, arena), step(poses, commands))

        return build

    def reference_check(poses, commands, arena):
        return _reference.validate(poses, commands, arena.bounds, **WHEELS)

    def reference_step(poses, commands):
        return _reference.unicycle_step(poses, commands, RPS.time_step)

    return [
        row(
            f"dynamics/{'ring' if ring else 'grid start'}/n={n}",
            n,
            tick(kernels.unicycle_step, kernels.validate, ring),
            tick(reference_step, reference_check, ring),
            4_000,
        )
        for ring in (False, True)
        for n in sizes
    ]


def neighbour_rows(sizes) -> list[list[object]]:
    """The whole swarm's neighbours within RANGE, on the lattice, the uniform and the ring scene."""
    rows = []
    for name in ("lattice", "uniform", "ring"):
        for n in sizes:

            def build(m: int, find: Callable = kernels.neighbours, make: Callable = SCENES[name]) -> Callable:
                p = make(m).positions
                return lambda: find(p, RANGE)

            def slow(m, build=build):
                return build(m, _reference.neighbours)

            rows.append(row(f"neighbours/{name}/n={n}", n, build, slow, 10_000))
    return rows


def hrvo_rows(sizes) -> list[list[object]]:
    """Whole-swarm HRVO through the public API, neighbour search included, on every scene."""
    rows = []
    for name, make in SCENES.items():
        for n in sizes:

            def build(m: int, hrvo: Callable = kernels.hrvo, make: Callable = make) -> Callable[[], object]:
                p, v, pref = make(m)
                return lambda: hrvo(p, v, pref, radius=RANGE)

            def slow(m, build=build):  # noqa: F811 (one reference per table)
                return build(m, _reference.hrvo)

            rows.append(row(f"hrvo/{name}/n={n}", n, build, slow, 1_000))
    return rows


def voronoi_rows(sizes) -> list[list[object]]:
    """Cells of radius 0.5 (the disc polygon has 64 vertices) in an arena that fits the swarm."""

    def build(m: int, cells: Callable = kernels.voronoi_cells) -> Callable[[], object]:
        p = lattice(m).positions
        box = (
            float(p[:, 0].min()) - 0.2,
            float(p[:, 0].max()) + 0.2,
            float(p[:, 1].min()) - 0.2,
            float(p[:, 1].max()) + 0.2,
        )
        return lambda: cells(p, radius=0.5, bounds=box)

    rows = [row(f"voronoi/lattice/n={n}", n, build, lambda m: build(m, _reference.voronoi_cells), 1_000) for n in sizes]

    def heard(m: int, cells: Callable = kernels.voronoi_cells) -> Callable[[], object]:
        p, (indptr, points), _ = crowd(m)
        return lambda: cells(p, radius=1.0, bounds=BIG, virtual=(indptr, points), neighbours=False)

    return rows + [
        row(f"voronoi/crowd heard/n={n}", n, heard, lambda m: heard(m, _reference_cells), 100) for n in sizes
    ]


#: Bounds that clip nothing in the crowd scene.
BIG = (-1e3, 1e3, -1e3, 1e3)


def _reference_cells(p, *, radius, bounds, virtual, neighbours):  # type: ignore[no-untyped-def]
    """The NumPy reference of ``voronoi_cells``, called as the public API is."""
    return _reference.voronoi_cells(
        p, radius=radius, bounds=bounds, virtual_indptr=virtual[0], virtual_points=virtual[1], neighbours=neighbours
    )


def crowd(m: int) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The voronoi-coverage start: ``m`` robots 0.2 m apart, each having heard the ~300 within 2 m
    and seen the ~20 within 0.5 m (CSR ``(offsets, points)`` of each, by robot)."""
    side = math.ceil(math.sqrt(m))
    p = 0.2 * np.column_stack(np.divmod(np.arange(m), side)).astype(np.float64)
    p += np.random.default_rng(0).uniform(-0.02, 0.02, p.shape)
    out = []
    for reach in (2.0, 0.5):
        indptr, indices, _ = kernels.neighbours(p, reach)
        out.append((indptr, p[indices]))
    return p, out[0], out[1]


def far_from_rows(sizes) -> list[list[object]]:
    """Robots seen but not heard in the crowd scene: each robot's ~20 detections against the ~300
    positions it heard (``far_from``, row by row)."""

    def build(m: int, far: Callable | None = None) -> Callable[[], object]:
        _, (heard, said), (seen, where) = crowd(m)
        if far is None:
            return lambda: kernels.far_from(where, said, 0.08, offsets=(seen, heard))
        return lambda: far(where, said, 0.08, seen, heard)

    return [row(f"far_from/crowd/n={n}", n, build, lambda m: build(m, _reference.far_from), 1_000) for n in sizes]


def heard_scene(m: int) -> dict[str, object]:
    """The voronoi-coverage start at a step: ``m`` robots 0.2 m apart (the crowd scene), their
    messages a few centimetres off, a fifth of them hearing (radio range 2 m: ~300 messages
    each) and each seeing the ~20 robots within 0.5 m."""
    p, _, (seen, where) = crowd(m)
    rng = np.random.default_rng(1)
    said = p + rng.uniform(-0.03, 0.03, p.shape)
    hearers = np.arange(0, m, 5)
    starts, counts = seen[hearers], np.diff(seen)[hearers]
    picks = spans(starts, counts)
    return dict(
        here=p[hearers],
        hearers=hearers,
        positions=p,
        said=said,
        seen=(np.concatenate(([0], np.cumsum(counts))), where[picks]),
    )


def heard_rows(sizes) -> list[list[object]]:
    """The cells of the robots that talk at a step of the coverage start, each clipped by what its
    radio heard: :func:`dream.kernels.heard_cells` (one pass) against the three kernels it
    replaces (neighbour rows of the hearers, ``far_from``, ``voronoi_cells`` of the gathered
    points, as the swarm mode called them before) and against the NumPy reference."""

    def fused(m: int, cells: Callable = kernels.heard_cells) -> Callable[[], object]:
        s = heard_scene(m)
        return lambda: cells(
            s["here"], s["hearers"], s["positions"], s["said"], range=2.0, seen=s["seen"], same=0.08, bounds=BIG
        )

    def three(m: int) -> Callable[[], object]:
        s = heard_scene(m)
        here, hearers, p, said, (seen_indptr, seen) = (s[k] for k in ("here", "hearers", "positions", "said", "seen"))

        def call() -> object:
            rows = np.zeros(len(p), dtype=bool)
            rows[hearers] = True
            indptr, senders, _ = kernels.neighbours(p, 2.0, rows=rows)
            heard = said[senders]
            offsets = np.concatenate(([0], indptr[1:][rows]))
            silent = kernels.far_from(seen, heard, 0.08, offsets=(seen_indptr, offsets))
            extra_rows = np.repeat(np.arange(len(hearers)), np.diff(seen_indptr))[silent]
            clips = np.insert(heard, offsets[1:][extra_rows], seen[silent], axis=0)
            counts = np.diff(offsets) + np.bincount(extra_rows, minlength=len(hearers))
            return kernels.voronoi_cells(
                here,
                radius=1.0,
                bounds=BIG,
                virtual=(np.concatenate(([0], np.cumsum(counts))), clips),
                neighbours=False,
            )

        return call

    def reference(m: int) -> Callable[[], object]:
        s = heard_scene(m)
        none = (np.zeros(len(s["hearers"]) + 1, dtype=np.int64), np.zeros((0, 2)))
        return lambda: _reference.heard_cells(
            s["here"], s["hearers"], s["positions"], s["said"], s["said"], range=2.0, seen_indptr=s["seen"][0],
            seen_points=s["seen"][1], same=0.08, virtual_indptr=none[0], virtual_points=none[1], radius=1.0, bounds=BIG,
        )  # fmt: skip

    rows = []
    for n in sizes:
        one, apart = median_seconds(fused(n)), median_seconds(three(n))
        slow = min(n, 100)
        ref = median_seconds(reference(slow), min_time=0.0)
        at = "" if slow == n else f" (at n={slow})"
        rows.append(
            [f"heard_cells/crowd/n={n}", show(one), show(apart), f"{apart / one:.1f}x", show(ref) + at,
             f"{(ref / slow) / (one / n):,.0f}x"]
        )  # fmt: skip
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


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes only")
    parser.add_argument(
        "--only",
        choices=("dynamics", "neighbours", "hrvo", "voronoi", "far_from", "heard", "per-robot"),
        help="one table",
    )
    parser.add_argument("--baseline", metavar="SO", help="another build of dream._core to time beside this one")
    args = parser.parse_args()
    if args.baseline:
        BASELINE = extension(args.baseline)
    print(machine())
    print(f"kernels: {kernels.IMPLEMENTATION}, {_core.__version__}, medians of >= 7 samples\n")
    quick = args.quick
    tables = {
        "dynamics": lambda: dynamics_rows((100, 1_000) if quick else (100, 1_000, 10_000)),
        "neighbours": lambda: neighbour_rows((1_000,) if quick else (1_000, 10_000, 100_000)),
        "hrvo": lambda: hrvo_rows((100,) if quick else (100, 1_000, 10_000)),
        "voronoi": lambda: voronoi_rows((100,) if quick else (100, 1_000, 10_000)),
        "far_from": lambda: far_from_rows((100,) if quick else (1_000, 10_000)),
    }
    for name, rows in tables.items():
        if args.only in (None, name):
            print(table(header(), rows()), "\n")
    if args.only in (None, "heard"):
        heard_header = [
            "kernel",
            "heard_cells (median)",
            "three kernels (median)",
            "ratio",
            "NumPy reference",
            "speed-up",
        ]
        print(table(heard_header, heard_rows((1_000,) if quick else (1_000, 10_000))), "\n")
    if args.only in (None, "per-robot"):
        print(table(["call", "DREAM (median)", "prototype-style Python (median)", "speed-up"], per_robot_rows()))
