"""dream.rl's batch form at scale: agent-steps per second of a linear policy on one large world.

One ``batch_env`` of ``examples/rendezvous.py`` (every robot a row; each decides on its own clock,
every 5 steps, and the others hold their commands), stepped with a linear policy evaluated on all
rows at once: the median wall time of one step (perception of the robots due, the padding of
their observations, the policy, the engine's drive, the simulator with its validation, the
rewards), as agent-steps per second (N per step), with and without the HRVO safety layer.
The issue's target: 1,000,000 agent-steps/s at N = 10,000 on 2 cores.
Run: ``python benches/bench_rl.py [N ...]`` (default 1,000 and 10,000).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from dream.rl import LinearPolicy, batch_env

sys.path.insert(0, str(Path(__file__).parent))
from harness import machine, median_seconds, show, table  # noqa: E402

RENDEZVOUS = str(Path(__file__).parents[1] / "examples" / "rendezvous.py")


def step_seconds(n: int, avoid: bool) -> float:
    env = batch_env(RENDEZVOUS, n=n, max_steps=10**6, avoid=avoid)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    policy = LinearPolicy(0.1 * rng.standard_normal((obs.shape[1], 2)), np.zeros(2))
    state = {"obs": obs}
    for _ in range(20):  # past the start-up delays: every robot on its clock, messages on the air
        state["obs"] = env.step(policy(state["obs"]))[0]

    def one() -> None:
        state["obs"] = env.step(policy(state["obs"]))[0]

    return median_seconds(one, min_time=0.2)


def main(sizes: list[int]) -> None:
    print(machine())
    rows = []
    for n in sizes:
        for avoid in (False, True):
            seconds = step_seconds(n, avoid)
            rows.append([f"{n:,}", "yes" if avoid else "no", show(seconds), f"{n / seconds:,.0f}"])
    print(table(["N", "HRVO", "step", "agent-steps/s"], rows))


if __name__ == "__main__":
    main([int(arg) for arg in sys.argv[1:]] or [1000, 10000])
