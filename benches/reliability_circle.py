"""Reliability of hrvo-circle: how many seeds finish three circles, with what violations and steps.

python benches/reliability_circle.py                       # the default sizes and seeds
python benches/reliability_circle.py --case 20:robotarium:0-29 --case 100:fast:0-9
python benches/reliability_circle.py --case 10000:batch:0

A case is ``N:MODE:SEEDS``; MODE is ``robotarium`` or ``fast`` (per-robot API, ``run``) or
``batch`` (``run_batch``); SEEDS is ``a-b`` (inclusive) or one seed. Each run goes to its
default step cap (``default_steps(n)``) unless ``--steps`` is given.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import time

from dream.experiments import hrvo_circle
from harness import table

DEFAULT_CASES = ["10:robotarium:0-29", "20:robotarium:0-29", "30:robotarium:0-9", "50:robotarium:0-9", "100:fast:0-9"]


def parse_case(text: str) -> tuple[int, str, range]:
    """``"N:MODE:a-b"`` -> (N, MODE, seeds)."""
    try:
        n, mode, seeds = text.split(":")
        first, _, last = seeds.partition("-")
        span = range(int(first), int(last or first) + 1)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a case is N:MODE:SEEDS such as 20:robotarium:0-29, got {text!r}") from None
    if mode not in ("robotarium", "fast", "batch"):
        raise argparse.ArgumentTypeError(f"MODE must be robotarium, fast or batch, got {mode!r}")
    return int(n), mode, span


def measure(n: int, mode: str, seeds: range, steps: int | None) -> list[object]:
    """One table row: successes, summed violations, and min/median/max steps of the successes."""
    done, collisions, boundary, actuator, wall = [], 0, 0, 0, 0.0
    for seed in seeds:
        start = time.perf_counter()
        if mode == "batch":
            result = hrvo_circle.run_batch(n=n, seed=seed, steps=steps)
        else:
            result = hrvo_circle.run(n=n, seed=seed, backend=mode, steps=steps)
        wall += time.perf_counter() - start
        collisions, boundary, actuator = (
            collisions + result.collisions,
            boundary + result.boundary,
            actuator + result.actuator,
        )
        if result.completed_step is not None:
            done.append(result.completed_step)
        print(
            f"  n={n} {mode} seed={seed}: completed at {result.completed_step}, violations "
            f"{result.collisions}/{result.boundary}/{result.actuator}",
            flush=True,
        )
    spread = f"{min(done)} / {statistics.median(done):.0f} / {max(done)}" if done else "-"
    cap = hrvo_circle.default_steps(n) if steps is None else steps
    seed_text = f"{seeds.start}-{seeds.stop - 1}"
    return [n, mode, seed_text, f"{len(done)}/{len(seeds)}", collisions, boundary, actuator, spread, cap, f"{wall:.0f}"]


def machine() -> str:
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as info:
            cpu = next(line.split(":", 1)[1].strip() for line in info if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return f"{cpu}, {os.cpu_count()} cores; load average {load}; {datetime.datetime.now():%Y-%m-%d %H:%M}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", action="append", type=parse_case, help="N:MODE:SEEDS (repeatable)")
    parser.add_argument("--steps", type=int, default=None, help="step cap (default: default_steps(n))")
    args = parser.parse_args()
    cases = args.case or [parse_case(text) for text in DEFAULT_CASES]
    print(machine())
    rows = [measure(n, mode, seeds, args.steps) for n, mode, seeds in cases]
    header = ["N", "mode", "seeds", "successes", "collisions", "boundary", "actuator", "steps min/median/max"]
    print(machine())
    print(table(header + ["cap", "wall s"], rows))


if __name__ == "__main__":
    main()
