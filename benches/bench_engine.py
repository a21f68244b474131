"""The swarm engine's step at scale: its whole cost, its kernels' share, and what is left per robot.

A rendezvous-like rule (radio mean plus HRVO, every robot deciding every step, the worst case)
on a swarm spread as rps spreads it, at each N: the median step, the median of the same step's
kernels called alone on the same inputs, and the difference per robot (the engine's own
Python and NumPy, the figure the swarm-engine issue bounds at 0.5 us per robot). Also the peak
RSS of the process. Run: ``python benches/bench_engine.py [N ...]``.
"""

from __future__ import annotations

import resource
import sys
import time
from collections.abc import Callable

import numpy as np

import dream
from dream import kernels
from dream.backends import initial_poses
from dream.specs import ROBOTARIUM, ArenaSpec
from dream.swarm import Avoid, Engine, Movement, Radio, SwarmRobot, View

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from harness import machine, median_seconds  # noqa: E402


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


def kernels_alone(engine: Engine, x: np.ndarray) -> float:
    """The median time of one step's kernels (perception, the radio mean's reductions of the
    messages read from the board, HRVO, the unicycle conversion and limits, the motion guard)
    called directly on this step's inputs."""
    n = engine.n
    positions, everyone = x[:2].T.copy(), np.arange(n)
    talking = np.ones(n, dtype=bool)
    (offsets, _, distances, bearings, *_), heard = kernels.perceive(
        positions, x[2], everyone, sight=(0.5, 2 * np.pi, 0.0), radio_range=1.0, talking=talking
    )
    still = np.zeros(len(distances))
    detections = (distances, bearings, still, still)
    dx, dy = distances * np.cos(bearings), distances * np.sin(bearings)
    bounds = engine.arena.shrunk(0.055)

    def run() -> None:
        kernels.perceive(positions, x[2], everyone, sight=(0.5, 2 * np.pi, 0.0), radio_range=1.0, talking=talking)
        for column in positions.T:  # the board's fields, read at the senders
            kernels.segment_reduce(column, heard[0], "sum", heard[1])
        kernels.hrvo_rows(
            engine.dxi, np.zeros((n, 2)), positions, offsets, detections, safety=0.2, bounds=bounds, towards=True
        )
        dxu = kernels.actuator_limit(kernels.dxi_to_dxu(engine.dxi.T, x, 0.8, 3.0))
        kernels.motion_guard(dxu[0], x[2], offsets, dx, dy, near=0.12, horizon=0.25)

    return median_seconds(run, repeat=5, min_time=0.0)


def stepper(engine: Engine, x: np.ndarray, commands: np.ndarray) -> Callable[[], None]:
    """One engine step per call, the clock going on."""
    clock = iter(range(2, 10**9))

    def step() -> None:
        engine.step(next(clock), x, commands)

    return step


def main() -> None:
    print(machine())
    sizes = [int(a) for a in sys.argv[1:]] or [1_000, 10_000, 100_000]
    print(f"{'robots':>9} {'step (ms)':>10} {'kernels (ms)':>13} {'engine per robot (us)':>22} {'robot-steps/s':>14}")
    for n in sizes:
        engine, x, commands = scene(n)
        whole = median_seconds(stepper(engine, x, commands), repeat=5, min_time=0.0)
        alone = kernels_alone(engine, x)
        own = (whole - alone) / n * 1e6
        print(f"{n:>9,} {whole * 1e3:>10.1f} {alone * 1e3:>13.1f} {own:>22.2f} {n / whole:>14,.0f}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    print(f"peak RSS {rss:,.0f} MiB; {when}; kernels: {dream.kernels.IMPLEMENTATION}")


if __name__ == "__main__":
    main()
