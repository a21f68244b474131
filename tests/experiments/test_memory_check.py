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
    with pytest.raises(
        ValueError, match=r"n=1,000,000 robots need about 2\.1 GiB of memory .* this machine's 1\.0 GiB"
    ):
        dream.run("hrvo-circle", n=10**6, swarm=True, backend="fast")


def test_cli_refuses_it_in_one_line(monkeypatch, capsys):
    monkeypatch.setattr(memory, "machine_memory", lambda: 2**30)
    assert main(["run", "hrvo-circle", "-n", "1000000000", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "1.9 TiB" in err and "1.0 GiB" in err and "run at most 421,888" in err
