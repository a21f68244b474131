"""End-to-end experiment speed: steps per second, per backend and swarm size.

python benches/bench_experiments.py
"""

from __future__ import annotations

import statistics

from dream.experiments import hrvo_circle
from dream.specs import RPS
from harness import table

#: (label, call): each call runs one seeded experiment and returns its result.
CASES = [
    ("hrvo-circle n=10, rps, to completion", lambda seed: hrvo_circle.run(n=10, seed=seed, backend="robotarium")),
    ("hrvo-circle n=10, fast, to completion", lambda seed: hrvo_circle.run(n=10, seed=seed, backend="fast")),
    (
        "hrvo-circle n=1000, fast, per-robot API, 300 steps",
        lambda seed: hrvo_circle.run(n=1000, seed=seed, backend="fast", steps=300),
    ),
    (
        "hrvo-circle n=10000, swarm mode, 100 steps",
        lambda seed: hrvo_circle.run(n=10_000, seed=seed, backend="fast", steps=100, swarm=True),
    ),
]


def circle_rows(seeds: range = range(3)) -> list[list[object]]:
    rows = []
    for label, call in CASES:
        rate = statistics.median(call(seed).steps_per_second for seed in seeds)
        rows.append([label, f"{rate:.0f}", f"{rate * RPS.time_step:.1f}x"])
    return rows


if __name__ == "__main__":
    print(table(["run", "steps/s (median of 3 seeds)", "vs real time (30 steps/s)"], circle_rows()))
