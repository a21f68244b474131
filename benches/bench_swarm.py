"""Whole swarm runs at scale: every built-in and the rendezvous example, in swarm mode on Fast.

For each experiment, robot count and thread count, one fresh process runs ``--steps`` steps of
``dream.run(..., swarm=True, backend="fast")`` and reports the step (robot-steps/s, µs
per robot-step), the set-up time before the first step and the peak RSS per robot. Thread
counts are set with ``RAYON_NUM_THREADS`` (the Rust kernels' pool), so one table also shows how
the whole step scales with cores. The step is the mean over the steps past ``--warm-up``: the
built-ins' robots first decide up to 30 steps in and do little before (a step then costs a third
to a tenth of one past it), and decisions on robots' own periods make steps unequal, hence a
mean over many. The memory per robot is the peak RSS above a fixed
:data:`FIXED` (the interpreter, NumPy, DREAM and their tables), over N: the cost issue's
measure. Every table starts with the machine, its load and the date.

Run::

    python benches/bench_swarm.py                                  # 1,000 and 10,000 robots
    python benches/bench_swarm.py -n 1000 10000 100000 1000000 --threads 1 2 4 8 16
    python benches/bench_swarm.py -e hrvo-circle examples/rendezvous.py --steps 30
    python benches/bench_swarm.py -n 100000 --steps 112 --baseline OLDER/_core.abi3.so
    python benches/bench_swarm.py -e examples/rendezvous.py -n 100000 --steps 70 --faults none loss=0.3
    python benches/bench_swarm.py -n 100000 --faults burst=0.05:0.3 sensor_noise=0.01,sensor_dropout=0.05

``--faults`` runs each experiment once with each set of faults (the CLI's ``--fault KIND=VALUE``
options, comma-separated; ``none`` for a run without), one row each: what the world's faults cost a
step, side by side.

``--baseline`` times instead each run's steps with the installed kernels and with another build of
them (an older commit's ``dream/_core.abi3.so``; a kernel it lacks is taken from this build), in
turns of :data:`BLOCK` steps within one run: whole runs on a shared machine wander by a third from
minute to minute, turns within one run see the same machine. The turns come in pairs, one of each
build, in an order drawn at random for each pair: experiments do some work every so many steps
(voronoi-coverage's cost every 30), and turns that simply alternated gave it all to one build
(identical builds then differed by up to 1.18x). A build's step is the median of its steps past
``--warm-up``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import dream

sys.path.insert(0, str(Path(__file__).parent))
from harness import machine  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
EXPERIMENTS = ["hrvo-circle", "line-consensus", "affine-formation", "voronoi-coverage", "examples/rendezvous.py"]
FIXED = 200 * 2**20  #: bytes of a run's peak RSS that do not grow with N
GROUPS = {"affine-formation": 7}  #: experiments whose robots come in groups: n is rounded down to whole groups

# One run in its own process (so that its peak RSS is its own): the step times come from the
# progress callback, which the runner calls after every step.
ONE_RUN = """
import cProfile, json, pstats, resource, statistics, sys, time
import dream
from dream.experiments import find

name, n, steps, warm_up, top = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
faults = None if sys.argv[7] == "none" else dream.Faults.parse(sys.argv[7].split(","))
if sys.argv[6] == "one-call":  # a threaded robot's swarm decides in one call, on one thread
    import dream.swarm.engine
    dream.swarm.engine.threads = lambda: 1
stamps = []
profile = cProfile.Profile()

def progress(step, cap):
    stamps.append(time.perf_counter())
    if top and len(stamps) == warm_up + 1:  # profile the steps that the mean covers
        profile.enable()

start = time.perf_counter()
result = dream.run(find(name), n=n, steps=steps, backend="fast", swarm=True, progress=progress, faults=faults)
profile.disable()
gaps = [b - a for a, b in zip(stamps, stamps[1:])]
own = sorted(((row[2], f[2]) for f, row in pstats.Stats(profile).stats.items()), reverse=True) if top else []
rust = sum(seconds for seconds, what in own if what.startswith("<built-in method dream._core."))
print(json.dumps({
    "n": result.n, "steps": result.steps, "step_s": statistics.mean(gaps[warm_up:]),
    "setup_s": stamps[0] - start - gaps[0],
    "rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, "collisions": result.collisions,
    "own": [(what, seconds / len(gaps[warm_up:])) for seconds, what in own[:top]],
    "rust_s": rust / len(gaps[warm_up:]), "rest_s": (sum(seconds for seconds, _ in own) - rust) / len(gaps[warm_up:]),
}))
"""


BLOCK = 5  #: steps of a turn in --baseline: the built-ins' decision period, so that turns do alike work

# One run whose steps alternate between this build of the kernels and another, BLOCK steps a turn.
AB_RUN = """
import json, random, statistics, sys, time
sys.path.insert(0, "benches")
import dream
import dream.kernels._dispatch as dispatch
from dream.experiments import find
from harness import extension

