"""The trajectory log (``dream.run(..., log=...)``): its schema, metadata and contents, checked
against the run that wrote it."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import dream
from dream import Experiment, Faults
from dream import trajectory_log as tl
from dream.trajectory_log import read_metadata

ROOT = Path(__file__).resolve().parents[2]


def columns(path):
    """The log at ``path`` as NumPy columns."""
    table = pq.read_table(path)
    return {name: table.column(name).to_numpy() for name in table.column_names}


class Sway(Experiment):
    """Robots turning in place, each at its own rate; a per-robot measure that says what the
    simulator carried out (for the log's ``v`` and ``w`` to be checked against)."""

    name = "sway"
    default_n = 5
    fail_at = dream.param(0, "raise in after_step at this step (0: never)", ge=0)

    def build(self, n):
        pass

    def build_swarm(self, n):
        pass

    has_swarm_mode = True

    def swarm_step(self, step, x):
        return np.vstack((np.full(self.n, 0.02), np.linspace(-0.5, 0.5, self.n)))

    def after_step(self, step, poses):
        if step == self.fail_at:
            raise RuntimeError("the experiment failed")

    def robot_measures(self):
        return {"w_carried": self.sim.velocities[1].copy(), "turn": np.arange(self.n) % 2}


def rendezvous():
    spec = importlib.util.spec_from_file_location("rendezvous_example", ROOT / "examples" / "rendezvous.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.Rendezvous


def test_log_holds_every_robot_at_every_logged_step(tmp_path):
    path = tmp_path / "run.parquet"
    result = dream.run("hrvo-circle", n=6, seed=3, backend="fast", steps=23, log=path, log_every=5, trace=True)
    log = columns(path)
    logged = [0, 5, 10, 15, 20, 23]  # every 5th step, and the last
    assert np.array_equal(log["step"], np.repeat(logged, 6))
    assert np.array_equal(log["robot"], np.tile(np.arange(6), len(logged)))
    for step in logged:
        rows = log["step"] == step
        poses = np.vstack([log[name][rows] for name in ("x", "y", "theta")])
        assert np.array_equal(poses, result.trace[step])
    assert np.allclose(log["time"], log["step"] * 0.033)
    assert not log["v"][:6].any() and not log["w"][:6].any()  # nothing carried out before the first step
    assert log["v"][6:].any()
    assert not (log["crashed"] | log["stuck"] | log["byzantine"]).any()


def test_log_schema_and_metadata_describe_the_run(tmp_path):
    path = tmp_path / "run.parquet"
    faults = Faults(loss=0.2, crash=0.25, crash_at=4)
    dream.run("hrvo-circle", n=4, seed=5, backend="fast", steps=6, log=path, faults=faults, radio_gap=10)
    schema = pq.read_schema(path)
    assert schema.names == [*tl.BASE_COLUMNS, *tl.MESSAGE_COLUMNS]
    assert schema.field("step").type == pa.int64() and schema.field("x").type == pa.float64()
    assert schema.field("crashed").type == pa.bool_() and schema.field("lost").type == pa.int64()
    meta = read_metadata(path)
    assert meta["experiment"] == "hrvo-circle" and meta["n"] == 4 and meta["seed"] == 5
    assert meta["params"] == {"radio_gap": 10}
    assert meta["faults"] == {"loss": 0.2, "crash": 0.25, "crash_at": 4}
    assert meta["version"] == dream.__version__ and meta["log_every"] == 1 and meta["backend"] == "fast"
    assert meta["arena"] == {"xmin": -1.6, "xmax": 1.6, "ymin": -1.0, "ymax": 1.0}


def test_log_flags_the_faulty_robots_from_the_step_they_fail(tmp_path):
    path = tmp_path / "run.parquet"
    faults = Faults(crash=0.5, crash_at=3, byzantine=1)
    result = dream.run("hrvo-circle", n=6, seed=2, backend="fast", steps=8, log=path, faults=faults)
    log = columns(path)
    crashes = {e["robot"] for e in result.faults["events"] if e["kind"] == "crash"}
    liar = {e["robot"] for e in result.faults["events"] if e["kind"] == "byzantine"}
    assert len(crashes) == 3 and len(liar) == 1
    # The runner advances the faults as step t begins: a crash at 3 shows from the pose after step 3.
    for step in range(9):
        rows = log["step"] == step
        crashed = set(log["robot"][rows & log["crashed"]].tolist())
        assert crashed == (crashes if step > 3 else set())
        assert set(log["robot"][rows & log["byzantine"]].tolist()) == liar


def test_log_counts_the_messages_of_robot_objects(tmp_path):
    path = tmp_path / "run.parquet"
    result = dream.run("hrvo-circle", n=8, seed=1, backend="fast", steps=40, log=path, faults=Faults(loss=0.4))
    log = columns(path)
    last = log["step"] == 40
    assert log["lost"][last].sum() == result.faults["messages_lost"] > 0
    assert log["heard"][last].sum() > 0 and log["sent"][last].sum() > 0
    for name in tl.MESSAGE_COLUMNS:  # counts so far: never less than at the step before
        per_robot = log[name].reshape(-1, 8)
        assert (np.diff(per_robot, axis=0) >= 0).all()


def test_log_counts_the_same_messages_robot_by_robot_and_as_a_swarm(tmp_path):
    faults = Faults(loss=0.3, latency=2, crash=0.2, crash_at=10)
    logs = []
    for swarm in (False, True):
        path = tmp_path / f"swarm-{swarm}.parquet"
        result = dream.run(rendezvous(), n=12, seed=4, backend="fast", steps=30, swarm=swarm, faults=faults, log=path)
        logs.append(columns(path))
        assert logs[-1]["lost"][-12:].sum() == result.faults["messages_lost"] > 0
    for name in tl.MESSAGE_COLUMNS + ("x", "y", "crashed"):
        assert np.array_equal(logs[0][name], logs[1][name])
    assert logs[0]["heard"][-12:].sum() > 0


class Handmade(dream.Experiment):
    """A hand-written swarm mode: every robot's command from the poses, no radios."""

    name = "handmade"
    has_swarm_mode = True

    def build_swarm(self, n):
        pass

    def swarm_step(self, step, x):
        return np.tile([[0.05], [0.1]], (1, self.n))


def test_log_of_a_hand_written_swarm_mode_has_no_message_columns(tmp_path):
    path = tmp_path / "run.parquet"
    dream.run(Handmade, n=5, backend="fast", steps=3, swarm=True, log=path)
    assert pq.read_schema(path).names == list(tl.BASE_COLUMNS)
    assert read_metadata(path)["swarm"] is True


def test_log_has_the_experiments_per_robot_measures(tmp_path):
    path = tmp_path / "run.parquet"
    dream.run(Sway, n=5, backend="fast", steps=10, swarm=True, log=path, log_every=3)
    log = columns(path)
    assert pq.read_schema(path).names[-2:] == ["w_carried", "turn"]
    assert np.array_equal(log["w"], log["w_carried"])  # w: what the simulator carried out in that step
    assert log["w"][log["step"] == 9].any()
    assert np.array_equal(log["turn"], np.tile(np.arange(5) % 2, 5))  # steps 0, 3, 6, 9, 10


def test_log_goes_out_in_row_groups_of_whole_steps(tmp_path, monkeypatch):
    monkeypatch.setattr(tl, "ROW_GROUP_ROWS", 12)
    path = tmp_path / "run.parquet"
    dream.run(Sway, n=5, backend="fast", steps=20, swarm=True, log=path)
    meta = pq.ParquetFile(path).metadata
    sizes = [meta.row_group(k).num_rows for k in range(meta.num_row_groups)]
    assert sizes == [15] * 7  # 21 steps of 5 robots, 3 steps (15 rows >= 12) a group
    assert len(columns(path)["step"]) == 105


def test_failed_run_leaves_no_log_and_the_old_one_whole(tmp_path):
    path = tmp_path / "run.parquet"
    path.write_bytes(b"the log of an earlier run")
    with pytest.raises(RuntimeError, match="the experiment failed"):
        dream.run(Sway, n=3, backend="fast", steps=10, swarm=True, log=path, fail_at=4)
    assert path.read_bytes() == b"the log of an earlier run"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.parquet"]  # no temporary file left


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"log_every": 0}, "log_every must be an integer >= 1"),
        ({"log": "{tmp}"}, "is a folder"),
        ({"log": "{tmp}/missing/run.parquet"}, "does not exist"),
    ],
)
def test_log_refuses_bad_arguments_before_the_run(tmp_path, options, message):
    options = {key: value.format(tmp=tmp_path) if isinstance(value, str) else value for key, value in options.items()}
    options.setdefault("log", tmp_path / "run.parquet")
    with pytest.raises(ValueError, match=message):
        dream.run(Sway, n=3, backend="fast", steps=2, swarm=True, **options)


class HalfMeasures(Sway):
    def robot_measures(self):
        return {"half": np.zeros(self.n // 2)}


class ClashingMeasures(Sway):
    def robot_measures(self):
        return {"x": np.zeros(self.n)}


@pytest.mark.parametrize(
    ("experiment", "message"),
    [(HalfMeasures, r"\['half'\] must be one number per robot"), (ClashingMeasures, "names 'x', a column")],
)
def test_log_refuses_measures_it_cannot_hold(tmp_path, experiment, message):
    path = tmp_path / "run.parquet"
    with pytest.raises(ValueError, match=message):
        dream.run(experiment, n=4, backend="fast", steps=2, swarm=True, log=path)
    assert not path.exists()
