"""Reliability at scale of line-consensus, voronoi-coverage and affine-formation on the Fast backend.

For each experiment and size: runs, successes (its own criterion, zero violations), the summed
collision, boundary and actuator counts, and the steps to success (min / median / max).

python benches/reliability_others.py                                  # N = 100 (seeds 0-9), 1000 (0-2)
python benches/reliability_others.py --sizes 100 --seeds 3 --jobs 2
python benches/reliability_others.py --experiments coverage-at-rest --sizes 1000 --large-seeds 1

The affine formation comes in groups of seven robots: a size is rounded to the nearest multiple
of 7 (100 -> 98, 1000 -> 1001). N = 1000 runs take minutes each (the per-robot API).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import sys
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import dream
from harness import table

#: name -> (experiment, its parameters)
CASES: dict[str, tuple[str, dict[str, Any]]] = {
    "line-consensus": ("line-consensus", {}),
    "voronoi-coverage": ("voronoi-coverage", {}),
    "coverage-at-rest": ("voronoi-coverage", {"moving_obstacles": False}),
    "affine-formation": ("affine-formation", {}),
}
LARGE = 1000  #: sizes from this up use the `--large-seeds`


def size_for(case: str, n: int) -> int:
    """``n``, or for the affine formation the nearest multiple of 7 (at least 7)."""
    return max(7, 7 * round(n / 7)) if CASES[case][0] == "affine-formation" else n


def one_run(case: str, n: int, seed: int) -> dict[str, Any]:
    experiment, params = CASES[case]
    result = dream.run(experiment, n=n, seed=seed, backend="fast", **params)
    return {"case": case, "n": n, "seed": seed, "result": result}


def machine() -> str:
    model = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as info:
            model = next(line.split(":", 1)[1].strip() for line in info if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return f"{model}, {os.cpu_count()} cores; load average {load}; {now}"


def summary_row(case: str, n: int, runs: list[Any]) -> list[object]:
    won = [r.completed_step for r in runs if r.success]
    spread = f"{min(won)} / {statistics.median(won):.0f} / {max(won)}" if won else "-"
    return [
        case,
        n,
        len(runs),
        len(won),
        sum(r.collisions for r in runs),
        sum(r.boundary for r in runs),
        sum(r.actuator for r in runs),
        spread,
        f"{max(r.steps for r in runs)}",
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--experiments", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument("--sizes", nargs="+", type=int, default=[100, 1000])
    parser.add_argument("--first-seed", type=int, default=0, help="start the seeds here (to resume)")
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..K-1 below N = 1000")
    parser.add_argument("--large-seeds", type=int, default=3, help="seeds 0..K-1 from N = 1000 up")
    parser.add_argument("--jobs", type=int, default=1, help="runs in parallel (processes)")
    args = parser.parse_args(argv)

    print(f"# machine: {machine()}", flush=True)
    work = [
        (case, size_for(case, n), seed)
        for n in args.sizes
        for seed in range(args.first_seed, args.large_seeds if n >= LARGE else args.seeds)
        for case in args.experiments
    ]
    done: dict[tuple[str, int], list[Any]] = {}
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for run in pool.map(one_run, *zip(*work)):
            r = run["result"]
            done.setdefault((run["case"], run["n"]), []).append(r)
            print(
                f"{run['case']} n={run['n']} seed={run['seed']}: success={r.success} at {r.completed_step} "
                f"(steps {r.steps}, collisions {r.collisions}, boundary {r.boundary}, actuator {r.actuator}, "
                f"{r.wall_time:.0f} s) {r.measures}",
                flush=True,
            )
    header = ["experiment", "N", "runs", "successes", "collisions", "boundary", "actuator"]
    header += ["steps to success min / median / max", "steps run (max)"]
    print(table(header, [summary_row(case, n, runs) for (case, n), runs in done.items()]))
    print(f"# done: {machine()}")


if __name__ == "__main__":
    sys.exit(main())
