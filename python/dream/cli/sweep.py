"""``dream sweep EXPERIMENT``: an experiment over seeds, sizes and parameters on Dask, to a CSV."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

from dream.backends import BACKENDS
from dream.cli._usage import Commands, UsageError, assignments, whole
from dream.experiments import EXPERIMENTS
from dream.sweep import sweep


def add(commands: Commands) -> None:
    sweeper = commands.add_parser("sweep", help="run an experiment over seeds, sizes and parameters on Dask, to a CSV")
    sweeper.add_argument("experiment", help=f"one of {', '.join(sorted(EXPERIMENTS))}, or a .py file")
    sweeper.add_argument(
        "--seeds", type=parse_seeds, default=list(range(8)), help="A:B (B excluded) or 1,5,9 (default: 0:8)"
    )
    sweeper.add_argument("-n", type=parse_counts, default=None, help="robot counts, 10,20 (default: the experiment's)")
    sweeper.add_argument(
        "--param", action="append", default=[], metavar="NAME=V1,V2", help="values of a parameter (repeatable)"
    )
    sweeper.add_argument(
        "--fault", action="append", default=[], metavar="KIND=V1,V2", help="sweep a fault's values (repeatable)"
    )
    sweeper.add_argument("--backend", choices=BACKENDS, default="auto")
    sweeper.add_argument("--swarm", action="store_true", help="run the experiment's swarm mode (see dream list)")
    sweeper.add_argument("--steps", type=whole(1), default=None, help="step cap (default: what the run needs)")
    sweeper.add_argument("--workers", type=whole(1), default=None, help="local worker processes (default: cores)")
    sweeper.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="use a running Dask scheduler instead")
    sweeper.add_argument("--out", metavar="PATH", required=True, help="CSV of one row per run (resumes what it holds)")
    sweeper.add_argument("--plot", metavar="PATH", help="PNG of success rate and measures against the swept values")
    sweeper.add_argument("--no-progress", action="store_true", help="no progress bar")
    sweeper.add_argument(
        "--dashboard", action="store_true", help="serve the local cluster's Dask dashboard on 127.0.0.1 (default: off)"
    )
    sweeper.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """The parsed command line to :func:`dream.sweep.sweep`, bad input as one line (exit 2)."""
    grid, fault_grid = _grid(args.param, "--param", "NAME"), _grid(args.fault, "--fault", "KIND")
    start = time.perf_counter()
    try:
        rows = sweep(
            args.experiment, args.seeds, args.n, grid, workers=args.workers, scheduler=args.scheduler,
            out=args.out, plot=args.plot, backend=args.backend, steps=args.steps, faults=fault_grid,
            swarm=args.swarm, progress=not args.no_progress, dashboard=args.dashboard,
        )  # fmt: skip
    except ValueError as err:  # bad values or parameters, an unreachable scheduler, --out not a sweep table
        raise UsageError(str(err)) from None
    except KeyboardInterrupt:
        print(f"\ninterrupted: the runs done so far are in {args.out}; run again to finish", file=sys.stderr)
        return 130
    failed = sum(1 for row in rows if row.get("error"))
    succeeded = sum(1 for row in rows if row.get("success") is True)
    print(
        f"{len(rows)} runs of {rows[0]['experiment']}: {succeeded} succeeded, {failed} raised; "
        f"{rows.new} new, {rows.kept} kept; {time.perf_counter() - start:.1f} s; rows in {args.out}"
        + (f", plot in {args.plot}" if args.plot else "")
    )
    return 0


def _grid(texts: Sequence[str], option: str, what: str) -> dict[str, list[str]]:
    """``NAME=V1,V2,...`` options as ``{NAME: [V1, V2, ...]}``, each name once."""
    grid: dict[str, list[str]] = {}
    for name, values in assignments(texts, option, f"{what}=V1,V2,..."):
        if name in grid:
            raise UsageError(f"{option} {name} given twice: list its values once, separated by commas")
        grid[name] = values.split(",")
    return grid


def parse_seeds(text: str) -> list[int]:
    """``A:B`` (B exclusive) or ``1,5,9``, for argparse."""
    start, colon, stop = text.partition(":")
    try:
        seeds = list(range(int(start), int(stop))) if colon else [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected A:B or a list 1,5,9 of integers, got {text!r}") from None
    if not seeds or min(seeds) < 0:
        raise argparse.ArgumentTypeError(f"expected seeds >= 0 (A:B with A < B), got {text!r}")
    return seeds


def parse_counts(text: str) -> list[int]:
    """``10,20``: robot counts, for argparse."""
    try:
        counts = [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected integers >= 1 separated by commas, got {text!r}") from None
    if min(counts) < 1:
        raise argparse.ArgumentTypeError(f"expected integers >= 1, got {text!r}")
    return counts
