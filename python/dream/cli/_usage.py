"""What every command shares, below the commands: the usage error, the checks of option values
and the one ``NAME=VALUE`` parser. The library never imports this: imports go cli -> library."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from typing import TypeAlias

from dream._files import check_writable
from dream.experiments import Experiment, find

#: The ``add_subparsers`` object each command module adds its parser to.
Commands: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"


class UsageError(Exception):
    """Input the command cannot act on: printed as one line, exit code 2."""


def whole(least: int) -> Callable[[str], int]:
    """An argparse type: an integer of at least ``least``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer >= {least}, got {text!r}") from None
        if value < least:
            raise argparse.ArgumentTypeError(f"expected an integer >= {least}, got {value}")
        return value

    parse.__name__ = f"integer >= {least}"
    return parse


def writable(path: str, option: str) -> None:
    """Refuse, before the run, an output path that cannot be written."""
    try:
        check_writable(path, option)
    except ValueError as err:
        raise UsageError(str(err)) from None


def assignments(texts: Sequence[str], option: str, form: str = "NAME=VALUE") -> list[tuple[str, str]]:
    """Repeated ``NAME=VALUE`` options as ``(NAME, VALUE)`` pairs, in order, the name stripped;
    ``form`` is what the error shows the option takes."""
    pairs = []
    for text in texts:
        name, equals, value = text.partition("=")
        if not equals or not name.strip():
            raise UsageError(f"{option} takes {form}, got {text!r}")
        pairs.append((name.strip(), value))
    return pairs


def experiment(source: str) -> type[Experiment]:
    """The experiment a command names: a built-in's name or a ``.py`` file."""
    try:
        return find(source)
    except ValueError as err:  # unknown name, or a file that does not define one experiment
        raise UsageError(str(err)) from None
