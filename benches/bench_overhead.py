"""DREAM's own cost per step on the rps backend: whole steps less the time spent inside rps.

    python benches/bench_overhead.py                  # hrvo-circle, N = 10, 600 steps, seeds 0-6
    python benches/bench_overhead.py --steps 300 --runs 9

Each run is hrvo-circle on the Robotarium backend (rps). rps's own ``get_poses``,
``set_velocities`` and ``step`` (its validation and dynamics) are timed by wrapping the methods
of its simulator class for the run; DREAM's share of a step is the runner's wall time per step
less the time inside rps: the robots' timers (sensors, radios, controllers), the backend's
checks and bookkeeping (DREAM's own validation, thresholding, copies) and the loop. The table
gives per-step medians over the runs (one seed each). Target (issue 10): DREAM's share
<= 0.2 ms per step at N = 10.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import statistics
import time
from collections.abc import Callable, Iterator
from typing import Any

import dream
from harness import REPEAT, machine, show, table

#: rps's methods that the backend calls once per step.
RPS_METHODS = ("get_poses", "set_velocities", "step")


@contextlib.contextmanager
def timed_rps() -> Iterator[dict[str, float]]:
    """Seconds spent in each of rps's per-step methods (all instances) while the block runs: wall
    time under the methods' names, and the thread's CPU time in all of them under ``"cpu"``."""
    from rps.robotarium import Robotarium

    spent = dict.fromkeys((*RPS_METHODS, "cpu"), 0.0)
    originals = {name: Robotarium.__dict__.get(name) for name in RPS_METHODS}

    def wrap(name: str, method: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(method)
        def timed(*args: Any, **kwargs: Any) -> Any:
            start, cpu = time.perf_counter(), time.thread_time()
            try:
                return method(*args, **kwargs)
            finally:
                spent[name] += time.perf_counter() - start
                spent["cpu"] += time.thread_time() - cpu

        return timed

    for name in RPS_METHODS:
        setattr(Robotarium, name, wrap(name, getattr(Robotarium, name)))
    try:
        yield spent
    finally:
        for name, original in originals.items():
            if original is None:
                delattr(Robotarium, name)  # inherited: the base class's method shows through again
            else:
                setattr(Robotarium, name, original)


def one_run(n: int, steps: int, seed: int) -> dict[str, float]:
    """Per-step seconds of one run: ``whole``, ``rps_step``, ``rps_other`` and ``dream`` (wall
    time), and ``dream_cpu``: the thread's CPU time outside rps, building the robots included."""
    with timed_rps() as spent:
        cpu = time.thread_time()
        result = dream.run("hrvo-circle", n=n, seed=seed, backend="robotarium", steps=steps)
        cpu = time.thread_time() - cpu
    count = result.steps
    whole = result.wall_time / count
    rps_step = spent["step"] / count
    rps_other = (spent["get_poses"] + spent["set_velocities"]) / count
    return {
        "whole": whole,
        "rps_step": rps_step,
        "rps_other": rps_other,
        "dream": whole - rps_step - rps_other,
        "dream_cpu": (cpu - spent["cpu"]) / count,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", type=int, default=10, help="robots (rps takes at most 50)")
    parser.add_argument("--steps", type=int, default=600, help="step cap of each run")
    parser.add_argument("--runs", type=int, default=REPEAT, help=f"runs (seeds 0..runs-1; at least {REPEAT})")
    args = parser.parse_args()
    runs = [one_run(args.n, args.steps, seed) for seed in range(max(args.runs, REPEAT))]
    median = {key: statistics.median(run[key] for run in runs) for key in runs[0]}
    print(f"# DREAM's overhead per step on rps: hrvo-circle, N = {args.n}, {args.steps} steps")
    print(machine())
    print(f"medians of {len(runs)} runs (seeds 0-{len(runs) - 1}); per step\n")
    rows = [
        ["whole step (runner's wall time)", show(median["whole"])],
        ["inside rps's step()", show(median["rps_step"])],
        ["inside rps's get_poses() and set_velocities()", show(median["rps_other"])],
        ["**DREAM's share** (target <= 0.2 ms)", show(median["dream"])],
        ["DREAM's share in CPU time (building the robots included)", show(median["dream_cpu"])],
    ]
    print(table(["part", "time per step"], rows))
    print(
        f"\nrps's step() is {median['rps_step'] / median['whole']:.0%} of a step; DREAM's share runs at "
        f"{1 / median['dream']:.0f} steps/s"
    )


if __name__ == "__main__":
    main()
