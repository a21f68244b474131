"""``dream bench``: the benchmarks of the repository's ``benches/`` (a source checkout)."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

from dream.cli._usage import Commands, UsageError


def add(commands: Commands) -> None:
    bench = commands.add_parser(
        "bench", help="run the benchmarks of the repository's benches/ (needs a source checkout)"
    )
    bench.add_argument("--full", action="store_true", help="all kernel sizes (minutes) instead of --quick")
    bench.set_defaults(handler=command)


def benches_dir() -> Path:
    """The repository's ``benches/``: in the current directory (a checkout, whatever the install),
    else beside the package's source (an editable install)."""
    here = Path.cwd() / "benches"
    if (here / "bench_kernels.py").is_file():
        return here
    return Path(__file__).resolve().parents[3] / "benches"


def command(args: argparse.Namespace) -> int:
    benches = benches_dir()
    scripts = [(benches / "bench_kernels.py", [] if args.full else ["--quick"]), (benches / "bench_experiments.py", [])]
    missing = [str(script) for script, _ in scripts if not script.is_file()]
    if missing:
        raise UsageError(
            f"no benchmarks at {benches} (missing {', '.join(missing)}); `dream bench` runs the "
            "benchmarks of a source checkout: run it from the repository's top folder"
        )
    for script, flags in scripts:
        print(f"$ python {script.name} {' '.join(flags)}".rstrip(), flush=True)
        done = subprocess.run([sys.executable, script.name, *flags], cwd=benches, check=False)
        if done.returncode != 0:
            print(f"dream: error: {script.name} failed with exit code {done.returncode}", file=sys.stderr)
            return done.returncode
    return 0
