"""The ``dream`` command: list and run the reference experiments, record them, benchmark.

dream list
dream run hrvo-circle -n 10 --seed 0 --backend auto --json metrics.json
dream run voronoi-coverage --video coverage.mp4 --every 2     # or .gif; --show for a window
dream bench                                                   # the repository's benches/
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Callable

from dream.experiments import EXPERIMENTS


def _progress_bar(enabled: bool) -> Callable[[int, int], None] | None:
    if not enabled:
        return None

    def show(step: int, cap: int) -> None:
        if step % 50 == 0 or step == cap:
            filled = int(30 * step / cap) if cap else 30
            sys.stderr.write(f"\r[{'#' * filled}{'.' * (30 - filled)}] step {step}/{cap}")
            sys.stderr.flush()

    return show


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="dream", description="Distributed multi-robot experiments on the Robotarium.")
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("list", help="list the experiments")
    run = commands.add_parser("run", help="run an experiment and print its metrics (headless unless --show)")
    run.add_argument("experiment", choices=sorted(EXPERIMENTS))
    run.add_argument("-n", type=int, default=None, help="number of robots (default: the thesis's)")
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--backend", choices=("auto", "robotarium", "fast"), default="auto")
    run.add_argument("--steps", type=int, default=None, help="iteration cap (default: what the experiment needs)")
    run.add_argument("--json", metavar="PATH", help="also write the metrics as JSON")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument("--video", metavar="PATH", help="record the run to a video: .gif (Pillow) or .mp4 (H.264)")
    run.add_argument("--show", action="store_true", help="show the run in a live window")
    run.add_argument(
        "--every",
        metavar="K",
        type=_positive_int,
        default=1,
        help="draw one step in K into the video/window (default: 1, every step)",
    )
    bench = commands.add_parser(
        "bench", help="run the benchmarks of the repository's benches/ (needs a source checkout)"
    )
    bench.add_argument("--full", action="store_true", help="all kernel sizes (minutes) instead of --quick")
    return parser


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {value}")
    return value


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
        print(
            f"dream: error: no benchmarks at {benches} (missing {', '.join(missing)}); `dream bench` runs the "
            "benchmarks of a source checkout: run it from the repository's top folder",
            file=sys.stderr,
        )
        return 2
    for script, flags in scripts:
        print(f"$ python {script.name} {' '.join(flags)}".rstrip(), flush=True)
        done = subprocess.run([sys.executable, script.name, *flags], cwd=benches, check=False)
        if done.returncode != 0:
            print(f"dream: error: {script.name} failed with exit code {done.returncode}", file=sys.stderr)
            return done.returncode
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "list":
        for name, module in sorted(EXPERIMENTS.items()):
            print(f"{name:<20} {(module.__doc__ or '').strip().splitlines()[0]}")
        return 0
    if args.command == "bench":
        return _bench(args.full)
    experiment = EXPERIMENTS[args.experiment]
    options = {"seed": args.seed, "backend": args.backend, "steps": args.steps}
    if args.n is not None:
        options["n"] = args.n
    recorder = None
    if args.video is not None or args.show:
        from dream.viz import Recorder  # matplotlib only when drawing

        try:  # a bad video path fails here, before the run
            recorder = Recorder(video=args.video, show=args.show, every=args.every)
        except (ValueError, OSError) as err:
            print(f"dream: error: {err}", file=sys.stderr)
            return 2
        options["record"] = recorder
    progress = _progress_bar(not args.no_progress and sys.stderr.isatty())
    try:
        result = experiment.run(progress=progress, **options)
    except (ValueError, IndexError) as err:
        print(f"dream: error: {err}", file=sys.stderr)
        return 2
    finally:
        if recorder is not None:
            recorder.close()  # a run that failed half-way still leaves a playable video
    if progress is not None:
        sys.stderr.write("\n")
    if recorder is not None and recorder.writer is not None:
        if recorder.writer.frames_written:
            print(f"video: {recorder.video} ({recorder.writer.frames_written} frames, one step in {args.every})")
        else:
            print(f"video: none written (no steps recorded) to {recorder.video}")
    print(result.summary())
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump(result.to_dict(), out, indent=2)
    if recorder is not None and recorder.live:
        print("close the window to exit", file=sys.stderr)
        recorder.hold()  # keep the live window on the last frame until the user closes it
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
