"""Reliability and resilience: how many seeds succeed, with what violations and steps, per experiment.

    python benches/reliability.py                      # every experiment at every size (hours)
    python benches/reliability.py --quick              # fewer seeds, no N = 1,000 (minutes)
    python benches/reliability.py --resilience         # N = 10 and 100 under each fault (Fast)
    python benches/reliability.py --case hrvo-circle:20:robotarium:0-29 --case line-consensus:100:fast:0-9
    python benches/reliability.py --case hrvo-circle:10000:swarm:0 --checkpoints runs/   # hours; resumable
    python benches/reliability.py --case line-consensus:100:fast:0-9:byzantine=1 --param resilient=1

A case is ``EXPERIMENT:N:BACKEND:SEEDS[:FAULTS]``: BACKEND is ``robotarium``, ``fast`` or
``swarm`` (Fast, in the experiment's swarm mode: ``dream.run(..., swarm=True)``), SEEDS ``a-b``
(inclusive) or one seed, FAULTS ``--fault`` settings joined by ``+`` (``loss=0.3+latency=5``);
``--param NAME=VALUE`` sets an experiment's parameter in every case (W-MSR: ``resilient=1``).
Runs go to each experiment's own step cap and, but for ``swarm``, through :func:`dream.sweep` on
a local Dask cluster of ``--workers`` processes. Every table is printed with the machine, its
load and the date.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import dream
from dream.experiments import find
from dream.faults import Faults
from harness import machine, table

#: Sizes, seeds and backends of the experiments whose arena grows: N = 1,000 in swarm mode (the
#: per-robot mode's rules, one call a step), where robot objects would take hours a seed.
LARGE = ((100, "0-9", "fast"), (1000, "0-2", "swarm"))
#: The table of issue "every experiment does its job at every size".
SIZES = [
    "hrvo-circle:10:robotarium:0-99",
    "hrvo-circle:20:robotarium:0-29",
    "hrvo-circle:30:robotarium:0-9",
    "hrvo-circle:40:robotarium:0-9",
    "hrvo-circle:50:robotarium:0-9",
    "hrvo-circle:100:fast:0-9",
    "hrvo-circle:1000:swarm:0-2",
    "hrvo-circle:10000:swarm:0",
    *(f"{name}:{n}:{how}:{seeds}" for name in ("line-consensus", "voronoi-coverage") for n, seeds, how in LARGE),
    "affine-formation:98:fast:0-9",
    "affine-formation:1001:swarm:0-2",  # moves as robot by robot, 60x faster
]
QUICK = [
    "hrvo-circle:10:robotarium:0-9",
    "hrvo-circle:20:robotarium:0-2",
    "hrvo-circle:100:fast:0",
    "line-consensus:100:fast:0-2",
    "voronoi-coverage:100:fast:0-2",
    "affine-formation:98:fast:0-2",
]
#: The faults of the resilience table.
FAULTS = {
    "none": "",
    "loss 0.3": "loss=0.3",
    "bursty loss": "burst=0.05:0.3",
    "latency 5 +- 2": "latency=5+jitter=2",
    "10 % crash at 300": "crash=0.1@300",
    "clock drift 5 %": "drift=0.05",
    "1 Byzantine": "byzantine=1",
}


def parse_case(text: str) -> tuple[str, int, str, range, str]:
    """``"EXPERIMENT:N:BACKEND:a-b[:FAULTS]"`` -> its parts."""
    try:
        name, n, backend, seeds, *faults = text.split(":", 4)
        first, _, last = seeds.partition("-")
        span = range(int(first), int(last or first) + 1)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a case is EXPERIMENT:N:BACKEND:SEEDS[:FAULTS], got {text!r}") from None
    if backend not in ("robotarium", "fast", "swarm") or (backend == "swarm" and not find(name).has_swarm_mode):
        raise argparse.ArgumentTypeError(
            f"BACKEND is robotarium, fast, or swarm for an experiment with a swarm mode, got {text!r}"
        )
    return name, int(n), backend, span, faults[0] if faults else ""


def parse_param(text: str) -> tuple[str, str]:
    """``"NAME=VALUE"`` -> ``(NAME, VALUE)`` (the experiment converts the value, as for the CLI)."""
    name, equals, value = text.partition("=")
    if not (name and equals and value):
        raise argparse.ArgumentTypeError(f"a parameter is NAME=VALUE, got {text!r}")
    return name, value


def measure(
    name: str,
    n: int,
    backend: str,
    seeds: range,
    faults: str,
    workers: int,
    params: dict[str, str],
    checkpoints: Path | None = None,
) -> list[object]:
    """One row: successes, summed violations, and min/median/max steps of the successful runs.

    With ``checkpoints``, a folder, each swarm-mode run is saved there as it goes (runs of hours:
    hrvo-circle at N = 10,000) and resumed from there when the row is measured again.
    """
    start = time.perf_counter()
    options = [option for option in faults.split("+") if option]
    if backend == "swarm":
        broken = Faults.parse(options) if options else None
        results = []
        settings = "+".join([faults or "none", *(f"{key}={value}" for key, value in sorted(params.items()))])
        for seed in seeds:
            saved = None if checkpoints is None else checkpoints / f"{name}-{n}-{seed}-{settings}.ckpt"
            if saved is not None and saved.exists():  # a run cut short: go on where it stopped
                result = dream.resume(saved)
            else:
                result = dream.run(name, n=n, seed=seed, backend="fast", swarm=True, faults=broken, checkpoint=saved,
                                   **params)  # fmt: skip
            if saved is not None:
                if result.interrupted:
                    raise SystemExit(f"interrupted: run the same command again to resume from {saved}")
                saved.unlink()  # measured: the next measurement starts afresh
            results.append(result.to_dict())
    else:
        grid = {kind: [value] for kind, _, value in (option.partition("=") for option in options)}
        results = dream.sweep(
            name,
            seeds,
            [n],
            {key: [value] for key, value in params.items()},
            backend=backend,
            faults=grid,
            workers=workers,
            progress=False,
        )
    done = [row["completed_step"] for row in results if row["success"]]
    failed = [row["seed"] for row in results if not row["success"]]
    steps = f"{min(done)} / {statistics.median(done):.0f} / {max(done)}" if done else "-"
    summed = [sum(row[key] or 0 for row in results) for key in ("collisions", "boundary", "actuator")]
    seed_text = f"{seeds.start}-{seeds.stop - 1}" if len(seeds) > 1 else str(seeds.start)
    # Swarm runs one after the other: their own wall times, summed over the parts of resumed runs.
    spent = sum(row["wall_time"] for row in results) if backend == "swarm" else time.perf_counter() - start
    wall = f"{spent:.0f}"
    successes = f"{len(done)}/{len(seeds)}"
    faults_text = "+".join([faults, *(f"{key}={value}" for key, value in params.items())][not faults :]) or "-"
    return [name, n, backend, faults_text, seed_text, successes, *summed, steps, failed or "-", wall]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", action="append", type=parse_case, help="EXPERIMENT:N:BACKEND:SEEDS[:FAULTS]")
    parser.add_argument("--quick", action="store_true", help="fewer seeds and sizes")
    parser.add_argument("--resilience", action="store_true", help="every experiment under each fault")
    parser.add_argument("--seeds", default="0-9", help="seeds of the resilience table (default 0-9)")
    parser.add_argument("--workers", type=int, default=2, help="local Dask worker processes")
    parser.add_argument("--param", action="append", type=parse_param, default=[], help="NAME=VALUE, every case")
    parser.add_argument(
        "--checkpoints", metavar="DIR", type=Path, help="save swarm-mode runs in DIR as they go; resume what it holds"
    )
    args = parser.parse_args()
    if args.checkpoints is not None:
        args.checkpoints.mkdir(parents=True, exist_ok=True)
    if args.case:
        cases = args.case
    elif args.resilience:
        sizes = {"hrvo-circle": (10, 100), "line-consensus": (10, 100), "voronoi-coverage": (10, 100)}
        sizes["affine-formation"] = (7, 98)
        cases = [
            parse_case(f"{name}:{n}:fast:{args.seeds}:{faults}")
            for name, counts in sizes.items()
            for n in counts
            for faults in FAULTS.values()
        ]
    else:
        cases = [parse_case(text) for text in (QUICK if args.quick else SIZES)]
    print(machine())
    rows = []
    for case in cases:
        rows.append(measure(*case, workers=args.workers, params=dict(args.param), checkpoints=args.checkpoints))
        print("  " + " | ".join(map(str, rows[-1])), flush=True)
    header = ["experiment", "N", "backend", "faults (+ params)", "seeds", "successes"]
    header += ["collisions", "boundary", "actuator"]
    print(machine())
    print(table([*header, "steps min/median/max", "failed seeds", "wall s"], rows))


if __name__ == "__main__":
    main()
