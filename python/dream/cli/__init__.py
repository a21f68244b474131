"""The ``dream`` command: list, run, record and start experiments, built-in or your own.

    dream list                                           # the built-in experiments
    dream list line-consensus                            # its success test and parameters
    dream run hrvo-circle -n 10 --seed 0 --json metrics.json
    dream run my_experiment.py --param gain=2 --video run.mp4 --every 2
    dream run hrvo-circle -n 2000 --swarm --backend fast   # the whole swarm decides in one call
    dream run hrvo-circle -n 10000 --swarm --checkpoint big.ckpt   # saved as it goes...
    dream resume big.ckpt                                # ...and resumed where it stopped
    dream resume theirs.ckpt --trust                     # a colleague's: loading a checkpoint runs its code
    dream new my_experiment                              # a starter file that runs as is
    dream bench                                          # the repository's benches/

Exit codes: 0 done, 1 the run failed its success test (with ``--check``), 2 bad input, 130
interrupted.

One module per command, each with ``add(commands)`` (its parser, whose ``handler`` default is
its ``command(args)``); what they share sits below them in ``_usage`` and ``_drive``. Imports go
one way: the commands use the library, the library never imports the command line.
"""

from __future__ import annotations

import argparse
import signal
import sys
import warnings
from collections.abc import Sequence
from typing import Any

from dream.cli import bench, export, new, resume, run, sweep
from dream.cli import list as listing
from dream.cli._usage import UsageError

__all__ = ["UsageError", "main"]

#: The commands, in the order ``dream --help`` lists them.
COMMANDS = (listing, run, resume, new, bench, sweep, export)


def _parser() -> argparse.ArgumentParser:
    from dream import __version__

    parser = argparse.ArgumentParser(prog="dream", description="Distributed multi-robot experiments on the Robotarium.")
    parser.add_argument("--version", action="version", version=f"dream {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    for module in COMMANDS:
        module.add(commands)
    return parser


def _warning(message: Warning | str, category: type[Warning], *where: Any, **more: Any) -> None:
    """A warning as the command prints it: one line, without the source line that raised it."""
    print(f"dream: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _warning
        return _command(args)


def _command(args: argparse.Namespace) -> int:
    try:
        code: int = args.handler(args)
        return code
    except UsageError as err:
        print(f"dream: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # before or after the steps, where the runner cannot keep a result
        print("dream: interrupted", file=sys.stderr)
        return 128 + signal.SIGINT
