"""``dream view LOG``: a trajectory log (``dream run --log``) in the Rerun viewer, or as a recording."""

from __future__ import annotations

import argparse

from dream.cli._looking import add_rerun, rerun_target
from dream.cli._usage import Commands, UsageError


def add(commands: Commands) -> None:
    viewer = commands.add_parser(
        "view", help="show a trajectory log (dream run --log) in the Rerun viewer, or write it as a recording"
    )
    viewer.add_argument("log", metavar="LOG", help="a trajectory log (.parquet) written by `dream run --log`")
    add_rerun(viewer, "live in a viewer it spawns (the default)")
    viewer.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    from dream.recording import from_log, wait_served

    target = rerun_target(args.rerun or "spawn")
    try:
        steps = from_log(args.log, target)
    except (ValueError, OSError) as err:  # not a log (pyarrow's errors are ValueErrors), no such file
        raise UsageError(f"{args.log}: {err}") from None
    print(f"{args.log}: {steps} steps" + ("" if target in ("spawn", "serve") else f", recorded in {target}"))
    wait_served()
    return 0
