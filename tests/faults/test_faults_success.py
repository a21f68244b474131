"""What success means under faults: the correct robots do the job."""

from __future__ import annotations

import json

import numpy as np
import pytest

import dream
from dream import rules
from dream.cli import main
from dream.experiments.line_consensus import line_errors


def test_wmsr_drops_the_extremes_on_each_side_of_the_own_value():
    values = [5.0, -9.0, 0.2, 0.1, 1.0, -0.5]
    assert sorted(rules.wmsr_keep(values, 0.0, 1)) == [-0.5, 0.1, 0.2, 1.0]
    assert sorted(rules.wmsr_keep(values, 0.0, 0)) == sorted(values)
    assert list(rules.wmsr_keep([3.0], 0.0, 2)) == []


def test_line_errors_of_the_correct_robots_keep_the_gaps_of_the_missing():
    x = np.array([0.9, 0.6, 5.0, 0.0])  # robot 2 has crashed far away
    poses = np.vstack((x, np.zeros(4), np.zeros(4)))
    assert line_errors(poses, 0.3, np.array([True, True, False, True])) == pytest.approx((0.0, 0.0))
    assert line_errors(poses, 0.3)[1] > 4


@pytest.mark.parametrize("seed", [0, 1])
def test_line_consensus_converges_under_loss_and_latency(tmp_path, seed):
    out = tmp_path / "out.json"
    argv = ["run", "line-consensus", "-n", "10", "--backend", "fast", "--seed", str(seed), "--json", str(out)]
    assert main([*argv, "--fault", "loss=0.3", "--fault", "latency=5", "--check", "--no-progress"]) == 0
    metrics = json.loads(out.read_text())
    assert metrics["success"] and metrics["collisions"] == 0
    assert metrics["faults"]["settings"] == {"loss": 0.3, "latency": 5}


def test_coverage_survivors_cover_without_touching_the_crashed():
    result = dream.run("voronoi-coverage", n=30, backend="fast", seed=0, faults=dream.Faults(crash=0.2, crash_at=200))
    crashed = [event["robot"] for event in result.faults["events"] if event["kind"] == "crash"]
    assert len(crashed) == 6 and {event["step"] for event in result.faults["events"]} == {200}
    assert result.success and result.collisions == 0 and result.measures["static_contacts"] == 0
