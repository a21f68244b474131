"""The built-ins robot by robot (robot objects' speed, issue 28 item 6): whole runs on Fast.

    python benches/bench_byrobot.py                 # every case, medians of 3 runs
    python benches/bench_byrobot.py --only hrvo --runs 5

Each case is one ``dream.run`` robot by robot (no ``swarm``) on the Fast backend, seed 0, timed
whole (its set-up included) after one warm-up run; the table gives the median wall time and
steps per second. To compare with another checkout, run this file with ``PYTHONPATH`` pointing
at that checkout's ``python/`` in the same minute (a case whose experiment it lacks is skipped).
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import dream
from harness import machine, table

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

#: (label, experiment, n, step cap or None: to completion)
CASES = [
    ("hrvo-circle n=10, to completion", "hrvo-circle", 10, None),
    ("hrvo-circle n=30, 600 steps", "hrvo-circle", 30, 600),
    ("line-consensus n=20, to completion", "line-consensus", 20, None),
    ("voronoi-coverage n=10, to completion", "voronoi-coverage", 10, None),
    ("affine-formation n=7, 800 steps", "affine-formation", None, 800),
    ("examples/rendezvous.py n=20, to completion", str(EXAMPLES / "rendezvous.py"), 20, None),
]


def measure(experiment: str, n: int | None, steps: int | None, runs: int) -> tuple[float, int]:
    """Median wall time (s) of ``runs`` runs after a warm-up, and the steps a run takes."""
    dream.run(experiment, n=n, seed=0, backend="fast", steps=steps)
    times, taken = [], 0
    for _ in range(runs):
        start = time.perf_counter()
        taken = dream.run(experiment, n=n, seed=0, backend="fast", steps=steps).steps
        times.append(time.perf_counter() - start)
    return statistics.median(times), taken


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--only", help="only the cases whose label contains this")
    args = parser.parse_args()
    print(machine())
    rows = []
    for label, experiment, n, steps in CASES:
        if args.only and args.only not in label:
            continue
        try:
            seconds, taken = measure(experiment, n, steps, args.runs)
        except (KeyError, ValueError, OSError) as err:  # an older checkout without this experiment
            rows.append([label, "-", "-", f"skipped: {type(err).__name__}"])
            continue
        rows.append([label, taken, f"{seconds:.3f}", f"{taken / seconds:.0f}"])
    print(table(["run (robot by robot, fast, seed 0)", "steps", "wall (s, median)", "steps/s"], rows))
    print(machine())


if __name__ == "__main__":
    main()
