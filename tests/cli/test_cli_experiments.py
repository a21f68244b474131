"""`dream run FILE.py`, `--param`, `dream list NAME`, `dream new`, and bad input refused up front."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from PIL import Image

from dream.cli import main

ROOT = Path(__file__).resolve().parents[2]
RENDEZVOUS = str(ROOT / "examples" / "rendezvous.py")


def test_rendezvous_example_succeeds_with_20_robots(tmp_path, capsys):
    out = tmp_path / "out.json"
    assert main(["run", RENDEZVOUS, "-n", "20", "--json", str(out), "--check"]) == 0
    metrics = json.loads(out.read_text())
    assert metrics["experiment"] == "rendezvous" and metrics["n"] == 20
    assert metrics["success"] and metrics["collisions"] == 0
    assert metrics["measures"]["spread"] <= metrics["params"]["radius"]  # the met radius, 0.85 m
    assert re.search(r"^success\s+yes$", capsys.readouterr().out, re.M)


def test_user_file_runs_with_params_json_and_video(tmp_path, capsys):
    out, video = tmp_path / "m.json", tmp_path / "x.gif"
    argv = ["run", RENDEZVOUS, "-n", "6", "--steps", "30", "--backend", "fast", "--param", "gain=0.8"]
    argv += ["--param", "radio_range=0.7", "--json", str(out), "--video", str(video), "--every", "10"]
    assert main(argv) == 0
    metrics = json.loads(out.read_text())
    assert metrics["params"]["gain"] == 0.8 and metrics["params"]["radio_range"] == 0.7
    assert metrics["steps"] == 30 and metrics["backend"] == "fast"
    assert Image.open(video).n_frames == 3
    assert "video:" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("x = 1\n", "defines no Experiment subclass"),
        ("from dream import Experiment\nclass A(Experiment): pass\nclass B(Experiment): pass\n", "2 Experiment"),
        ("def broken(:\n", "line 1: syntax error"),
    ],
)
def test_bad_files_give_one_line(tmp_path, capsys, text, message):
    path = tmp_path / "bad.py"
    path.write_text(text)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--param", "speed=1"], "has no parameter 'speed' (its parameters: radius, radio_range, gain, safety)"),
        (["--param", "gain=fast"], "parameter 'gain' of rendezvous expects a number, got 'fast'"),
        (["--param", "gain"], "--param takes NAME=VALUE, got 'gain'"),
    ],
)
def test_bad_params_are_named(capsys, argv, message):
    assert main(["run", RENDEZVOUS, *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["-n", "0"], "argument -n: expected an integer >= 1, got 0"),
        (["--steps", "-3"], "argument --steps: expected an integer >= 1, got -3"),
        (["--seed", "-1"], "argument --seed: expected an integer >= 0, got -1"),
    ],
)
def test_bad_values_name_the_option(capsys, argv, message):
    with pytest.raises(SystemExit) as exited:
        main(["run", "hrvo-circle", *argv])
    assert exited.value.code == 2
    assert message in capsys.readouterr().err


def test_too_many_robots_for_the_robotarium_says_the_way_out(capsys):
    assert main(["run", "hrvo-circle", "-n", "100", "--backend", "robotarium"]) == 2
    assert "at most 50 robots; use --backend fast" in capsys.readouterr().err


def test_unwritable_json_is_refused_before_the_run(tmp_path, capsys):
    missing = tmp_path / "no" / "out.json"
    assert main(["run", "hrvo-circle", "--json", str(missing)]) == 2
    err = capsys.readouterr().err
    assert "does not exist" in err and "--json" in err
    assert not missing.parent.exists()


def test_list_shows_parameters_and_success(capsys):
    assert main(["list", "line-consensus"]) == 0
    out = capsys.readouterr().out
    assert "--param spacing=0.3" in out and "(float, finite and > 0)" in out
    assert "success:" in out and "robots by default: 6" in out


def test_new_writes_a_starter_that_succeeds(tmp_path, capsys):
    path = tmp_path / "spread.py"
    assert main(["new", "spread", "-o", str(path)]) == 0
    assert main(["run", str(path), "--backend", "fast", "--check"]) == 0
    assert re.search(r"^experiment\s+spread$", capsys.readouterr().out, re.M)
    assert main(["new", "spread", "-o", str(path)]) == 2  # never overwrites
    assert "exists already" in capsys.readouterr().err


def test_check_exits_1_when_the_run_fails(capsys):
    assert main(["run", "line-consensus", "--steps", "5", "--backend", "fast", "--check"]) == 1
    assert re.search(r"^success\s+no$", capsys.readouterr().out, re.M)


def test_swarm_mode_runs_from_the_command_line(tmp_path, capsys):
    out = tmp_path / "swarm.json"
    argv = ["run", "hrvo-circle", "-n", "2000", "--swarm", "--backend", "fast", "--steps", "100"]
    assert main([*argv, "--json", str(out), "--no-progress"]) == 0
    metrics = json.loads(out.read_text())
    assert metrics["swarm"] and metrics["experiment"] == "hrvo-circle" and metrics["backend"] == "fast"
    assert metrics["n"] == 2000 and metrics["steps"] == 100 and metrics["collisions"] == 0
    assert re.search(r"^mode\s+swarm", capsys.readouterr().out, re.M)


def test_list_says_which_experiments_have_a_swarm_mode(tmp_path, capsys):
    assert main(["list", "hrvo-circle"]) == 0
    assert "swarm mode: yes (dream run hrvo-circle --swarm)" in capsys.readouterr().out
    assert main(["list", "line-consensus"]) == 0
    assert "swarm mode: yes (dream run line-consensus --swarm)" in capsys.readouterr().out
    assert main(["list", "affine-formation"]) == 0
    assert "swarm mode: yes (dream run affine-formation --swarm)" in capsys.readouterr().out
    assert main(["list", RENDEZVOUS]) == 0  # a swarm robot runs both ways
    assert f"swarm mode: yes (dream run {RENDEZVOUS} --swarm)" in capsys.readouterr().out
    starter = tmp_path / "spread.py"
    assert main(["new", "spread", "-o", str(starter)]) == 0
    assert main(["list", str(starter)]) == 0
    assert "swarm mode: no" in capsys.readouterr().out


def test_swarm_mode_of_an_experiment_without_one_is_refused(tmp_path, capsys):
    starter = tmp_path / "spread.py"
    assert main(["new", "spread", "-o", str(starter)]) == 0
    capsys.readouterr()
    assert main(["run", str(starter), "--swarm", "--steps", "5"]) == 2
    err = capsys.readouterr().err
    assert "spread has no swarm mode" in err and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize("value", ["inf", "0", "-1"])
def test_a_parameter_out_of_its_range_is_refused_in_one_line_before_any_step(capsys, value):
    assert main(["run", "line-consensus", "--param", f"spacing={value}"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "parameter 'spacing' of line-consensus must be finite and > 0, got" in captured.err


# -- messages that say what is wrong, in the user's terms (issue 30, item 10) -------------------
SHORT = ["run", "hrvo-circle", "-n", "4", "--steps", "3", "--backend", "fast"]


def _one_line(capsys) -> str:
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and "Traceback" not in captured.err
    return captured.err


def test_a_line_of_one_robot_is_refused_in_the_experiments_terms(capsys):
    assert main(["run", "line-consensus", "-n", "1"]) == 2
    assert "line-consensus needs at least 2 robots to form a line" in _one_line(capsys)


def test_resume_blames_the_json_path_not_the_checkpoint(tmp_path, capsys):
    if not Path("/proc/self").is_dir():
        pytest.skip("needs Linux's /proc, where no file can be made")
    checkpoint = tmp_path / "run.ckpt"
    assert main([*SHORT, "--checkpoint", str(checkpoint)]) == 0
    capsys.readouterr()
    assert main(["resume", str(checkpoint), "--steps", "6", "--json", "/proc/x.json"]) == 2
    err = _one_line(capsys)
    assert err.startswith("dream: error: --json /proc/x.json: cannot write") and "run.ckpt" not in err


@pytest.mark.parametrize(
    ("outputs", "message"),
    [
        (["--json", "X", "--checkpoint", "X"], "--json and --checkpoint name the same file X"),
        (["--json", "out.gif", "--video", "./out.gif"], "--json and --video name the same file out.gif"),
        (["--video", "X.gif", "--checkpoint", "X.gif"], "--video and --checkpoint name the same file X.gif"),
    ],
)
def test_two_outputs_on_one_file_are_refused(tmp_path, monkeypatch, capsys, outputs, message):
    monkeypatch.chdir(tmp_path)
    assert main([*SHORT, *outputs]) == 2
    assert message in _one_line(capsys)
    assert not list(tmp_path.iterdir())


def test_resume_refuses_json_on_its_own_checkpoint(tmp_path, capsys):
    checkpoint = tmp_path / "run.ckpt"
    assert main([*SHORT, "--checkpoint", str(checkpoint)]) == 0
    capsys.readouterr()
    saved = checkpoint.read_bytes()
    assert main(["resume", str(checkpoint), "--json", str(checkpoint)]) == 2
    assert "--json and the checkpoint name the same file" in _one_line(capsys)
    assert checkpoint.read_bytes() == saved


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (
            ["--fault", "crash=0.1@300", "--fault", "crash=0.2"],
            "--fault crash given twice ('crash=0.1@300', 'crash=0.2')",
        ),
        (["--realtime"], "--realtime paces what is drawn: give --show or --video too"),
        (["--hold", "--video", "x.gif"], "--hold keeps the live window open: give --show too"),
    ],
)
def test_options_that_would_be_silently_lost_are_refused(tmp_path, monkeypatch, capsys, options, message):
    monkeypatch.chdir(tmp_path)  # where a DREAM that took them would write its video
    assert main([*SHORT, *options]) == 2
    assert message in _one_line(capsys)


def test_new_writes_a_name_that_holds_a_placeholder_as_given(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["new", "NAME_x"]) == 0
    assert capsys.readouterr().out == "wrote NAME_x.py: run it with `dream run NAME_x.py`\n"
    text = (tmp_path / "NAME_x.py").read_text()
    assert "dream run NAME_x.py\n" in text and 'name = "NAME_x"' in text and "NAME_x_x" not in text


def test_a_json_that_cannot_be_written_after_the_run_is_one_line(tmp_path, monkeypatch, capsys):
    def full(path, data):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("dream.cli._drive._write_json", full)
    assert main([*SHORT, "--json", str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err
    assert err == f"dream: error: --json {tmp_path / 'm.json'}: not written: No space left on device\n"
