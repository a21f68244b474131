"""Output paths (`--json`, `--checkpoint`, `sweep --out`): DREAM writes only regular files and new
paths, refuses anything else in one line before any run, and gives new files the umask's mode."""

from __future__ import annotations

import json
import os
import re
import stat
from pathlib import Path

import pytest

from dream._files import replaced
from dream.cli import main

RUN = ["run", "hrvo-circle", "-n", "4", "--steps", "5", "--backend", "fast", "--no-progress"]


def _symlink(path: Path) -> None:
    (path.parent / "target.txt").write_text("keep me")
    path.symlink_to(path.parent / "target.txt")


def _device(path: Path) -> None:
    try:  # the null device's numbers, in tmp_path: the system's /dev/null is never at risk
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a device file needs root")


#: How to make each thing that is not a regular file, and how the refusal names it.
SPECIAL = {
    "symlink": (_symlink, "is a symlink"),
    "fifo": (os.mkfifo, "is a FIFO (named pipe)"),
    "device": (_device, "is a character device"),
    "folder": (Path.mkdir, "is a folder"),
}


@pytest.fixture(params=sorted(SPECIAL))
def special(request, tmp_path) -> tuple[Path, str, int]:
    """A path in tmp_path holding something that is not a regular file, what it is, and its lstat mode."""
    make, said = SPECIAL[request.param]
    path = tmp_path / "out"
    make(path)
    return path, said, os.lstat(path).st_mode


def _untouched(path: Path, mode: int) -> None:
    assert os.lstat(path).st_mode == mode
    if path.is_symlink():
        assert path.read_text() == "keep me"
    assert not [p.name for p in path.parent.iterdir() if p.name.endswith(".part")]


@pytest.mark.parametrize(
    "argv",
    [
        [*RUN, "--json"],
        [*RUN, "--checkpoint"],
        ["sweep", "hrvo-circle", "--seeds", "0", "-n", "4", "--steps", "5", "--workers", "1", "--out"],
    ],
    ids=["json", "checkpoint", "sweep-out"],
)
def test_outputs_that_are_not_regular_files_are_refused_before_any_run(special, capsys, argv):
    path, said, mode = special
    assert main([*argv, str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # no run, no summary
    assert captured.err.count("\n") == 1 and str(path) in captured.err and said in captured.err
    _untouched(path, mode)


def test_resume_refuses_a_json_path_that_is_not_a_regular_file(special, tmp_path, capsys):
    path, said, mode = special
    checkpoint = tmp_path / "run.ckpt"
    assert main([*RUN, "--checkpoint", str(checkpoint)]) == 0
    capsys.readouterr()
    assert main(["resume", str(checkpoint), "--steps", "9", "--json", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and said in captured.err
    _untouched(path, mode)


def test_a_write_refuses_what_appeared_at_the_path_after_the_check(special):
    path, said, mode = special
    refusal = re.escape(f"{path}: {said}; DREAM writes only to regular files")
    with pytest.raises(OSError, match=refusal), replaced(path) as out:
        out.write("never")
    _untouched(path, mode)


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002], ids=["022", "077", "002"])
def test_new_files_get_the_umasks_mode_and_replaced_files_keep_theirs(tmp_path, capsys, umask):
    previous = os.umask(umask)
    try:
        metrics, checkpoint = tmp_path / "m.json", tmp_path / "run.ckpt"
        assert main([*RUN, "--json", str(metrics), "--checkpoint", str(checkpoint)]) == 0
        for path in (metrics, checkpoint):
            assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask, path
        metrics.chmod(0o640)
        assert main([*RUN, "--json", str(metrics)]) == 0
        assert stat.S_IMODE(metrics.stat().st_mode) == 0o640
    finally:
        os.umask(previous)


def test_a_json_name_of_the_longest_legal_length_is_written(tmp_path, capsys):
    metrics = tmp_path / ("m" * 250 + ".json")  # 255 bytes: the longest name most file systems take
    assert main([*RUN, "--json", str(metrics)]) == 0
    assert json.loads(metrics.read_text())["steps"] == 5
    assert [p.name for p in tmp_path.iterdir()] == [metrics.name]  # no temporary file left


SWEEP = ["sweep", "hrvo-circle", "--seeds", "0", "-n", "4", "--steps", "5", "--workers", "1", "--no-progress"]


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (RUN, "--json"),
        (RUN, "--checkpoint"),
        (RUN, "--video"),
        (SWEEP, "--out"),
        ([*SWEEP, "--out", "s.csv"], "--plot"),
    ],
    ids=["json", "checkpoint", "video", "sweep-out", "sweep-plot"],
)
def test_every_output_path_is_checked_before_the_first_step(tmp_path, monkeypatch, capsys, argv, option):
    monkeypatch.chdir(tmp_path)
    suffix = {"--video": ".mp4", "--plot": ".png"}.get(option, ".out")
    too_long = "x" * 256 + suffix
    assert main([*argv, option, too_long]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # no run, no summary
    assert captured.err.count("\n") == 1 and "longer than the 255 bytes the file system allows" in captured.err
    assert not list(tmp_path.iterdir())


def test_a_folder_where_no_file_can_be_made_is_refused_before_the_run(capsys):
    if not os.path.isdir("/proc/self"):
        pytest.skip("needs Linux's /proc, where no file can be made")
    assert main([*RUN, "--json", "/proc/x.json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "--json /proc/x.json: cannot write in the folder /proc" in captured.err


def test_a_plot_that_names_no_image_format_is_refused_before_the_sweep(tmp_path, capsys):
    assert main([*SWEEP, "--out", str(tmp_path / "s.csv"), "--plot", str(tmp_path / "s.txt")]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "suffix '.txt'; give an image file, such as .png" in captured.err
    assert not list(tmp_path.iterdir())
