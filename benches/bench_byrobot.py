"""The built-ins robot by robot (issue 28 item 6: the per-robot API keeps its speed): whole runs
on Fast, one checkout or several side by side.

    python benches/bench_byrobot.py                      # this checkout, medians of 5 runs
    python benches/bench_byrobot.py --only hrvo --runs 3
    python benches/bench_byrobot.py --checkouts /tmp/old/python python   # side by side

Each case is one ``dream.run`` robot by robot (no ``swarm``) on the Fast backend, seed 0, timed
whole (wall and the process's CPU time) after one warm-up run. With ``--checkouts``, one worker
process per checkout (its ``python/`` folder first on its path) runs each case in turn, one run
at a time, so that every checkout sees the same minute of a shared machine; the last columns
give each checkout's median against the first one's. A case a checkout cannot run is marked.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from harness import machine, table

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

#: (label, experiment, n (None: its own), step cap or None: to completion)
CASES = [
    ("hrvo-circle n=10, to completion", "hrvo-circle", 10, None),
    ("hrvo-circle n=30, 600 steps", "hrvo-circle", 30, 600),
    ("hrvo-circle n=100, 200 steps", "hrvo-circle", 100, 200),
    ("line-consensus n=20, to completion", "line-consensus", 20, None),
    ("voronoi-coverage n=10, to completion", "voronoi-coverage", 10, None),
    ("affine-formation n=7, 800 steps", "affine-formation", None, 800),
    ("examples/rendezvous.py n=20, to completion", str(EXAMPLES / "rendezvous.py"), 20, None),
]


def one_run(experiment: str, n: int | None, steps: int | None) -> tuple[float, float, int]:
    """Wall and CPU seconds of one run, and its steps."""
    import dream

    start, cpu = time.perf_counter(), time.process_time()
    taken = dream.run(experiment, n=n, seed=0, backend="fast", steps=steps).steps
    return time.perf_counter() - start, time.process_time() - cpu, taken


def worker() -> None:
    """Answer one line of JSON per case read (``[experiment, n, steps]``) with its run's figures."""
    for line in sys.stdin:
        try:
            answer: list[object] = list(one_run(*json.loads(line)))
        except Exception as err:  # noqa: BLE001 (an older checkout without this experiment)
            answer = [f"{type(err).__name__}: {err}"]
        print(json.dumps(answer), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--only", help="only the cases whose label contains this")
    parser.add_argument("--checkouts", nargs="+", help="the python/ folders of the checkouts to compare")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        return worker()
    paths = args.checkouts or [os.environ.get("PYTHONPATH", "")]
    workers = [
        subprocess.Popen(
            [sys.executable, __file__, "--worker"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env={**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (path, str(Path(__file__).parent))))},
        )
        for path in paths
    ]

    def ask(process: subprocess.Popen[str], case: tuple[str, int | None, int | None]) -> list[object]:
        assert process.stdin is not None and process.stdout is not None
        process.stdin.write(json.dumps(case) + "\n")
        process.stdin.flush()
        answer: list[object] = json.loads(process.stdout.readline())
        return answer

    print(machine())
    rows = []
    for label, *case in CASES:
        if args.only and args.only not in label:
            continue
        walls: list[list[float]] = [[] for _ in paths]
        cpus: list[list[float]] = [[] for _ in paths]
        steps: list[object] = ["-"] * len(paths)
        for round_ in range(args.runs + 1):  # the first round warms up
            for at, process in enumerate(workers):
                answer = ask(process, tuple(case))  # type: ignore[arg-type]
                if len(answer) == 1:
                    steps[at] = f"failed ({answer[0]})"[:60]
                elif round_:
                    walls[at].append(float(answer[0]))  # type: ignore[arg-type]
                    cpus[at].append(float(answer[1]))  # type: ignore[arg-type]
                    steps[at] = answer[2]
        medians = [statistics.median(w) if w else None for w in walls]
        cells = [
            f"{wall:.3f} s, CPU {statistics.median(cpu):.3f} s ({taken} steps)" if wall is not None else str(taken)
            for wall, cpu, taken in zip(medians, cpus, steps)
        ]
        first = medians[0]
        ratios = [f"{m / first:.2f}x" if m is not None and first else "-" for m in medians[1:]]
        rows.append([label, *cells, *ratios])
    for process in workers:
        assert process.stdin is not None
        process.stdin.close()
        process.wait()
    header = ["run (robot by robot, Fast, seed 0)", *paths, *(f"{path} / {paths[0]}" for path in paths[1:])]
    print(table(header, rows))
    print(machine())


if __name__ == "__main__":
    main()
