"""What ``dream run`` and ``dream resume`` share: the options of what a run prints, records and
saves, their checks before the run, and the run itself with its recorder, progress bar and report."""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
from collections.abc import Callable
from typing import Any

from dream._files import replaced
from dream.cli._usage import UsageError, whole, writable
from dream.experiments import ExperimentResult
from dream.experiments.checkpoint import CHECKPOINT_EVERY
from dream.experiments.runner import outputs_kept


def add_options(sub: argparse.ArgumentParser) -> None:
    """The options of what a run prints, records and saves."""
    sub.add_argument("--json", metavar="PATH", help="also write the metrics as JSON")
    sub.add_argument("--no-progress", action="store_true", help="no progress bar")
    sub.add_argument("--video", metavar="PATH", help="record the run to a video: .gif (Pillow) or .mp4 (H.264)")
    sub.add_argument("--show", action="store_true", help="show the run in a live window")
    sub.add_argument("--every", metavar="K", type=whole(1), default=1, help="draw one step in K into the video/window")
    sub.add_argument("--size", metavar="WxH", type=_size, default=(1280, 800), help="image size (default: 1280x800)")
    sub.add_argument("--focus", metavar="ID", type=whole(0), help="draw this robot's ranges and who it hears")
    sub.add_argument("--realtime", action="store_true", help="pace the run to wall time (30 steps/s)")
    sub.add_argument("--hold", action="store_true", help="keep the live window open at the end until closed")
    sub.add_argument("--check", action="store_true", help="exit with 1 when the run fails its success test")
    sub.add_argument(
        "--checkpoint-every", metavar="K", type=whole(1), default=None,
        help=f"steps between two saves of the checkpoint (default: {CHECKPOINT_EVERY:,}; resume: the run's own)",
    )  # fmt: skip


def _size(text: str) -> tuple[int, int]:
    from dream.viz import parse_size  # no matplotlib import

    try:
        return parse_size(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def check_outputs(args: argparse.Namespace, saved: tuple[str | None, str]) -> None:
    """Refuse, before the run, drawing options that draw nothing, a ``--json`` path that cannot be
    written (the video's is the recorder's to check) and two outputs on one file (``--json``,
    ``--video`` and ``saved``, the checkpoint the run writes: ``(path, what)``)."""
    if args.realtime and not (args.show or args.video):
        raise UsageError("--realtime paces what is drawn: give --show or --video too")
    if args.hold and not args.show:
        raise UsageError("--hold keeps the live window open: give --show too")
    if args.json:
        writable(args.json, "--json")
    outputs = [(path, option) for path, option in ((args.json, "--json"), (args.video, "--video"), saved) if path]
    for i, (path, option) in enumerate(outputs):
        for other, other_option in outputs[i + 1 :]:
            if os.path.realpath(path) == os.path.realpath(other):
                raise UsageError(f"{option} and {other_option} name the same file {path}: give each its own")


def drive(args: argparse.Namespace, n: int | None, call: Callable[[Any, Any], ExperimentResult]) -> int:
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


def _write_json(path: str, data: dict[str, Any]) -> None:
    with replaced(path) as out:
        json.dump(data, out, indent=2)