name, baseline = sys.argv[1], sys.argv[5]
n, steps, warm_up, block = (int(arg) for arg in (*sys.argv[2:5], sys.argv[6]))
class Older:  # the baseline's kernels, and this build's for those it lacks (added since)
    def __init__(self, older, newer):
        self.older, self.newer = older, newer

    def __getattr__(self, name):
        return getattr(self.older, name, None) or getattr(self.newer, name)

builds = [dispatch._core, Older(extension(baseline), dispatch._core)]
spent = [[], []]
flips = random.Random(0)  # the order of each pair of turns
order = []
state = {"last": None, "turn": 0}

def turn(block):  # the build of turn `block` (0, 1, ...): one of each a pair, in the drawn order
    pair, second = divmod(block, 2)
    while len(order) <= pair:
        order.append(flips.random() < 0.5)
    return int(second != order[pair])

def progress(step, cap):
    now = time.perf_counter()
    done = step - warm_up  # steps past the warm-up, this one included
    if state["last"] is not None and done > 0:
        spent[state["turn"]].append(now - state["last"])
    if done >= 0:  # the build of the next step
        state["turn"] = turn(done // block)
        dispatch._core = builds[state["turn"]]
    state["last"] = now

dream.run(find(name), n=n, steps=steps, backend="fast", swarm=True, progress=progress)
print(json.dumps({"this": statistics.median(spent[0]), "baseline": statistics.median(spent[1])}))
"""


def ab_run(name: str, n: int, steps: int, warm_up: int, baseline: str, timeout: float) -> dict[str, Any] | str:
    """This build's and the baseline's mean step in one run, or why there are none."""
    return _child([AB_RUN, name, str(n), str(steps), str(warm_up), baseline, str(BLOCK)], None, timeout)


def one_run(
    name: str,
    n: int,
    steps: int,
    warm_up: int,
    threads: int | None,
    timeout: float,
    top: int = 0,
    one_call: bool = False,
    faults: str = "none",
) -> dict[str, Any] | str:
    """The figures of one run (with the world's ``faults``, as ``--faults`` gives a set), or why
    there are none."""
    how = "one-call" if one_call else "blocks"
    return _child([ONE_RUN, name, str(n), str(steps), str(warm_up), str(top), how, faults], threads, timeout)


def _child(script: list[str], threads: int | None, timeout: float) -> dict[str, Any] | str:
    """What a script run in a process of its own printed last (JSON), or why it printed nothing."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    if threads is not None:
        env["RAYON_NUM_THREADS"] = str(threads)
    try:
        done = subprocess.run(
            [sys.executable, "-c", *script],
            capture_output=True,
            text=True,
            env=env,
            cwd=ROOT,
            timeout=timeout,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return f"over {timeout:.0f} s"
    if done.returncode:
        lines = (done.stderr or done.stdout).strip().splitlines()
        return lines[-1][:100] if lines else f"exit {done.returncode}"
    return json.loads(done.stdout.strip().splitlines()[-1])


def short(function: str) -> str:
    """A profiled function's name, shortened: `perceive [Rust]` for `<built-in method dream._core.perceive>`."""
    if function.startswith("<built-in method dream._core."):
        return function.removeprefix("<built-in method dream._core.").rstrip(">") + " [Rust]"
    return function.removeprefix("<").removesuffix(">")


def versus(args: argparse.Namespace, baseline: str) -> None:
    """Print each run's mean step with the baseline's kernels and with this build's, in turns."""
    if args.steps < args.warm_up + 4 * BLOCK:
        raise SystemExit(f"--baseline needs --steps of at least --warm-up + {4 * BLOCK}: two turns of each build")
    print(f"{args.steps} steps a run, turns of {BLOCK} steps past the first {args.warm_up}; swarm mode on Fast")
    print("| experiment | robots | baseline step (ms) | this build's step (ms) | speed-up |\n|---|---|---|---|---|")
    for name in args.experiments:
        for asked in args.robots:
            n = asked - asked % GROUPS.get(name, 1)
            got = ab_run(name, n, args.steps, args.warm_up, baseline, args.timeout)
            if isinstance(got, str):
                print(f"| {name} | {n:,} | {got} | | |", flush=True)
                continue
            before, after = got["baseline"], got["this"]
            print(f"| {name} | {n:,} | {before * 1e3:,.1f} | {after * 1e3:,.1f} | {before / after:.2f}x |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-e", "--experiments", nargs="+", default=EXPERIMENTS)
    parser.add_argument("-n", "--robots", nargs="+", type=int, default=[1_000, 10_000])
    parser.add_argument("--threads", nargs="+", type=int, default=None, help="RAYON_NUM_THREADS values")
    parser.add_argument("--steps", type=int, default=44, help="steps a run")
    parser.add_argument(
        "--warm-up", type=int, default=32, help="steps left out of the mean: the robots' staggered start"
    )
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds a run may take")
    parser.add_argument(
        "--breakdown",
        type=int,
        default=0,
        metavar="K",
        help="also profile the steps the mean covers (cProfile): the Rust kernels' own time and the rest's, and "
        "the K functions of most own time",
    )
    parser.add_argument("--baseline", metavar="SO", help="another build's _core.abi3.so, timed in turns with this one")
    parser.add_argument(
        "--one-call",
        action="store_true",
        help="decide a threaded robot's swarm in one call (SwarmRobot.threaded's A/B: the default cuts it in blocks)",
    )
    parser.add_argument(
        "--faults",
        nargs="+",
        default=["none"],
        metavar="SET",
        help="sets of the world's faults to run each experiment with, one row each: KIND=VALUE options "
        "(as the CLI's --fault) joined by commas, or none (default: none)",
    )
    args = parser.parse_args()
    for faults in args.faults:
        if faults != "none":
            try:
                dream.Faults.parse(faults.split(","))
            except ValueError as err:
                parser.error(str(err))
    print(machine())
    threads: list[int | None] = list(args.threads) if args.threads else [None]
    if args.steps < args.warm_up + 2:
        parser.error(f"--steps must be at least --warm-up + 2 = {args.warm_up + 2}")
    if args.baseline:
        if args.faults != ["none"]:
            parser.error("--baseline runs without faults: give --faults or --baseline, not both")
        versus(args, args.baseline)
        return
    print(
        f"{args.steps} steps a run, the mean step past the first {args.warm_up}, swarm mode on Fast; "
        f"threads: {'all' if threads == [None] else threads}; decisions "
        f"{'in one call' if args.one_call else 'in blocks on the threads (threaded robots)'}"
    )
    print(
        f"| experiment | robots | faults | threads | step (ms) | robot-steps/s | µs per robot-step | set-up (s) "
        f"| peak RSS | above 200 MiB, per robot | scaling |\n|{'---|' * 11}"
    )
    breakdowns: list[str] = []
    for name, asked, faults in itertools.product(args.experiments, args.robots, args.faults):
        n = asked - asked % GROUPS.get(name, 1)
        first: float | None = None
        for count in threads:
            got = one_run(name, n, args.steps, args.warm_up, count, args.timeout, args.breakdown, args.one_call, faults)
            shown = "all" if count is None else str(count)
            if isinstance(got, str):
                print(f"| {name} | {n:,} | {faults} | {shown} | {got} | | | | | | |", flush=True)
                continue
            step = got["step_s"]
            first = step if first is None else first
            rss = got["rss"] / 2**20
            print(
                f"| {name} | {n:,} | {faults} | {shown} | {step * 1e3:,.1f} | {n / step:,.0f} | {step / n * 1e6:.2f} "
                f"| {got['setup_s']:.1f} | {rss:,.0f} MiB | {max(got['rss'] - FIXED, 0) / n / 1024:.2f} KiB "
                f"| {first / step:.1f}x |",
                flush=True,
            )
            if args.breakdown:
                parts = ", ".join(f"{short(what)} {seconds * 1e3:,.1f}" for what, seconds in got["own"])
                totals = f"Rust kernels {got['rust_s'] * 1e3:,.1f}, the rest {got['rest_s'] * 1e3:,.1f}"
                breakdowns.append(f"- {name}, {n:,} robots, faults {faults}, {shown} threads ({totals}): {parts}")
    if breakdowns:
        print(
            "\nOwn time per step (ms, cProfile of the steps the mean covers, on the main thread: decisions in"
            " blocks on other threads show as its wait; the rest, Python and NumPy, runs on one core whatever"
            " the threads: it bounds the speed-up on many):"
        )
        print("\n".join(breakdowns))


if __name__ == "__main__":
    main()
