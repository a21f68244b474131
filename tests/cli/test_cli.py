"""The `dream` command and the example scripts, run as a user would."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from dream.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_cli_list_names_the_experiments(capsys):
    assert main(["list"]) == 0
    listed = capsys.readouterr().out
    assert all(name in listed for name in ("hrvo-circle", "line-consensus", "voronoi-coverage", "affine-formation"))
    assert re.search(r"^line-consensus\s+swarm\s", listed, re.M)
    assert re.search(r"^affine-formation\s+swarm\s", listed, re.M)


def test_cli_run_prints_summary_and_writes_json(tmp_path, capsys):
    out = tmp_path / "metrics.json"
    assert main(["run", "hrvo-circle", "-n", "4", "--steps", "80", "--backend", "fast", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "collisions" in printed and "steps/s" in printed
    metrics = json.loads(out.read_text())
    assert metrics["steps"] == 80 and metrics["n"] == 4 and metrics["backend"] == "fast"
    assert metrics["collisions"] == 0


def test_cli_run_reports_bad_input_without_traceback(capsys):
    assert main(["run", "hrvo-circle", "-n", "52", "--backend", "robotarium", "--swarm", "--steps", "5"]) == 2
    err = capsys.readouterr().err
    assert "the Robotarium backend runs at most 50 robots" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "script", ["hrvo_circle.py", "line_consensus.py", "voronoi_coverage.py", "affine_formation.py"]
)
def test_example_script_runs(script):
    done = subprocess.run(
        [sys.executable, str(ROOT / "examples" / script), "--steps", "120", "--backend", "fast"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "120 iterations" in done.stdout


EXPLICIT_LOOP = ["hrvo_circle.py", "line_consensus.py", "voronoi_coverage.py", "affine_formation.py"]


def run_example(script: str, *options: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(ROOT / "examples" / script), "--backend", "fast", *options],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


@pytest.mark.parametrize("script", EXPLICIT_LOOP)
def test_example_script_succeeds_at_its_default_size(script):
    # Each example holds its own robot classes; at its default size it must reach its success measure.
    done = run_example(script)
    assert done.returncode == 0, done.stderr
    last = done.stdout.strip().splitlines()[-1]
    assert last.startswith("success: "), done.stdout
    assert " 0 collisions" in last


def test_example_script_says_failure_and_exits_0():
    done = run_example("hrvo_circle.py", "--steps", "30")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "failure: 0 circles in 30 steps, 0 collisions"


def test_example_script_writes_a_video(tmp_path):
    video = tmp_path / "x.gif"
    done = run_example("line_consensus.py", "--steps", "20", "--every", "5", "--video", str(video))
    assert done.returncode == 0, done.stderr
    assert video.is_file() and video.stat().st_size > 0


def test_example_script_refuses_a_bad_video_path(tmp_path):
    done = run_example("affine_formation.py", "--steps", "5", "--video", str(tmp_path / "missing" / "x.gif"))
    assert done.returncode == 2
    assert "does not exist" in done.stderr and "Traceback" not in done.stderr
