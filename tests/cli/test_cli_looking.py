"""`dream run --log / --log-every / --rerun / --rerun-serve` and `dream view`: what they write, and
bad input refused before the run."""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

from dream.cli import main

RUN = ["run", "hrvo-circle", "-n", "4", "--backend", "fast", "--steps", "5", "--no-progress"]


def test_run_writes_the_log_and_the_recording(tmp_path, capsys):
    pytest.importorskip("rerun", reason="Rerun recordings need rerun-sdk (the rerun extra, Python >= 3.11)")
    from rerun.chunk import RrdReader

    log, rrd = tmp_path / "run.parquet", tmp_path / "run.rrd"
    assert main([*RUN, "--log", str(log), "--log-every", "2", "--rerun", str(rrd)]) == 0
    steps = pq.read_table(log).column("step").to_numpy()
    assert np.array_equal(steps, np.repeat([0, 2, 4, 5], 4))  # 4 rows a logged step, and the last
    recorded: dict[str, int] = {}  # rows per entity, summed over chunks (Rerun splits a stream as it batches)
    for chunk in RrdReader(rrd).stream().to_chunks():
        if not chunk.is_static:
            recorded[chunk.entity_path] = recorded.get(chunk.entity_path, 0) + chunk.num_rows
    assert recorded["/robots"] == 4
    out = capsys.readouterr().out
    assert f"log: {log}" in out and f"recording: {rrd}" in out


def test_view_turns_a_log_into_a_recording(tmp_path, capsys):
    pytest.importorskip("rerun", reason="Rerun recordings need rerun-sdk (the rerun extra, Python >= 3.11)")
    log, rrd = tmp_path / "run.parquet", tmp_path / "view.rrd"
    assert main([*RUN, "--log", str(log)]) == 0
    assert main(["view", str(log), "--rerun", str(rrd)]) == 0
    assert f"6 steps, recorded in {rrd}" in capsys.readouterr().out
    assert rrd.stat().st_size > 0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--log-every", "3"], "--log-every sets how often --log and --rerun look: give one of them"),
        (["--log", "{tmp}"], "--log {tmp}: is a folder"),
        (["--rerun", "{tmp}/run.mp4"], "--rerun {tmp}/run.mp4: give a file name ending in .rrd"),
        (["--log", "{tmp}/same", "--json", "{tmp}/same"], "--json and --log name the same file"),
    ],
)
def test_run_refuses_bad_looking_options_in_one_line(tmp_path, capsys, extra, message):
    argv = [*RUN, *(part.format(tmp=tmp_path) for part in extra)]
    assert main(argv) == 2
    assert message.format(tmp=tmp_path) in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_rerun_and_rerun_serve_exclude_each_other(capsys):
    with pytest.raises(SystemExit) as exit:
        main([*RUN, "--rerun", "--rerun-serve"])
    assert exit.value.code == 2 and "not allowed with argument" in capsys.readouterr().err


def test_view_refuses_what_is_not_a_log(tmp_path, capsys):
    pytest.importorskip("rerun", reason="Rerun recordings need rerun-sdk (the rerun extra, Python >= 3.11)")
    missing = tmp_path / "missing.parquet"
    assert main(["view", str(missing), "--rerun", str(tmp_path / "v.rrd")]) == 2
    assert str(missing) in capsys.readouterr().err
    assert not (tmp_path / "v.rrd").exists()
