"""Ctrl-C or SIGTERM during `dream run` loses nothing: metrics so far, a playable video, one line."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import imageio_ffmpeg
import pytest


def _wait_for_frames(path, process, timeout=120.0):
    """Until ffmpeg has written part of the video: the run is stepping."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and process.poll() is None:
        if path.exists() and path.stat().st_size > 0:
            return
        time.sleep(0.1)
    raise AssertionError("the run wrote no video frames in time")


@pytest.mark.parametrize(("sent", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupted_run_keeps_metrics_and_video(tmp_path, sent, code):
    out, video = tmp_path / "out.json", tmp_path / "out.mp4"
    argv = [sys.executable, "-m", "dream.cli", "run", "hrvo-circle", "-n", "30", "--backend", "fast"]
    argv += ["--steps", "100000", "--json", str(out), "--video", str(video)]
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_frames(video, process)
        process.send_signal(sent)
        _, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == code
    assert err.count("\n") == 1 and err.startswith("dream: interrupted after") and "Traceback" not in err
    metrics = json.loads(out.read_text())
    assert metrics["interrupted"] is True and not metrics["success"] and 0 < metrics["steps"] < 100000
    decoded = subprocess.run(
        [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(video), "-f", "null", "-"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert decoded.returncode == 0 and decoded.stderr == ""
