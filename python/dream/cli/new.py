"""``dream new NAME``: a starter experiment file that runs as is."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from dream.cli._usage import Commands, UsageError, writable

STARTER = Path(__file__).parent.parent / "templates" / "starter.py"


def add(commands: Commands) -> None:
    new = commands.add_parser("new", help="write a starter experiment file that runs as is")
    new.add_argument("name", help="the experiment's name; the file is NAME.py")
    new.add_argument("-o", "--output", metavar="PATH", help="where to write it (default: ./NAME.py)")
    new.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    name: str = args.name
    path = Path(args.output or f"{name}.py")
    if path.exists():
        raise UsageError(f"{path} exists already: choose another name or -o PATH")
    writable(str(path), "-o")
    words = {"FILE_STEM": path.stem, "FILE": str(path), "NAME": name}
    # One pass: a name that holds a placeholder (NAME_x) is written as given, not replaced again.
    text = re.sub("|".join(words), lambda found: words[found.group(0)], STARTER.read_text(encoding="utf-8"))
    path.write_text(text, encoding="utf-8")
    print(f"wrote {path}: run it with `dream run {path}`")
    return 0
