"""``dream list [EXPERIMENT]``: the built-in experiments, or one experiment's parameters."""

from __future__ import annotations

import argparse
import sys

from dream.cli._usage import Commands, experiment
from dream.experiments import EXPERIMENTS, Experiment


def add(commands: Commands) -> None:
    listing = commands.add_parser("list", help="list the experiments, or one experiment's parameters")
    listing.add_argument("experiment", nargs="?", help="a built-in experiment's name or a .py file")
    listing.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    source: str | None = args.experiment
    if source is None:
        for name, cls in sorted(EXPERIMENTS.items()):
            print(f"{name:<18} {'swarm' if cls.has_swarm_mode else '':<6} {_summary(cls)}")
        print(
            "\n`dream list NAME` shows an experiment's parameters; `dream run FILE.py` runs your own;"
            "\n`swarm`: it also runs in swarm mode (`dream run NAME --swarm`)."
        )
        return 0
    cls = experiment(source)
    print(f"{cls.label()}: {_summary(cls)}")
    print(f"robots by default: {cls.default_n}")
    print(f"success: {cls.success}")
    print(f"swarm mode: yes (dream run {source} --swarm)" if cls.has_swarm_mode else "swarm mode: no")
    declared = cls.parameters()
    print("parameters:" if declared else "parameters: none")
    for name, spec in declared.items():
        setting, kind = f"{name}={spec.default}", ", ".join(filter(None, (spec.kind.__name__, spec.range)))
        print(f"  --param {setting:<22} ({kind}) {spec.help}")
    return 0


def _summary(cls: type[Experiment]) -> str:
    """The first line of the experiment's module docstring (else of its class docstring)."""
    text = sys.modules[cls.__module__].__doc__ or cls.__doc__ or ""
    return (text.strip().splitlines() or [""])[0]
