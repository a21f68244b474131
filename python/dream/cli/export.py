"""``dream export EXPERIMENT -o DIR``: a folder the Robotarium lab runs."""

from __future__ import annotations

import argparse
import sys
import warnings

from dream.cli._usage import Commands, UsageError, assignments, whole
from dream.experiments import EXPERIMENTS
from dream.export import LAB_MAX_ROBOTS, MARKER, ExportError, ExportWarning, export


def add(commands: Commands) -> None:
    exporter = commands.add_parser(
        "export", help="write a folder the Robotarium lab runs: main.py in its loop shape + pure-Python DREAM"
    )
    exporter.add_argument("experiment", help=f"one of {', '.join(sorted(EXPERIMENTS))}, or a .py file")
    exporter.add_argument(
        "-o", "--output", metavar="DIR", required=True, help="the bundle's folder (new, empty, or a previous export)"
    )
    exporter.add_argument(
        "-n", type=whole(1), default=None, help=f"number of robots, at most {LAB_MAX_ROBOTS} (the lab's)"
    )
    exporter.add_argument("--seed", type=whole(0), default=0, help="random seed (default: 0)")
    exporter.add_argument(
        "--param", action="append", default=[], metavar="NAME=VALUE", help="set a parameter (repeatable)"
    )
    exporter.add_argument(
        "--force", action="store_true", help=f"replace DIR if it holds a previous export (a {MARKER} file)"
    )
    exporter.add_argument(
        "--policy", metavar="FILE", default=None, help="a trained dream.rl.LinearPolicy (.npz) for the robots to run"
    )
    exporter.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """The parsed command line to :func:`dream.export.export`, bad input as one line (exit 2)."""
    params = dict(assignments(args.param, "--param"))
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExportWarning)
            folder = export(
                args.experiment,
                args.output,
                n=args.n,
                seed=args.seed,
                params=params,
                force=args.force,
                policy=args.policy,
            )
    except ExportError as err:
        raise UsageError(str(err)) from None
    for warning in caught:
        print(f"dream: warning: {warning.message}", file=sys.stderr)
    print(f"wrote {folder}: run `DREAM_HEADLESS=1 python {folder / 'main.py'}` to check it, then submit the folder")
    return 0
