"""A run saved to a checkpoint and resumed takes exactly the steps of the uninterrupted run."""

from __future__ import annotations

import json
import os
import pickle
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

import dream
from dream.experiments import checkpoint as checkpoints
from dream.experiments.checkpoint import CheckpointError

CASES = [
    # robots, timers, radios and the world's random generator, under faults that draw from it
    ("hrvo-circle", 10, False, dream.Faults(loss=0.3, drift=0.05, latency=3)),
    ("voronoi-coverage", 12, False, None),
    ("line-consensus", 100, True, None),  # swarm mode
    ("hrvo-circle", 30, True, None),  # swarm mode: the runs of hours this is for
]


@pytest.mark.parametrize(("name", "n", "swarm", "faults"), CASES)
def test_resumed_run_equals_the_uninterrupted_one(tmp_path, name, n, swarm, faults):
    path = tmp_path / "run.ckpt"
    common = dict(n=n, seed=4, backend="fast", swarm=swarm, trace=True, faults=faults)
    whole = dream.run(name, steps=700, **common)
    first = dream.run(name, steps=300, checkpoint=path, checkpoint_every=100, **common)
    assert first.steps == 300 and checkpoints.load(path).step == 300  # saved at the cap
    rest = dream.resume(path, steps=700)
    assert rest.steps == whole.steps and rest.completed_step == whole.completed_step
    np.testing.assert_array_equal(rest.trace, whole.trace)
    assert rest.measures == whole.measures and rest.faults == whole.faults
    assert (rest.collisions, rest.boundary, rest.actuator) == (whole.collisions, whole.boundary, whole.actuator)


def test_a_run_that_dies_resumes_from_its_last_periodic_save(tmp_path):
    path = tmp_path / "run.ckpt"
    common = dict(n=10, seed=2, backend="fast", trace=True)

    def crash(step, cap):
        if step == 250:
            raise MemoryError("the machine ran out")  # the process dies: no save at the end

    with pytest.raises(MemoryError):
        dream.run("hrvo-circle", steps=400, checkpoint=path, checkpoint_every=100, progress=crash, **common)
    saved = checkpoints.load(path)
    assert (saved.step, saved.every) == (200, 100)
    rest = dream.resume(path, steps=saved.step + 1)  # one step more: the wall time is the parts' sum
    assert rest.wall_time >= saved.wall_time > 0
    rest = dream.resume(path, steps=400)
    np.testing.assert_array_equal(rest.trace, dream.run("hrvo-circle", steps=400, **common).trace)
    with pytest.raises(ValueError, match="has taken 400 steps already"):
        dream.resume(path, steps=300)


def test_a_save_that_fails_mid_run_warns_and_the_run_goes_on(tmp_path):
    folder = tmp_path / "gone"
    folder.mkdir()

    def remove(step, cap):
        if step == 150:
            (folder / "run.ckpt").unlink()
            folder.rmdir()

    with pytest.warns(RuntimeWarning) as caught:
        result = dream.run(
            "hrvo-circle", n=10, backend="fast", steps=300, checkpoint=folder / "run.ckpt", checkpoint_every=100,
            progress=remove,
        )  # fmt: skip
    assert result.steps == 300 and not result.interrupted
    said = [str(warning.message) for warning in caught]
    assert len(said) == 2 and all("the run goes on" in text for text in said)  # step 200, and at the cap
    assert said[0].startswith("checkpoint not saved at step 200: ") and "step 300" in said[1]


def test_checkpoint_is_saved_every_k_steps(tmp_path):
    path, seen = tmp_path / "run.ckpt", []

    def progress(step, cap):  # the file as the run sees it after each step
        if step % 50 == 1:
            seen.append(checkpoints.load(path).step)

    dream.run("hrvo-circle", n=10, backend="fast", steps=260, checkpoint=path, checkpoint_every=100, progress=progress)
    assert seen == [0, 0, 100, 100, 200, 200]
    assert checkpoints.load(path).step == 260
    seen.clear()
    dream.resume(path, steps=420, progress=progress)  # every 100 steps, as the run was started
    assert seen == [300, 300, 400]


def test_a_signal_saves_the_run_where_it_stopped(tmp_path):
    path = tmp_path / "run.ckpt"

    def progress(step, cap):
        if step == 123:
            os.kill(os.getpid(), signal.SIGTERM)

    common = dict(n=10, seed=1, backend="fast", steps=500, trace=True)
    stopped = dream.run("hrvo-circle", checkpoint=path, progress=progress, **common)
    assert stopped.interrupted and stopped.steps == 123 and checkpoints.load(path).step == 123
    rest, whole = dream.resume(path), dream.run("hrvo-circle", **common)
    assert not rest.interrupted and rest.steps == 500 and rest.measures == whole.measures
    np.testing.assert_array_equal(rest.trace, whole.trace)


def test_a_finished_run_leaves_its_last_save(tmp_path):
    path = tmp_path / "run.ckpt"
    done = dream.run("hrvo-circle", n=4, backend="fast", checkpoint=path, checkpoint_every=10_000)
    assert done.success and checkpoints.load(path).step == 0  # saved before the first step only


class Locked(dream.Experiment):
    name = "locked"

    def build(self, n):
        self.lock = threading.Lock()  # pickle cannot write a lock


