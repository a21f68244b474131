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
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from dream._files import check_writable, replaced
from dream.backends import BACKENDS
from dream.backends.robotarium import MAX_ROBOTS
from dream.experiments import EXPERIMENTS, Experiment, ExperimentResult, find, resume, run
from dream.experiments.checkpoint import CHECKPOINT_EVERY, load
from dream.experiments.runner import outputs_kept
from dream.faults import KINDS, Faults
from dream.specs import RULES

STARTER = Path(__file__).parent / "templates" / "starter.py"


class UsageError(Exception):
    """Input the command cannot act on: printed as one line, exit code 2."""


def _whole(least: int) -> Callable[[str], int]:
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


def _size(text: str) -> tuple[int, int]:
    from dream.viz import parse_size  # no matplotlib import

    try:
        return parse_size(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _parser() -> argparse.ArgumentParser:
    from dream import __version__

    parser = argparse.ArgumentParser(prog="dream", description="Distributed multi-robot experiments on the Robotarium.")
    parser.add_argument("--version", action="version", version=f"dream {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    listing = commands.add_parser("list", help="list the experiments, or one experiment's parameters")
    listing.add_argument("experiment", nargs="?", help="a built-in experiment's name or a .py file")
    runner = commands.add_parser("run", help="run an experiment and print its metrics (headless unless --show)")
    runner.add_argument("experiment", help=f"one of {', '.join(sorted(EXPERIMENTS))}, or a .py file")
    runner.add_argument("-n", type=_whole(1), default=None, help="number of robots (default: the experiment's)")
    runner.add_argument("--seed", type=_whole(0), default=0, help="random seed (default: 0)")
    runner.add_argument("--backend", choices=BACKENDS, default="auto")
    runner.add_argument("--rules", choices=RULES, help="the rps generation to follow (default: the installed rps's)")
    runner.add_argument("--steps", type=_whole(1), default=None, help="step cap (default: what the run needs)")
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
    resumer = commands.add_parser("resume", help="go on with a run saved by `dream run --checkpoint PATH`")
    resumer.add_argument("checkpoint", metavar="PATH", help="the checkpoint (it is saved again as the run goes on)")
    resumer.add_argument("--steps", type=_whole(1), default=None, help="a new step cap (default: the run's own)")
    resumer.add_argument(
        "--trust",
        action="store_true",
        help="resume a checkpoint not signed with your key (a colleague's): loading it runs its code",
    )
    for sub in (runner, resumer):  # what a run prints, records and saves
        sub.add_argument("--json", metavar="PATH", help="also write the metrics as JSON")
        sub.add_argument("--no-progress", action="store_true", help="no progress bar")
        sub.add_argument("--video", metavar="PATH", help="record the run to a video: .gif (Pillow) or .mp4 (H.264)")
        sub.add_argument("--show", action="store_true", help="show the run in a live window")
        sub.add_argument(
            "--every", metavar="K", type=_whole(1), default=1, help="draw one step in K into the video/window"
        )
        sub.add_argument(
            "--size", metavar="WxH", type=_size, default=(1280, 800), help="image size (default: 1280x800)"
        )
        sub.add_argument("--focus", metavar="ID", type=_whole(0), help="draw this robot's ranges and who it hears")
        sub.add_argument("--realtime", action="store_true", help="pace the run to wall time (30 steps/s)")
        sub.add_argument("--hold", action="store_true", help="keep the live window open at the end until closed")
        sub.add_argument("--check", action="store_true", help="exit with 1 when the run fails its success test")
        sub.add_argument(
            "--checkpoint-every", metavar="K", type=_whole(1), default=None,
            help=f"steps between two saves of the checkpoint (default: {CHECKPOINT_EVERY:,}; resume: the run's own)",
        )  # fmt: skip
    new = commands.add_parser("new", help="write a starter experiment file that runs as is")
    new.add_argument("name", help="the experiment's name; the file is NAME.py")
    new.add_argument("-o", "--output", metavar="PATH", help="where to write it (default: ./NAME.py)")
    bench = commands.add_parser(
        "bench", help="run the benchmarks of the repository's benches/ (needs a source checkout)"
    )
    bench.add_argument("--full", action="store_true", help="all kernel sizes (minutes) instead of --quick")
    from dream.sweep import command, parse_counts, parse_seeds

    sweeper = commands.add_parser("sweep", help="run an experiment over seeds, sizes and parameters on Dask, to a CSV")
    sweeper.add_argument("experiment", help=f"one of {', '.join(sorted(EXPERIMENTS))}, or a .py file")
    sweeper.add_argument(
        "--seeds", type=parse_seeds, default=list(range(8)), help="A:B (B excluded) or 1,5,9 (default: 0:8)"
    )
    sweeper.add_argument("-n", type=parse_counts, default=None, help="robot counts, 10,20 (default: the experiment's)")
    sweeper.add_argument(
        "--param", action="append", default=[], metavar="NAME=V1,V2", help="values of a parameter (repeatable)"
    )
    sweeper.add_argument(
        "--fault", action="append", default=[], metavar="KIND=V1,V2", help="sweep a fault's values (repeatable)"
    )
    sweeper.add_argument("--backend", choices=BACKENDS, default="auto")
    sweeper.add_argument("--swarm", action="store_true", help="run the experiment's swarm mode (see dream list)")
    sweeper.add_argument("--steps", type=_whole(1), default=None, help="step cap (default: what the run needs)")
    sweeper.add_argument("--workers", type=_whole(1), default=None, help="local worker processes (default: cores)")
    sweeper.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="use a running Dask scheduler instead")
    sweeper.add_argument("--out", metavar="PATH", required=True, help="CSV of one row per run (resumes what it holds)")
    sweeper.add_argument("--plot", metavar="PATH", help="PNG of success rate and measures against the swept values")
    sweeper.add_argument("--no-progress", action="store_true", help="no progress bar")
    sweeper.add_argument(
        "--dashboard", action="store_true", help="serve the local cluster's Dask dashboard on 127.0.0.1 (default: off)"
    )
    sweeper.set_defaults(handler=command)
    from dream import export

    exporter = commands.add_parser(
        "export", help="write a folder the Robotarium lab runs: main.py in its loop shape + pure-Python DREAM"
    )
    exporter.add_argument("experiment", help=f"one of {', '.join(sorted(EXPERIMENTS))}, or a .py file")
    exporter.add_argument(
        "-o", "--output", metavar="DIR", required=True, help="the bundle's folder (new, empty, or a previous export)"
    )
    exporter.add_argument(
        "-n", type=_whole(1), default=None, help=f"number of robots, at most {export.LAB_MAX_ROBOTS} (the lab's)"
    )
    exporter.add_argument("--seed", type=_whole(0), default=0, help="random seed (default: 0)")
    exporter.add_argument(
        "--param", action="append", default=[], metavar="NAME=VALUE", help="set a parameter (repeatable)"
    )
    exporter.add_argument(
        "--force", action="store_true", help=f"replace DIR if it holds a previous export (a {export.MARKER} file)"
    )
    exporter.add_argument(
        "--policy", metavar="FILE", default=None, help="a trained dream.rl.LinearPolicy (.npz) for the robots to run"
    )
    exporter.set_defaults(handler=export.command)
    return parser


def benches_dir() -> Path:
    """The repository's ``benches/``: in the current directory (a checkout, whatever the install),
    else beside the package's source (an editable install)."""
    here = Path.cwd() / "benches"
    if (here / "bench_kernels.py").is_file():
        return here
    return Path(__file__).resolve().parents[2] / "benches"


def _bench(full: bool) -> int:
    benches = benches_dir()
    scripts = [(benches / "bench_kernels.py", [] if full else ["--quick"]), (benches / "bench_experiments.py", [])]
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


def _experiment(source: str) -> type[Experiment]:
    try:
        return find(source)
    except ValueError as err:  # unknown name, or a file that does not define one experiment
        raise UsageError(str(err)) from None


def _summary(cls: type[Experiment]) -> str:
    """The first line of the experiment's module docstring (else of its class docstring)."""
    text = sys.modules[cls.__module__].__doc__ or cls.__doc__ or ""
    return (text.strip().splitlines() or [""])[0]


def _list(source: str | None) -> int:
    if source is None:
        for name, cls in sorted(EXPERIMENTS.items()):
            print(f"{name:<18} {'swarm' if cls.has_swarm_mode else '':<6} {_summary(cls)}")
        print(
            "\n`dream list NAME` shows an experiment's parameters; `dream run FILE.py` runs your own;"
            "\n`swarm`: it also runs in swarm mode (`dream run NAME --swarm`)."
        )
        return 0
    cls = _experiment(source)
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


def _params(cls: type[Experiment], pairs: Sequence[str]) -> dict[str, Any]:
    params: dict[str, Any] = {}
    for pair in pairs:
        name, equals, value = pair.partition("=")
        if not equals or not name:
            raise UsageError(f"--param takes NAME=VALUE, got {pair!r}")
        params[name.strip()] = value
    try:
        return cls(**params).params  # converted and checked against the declarations
    except ValueError as err:
        raise UsageError(f"--param: {err}") from None


def _writable(path: str, option: str) -> None:
    """Refuse, before the run, an output path that cannot be written."""
    try:
        check_writable(path, option)
    except ValueError as err:
        raise UsageError(str(err)) from None


def _outputs(args: argparse.Namespace, saved: tuple[str | None, str]) -> None:
    """Refuse, before the run, drawing options that draw nothing, a ``--json`` path that cannot be
    written (the video's is the recorder's to check) and two outputs on one file (``--json``,
    ``--video`` and ``saved``, the checkpoint the run writes: ``(path, what)``)."""
    if args.realtime and not (args.show or args.video):
        raise UsageError("--realtime paces what is drawn: give --show or --video too")
    if args.hold and not args.show:
        raise UsageError("--hold keeps the live window open: give --show too")
    if args.json:
        _writable(args.json, "--json")
    outputs = [(path, option) for path, option in ((args.json, "--json"), (args.video, "--video"), saved) if path]
    for i, (path, option) in enumerate(outputs):
        for other, other_option in outputs[i + 1 :]:
            if os.path.realpath(path) == os.path.realpath(other):
                raise UsageError(f"{option} and {other_option} name the same file {path}: give each its own")


def _write_json(path: str, data: dict[str, Any]) -> None:
    with replaced(path) as out:
        json.dump(data, out, indent=2)


def _progress(enabled: bool) -> Any:
    """A tqdm bar on stderr (off when stderr is not a terminal), created at the first step."""
    if not enabled:
        return None
    from tqdm import tqdm

    class Bar:
        bar: Any = None

        def __call__(self, step: int, cap: int) -> None:
            if self.bar is None:
                self.bar = tqdm(total=cap, unit="step", file=sys.stderr, disable=None, dynamic_ncols=True)
            self.bar.update(step - self.bar.n)

        def close(self) -> None:
            if self.bar is not None:
                self.bar.close()

    return Bar()


def _run(args: argparse.Namespace) -> int:
    cls = _experiment(args.experiment)
    params = _params(cls, args.param)
    try:
        faults = Faults.parse(args.fault)
    except ValueError as err:
        raise UsageError(str(err)) from None
    n = cls.default_n if args.n is None else args.n
    if args.backend == "robotarium" and n > MAX_ROBOTS:
        raise UsageError(f"-n {n}: the Robotarium backend runs at most {MAX_ROBOTS} robots; use --backend fast")
    if args.checkpoint:
        _writable(args.checkpoint, "--checkpoint")
    _outputs(args, (args.checkpoint, "--checkpoint"))
    every = CHECKPOINT_EVERY if args.checkpoint_every is None else args.checkpoint_every
    return _drive(
        args,
        n,
        lambda recorder, progress: run(
            cls, n=n, seed=args.seed, backend=args.backend, steps=args.steps, progress=progress, faults=faults,
            rules=args.rules, swarm=args.swarm, record=recorder, checkpoint=args.checkpoint, checkpoint_every=every,
            **params,
        ),
    )  # fmt: skip


def _resume(args: argparse.Namespace) -> int:
    if not Path(args.checkpoint).is_file():
        raise UsageError(f"{args.checkpoint}: no such checkpoint")
    _outputs(args, (args.checkpoint, "the checkpoint"))  # saved again as the run goes on
    try:
        n = None if args.focus is None else load(args.checkpoint, trust=args.trust).stepper.exp.n  # for --focus
    except ValueError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        raise UsageError(f"{args.checkpoint}: {err.strerror or err}") from None
    return _drive(
        args,
        n,
        lambda recorder, progress: resume(
            args.checkpoint, args.steps, record=recorder, progress=progress,
            checkpoint_every=args.checkpoint_every, trust=args.trust,
        ),
    )  # fmt: skip


def _drive(args: argparse.Namespace, n: int | None, call: Callable[[Any, Any], ExperimentResult]) -> int:
    """Run ``call(recorder, progress)`` with the recorder and progress bar the options ask for,
    then print and report; refusals before the first step (``ValueError``) are usage errors."""
    if args.focus is not None and n is not None and args.focus >= n:
        raise UsageError(f"--focus {args.focus}: no such robot; the run has {n} (ids 0 to {n - 1})")
    recorder = None
    if args.video is not None or args.show:
        from dream.viz import Recorder  # matplotlib only when drawing

        try:  # a bad video path fails here, before the run
            recorder = Recorder(video=args.video, show=args.show, every=args.every, size=args.size, focus=args.focus,
                                realtime=args.realtime, hold=args.hold)  # fmt: skip
        except (ValueError, OSError) as err:
            raise UsageError(str(err)) from None
    progress = _progress(not args.no_progress)
    with outputs_kept() as guard:  # once the run steps, a Ctrl-C waits for the video and the JSON
        try:
            result = call(recorder, progress)
        except ValueError as err:  # a refusal (a size the experiment cannot do, a bad checkpoint), before any step
            raise UsageError(str(err)) from None
        finally:
            if progress is not None:
                progress.close()
            if recorder is not None:
                recorder.close()  # a run that failed half-way still leaves a playable video
        if recorder is not None and recorder.writer is not None:
            if recorder.writer.frames_written:
                print(f"video: {recorder.video} ({recorder.writer.frames_written} frames, one step in {args.every})")
            else:
                print(f"video: none written (no steps recorded) to {recorder.video}")
        code = _report(result, args)
        if guard.signal is not None:  # the command ends now, all written: a late Ctrl-C has nothing to stop
            guard.ignore_from_now()
    if guard.signal is not None and not result.interrupted:  # it came as the run ended
        print("dream: interrupted", file=sys.stderr)
        return 128 + guard.signal
    if not result.interrupted and recorder is not None and recorder.live:
        print("close the window to exit", file=sys.stderr)
        recorder.hold()  # keep the live window on the last frame until the user closes it
    return code


def _report(result: ExperimentResult, args: argparse.Namespace) -> int:
    """Print (and with ``--json`` write) a run's metrics; its exit code."""
    print(result.summary())
    if args.json:
        try:
            _write_json(args.json, result.to_dict())
        except OSError as err:  # checked before the run, yet the disk filled or the folder went
            raise UsageError(f"--json {args.json}: not written: {err.strerror or err}") from None
    if result.interrupted:
        kept = f"; metrics so far in {args.json}" if args.json else ""
        if args.checkpoint:
            kept += f"; go on with `dream resume {args.checkpoint}`"
        print(f"dream: interrupted after {result.steps} steps{kept}", file=sys.stderr)
        return 128 + (result.signal or signal.SIGINT)
    return 1 if args.check and not result.success else 0


def _new(name: str, output: str | None) -> int:
    path = Path(output or f"{name}.py")
    if path.exists():
        raise UsageError(f"{path} exists already: choose another name or -o PATH")
    _writable(str(path), "-o")
    words = {"FILE_STEM": path.stem, "FILE": str(path), "NAME": name}
    # One pass: a name that holds a placeholder (NAME_x) is written as given, not replaced again.
    text = re.sub("|".join(words), lambda found: words[found.group(0)], STARTER.read_text(encoding="utf-8"))
    path.write_text(text, encoding="utf-8")
    print(f"wrote {path}: run it with `dream run {path}`")
    return 0


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
        if args.command == "list":
            return _list(args.experiment)
        if args.command == "bench":
            return _bench(args.full)
        if args.command == "new":
            return _new(args.name, args.output)
        if args.command == "resume":
            return _resume(args)
        if args.command in ("sweep", "export"):
            return args.handler(args)
        return _run(args)
    except UsageError as err:
        print(f"dream: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # before or after the steps, where the runner cannot keep a result
        print("dream: interrupted", file=sys.stderr)
        return 128 + signal.SIGINT


if __name__ == "__main__":
    raise SystemExit(main())
