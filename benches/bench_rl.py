"""dream.rl's batch form at scale: agent-steps per second of a linear policy on one large world.

One ``batch_env`` of ``examples/rendezvous.py`` (every robot a row; each decides on its own clock,
every 5 steps, and the others hold their commands), stepped with a linear policy evaluated on all
rows at once: the median wall time of one step (perception of the robots due, the padding of
their observations, the policy, the engine's drive, the simulator with its validation, the
rewards), as agent-steps per second (N per step), with and without the HRVO safety layer.
The issue's target: 1,000,000 agent-steps/s at N = 10,000 on 2 cores.

``--baseline OTHER.so`` times the step instead with the installed kernels and with another build
of them (``dream/_core.abi3.so`` of an older commit), in turns on one world: whole runs on a
shared machine wander by a third from minute to minute, turns within one process see the same
machine.

``--parts`` prints instead where a step's time goes (without HRVO): the process's CPU time in
each part, over 60 steps. CPU time, unlike wall time, hardly grows when other jobs share the
cores; with ``RAYON_NUM_THREADS=1`` it is the step's cost on one core.

Run: ``python benches/bench_rl.py [--parts | --baseline OTHER.so] [N ...]`` (default 1,000 and
10,000).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import dream.kernels._dispatch as dispatch
from dream.rl import BatchEnv, LinearPolicy, batch_env

sys.path.insert(0, str(Path(__file__).parent))
from harness import extension, machine, median_seconds, show, table  # noqa: E402

RENDEZVOUS = str(Path(__file__).parents[1] / "examples" / "rendezvous.py")


def started(n: int, avoid: bool) -> tuple[BatchEnv, Callable[[], None]]:
    """The world past its start-up delays, and one step of it with a linear policy."""
    env = batch_env(RENDEZVOUS, n=n, max_steps=10**6, avoid=avoid)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    policy = LinearPolicy(0.1 * rng.standard_normal((obs.shape[1], 2)), np.zeros(2))
    state = {"obs": obs}

    def one() -> None:
        state["obs"] = env.step(policy(state["obs"]))[0]

    for _ in range(20):  # past the start-up delays: every robot on its clock, messages on the air
        one()
    return env, one


def parts(n: int, steps: int = 60) -> None:
    """Print the CPU time per step of each part of a step."""
    env, one = started(n, avoid=False)
    team, spent = env.team, defaultdict(float)

    def timed(owner: Any, name: str, label: str) -> None:
        call = getattr(owner, name)

        def wrapper(*args: Any, **kwargs: Any) -> Any:
            start = time.process_time()
            try:
                return call(*args, **kwargs)
            finally:
                spent[label] += time.process_time() - start

        setattr(owner, name, wrapper)

    timed(team.engine, "perceive", "engine: perception (kernels.perceive, noise, radio)")
    timed(team.layout, "rows", "observation rows (k nearest, masks)")
    timed(team.sim, "step", "simulator: validation and motion")
    timed(team.engine, "act", "engine: drive (conversion, limits)")
    timed(team, "_rewards", "reward: potential hook, arena")
    timed(team.stepper, "after", "runner: after the step (done())")
    timed(LinearPolicy, "__call__", "policy")
    start = time.process_time()
    for _ in range(steps):
        one()
    total = time.process_time() - start
    print(f"N = {n:,}: {show(total / steps)} of CPU time a step")
    rows = [[label, show(seconds / steps)] for label, seconds in sorted(spent.items(), key=lambda kv: -kv[1])]
    rows.append(["the rest (environment, engine bookkeeping)", show((total - sum(spent.values())) / steps)])
    print(table(["part", "CPU a step"], rows))


TURNS = 12  #: turns of each build in --baseline
STEPS_A_TURN = 8  #: steps timed a turn, after one untimed (it wakes that build's threads)


def versus(sizes: list[int], baseline: str) -> None:
    """Print the step's median with another build of the kernels and with the installed one."""
    if dispatch._core is None:
        raise SystemExit("--baseline compares two builds of the Rust kernels; DREAM runs the NumPy reference here")
    builds = {"baseline": extension(baseline), "this build": dispatch._core}
    rows = []
    for n in sizes:
        one = started(n, avoid=False)[1]
        times: dict[str, list[float]] = {label: [] for label in builds}
        for _ in range(TURNS):
            for label, build in builds.items():
                dispatch._core = build
                one()
                for _ in range(STEPS_A_TURN):
                    start = time.perf_counter()
                    one()
                    times[label].append(time.perf_counter() - start)
        dispatch._core = builds["this build"]
        before, after = (statistics.median(times[label]) for label in builds)
        rows.append([f"{n:,}", show(before), show(after), f"{before / after:.2f}x"])
    print(table(["N", "baseline step", "this build's step", "speed-up"], rows))


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sizes", type=int, nargs="*", default=[1000, 10000], help="robots in the world (N)")
    what = parser.add_mutually_exclusive_group()
    what.add_argument("--parts", action="store_true", help="the CPU time of each part of a step")
    what.add_argument("--baseline", metavar="SO", help="another build's _core.abi3.so, timed in turns with this one")
    args = parser.parse_args(argv)
    print(machine())
    if args.baseline is not None:
        versus(args.sizes, args.baseline)
        return
    if args.parts:
        for n in args.sizes:
            parts(n)
        return
    rows = []
    for n in args.sizes:
        for avoid in (False, True):
            seconds = median_seconds(started(n, avoid)[1], min_time=0.2)
            rows.append([f"{n:,}", "yes" if avoid else "no", show(seconds), f"{n / seconds:,.0f}"])
    print(table(["N", "HRVO", "step", "agent-steps/s"], rows))


if __name__ == "__main__":
    main(sys.argv[1:])
