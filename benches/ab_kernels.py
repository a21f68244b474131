"""Two builds of the Rust kernels side by side in one process: before and after a change.

Whole runs on a shared machine wander by a third from minute to minute; two builds loaded in one
process and called in turns on the same inputs see the same machine. Each scene runs both builds
alternately twelve times, three calls a turn, and prints the medians, their ratio and whether the
two answers are the same, to the bit.

Scenes: the rendezvous example's perception (``perceive``, its inbox listed; and summed in the
same pass, which builds before cf5543d cannot: "n/a"), inbox sums (``segment_reduce`` with an
index) and HRVO (``hrvo_rows``), and voronoi-coverage's perception and cells from the radio
(``perceive``, ``heard_cells``), captured from swarm runs of ``--robots`` robots (the rendezvous
example's with its inbox listed at every step, as the engine did before it learnt to sum it in
the perception's pass); ``validate`` on robots 0.3 m apart, uniformly at random, at that count
and at ten times it, and 1 m apart (where a dense table of cells of the robots' diameter would
be too large); ``unicycle_step``.

Each round draws which build goes first: a fixed order favoured the second (two copies of one
build measured 1.08x on ``perceive`` at 100,000 robots), whose first call finds memory the other's
last call freed.

Run: ``python benches/ab_kernels.py BEFORE.so AFTER.so [--robots N] [--only KERNEL ...]``, where each ``.so`` is a
build's ``dream/_core.abi3.so`` (``git worktree add`` the older commit and build it there).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

import dream
import dream.kernels._hrvo as hrvo_kernels
import dream.kernels._neighbours as neighbour_kernels
import dream.kernels._reduce as reduce_kernels
import dream.kernels._voronoi as voronoi_kernels
import dream.swarm.engine as swarm_engine

sys.path.insert(0, str(Path(__file__).parent))
from harness import extension, machine, table  # noqa: E402

RENDEZVOUS = str(Path(__file__).parents[1] / "examples" / "rendezvous.py")
#: validate's arguments: rps 0.0.0's criteria, an arena wider than any scene
CHECKS = {
    "diameter": 0.11,
    "wheel_radius": 0.016,
    "base_length": 0.105,
    "max_wheel": 12.5,
    "collider_offset": 0.0,
    "boundary_per_iteration": False,
}
BOUNDS = (-1e9, 1e9, -1e9, 1e9)
ROUNDS = 16  #: turns of each build per scene
RENDEZVOUS_KERNELS = ("perceive", "segment_reduce", "hrvo_rows")  #: timed on the rendezvous example's calls
PAUSE = 2e-4  #: seconds before each call (a run's Python between two kernels)


Call = tuple[tuple[Any, ...], dict[str, Any]]


def captured(n: int) -> dict[tuple[str, str], Call]:
    """The last ``perceive``, ``segment_reduce`` (with an index) and ``hrvo_rows`` calls of a swarm
    run of the rendezvous example, and the last ``perceive`` and ``heard_cells`` calls of one of
    voronoi-coverage, past their robots' staggered start, by (kernel, scene)."""
    calls: dict[str, Call] = {}

    def spy(module: ModuleType, name: str, keep: Callable[[tuple[Any, ...]], bool]) -> None:
        chosen = module.implementation  # type: ignore[attr-defined]

        def implementation(asked: str) -> Callable[..., Any]:
            kernel = chosen(asked)
            if asked != name:
                return kernel

            def call(*args: Any, **kwargs: Any) -> Any:
                if keep(args):
                    calls[name] = (args, kwargs)
                return kernel(*args, **kwargs)

            return call

        module.implementation = implementation  # type: ignore[attr-defined]

    spy(neighbour_kernels, "perceive", lambda args: True)
    spy(reduce_kernels, "segment_reduce", lambda args: len(args) > 3 and args[3] is not None)
    spy(hrvo_kernels, "hrvo_rows", lambda args: True)
    spy(voronoi_kernels, "heard_cells", lambda args: True)
    scenes: dict[tuple[str, str], Call] = {}
    listed = swarm_engine.summing
    swarm_engine.summing = lambda: False  # every inbox read taken for more than its sums
    try:
        for scene, experiment in (("the rendezvous example", RENDEZVOUS), ("voronoi-coverage", "voronoi-coverage")):
            calls.clear()
            dream.run(experiment, n=n, swarm=True, backend="fast", steps=36)
            scenes.update(((name, scene), call) for name, call in calls.items())
    finally:
        swarm_engine.summing = listed
    return scenes


