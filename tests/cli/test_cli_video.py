"""`dream run --video/--show/--every` and `dream bench`, with a stand-in experiment that emits frames."""

from __future__ import annotations

import json
from typing import ClassVar

import pytest
from PIL import Image

from dream.cli import _parser, main
from dream.cli import bench as cli  # `dream bench` and where it finds benches/
from dream.experiments import EXPERIMENTS, Experiment


class FakeExperiment(Experiment):
    """A stand-in experiment: robots that never move, ``steps`` default 10; runs are logged."""

    name = "hrvo-circle"
    default_n = 3
    calls: ClassVar[list[dict]] = []

    def build(self, n):
        self.calls.append({"n": n, "backend": self.sim_backend})

    def check(self, n, backend):
        self.sim_backend = backend

    def steps(self, n):
        return 10

    def measures(self):
        return {"fake": 1.0}


@pytest.fixture
def fake(monkeypatch):
    monkeypatch.setattr(FakeExperiment, "calls", [])
    monkeypatch.setitem(EXPERIMENTS, "hrvo-circle", FakeExperiment)
    return FakeExperiment


def test_cli_parses_video_show_every():
    args = _parser().parse_args(["run", "hrvo-circle", "--video", "out.mp4", "--show", "--every", "3"])
    assert (args.video, args.show, args.every) == ("out.mp4", True, 3)
    args = _parser().parse_args(["run", "hrvo-circle"])
    assert (args.video, args.show, args.every) == (None, False, 1)


@pytest.mark.parametrize("every", ["0", "-2", "x"])
def test_cli_rejects_bad_every(capsys, every):
    with pytest.raises(SystemExit) as exited:
        main(["run", "hrvo-circle", "--video", "out.gif", "--every", every])
    assert exited.value.code == 2
    assert "--every" in capsys.readouterr().err


def test_cli_rejects_unknown_video_suffix_before_running(tmp_path, capsys, fake):
    path = tmp_path / "out.avi"
    assert main(["run", "hrvo-circle", "--video", str(path)]) == 2
    err = capsys.readouterr().err
    assert "'.avi'" in err and ".gif, .mp4" in err and "Traceback" not in err
    assert fake.calls == [] and not path.exists()


def test_cli_rejects_video_in_missing_directory(tmp_path, capsys, fake):
    assert main(["run", "hrvo-circle", "--video", str(tmp_path / "no" / "out.gif")]) == 2
    assert "does not exist" in capsys.readouterr().err and fake.calls == []


def test_cli_run_records_every_kth_step_to_gif(tmp_path, capsys, fake):
    path, metrics = tmp_path / "out.gif", tmp_path / "metrics.json"
    argv = [
        "run",
        "hrvo-circle",
        "-n",
        "3",
        "--steps",
        "10",
        "--video",
        str(path),
        "--every",
        "4",
        "--json",
        str(metrics),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert f"video: {path} (3 frames, one step in 4)" in out  # steps 1, 5, 9
    assert "collisions" in out and "fake" in out  # the metrics table as before
    assert Image.open(path).n_frames == 3
    assert json.loads(metrics.read_text())["steps"] == 10


def test_cli_run_without_drawing_writes_no_video(fake, capsys):
    assert main(["run", "hrvo-circle", "--steps", "5"]) == 0
    assert len(fake.calls) == 1
    assert "video:" not in capsys.readouterr().out


def test_cli_help_lists_bench(capsys):
    with pytest.raises(SystemExit) as exited:
        main(["--help"])
    assert exited.value.code == 0
    assert "bench" in capsys.readouterr().out


def test_cli_bench_without_repository_fails_clearly(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(cli, "benches_dir", lambda: tmp_path / "benches")
    assert main(["bench"]) == 2
    err = capsys.readouterr().err
    assert "no benchmarks at" in err and "bench_kernels.py" in err


def test_cli_bench_runs_both_scripts_quick(tmp_path, monkeypatch, capfd):
    benches = tmp_path / "benches"
    benches.mkdir()
    for name in ("bench_kernels.py", "bench_experiments.py"):
        (benches / name).write_text(f"import sys\nprint('ran {name}', sys.argv[1:])\n")
    monkeypatch.setattr(cli, "benches_dir", lambda: benches)
    assert main(["bench"]) == 0
    out = capfd.readouterr().out
    assert "ran bench_kernels.py ['--quick']" in out and "ran bench_experiments.py []" in out
    (benches / "bench_experiments.py").write_text("raise SystemExit(3)\n")
    assert main(["bench"]) == 3


def test_cli_bench_finds_the_repository_benches():
    assert (cli.benches_dir() / "bench_kernels.py").is_file()
