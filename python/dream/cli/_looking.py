"""What ``dream run`` and ``dream view`` share to look into a run: the trajectory log's and the
Rerun recording's options, checked before the run (:mod:`dream.trajectory_log`,
:mod:`dream.recording`)."""

from __future__ import annotations

import argparse

from dream.cli._usage import UsageError, whole, writable


def add_log(sub: argparse.ArgumentParser) -> None:
    """``--log PATH`` and ``--log-every K``."""
    sub.add_argument(
        "--log", metavar="PATH", help="write the trajectory log, a Parquet table (one row per robot and step)"
    )
    sub.add_argument(
        "--log-every", metavar="K", type=whole(1), default=None,
        help="log (and record, with --rerun) one step in K, and the first and last (default: 1)",
    )  # fmt: skip


def add_rerun(sub: argparse.ArgumentParser, alone: str) -> None:
    """``--rerun [FILE.rrd]`` (``alone``: what ``--rerun`` without a file does) or ``--rerun-serve``."""
    where = sub.add_mutually_exclusive_group()
    where.add_argument(
        "--rerun", nargs="?", const="spawn", metavar="FILE.rrd",
        help=f"a Rerun recording: into FILE.rrd, or {alone} (needs the rerun extra)",
    )  # fmt: skip
    where.add_argument(
        "--rerun-serve", dest="rerun", action="store_const", const="serve",
        help="serve the recording to a web viewer on 127.0.0.1 (its address is printed; kept up until Ctrl-C)",
    )  # fmt: skip


def rerun_target(target: str) -> str:
    """``target`` checked before the run: Rerun installed, a ``.rrd`` path that can be written."""
    from dream.recording import check_target

    try:
        check_target(target)
    except (ValueError, ImportError) as err:
        raise UsageError(f"--{err}" if isinstance(err, ValueError) else str(err)) from None
    return target


def check_looking(args: argparse.Namespace) -> list[tuple[str | None, str]]:
    """Refuse, before the run, a log or a recording that cannot be written and ``--log-every``
    with neither; returns the files they write, ``(path, option)``, for the same-file check."""
    if args.log_every is not None and not (args.log or args.rerun):
        raise UsageError("--log-every sets how often --log and --rerun look: give one of them")
    if args.log:
        writable(args.log, "--log")
    if args.rerun:
        rerun_target(args.rerun)
    return [(args.log, "--log"), (None if args.rerun in (None, "spawn", "serve") else args.rerun, "--rerun")]