def scattered(n: int, rng: np.random.Generator, spacing: float = 0.3) -> np.ndarray:
    """Poses ``(3, n)`` of robots ``spacing`` (m) apart on average, uniformly at random."""
    side = np.sqrt(n) * spacing
    xy = rng.uniform(-side / 2, side / 2, (2, n))
    return np.ascontiguousarray(np.vstack((xy, rng.uniform(-np.pi, np.pi, n))))


def same(a: Any, b: Any) -> bool:
    if isinstance(a, tuple):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))  # NaN: nothing yet, on both


def compare(
    before: ModuleType, after: ModuleType, call: Callable[[ModuleType], Any], rng: np.random.Generator
) -> list[str]:
    """Median ms of each build, in turns (each round's order drawn from ``rng``), their ratio and
    whether the answers agree."""
    times: dict[str, list[float]] = {"before": [], "after": []}
    builds = (("before", before), ("after", after))
    try:
        call(before)
    except TypeError:  # an argument the older build lacks
        return ["n/a", "", "", ""]
    for _ in range(ROUNDS):
        for label, module in builds if rng.random() < 0.5 else builds[::-1]:
            samples = []
            for _ in range(3):
                time.sleep(PAUSE)
                start = time.perf_counter()
                call(module)
                samples.append(time.perf_counter() - start)
            times[label].append(float(np.median(samples)) * 1e3)
    old, new = np.median(times["before"]), np.median(times["after"])
    return [f"{old:.2f}", f"{new:.2f}", f"{old / new:.2f}x", "yes" if same(call(before), call(after)) else "NO"]


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("before", help="the older build's _core.abi3.so")
    parser.add_argument("after", help="the newer build's _core.abi3.so")
    parser.add_argument("--robots", type=int, default=100_000)
    parser.add_argument("--only", nargs="+", metavar="KERNEL", help="time only these kernels' scenes")
    args = parser.parse_args(argv)
    before, after = extension(args.before), extension(args.after)
    print(machine())
    calls = captured(args.robots)
    rng = np.random.default_rng(0)
    scenes: list[tuple[str, Callable[[ModuleType], Any]]] = []
    for name, scene in [
        *((name, "the rendezvous example") for name in RENDEZVOUS_KERNELS),
        ("perceive", "voronoi-coverage"),
        ("heard_cells", "voronoi-coverage"),
    ]:
        positional, keywords = calls[name, scene]
        if not keywords.get("summed", True):  # nothing summed: a call the builds before cf5543d take too
            keywords = {key: value for key, value in keywords.items() if key != "summed"}
        scenes.append((f"`{name}`: {scene}, {args.robots:,} robots", partial_call(name, positional, keywords)))
        if (name, scene) == ("perceive", "the rendezvous example"):  # its inbox summed (two values a robot)
            summed = {"summed": [np.ascontiguousarray(column) for column in np.asarray(positional[0]).T]}
            label = f"`{name}`: {scene}, its inbox summed, {args.robots:,} robots"
            scenes.append((label, partial_call(name, positional, keywords | summed)))
    for n, spacing in ((args.robots, 0.3), (10 * args.robots, 0.3), (args.robots, 1.0)):
        poses, commands = scattered(n, rng, spacing), np.zeros((2, n))
        scenes.append(
            (
                f"`validate`: {n:,} robots {spacing} m apart",
                lambda m, p=poses, u=commands: m.validate(p, u, BOUNDS, **CHECKS),
            )
        )
    poses = scattered(args.robots, rng)
    commands = np.vstack((rng.uniform(-0.2, 0.2, args.robots), rng.uniform(-3.0, 3.0, args.robots)))
    scenes.append((f"`unicycle_step`: {args.robots:,} robots", lambda m: m.unicycle_step(poses, commands, 0.033)))
    order = np.random.default_rng(1)  # who goes first in each round
    wanted = [(label, call) for label, call in scenes if not args.only or any(f"`{k}`" in label for k in args.only)]
    rows = [[label, *compare(before, after, call, order)] for label, call in wanted]
    print(table(["kernel, scene", "before (ms)", "after (ms)", "speed-up", "same answer"], rows))


def partial_call(name: str, positional: tuple[Any, ...], keywords: dict[str, Any]) -> Callable[[ModuleType], Any]:
    return lambda module: getattr(module, name)(*positional, **keywords)


if __name__ == "__main__":
    main(sys.argv[1:])
