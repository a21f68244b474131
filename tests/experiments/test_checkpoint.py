"""A run saved to a checkpoint and resumed takes exactly the steps of the uninterrupted run."""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import pickle
import re
import signal
import stat
import subprocess
import sys
import threading

import numpy as np
import pytest

import dream
from dream.cli import main
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
    other.write_bytes(b"DREAM-CHECKPOINT 1\n{}\n")  # the unsigned format of DREAM before 30
    with pytest.raises(CheckpointError, match="other.ckpt: an unsigned checkpoint of an older DREAM"):
        dream.resume(other)
    path = tmp_path / "run.ckpt"
    dream.run("hrvo-circle", n=4, backend="fast", steps=5, checkpoint=path)
    magic, signature, header, data = path.read_bytes().split(b"\n", 3)
    # Each file changed after its save, resumed as trusted: the checks after the signature's.
    old = header.replace(b'"version": "', b'"version": "0.0.0-old')
    for changed, pickled, message in (
        (old, data, r"written by DREAM 0\.0\.0-old.*; this is DREAM"),
        (b"{not json", data, "damaged checkpoint header"),
        (header, data[: len(data) // 2], "cannot read the checkpoint"),
        (header, pickle.dumps({"not": "a run"}), "is not a DREAM checkpoint"),
    ):
        path.write_bytes(b"\n".join([magic, signature, changed, pickled]))
        with pytest.raises(CheckpointError, match=message), pytest.warns(RuntimeWarning, match="resumed as trusted"):
            dream.resume(path, trust=True)
    with pytest.raises(ValueError, match="is a folder"):
        dream.run("hrvo-circle", n=4, backend="fast", checkpoint=tmp_path)
    with pytest.raises(ValueError, match="nowhere does not exist"):
        dream.run("hrvo-circle", n=4, backend="fast", checkpoint=tmp_path / "nowhere" / "run.ckpt")
    with pytest.raises(ValueError, match="checkpoint_every must be an integer >= 1"):
        dream.run("hrvo-circle", n=4, backend="fast", checkpoint=path, checkpoint_every=0)


# -- signatures: a checkpoint is code, so only the user's own (or a trusted file) is loaded ------
class Marker:
    """Unpickled, it writes its marker file: what a crafted checkpoint could do."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return exec, (f"open({self.marker!r}, 'w').write('ran')",)


def _crafted(path, source=None, data=b"", magic=checkpoints.MAGIC, signature=b"0" * 64, key=None):
    """A checkpoint file as an attacker writes it: a header naming ``source``, the pickle ``data``,
    and a made-up signature (or one by another ``key``, or none)."""
    header = json.dumps({"version": dream.__version__, "source": source, "digest": None}).encode() + b"\n"
    if key is not None:
        signature = hmac.new(key, magic + header + data, hashlib.sha256).hexdigest().encode()
    path.write_bytes(magic + (b"" if signature is None else signature + b"\n") + header + data)
    return path


def test_a_crafted_pickle_is_refused_before_it_runs(tmp_path, capsys):
    marker = tmp_path / "marker"
    data = pickle.dumps(Marker(marker))
    for name, extra, said in (
        (
            "old-format.ckpt",
            {"magic": b"DREAM-CHECKPOINT 1\n", "signature": None},
            "an unsigned checkpoint",
        ),  # no signature
        ("made-up.ckpt", {}, "resume only a file you trust, with --trust"),  # a signature that is no HMAC
        ("other-key.ckpt", {"key": os.urandom(32)}, "with --trust"),  # an HMAC, with a key not the user's
    ):
        path = _crafted(tmp_path / name, data=data, **extra)
        with pytest.raises(CheckpointError, match=re.escape(said)):
            dream.resume(path)
        assert main(["resume", str(path), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith(f"dream: error: {path}") and said in err
        assert not marker.exists()


def test_a_header_naming_a_python_file_is_refused_before_the_import(tmp_path, capsys):
    marker, evil = tmp_path / "marker", tmp_path / "evil_experiment.py"
    evil.write_text(f"open({str(marker)!r}, 'w').write('ran')\n")
    path = _crafted(tmp_path / "run.ckpt", source=str(evil), data=pickle.dumps(None))
    with pytest.raises(CheckpointError, match="signature does not match your checkpoint key .*, with --trust"):
        dream.resume(path)
    assert main(["resume", str(path), "--no-progress"]) == 2
    assert "signature does not match" in capsys.readouterr().err
    assert not marker.exists() and dream.experiments.files.module_name(evil) not in sys.modules


def test_a_checkpoint_changed_by_one_byte_is_refused(tmp_path):
    path = tmp_path / "run.ckpt"
    dream.run("hrvo-circle", n=4, backend="fast", steps=5, checkpoint=path)
    saved = path.read_bytes()
    header = saved.index(b"\n", len(checkpoints.MAGIC)) + 1
    for at in (len(checkpoints.MAGIC), header + 3, header + 100, (header + len(saved)) // 2, len(saved) - 1):
        changed = bytearray(saved)
        changed[at] ^= 0x01
        path.write_bytes(changed)
        with pytest.raises(CheckpointError, match="signature does not match"):
            checkpoints.load(path)
    for changed in (saved + b"\0", saved[:-1]):
        path.write_bytes(changed)
        with pytest.raises(CheckpointError, match="signature does not match"):
            checkpoints.load(path)
    path.write_bytes(saved)
    assert checkpoints.load(path).step == 5


def test_a_colleagues_checkpoint_resumes_only_with_trust_and_a_warning(tmp_path, monkeypatch, capsys):
    path, metrics = tmp_path / "theirs.ckpt", tmp_path / "m.json"
    common = dict(n=10, seed=3, backend="fast", trace=True)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "colleague"))
    dream.run("hrvo-circle", steps=100, checkpoint=path, **common)
    theirs = path.read_bytes()
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "me"))
    with pytest.raises(CheckpointError, match="signature does not match"):
        dream.resume(path, steps=250)
    assert main(["resume", str(path), "--steps", "250", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "resume only a file you trust, with --trust" in err
    whole = dream.run("hrvo-circle", steps=250, **common)
    with pytest.warns(RuntimeWarning, match=r"theirs\.ckpt: its signature does not match .* resumed as trusted"):
        rest = dream.resume(path, steps=250, trust=True)
    np.testing.assert_array_equal(rest.trace, whole.trace)  # the same steps as the uninterrupted run
    assert checkpoints.load(path).step == 250  # saved again, with the user's own key
    path.write_bytes(theirs)
    assert main(["resume", str(path), "--trust", "--steps", "250", "--no-progress", "--json", str(metrics)]) == 0
    warned = capsys.readouterr().err
    assert warned.startswith("dream: warning: ") and warned.count("\n") == 1 and "resumed as trusted" in warned
    assert json.loads(metrics.read_text())["measures"] == whole.measures


def test_the_key_is_made_once_with_mode_0600_in_the_config_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("HOME", str(tmp_path))
    monkeypatch.setenv("XDG_CONFIG_HOME", "relative/ignored")  # XDG: only an absolute path counts
    key = tmp_path / ".config" / "dream" / "checkpoint.key"
    previous = os.umask(0)  # the key's mode is 0600 whatever the umask
    try:
        dream.run("hrvo-circle", n=4, backend="fast", steps=2, checkpoint=tmp_path / "run.ckpt")
    finally:
        os.umask(previous)
    assert checkpoints.key_path() == key and stat.S_IMODE(key.stat().st_mode) == 0o600
    made = key.read_text()
    assert re.fullmatch(r"[0-9a-f]{64}\n", made)
    dream.run("hrvo-circle", n=4, backend="fast", steps=2, checkpoint=tmp_path / "run.ckpt")
    assert key.read_text() == made and checkpoints.load(tmp_path / "run.ckpt").step == 2
    assert os.listdir(key.parent) == ["checkpoint.key"]  # no temporary left
    key.write_text("not a key\n")
    with pytest.raises(CheckpointError, match="checkpoint.key is not a checkpoint key"):
        dream.run("hrvo-circle", n=4, backend="fast", steps=2, checkpoint=tmp_path / "run.ckpt")


def test_processes_making_the_key_at_once_all_get_the_one_key(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    code = "from dream.experiments.checkpoint import _key; print(flush=True); input(); print(_key().hex())"
    racers = [subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
              for _ in range(4)]  # fmt: skip
    for racer in racers:  # each has imported DREAM and waits for a line
        assert racer.stdout.readline() == "\n"
    for racer in racers:  # then they make the key at once
        racer.stdin.write("go\n")
        racer.stdin.close()
    keys = {racer.stdout.read() for racer in racers}
    assert [racer.wait() for racer in racers] == [0] * 4
    assert len(keys) == 1 and (tmp_path / "dream" / "checkpoint.key").read_text() == keys.pop()
    assert os.listdir(tmp_path / "dream") == ["checkpoint.key"]


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
    assert main(["run", "hrvo-circle", "-n", "4", "--backend", "fast", "--steps", "20", "--checkpoint", str(path),
                 "--no-progress"]) == 0  # fmt: skip
    assert main(["resume", str(path), "--steps", "30", "--video", str(video), "--no-progress"]) == 0
    assert video.stat().st_size > 0
    assert main(["resume", str(path), "--focus", "4", "--no-progress"]) == 2  # robots 0 to 3
