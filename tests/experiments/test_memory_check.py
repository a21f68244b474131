"""A robot count whose arrays cannot fit is refused before anything is allocated."""

from __future__ import annotations

import pytest

import dream
from dream import memory
from dream.cli import main
from dream.experiments import hrvo_circle


def test_estimate_is_linear_in_the_robots():
    assert memory.estimate(0) == memory.FIXED
    assert memory.estimate(2000) - memory.estimate(1000) == 1000 * memory.PER_ROBOT


def test_run_refuses_a_count_beyond_the_machine_before_sizing_anything(monkeypatch):
    monkeypatch.setattr(memory, "machine_memory", lambda: 2**30)  # a 1 GiB machine
    monkeypatch.setattr(hrvo_circle, "circle_layout", lambda *a: pytest.fail("sized the run"))
    n = (2**30 - memory.FIXED) // memory.PER_ROBOT + 1
    with pytest.raises(ValueError, match=rf"n={n:,} robots need about 1\.0 GiB of memory .* this machine's 1\.0 GiB"):
        dream.run("hrvo-circle", n=n, swarm=True, backend="fast")


def test_cli_refuses_it_in_one_line(monkeypatch, capsys):
    monkeypatch.setattr(memory, "machine_memory", lambda: 2**30)
    assert main(["run", "hrvo-circle", "-n", "1000000000", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    most = (2**30 - memory.FIXED) // memory.PER_ROBOT
    assert "\n" not in err and f"run at most {most:,}" in err
    assert f"need about {memory._size(memory.estimate(10**9))}" in err and "this machine's 1.0 GiB" in err


def test_sizes_read_in_binary_units():
    sizes = (512, 1536, 2**30, int(15.7 * 2**40))
    assert [memory._size(b) for b in sizes] == ["512.0 B", "1.5 KiB", "1.0 GiB", "15.7 TiB"]
