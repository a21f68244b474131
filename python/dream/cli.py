"""The ``dream`` command: list and run the reference experiments headless.

    dream list
    dream run hrvo-circle -n 10 --seed 0 --backend auto --json metrics.json
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import Callable

from dream.experiments import EXPERIMENTS


def _progress_bar(enabled: bool) -> Callable[[int, int], None] | None:
    if not enabled:
        return None

    def show(step: int, cap: int) -> None:
        if step % 50 == 0 or step == cap:
            filled = int(30 * step / cap) if cap else 30
            sys.stderr.write(f"\r[{'#' * filled}{'.' * (30 - filled)}] step {step}/{cap}")
            sys.stderr.flush()

    return show


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="dream", description="Distributed multi-robot experiments on the Robotarium.")
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("list", help="list the experiments")
    run = commands.add_parser("run", help="run an experiment headless and print its metrics")
    run.add_argument("experiment", choices=sorted(EXPERIMENTS))
    run.add_argument("-n", type=int, default=None, help="number of robots (default: the thesis's)")
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--backend", choices=("auto", "robotarium", "fast"), default="auto")
    run.add_argument("--steps", type=int, default=None, help="iteration cap (default: what the experiment needs)")
    run.add_argument("--json", metavar="PATH", help="also write the metrics as JSON")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "list":
        for name, module in sorted(EXPERIMENTS.items()):
            print(f"{name:<20} {(module.__doc__ or '').strip().splitlines()[0]}")
        return 0
    experiment = EXPERIMENTS[args.experiment]
    options = {"seed": args.seed, "backend": args.backend, "steps": args.steps}
    if args.n is not None:
        options["n"] = args.n
    progress = _progress_bar(not args.no_progress and sys.stderr.isatty())
    try:
        result = experiment.run(progress=progress, **options)
    except (ValueError, IndexError) as err:
        print(f"dream: error: {err}", file=sys.stderr)
        return 2
    if progress is not None:
        sys.stderr.write("\n")
    print(result.summary())
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump(result.to_dict(), out, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
