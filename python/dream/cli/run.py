"""``dream run EXPERIMENT``: run an experiment and print its metrics."""

from __future__ import annotations

import argparse

from dream.backends import BACKENDS
from dream.backends.robotarium import MAX_ROBOTS
from dream.cli._drive import add_options, check_outputs, drive
from dream.cli._usage import Commands, UsageError, assignments, experiment, whole, writable
from dream.experiments import EXPERIMENTS, run
from dream.experiments.checkpoint import CHECKPOINT_EVERY
from dream.faults import KINDS, Faults
from dream.specs import RULES


def add(commands: Commands) -> None:
    runner = commands.add_parser("run", help="run an experiment and print its metrics (headless unless --show)")
    runner.add_argument("experiment", help=f"one of {', '.join(sorted(EXPERIMENTS))}, or a .py file")
    runner.add_argument("-n", type=whole(1), default=None, help="number of robots (default: the experiment's)")
    runner.add_argument("--seed", type=whole(0), default=0, help="random seed (default: 0)")
    runner.add_argument("--backend", choices=BACKENDS, default="auto")
    runner.add_argument("--rules", choices=RULES, help="the rps generation to follow (default: the installed rps's)")
    runner.add_argument("--steps", type=whole(1), default=None, help="step cap (default: what the run needs)")
    runner.add_argument(
        "--swarm",
        action="store_true",
        help="swarm mode: the whole swarm decides every step in one call (if it has one)",
    )
    runner.add_argument(
        "--param", action="append", default=[], metavar="NAME=VALUE", help="set a parameter (repeatable)"
    )
    runner.add_argument(
        "--fault",
        action="append",
        default=[],
        metavar="KIND=VALUE",
        help="inject a fault (repeatable): " + ", ".join(f"{kind}={form}" for kind, form in KINDS.items()),
    )
    runner.add_argument("--checkpoint", metavar="PATH", help="save the run to PATH as it goes (see `dream resume`)")
    add_options(runner)
    runner.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    cls = experiment(args.experiment)
    try:
        params = cls(**dict(assignments(args.param, "--param"))).params  # converted and checked
    except ValueError as err:
        raise UsageError(f"--param: {err}") from None
    try:
        faults = Faults.parse(args.fault)
    except ValueError as err:
        raise UsageError(str(err)) from None
    n = cls.default_n if args.n is None else args.n
    if args.backend == "robotarium" and n > MAX_ROBOTS:
        raise UsageError(f"-n {n}: the Robotarium backend runs at most {MAX_ROBOTS} robots; use --backend fast")
    if args.checkpoint:
        writable(args.checkpoint, "--checkpoint")
    check_outputs(args, (args.checkpoint, "--checkpoint"))
    every = CHECKPOINT_EVERY if args.checkpoint_every is None else args.checkpoint_every
    return drive(
        args,
        n,
        lambda recorder, progress: run(
            cls, n=n, seed=args.seed, backend=args.backend, steps=args.steps, progress=progress, faults=faults,
            rules=args.rules, swarm=args.swarm, record=recorder, checkpoint=args.checkpoint, checkpoint_every=every,
            **params,
        ),
    )  # fmt: skip
