"""`dream run ... --video` on real experiments: one frame per rendered step."""

from __future__ import annotations

import json

import imageio_ffmpeg
import pytest
from PIL import Image

from dream.cli import main


@pytest.mark.parametrize(
    ("name", "suffix", "every", "frames"),
    [
        ("line-consensus", ".gif", 1, 30),
        ("voronoi-coverage", ".mp4", 3, 10),
        ("affine-formation", ".gif", 5, 6),
    ],
)
def test_cli_video_has_one_frame_per_rendered_step(tmp_path, capsys, name, suffix, every, frames):
    video, metrics = tmp_path / f"run{suffix}", tmp_path / "metrics.json"
    args = [
        "run",
        name,
        "--steps",
        "30",
        "--backend",
        "fast",
        "--video",
        str(video),
        "--every",
        str(every),
        "--json",
        str(metrics),
    ]
    assert main(args) == 0
    assert json.loads(metrics.read_text())["steps"] == 30
    if suffix == ".gif":
        assert Image.open(video).n_frames == frames
    else:
        assert imageio_ffmpeg.count_frames_and_secs(str(video))[0] == frames
    assert str(video) in capsys.readouterr().out
