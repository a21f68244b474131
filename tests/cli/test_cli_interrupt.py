"""Ctrl-C or SIGTERM during `dream run` loses nothing: metrics so far, a playable video, one line."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import imageio_ffmpeg
import pytest
from PIL import Image

import dream


def _wait_for_frames(path, process, timeout=120.0):
    """Until ffmpeg has written part of the video: the run is stepping."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and process.poll() is None:
        if path.exists() and path.stat().st_size > 0:
            return
        time.sleep(0.1)
    raise AssertionError("the run wrote no video frames in time")


def _plays(video):
    decoded = subprocess.run(
        [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(video), "-f", "null", "-"],
        capture_output=True,
        text=True,
        check=False,
    )
    return decoded.returncode == 0 and decoded.stderr == ""


@pytest.mark.parametrize(
    ("sent", "gap", "code"),
    [
        ((signal.SIGINT,), 0.0, 130),
        ((signal.SIGTERM,), 0.0, 143),
        ((signal.SIGINT, signal.SIGINT), 0.01, 130),
        ((signal.SIGINT, signal.SIGINT), 0.05, 130),
    ],
    ids=["ctrl-c", "sigterm", "ctrl-c-twice-10ms-apart", "ctrl-c-twice-50ms-apart"],
)
def test_interrupted_run_keeps_metrics_and_video(tmp_path, sent, gap, code):
    out, video = tmp_path / "out.json", tmp_path / "out.mp4"
    argv = [sys.executable, "-m", "dream.cli", "run", "hrvo-circle", "-n", "30", "--backend", "fast"]
    argv += ["--steps", "100000", "--json", str(out), "--video", str(video)]
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_frames(video, process)
        for i, signum in enumerate(sent):  # a second Ctrl-C lets the video close and the JSON be written
            time.sleep(gap if i else 0.0)
            process.send_signal(signum)
        _, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == code
    assert err.count("\n") == 1 and err.startswith("dream: interrupted after") and "Traceback" not in err
    metrics = json.loads(out.read_text())
    assert metrics["interrupted"] is True and not metrics["success"] and 0 < metrics["steps"] < 100000
    assert _plays(video)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json", "out.mp4"]  # no temporary file left


HANG = """\
from dream import Experiment


class Hang(Experiment):
    name = "hang"
    default_n = 3

    def build(self, n):
        pass

    def before_step(self, step):
        if step == 10:
            print("hanging", flush=True)
            while True:
                pass
"""


def test_a_second_ctrl_c_cuts_a_hanging_step_and_keeps_what_the_whole_steps_made(tmp_path):
    source, out, checkpoint, video = (tmp_path / name for name in ("hang.py", "out.json", "run.ckpt", "x.gif"))
    source.write_text(HANG)
    argv = [sys.executable, "-m", "dream.cli", "run", str(source), "--backend", "fast", "--json", str(out)]
    argv += ["--checkpoint", str(checkpoint), "--video", str(video)]
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert process.stdout.readline() == "hanging\n"
        process.send_signal(signal.SIGINT)  # asks the run to stop after a step that never ends...
        time.sleep(0.2)
        process.send_signal(signal.SIGINT)  # ...so the second cuts it short
        _, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130 and err.count("\n") == 1 and err.startswith("dream: interrupted after 10 steps")
    metrics = json.loads(out.read_text())
    assert metrics["interrupted"] is True and metrics["steps"] == 10
    assert Image.open(video).n_frames == 10
    assert dream.experiments.checkpoint.load(checkpoint).step == 0  # the half step saved nothing; the first save stands
