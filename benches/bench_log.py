"""What looking into a run costs: the trajectory log and the Rerun recording against the bare run.

    python benches/bench_log.py                  # both scenes, 5 runs of each variant
    python benches/bench_log.py --runs 3 --quick

Each scene runs bare, with ``log=`` at ``log_every`` 10 and 1, and with ``rerun=`` (a ``.rrd``
file) at 10, the variants interleaved run by run so that the machine's load falls on all alike.
The time is the whole ``dream.run`` call (outputs closed and renamed included), median over the
runs, as wall time and as the process's CPU time (all threads: on a shared machine, the steadier
of the two); the overhead is the median's excess over the bare run's. The issue's bound: the log
at ``log_every`` 10 costs at most 5 %.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import dream
from dream.experiments.files import load_file
from harness import machine, table

ROOT = Path(__file__).resolve().parents[1]


def scenes(quick: bool) -> list[tuple[str, Any, dict[str, Any]]]:
    """(label, experiment, run options) of each scene: robot objects, and a SwarmRobot's swarm."""
    rendezvous = load_file(ROOT / "examples" / "rendezvous.py")
    return [
        ("hrvo-circle, 30 robot objects", "hrvo-circle", {"n": 30, "steps": 200 if quick else 1000}),
        ("rendezvous swarm, 10,000 robots", rendezvous, {"n": 10_000, "steps": 20 if quick else 100, "swarm": True}),
    ]


def variants(folder: Path) -> dict[str, dict[str, Any]]:
    return {
        "bare": {},
        "log, every 10": {"log": folder / "run.parquet", "log_every": 10},
        "log, every step": {"log": folder / "run.parquet", "log_every": 1},
        "rerun .rrd, every 10": {"rerun": folder / "run.rrd", "log_every": 10},
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="runs of each variant (default 5)")
    parser.add_argument("--quick", action="store_true", help="fewer steps")
    args = parser.parse_args(argv)
    has_rerun = True
    try:
        import rerun  # noqa: F401
    except ImportError:
        has_rerun = False
    print(machine())
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        kinds = variants(Path(folder))
        if not has_rerun:
            kinds.pop("rerun .rrd, every 10")
        for label, experiment, options in scenes(args.quick):
            wall: dict[str, list[float]] = {name: [] for name in kinds}
            cpu: dict[str, list[float]] = {name: [] for name in kinds}
            for _ in range(args.runs):
                for name, extra in kinds.items():
                    start, used = time.perf_counter(), time.process_time()
                    result = dream.run(experiment, seed=1, backend="fast", **options, **extra)
                    wall[name].append(time.perf_counter() - start)
                    cpu[name].append(time.process_time() - used)
            bare_wall, bare_cpu = statistics.median(wall["bare"]), statistics.median(cpu["bare"])
            for name in kinds:
                median_wall, median_cpu = statistics.median(wall[name]), statistics.median(cpu[name])
                over = "-" if name == "bare" else f"{100 * (median_wall / bare_wall - 1):+.1f} %"
                over_cpu = "-" if name == "bare" else f"{100 * (median_cpu / bare_cpu - 1):+.1f} %"
                per_step = f"{1e3 * median_wall / result.steps:.2f}"
                rows.append((label, name, f"{median_wall:.3f}", per_step, over, f"{median_cpu:.3f}", over_cpu))
    header = ("scene", "variant", "wall (s)", "wall per step (ms)", "wall overhead", "CPU (s)", "CPU overhead")
    print(table(header, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
