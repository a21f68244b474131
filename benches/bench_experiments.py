"""End-to-end experiment speed: steps per second, per backend and swarm size.

python benches/bench_experiments.py

The swarm-mode rows at N = 10,000 run the first 100 steps, from the packed start: the hardest
stretch (voronoi-coverage's robots each hear about 300 others there, ten times as many as once
spread); affine-formation's runs through its first bar pass.
"""

from __future__ import annotations

import statistics

import dream
from dream.specs import RPS
from harness import machine, table


def _run(name: str, n: int, backend: str = "fast", steps: int | None = None, swarm: bool = False):  # type: ignore[no-untyped-def]
    return lambda seed: dream.run(name, n=n, seed=seed, backend=backend, steps=steps, swarm=swarm)


#: (label, call): each call runs one seeded experiment and returns its result.
CASES = [
    ("hrvo-circle n=10, rps, to completion", _run("hrvo-circle", 10, "robotarium")),
    ("hrvo-circle n=10, fast, to completion", _run("hrvo-circle", 10)),
    ("hrvo-circle n=1000, fast, per-robot API, 300 steps", _run("hrvo-circle", 1000, steps=300)),
    ("voronoi-coverage n=1000, fast, per-robot API, 300 steps", _run("voronoi-coverage", 1000, steps=300)),
    *(
        (f"{name} n=10000, swarm mode, 100 steps", _run(name, 10_000, steps=100, swarm=True))
        for name in ("hrvo-circle", "line-consensus", "voronoi-coverage")
    ),
    # Through the first pass of its 2,858 bars (steps 1,800-2,507), the costliest stretch.
    ("affine-formation n=10003, swarm mode, 2507 steps", _run("affine-formation", 10_003, steps=2507, swarm=True)),
]


def rows(seeds: range = range(3)) -> list[list[object]]:
    out = []
    for label, call in CASES:
        rate = statistics.median(call(seed).steps_per_second for seed in seeds)
        out.append([label, f"{rate:.1f}", f"{rate * RPS.time_step:.2f}x"])
    return out


if __name__ == "__main__":
    print(machine())
    print(table(["run", "steps/s (median of 3 seeds)", "vs real time (30 steps/s)"], rows()))
    print(machine())