def test_an_unpicklable_run_fails_before_its_first_step_and_keeps_the_old_file(tmp_path):
    path = tmp_path / "run.ckpt"
    path.write_bytes(b"previous")
    with pytest.raises(CheckpointError, match=r"cannot checkpoint this run to .*run\.ckpt.*lock"):
        dream.run(Locked, n=2, backend="fast", checkpoint=path, progress=lambda step, cap: pytest.fail("stepped"))
    assert path.read_bytes() == b"previous"
    assert [p.name for p in tmp_path.iterdir()] == ["run.ckpt"]  # no temporary file left


def test_bad_checkpoints_are_refused_with_what_is_wrong(tmp_path):
    with pytest.raises(FileNotFoundError):
        dream.resume(tmp_path / "missing.ckpt")
    other = tmp_path / "other.ckpt"
    other.write_bytes(b"hello\n")
    with pytest.raises(CheckpointError, match="other.ckpt is not a DREAM checkpoint"):
        dream.resume(other)
    path = tmp_path / "run.ckpt"
    dream.run("hrvo-circle", n=4, backend="fast", steps=5, checkpoint=path)
    magic, _, body = path.read_bytes().partition(b"\n")
    header, _, data = body.partition(b"\n")
    path.write_bytes(magic + b"\n" + header.replace(b'"version": "', b'"version": "0.0.0-old') + b"\n" + data)
    with pytest.raises(CheckpointError, match=r"written by DREAM 0\.0\.0-old.*; this is DREAM"):
        dream.resume(path)
    path.write_bytes(magic + b"\n" + header + b"\n" + data[: len(data) // 2])
    with pytest.raises(CheckpointError, match="cannot read the checkpoint"):
        dream.resume(path)
    path.write_bytes(magic + b"\n" + header + b"\n" + pickle.dumps({"not": "a run"}))
    with pytest.raises(CheckpointError, match="is not a DREAM checkpoint"):
        dream.resume(path)
    with pytest.raises(ValueError, match="is a folder"):
        dream.run("hrvo-circle", n=4, backend="fast", checkpoint=tmp_path)
    with pytest.raises(ValueError, match="nowhere does not exist"):
        dream.run("hrvo-circle", n=4, backend="fast", checkpoint=tmp_path / "nowhere" / "run.ckpt")
    with pytest.raises(ValueError, match="checkpoint_every must be an integer >= 1"):
        dream.run("hrvo-circle", n=4, backend="fast", checkpoint=path, checkpoint_every=0)


STARTER = """
import numpy as np
import dream


class Drift(dream.Experiment):
    name = "drift"
    default_n = 3

    def build(self, n):
        self.moved = 0

    def before_step(self, step):
        self.dxu[0] = 0.05 * self.world.rng.uniform(size=self.n)
        self.moved += 1

    def measures(self):
        return {"moved": self.moved, "x": self.sim.poses[0].tolist()}
"""


def test_a_researchers_experiment_resumes_in_another_process(tmp_path):
    source, path = tmp_path / "drift.py", tmp_path / "run.ckpt"
    source.write_text(STARTER)
    cli = [sys.executable, "-m", "dream.cli"]
    first = subprocess.run(cli + ["run", str(source), "--steps", "40", "--checkpoint", str(path), "--no-progress"],
                           capture_output=True, text=True, check=False)  # fmt: skip
    assert first.returncode == 0, first.stderr
    metrics = tmp_path / "m.json"
    rest = subprocess.run(cli + ["resume", str(path), "--steps", "90", "--no-progress", "--json", str(metrics)],
                          capture_output=True, text=True, check=False)  # fmt: skip
    assert rest.returncode == 0, rest.stderr
    whole = dream.run(dream.experiments.load_file(source), steps=90)
    assert json.loads(metrics.read_text())["measures"] == whole.measures
    for argv, said in (([str(tmp_path / "nope.ckpt")], "no such checkpoint"), ([str(tmp_path)], "no such checkpoint"),
                       ([str(path), "--steps", "10"], "has taken 90 steps already")):  # fmt: skip
        refused = subprocess.run(cli + ["resume", *argv], capture_output=True, text=True, check=False)
        assert refused.returncode == 2 and refused.stderr.startswith("dream: error: ") and said in refused.stderr
        assert refused.stderr.count("\n") == 1


def test_a_changed_experiment_file_is_resumed_with_a_warning(tmp_path):
    source, path = tmp_path / "drift_changed.py", tmp_path / "run.ckpt"
    source.write_text(STARTER)
    dream.run(dream.experiments.load_file(source), steps=20, checkpoint=path)
    assert dream.resume(path, steps=30).measures["moved"] == 30  # the loaded module is used as it is
    sys.modules.pop(dream.experiments.files.module_name(source))
    source.write_text(STARTER + "\n# a comment\n")
    with pytest.warns(RuntimeWarning, match="has changed since"):
        assert dream.resume(path, steps=40).measures["moved"] == 40


def test_dream_resume_records_the_rest_of_the_run_to_a_video(tmp_path):
    path, video = tmp_path / "run.ckpt", tmp_path / "rest.gif"
    from dream.cli import main

    assert main(["run", "hrvo-circle", "-n", "4", "--backend", "fast", "--steps", "20", "--checkpoint", str(path),
                 "--no-progress"]) == 0  # fmt: skip
    assert main(["resume", str(path), "--steps", "30", "--video", str(video), "--no-progress"]) == 0
    assert video.stat().st_size > 0
    assert main(["resume", str(path), "--focus", "4", "--no-progress"]) == 2  # robots 0 to 3
