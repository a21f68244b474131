"""The lab's verifier runs rps 2.1's start-up phase: exported bundles hand rps 2.1 starts that the
phase reaches. What the real 2.1 does with them was recorded by ``tests/data/rps21/record.py``
(``lab_startup.json``); these tests check that a bundle exported today hands rps 2.x exactly those
starts, and what the recording shows."""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from dream import export
from dream.backends.startup import RPS2_BARRIER_SPACING, RPS2_PROJECTION, START_SPACING
from dream.experiments import EXPERIMENTS

GOLDEN = Path(__file__).parents[1] / "data" / "rps21"
LAB = json.loads((GOLDEN / "lab_startup.json").read_text())
SUCCESS = "dream: success, 0 collisions, 0 boundary, 0 actuator"

#: An rps 2.x that writes the initial conditions the bundle hands it to a file, then ends the run.
CAPTURE_RPS2 = """\
import os
import numpy as np


class Robotarium:
    def __init__(self, **kwargs):
        np.save(os.environ["STARTS_FILE"], kwargs["initial_conditions"])
        raise SystemExit(0)

    def debug(self):  # rps 2.x's report: what tells the bundle that this is 2.x
        pass
"""


def bundle_starts(tmp_path: Path, experiment: str, n: int, seed: int) -> np.ndarray:
    """The initial conditions that the exported bundle of ``experiment`` hands rps 2.x."""
    fake = tmp_path / "fake" / "rps"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("")
    (fake / "robotarium.py").write_text(CAPTURE_RPS2)
    with (
        pytest.warns(export.ExportWarning, match="start-up phase") if experiment in MOVED else contextlib.nullcontext()
    ):
        folder = export.export(experiment, tmp_path / "bundle", n=n, seed=seed)
    starts = tmp_path / "starts.npy"
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(fake.parent), "STARTS_FILE": str(starts), "DREAM_HEADLESS": "1"}
    done = subprocess.run(
        [sys.executable, str(folder / "main.py")], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return np.load(starts)


def _blocked(starts: np.ndarray) -> set[int]:
    """Robots of a pair whose points ahead (those that 2.1's barrier certificate keeps apart) are too close."""
    ahead = starts[:2] + RPS2_PROJECTION * np.vstack((np.cos(starts[2]), np.sin(starts[2])))
    gaps = np.hypot(*(ahead[:, :, None] - ahead[:, None, :])) + np.eye(starts.shape[1])
    return set(np.flatnonzero((gaps < RPS2_BARRIER_SPACING).any(axis=0)).tolist())


#: The built-ins whose own starts a bundle moves (recorded: 2.1's start-up never reaches them).
MOVED = {case["experiment"] for case in LAB if case["own_starts"] != case["bundle_starts"]}


def test_the_recording_holds_every_built_in_at_its_lab_size():
    assert {case["experiment"]: case["n"] for case in LAB} == {name: cls.default_n for name, cls in EXPERIMENTS.items()}


@pytest.mark.parametrize("case", LAB, ids=lambda case: f"{case['experiment']}-{case['n']}")
def test_an_exported_bundle_starts_where_rps21s_start_up_phase_was_recorded_arriving(case, tmp_path):
    starts = bundle_starts(tmp_path, case["experiment"], case["n"], case["seed"])
    assert_allclose(starts, case["bundle_starts"], rtol=0, atol=1e-12)
    gaps = np.hypot(*(starts[:2, :, None] - starts[:2, None, :])) + 9 * np.eye(case["n"])
    assert gaps.min() >= START_SPACING - 1e-12
    # The real 2.1, with five draws of its charger slots and detours: every robot arrived.
    for startup in case["bundle_startups"]:
        assert startup["iterations"] is not None and all(startup["at_pose"]), startup
    # And the bundle itself, run on 2.1 as the verifier runs it, passed it and then the experiment.
    assert case["bundle_exit"] == 0
    assert case["bundle_lines"][0] == "At initial conditions... Starting Experiment"
    assert case["bundle_lines"][-1] == SUCCESS
    assert any(line.startswith("No errors or warnings in your simulation!") for line in case["bundle_lines"])


def test_rps21s_start_up_phase_never_ends_where_its_barrier_keeps_two_robots_apart():
    stuck = [case for case in LAB if case["own_startup"]["iterations"] is None]
    assert {case["experiment"] for case in stuck} >= {"hrvo-circle", "voronoi-coverage"}
    for case in LAB:
        own = np.array(case["own_starts"])
        blocked = _blocked(own)
        if case["own_startup"]["iterations"] is None:
            # Robots in a blocked pair never both arrive; every robot of no blocked pair did.
            missing = {i for i, arrived in enumerate(case["own_startup"]["at_pose"]) if not arrived}
            assert missing and missing <= blocked
        else:
            assert not blocked
        assert not _blocked(np.array(case["bundle_starts"]))
