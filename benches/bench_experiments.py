"""End-to-end experiment speed: steps per second, per backend.

    python benches/bench_experiments.py
"""

from __future__ import annotations

import statistics

from harness import table

from dream.experiments import hrvo_circle
from dream.specs import RPS


def circle_rows(seeds: range = range(3)) -> list[list[object]]:
    rows = []
    for n, backend in ((10, "robotarium"), (10, "fast"), (50, "fast")):
        runs = [hrvo_circle.run(n=n, seed=seed, backend=backend, steps=1500) for seed in seeds]
        rate = statistics.median(r.steps_per_second for r in runs)
        rows.append([f"hrvo-circle n={n}", backend, f"{rate:.0f}", f"{rate * RPS.time_step:.0f}x"])
    return rows


if __name__ == "__main__":
    print(table(["experiment", "backend", "steps/s (median of 3)", "vs real time"], circle_rows()))
