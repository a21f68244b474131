"""The swarm engine's step at scale: its whole cost, its kernels' share, and what is left per robot.

A rendezvous-like rule (radio mean plus HRVO, every robot deciding every step, the worst case)
on a swarm spread as rps spreads it, at each N: the median step, the median time spent in the
step's kernel calls (timed as the step makes them, on its own inputs), and the median of the
rest per robot (the engine's own Python and NumPy, the kernels' Python wrappers included: the
figure the swarm-engine issue bounds at 0.5 us per robot), also in CPU time (steadier when other
jobs share the cores). Also the peak RSS of the process.
Run: ``python benches/bench_engine.py [N ...]``.
"""

from __future__ import annotations

import resource
import sys
import time
from collections.abc import Callable
from typing import Any
from unittest.mock import patch

import numpy as np

import dream
from dream.backends import initial_poses
from dream.kernels import _dispatch
from dream.specs import ROBOTARIUM, ArenaSpec
from dream.swarm import Avoid, Engine, Movement, Radio, SwarmRobot, View

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from harness import machine  # noqa: E402


class Meet(SwarmRobot):
    """Heads for the mean of the positions it hears, HRVO on what it sees: every step."""

    period = 0
    movement = Movement(range=0.5)
    radio = Radio(range=1.0, fields=("x", "y"))
    avoid = Avoid(safety=0.2)

    def decide(self, view: View) -> np.ndarray:
        here = view.pose[:, :2]
        view.send(x=here[:, 0], y=here[:, 1])
        centre = (view.heard.sum(["x", "y"]) + here) / (view.heard.count + 1)[:, None]
        return np.clip(0.5 * (centre - here), -0.1, 0.1)


def scene(n: int) -> tuple[Engine, np.ndarray, np.ndarray]:
    scale = np.sqrt(2 * n / 84)
    arena = ArenaSpec.centred(ROBOTARIUM.width * scale, ROBOTARIUM.height * scale)
    x = initial_poses(n, np.random.default_rng(0), arena)
    engine = Engine(Meet(), n, 0, arena)
    commands = np.zeros((2, n))
    for t in range(2):  # a first message from everyone on the board
        engine.step(t, x, commands)
    return engine, x, commands


def clocks() -> tuple[float, float]:
    """Wall time and the calling thread's CPU time (s). The Python and NumPy of a step run on
    this thread; the Rust kernels' threads, which it waits for, are not counted in its CPU time."""
    return time.perf_counter(), time.thread_time()


class Timed:
    """Stands for the kernels' module (:mod:`dream._core`, or :mod:`dream._reference` in pure
    Python) in :mod:`dream.kernels._dispatch`: passes each call on and adds up the wall and this
    thread's CPU time spent in the kernels (``spent``, s)."""

    def __init__(self, module: Any) -> None:
        self.module, self.spent = module, np.zeros(2)

    def __getattr__(self, name: str) -> Callable[..., Any]:
        kernel = getattr(self.module, name)

        def call(*args: Any, **kwargs: Any) -> Any:
            start = clocks()
            try:
                return kernel(*args, **kwargs)
            finally:
                self.spent += np.subtract(clocks(), start)

        return call


def timed_steps(step: Callable[[], None], repeat: int = 7) -> tuple[float, float, float, float]:
    """Medians over ``repeat`` calls of ``step()`` (one warm-up first), in seconds: its wall time,
    the wall time in its kernel calls (perception, the radio mean's reductions, HRVO, the
    unicycle conversion and limits, the motion guard: the Rust, or NumPy reference, kernels
    themselves, not their Python wrappers' checks), the rest, and the rest in this thread's CPU
    time (the engine's own Python and NumPy, steadier than wall time when other jobs share the
    cores: waiting for a core is not counted)."""
    pure = _dispatch._core is None
    timed = Timed(_dispatch._reference if pure else _dispatch._core)
    samples = []
    with patch.object(_dispatch, "_reference" if pure else "_core", timed):
        step()
        for _ in range(repeat):
            timed.spent[:] = 0.0
            start = clocks()
            step()
            (whole, cpu), (inside, cpu_inside) = np.subtract(clocks(), start), timed.spent
            samples.append((whole, inside, whole - inside, cpu - cpu_inside))
    whole, inside, rest, cpu_rest = np.median(samples, axis=0)
    return float(whole), float(inside), float(rest), float(cpu_rest)


def stepper(engine: Engine, x: np.ndarray, commands: np.ndarray) -> Callable[[], None]:
    """One engine step per call, the clock going on."""
    clock = iter(range(2, 10**9))

    def step() -> None:
        engine.step(next(clock), x, commands)

    return step


def main() -> None:
    print(machine())
    sizes = [int(a) for a in sys.argv[1:]] or [1_000, 10_000, 100_000]
    print(
        f"{'robots':>9} {'step (ms)':>10} {'kernels (ms)':>13} {'engine per robot (us)':>22} "
        f"{'its CPU time (us)':>18} {'robot-steps/s':>14}"
    )
    for n in sizes:
        engine, x, commands = scene(n)
        whole, inside, rest, cpu_rest = timed_steps(stepper(engine, x, commands))
        own, cpu_own = rest / n * 1e6, cpu_rest / n * 1e6
        print(f"{n:>9,} {whole * 1e3:>10.1f} {inside * 1e3:>13.1f} {own:>22.2f} {cpu_own:>18.2f} {n / whole:>14,.0f}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    print(f"peak RSS {rss:,.0f} MiB; {when}; kernels: {dream.kernels.IMPLEMENTATION}")


if __name__ == "__main__":
    main()
