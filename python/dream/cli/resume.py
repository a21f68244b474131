"""``dream resume PATH``: go on with a run saved by ``dream run --checkpoint PATH``."""

from __future__ import annotations

import argparse
from pathlib import Path

from dream.cli._drive import add_options, check_outputs, drive
from dream.cli._usage import Commands, UsageError, whole
from dream.experiments import resume
from dream.experiments.checkpoint import load


def add(commands: Commands) -> None:
    resumer = commands.add_parser("resume", help="go on with a run saved by `dream run --checkpoint PATH`")
    resumer.add_argument("checkpoint", metavar="PATH", help="the checkpoint (it is saved again as the run goes on)")
    resumer.add_argument("--steps", type=whole(1), default=None, help="a new step cap (default: the run's own)")
    resumer.add_argument(
        "--trust",
        action="store_true",
        help="resume a checkpoint not signed with your key (a colleague's): loading it runs its code",
    )
    add_options(resumer)
    resumer.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    if not Path(args.checkpoint).is_file():
        raise UsageError(f"{args.checkpoint}: no such checkpoint")
    check_outputs(args, (args.checkpoint, "the checkpoint"))  # saved again as the run goes on
    try:
        n = None if args.focus is None else load(args.checkpoint, trust=args.trust).stepper.exp.n  # for --focus
    except ValueError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        raise UsageError(f"{args.checkpoint}: {err.strerror or err}") from None
    return drive(
        args,
        n,
        lambda recorder, progress: resume(
            args.checkpoint, args.steps, record=recorder, progress=progress,
            checkpoint_every=args.checkpoint_every, trust=args.trust,
        ),
    )  # fmt: skip
