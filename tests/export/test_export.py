"""`dream export`: bundles that run where the lab runs them (rps and the scientific packages, no
DREAM installed), on rps 0.0.0 and on rps 2.x's shape, and the refusals."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import venv
from pathlib import Path

import pytest

import dream
from dream import cli, export
from dream.experiments import load_file

ROOT = Path(__file__).parents[2]
RENDEZVOUS = ROOT / "examples" / "rendezvous.py"
VERDICT = re.compile(r"^dream: (\w+[^,]*), (\d+) collisions, (\d+) boundary, (\d+) actuator$")


def lab_env() -> dict[str, str]:
    """The environment of a lab run: headless, nothing of DREAM's on the path."""
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "DREAM_PURE_PYTHON")}
    return {**env, "DREAM_HEADLESS": "1", "MPLBACKEND": "Agg"}


def run_bundle(python: Path | str, folder: Path, env: dict[str, str]) -> tuple[str, dict[str, str]]:
    """Runs the bundle's main.py from another folder; returns its output and its parsed last line."""
    done = subprocess.run(
        [str(python), str(folder / "main.py")],
        check=False,
        cwd=folder.parent,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
    verdict = VERDICT.match(done.stdout.strip().splitlines()[-1])
    assert verdict, done.stdout[-2000:]
    keys = ("verdict", "collisions", "boundary", "actuator")
    return done.stdout, dict(zip(keys, verdict.groups()))


@pytest.fixture(scope="session")
def lab_python(tmp_path_factory) -> Path:
    """A clean venv with what the lab has (rps 0.0.0 from PyPI, numpy, scipy, matplotlib, cvxopt) and no DREAM."""
    folder = tmp_path_factory.mktemp("lab-venv")
    venv.create(folder, with_pip=True)
    python = folder / "bin" / "python"
    packages = ["robotarium-python-simulator", "numpy", "scipy", "matplotlib", "cvxopt"]
    install = subprocess.run(
        [str(python), "-m", "pip", "install", "-q", *packages], check=False, capture_output=True, text=True, timeout=900
    )
    assert install.returncode == 0, install.stderr[-4000:]
    probe = subprocess.run(
        [str(python), "-c", "import dream"], check=False, env=lab_env(), capture_output=True, text=True
    )
    assert probe.returncode != 0 and "No module named 'dream'" in probe.stderr
    return python


@pytest.mark.parametrize("source", ["hrvo-circle", str(RENDEZVOUS)])
def test_exported_bundle_runs_to_success_on_rps0_without_dream_installed(lab_python, tmp_path, source):
    with pytest.warns(export.ExportWarning, match=r"robots start up to .* start-up phase"):
        folder = export.export(source, tmp_path / "bundle", n=10, seed=0)
    files = {path.relative_to(folder).as_posix() for path in folder.rglob("*") if path.is_file()}
    assert "main.py" in files and "dream/experiments/runner.py" in files and "dream/_reference/hrvo.py" in files
    assert not [name for name in files if re.search(r"\.so$|/(viz|cli|sweep|sweep_plot|onboard)\.py$|templates/", name)]
    assert ("rendezvous.py" in files) == source.endswith(".py")
    output, verdict = run_bundle(lab_python, folder, lab_env())
    assert verdict == {"verdict": "success", "collisions": "0", "boundary": "0", "actuator": "0"}
    assert "No errors in your simulation!" in output  # rps 0.0.0's own report agrees
    # The same run as `dream run` (the bundle steps through the same Stepper).
    cls = source if not source.endswith(".py") else load_file(source)
    assert int(re.search(r"steps run +(\d+)", output).group(1)) == dream.run(cls, n=10, seed=0).steps


FAKE_RPS2 = '''\
"""Stands in for rps 2.x: keyword-only constructor with 2.1's type checks, a start-up phase that
ends near (not at) the initial conditions, debug() and no call_at_scripts_end()."""
import numpy as np


class Robotarium:
    def __init__(self, **kwargs):
        assert isinstance(kwargs["number_of_robots"], int), "NumberOfRobots must be an integer"
        assert isinstance(kwargs["show_figure"], bool) and isinstance(kwargs["sim_in_real_time"], bool)
        assert isinstance(kwargs["initial_conditions"], np.ndarray)
        self.number_of_robots = kwargs["number_of_robots"]
        self._poses = kwargs["initial_conditions"].copy()
        self._poses[:2] += 0.01
        self._velocities = np.zeros((2, self.number_of_robots))
        self._called_step_already, self._checked_poses_already = True, False
        self._iteration = 0

    def get_poses(self):
        assert not self._checked_poses_already, "Can only call get_poses() once per call of step()!"
        self._called_step_already, self._checked_poses_already = False, True
        return self._poses.copy()

    def set_velocities(self, ids, velocities):
        self._velocities[:, ids] = velocities

    def step(self):
        assert not self._called_step_already, "Make sure you call get_poses before calling step()!"
        self._called_step_already, self._checked_poses_already = True, False
        self._iteration += 1
        v, w = self._velocities
        self._poses[0] += 0.033 * v * np.cos(self._poses[2])
        self._poses[1] += 0.033 * v * np.sin(self._poses[2])
        self._poses[2] = np.arctan2(np.sin(self._poses[2] + 0.033 * w), np.cos(self._poses[2] + 0.033 * w))

    def debug(self):
        print(f"fake rps 2.x debug() after {self._iteration} iterations")
'''


@pytest.mark.filterwarnings("ignore::dream.export.ExportWarning")
def test_exported_bundle_runs_on_rps2s_shape(tmp_path):
    fake = tmp_path / "fake" / "rps"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("")
    (fake / "robotarium.py").write_text(FAKE_RPS2)
    # Seed 0: a start whose robots all hear each other (rendezvous by range radio needs that).
    folder = export.export(RENDEZVOUS, tmp_path / "bundle", n=6, seed=0)
    env = {**lab_env(), "PYTHONPATH": str(fake.parent)}  # the fake rps before the installed 0.0.0
    output, verdict = run_bundle(sys.executable, folder, env)
    # DREAM counted by rps 2.1's rules, whose actuator test (0.11 m wheel base, commands checked
    # before clipping) is stricter than 0.0.0's: the robots keep within it.
    assert (verdict["collisions"], verdict["boundary"], verdict["actuator"]) == ("0", "0", "0")
    steps = int(re.search(r"steps run +(\d+)", output).group(1))
    assert re.search(rf"completed at step +{steps}\n", output)
    assert f"fake rps 2.x debug() after {steps} iterations" in output
    assert "backend            lab" in output


# -- refusals: one line, exit code 2, nothing written ---------------------------------------------
SCRIPT = """\
from dream import Experiment{imports}


class Mine(Experiment):
    name = "mine"

    def build(self, n):
        {body}
"""


@pytest.mark.parametrize(
    ("imports", "body", "message"),
    [
        ("\nimport tqdm", "pass", "line 2: imports tqdm, which the lab does not have"),
        ("\nfrom dream.viz import Recorder", "pass", "line 2: uses dream.viz, which a lab bundle leaves out"),
        ("\nfrom dream import sweep", "pass", "uses dream.sweep, which a lab bundle leaves out: sweeps (Dask)"),
        ("\nfrom dream import *", "DistanceSensor(0, 'd', print)", "line 9: uses DistanceSensor: onboard sensors"),
        ("\nfrom . import helpers", "pass", "line 2: a relative import"),
        ("", "__import__('tqdm')", "line 8: uses __import__, an import by name that the check cannot follow"),
        ("", "builtins.__import__('tqdm')", "line 8: uses __import__, an import by name"),
        ("\nimport importlib", "importlib.import_module('tqdm')", "line 2: imports importlib, an import by name"),
        ("\nfrom importlib import import_module", "pass", "line 2: imports importlib, an import by name"),
    ],
)
def test_export_refuses_a_script_the_lab_cannot_run(tmp_path, capsys, imports, body, message):
    script = tmp_path / "mine.py"
    script.write_text(SCRIPT.format(imports=imports, body=body))
    assert cli.main(["export", str(script), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.py"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.py"], "missing.py: no such file"),
        (["hrvo-circle", "-n", "21"], "runs 1 to 20 robots"),
        (["rendezvous-ish"], "unknown experiment"),
        ([str(RENDEZVOUS), "--param", "gain=fast"], "parameter 'gain' of rendezvous expects a number"),
        ([str(RENDEZVOUS), "--param", "nope=1"], "has no parameter 'nope'"),
    ],
)
def test_export_refuses_bad_input_in_one_line(tmp_path, capsys, args, message):
    assert cli.main(["export", *args, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.filterwarnings("ignore::dream.export.ExportWarning")
def test_force_replaces_only_a_previous_export_and_a_failed_export_keeps_it(tmp_path, capsys, monkeypatch):
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "notes.txt").write_text("mine")
    for force in ([], ["--force"]):
        assert cli.main(["export", "hrvo-circle", "-o", str(notes), *force]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "exists and is not empty, and holds no previous export (no .dream-export" in err
    assert [p.name for p in notes.iterdir()] == ["notes.txt"]
    assert cli.main(["export", "hrvo-circle", "-o", str(notes / "notes.txt")]) == 2
    assert "is a file" in capsys.readouterr().err
    out = tmp_path / "out"
    assert cli.main(["export", "hrvo-circle", "-o", str(out)]) == 0
    assert (out / export.MARKER).is_file()
    assert cli.main(["export", "hrvo-circle", "-o", str(out)]) == 2
    assert "holds a previous export; pass --force to replace it" in capsys.readouterr().err
    (out / "stale.py").write_text("")

    def broken(destination):
        (destination / "half.py").parent.mkdir()
        (destination / "half.py").write_text("")
        raise OSError("disk full")

    monkeypatch.setattr(export, "_copy_package", broken)
    with pytest.raises(OSError, match="disk full"):
        export.export("hrvo-circle", out, force=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes", "out"] and (out / "stale.py").exists()
    monkeypatch.undo()
    assert cli.main(["export", "hrvo-circle", "-o", str(out), "--force", "-n", "12", "--seed", "4"]) == 0
    assert "dream: warning: on rps 2.x, 4 of hrvo-circle's 12 robots start up to 0.25 m" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes", "out"] and not (out / "stale.py").exists()
    main = (out / "main.py").read_text()
    assert "\nN = 12\nSEED = 4\n" in main and "EXPERIMENT = 'hrvo-circle'" in main
    assert "number_of_robots=N, show_figure=SHOW" in main


@pytest.mark.parametrize(
    ("output", "said"),
    [
        (".", "is the working folder or one above it"),
        ("..", "is the working folder or one above it"),
        ("{tmp}", "is the working folder or one above it"),
        ("/", "is the working folder or one above it"),
        ("{tmp}/home", "is the home folder"),
    ],
    ids=["dot", "dot-dot", "above", "root", "home"],
)
def test_export_never_replaces_the_working_folder_a_folder_above_it_or_home(
    tmp_path, monkeypatch, capsys, output, said
):
    home, work = tmp_path / "home", tmp_path / "work" / "here"
    work.mkdir(parents=True)
    home.mkdir()
    for folder in (work, work.parent, tmp_path, home):  # a marker does not make them bundles
        (folder / export.MARKER).write_text("")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(work)
    before = sorted(tmp_path.rglob("*"))
    output = output.format(tmp=tmp_path)
    for force in ([], ["--force"]):
        assert cli.main(["export", "hrvo-circle", "-o", output, *force]) == 2
        err = capsys.readouterr().err
        assert err == f"dream: error: -o {output}: {said}; give a new folder's name\n"
    assert sorted(tmp_path.rglob("*")) == before


TRAINED = ROOT / "tests" / "data" / "rendezvous_policy.npz"


def test_exported_policy_bundle_runs_to_the_end_on_rps0_without_dream_installed(lab_python, tmp_path):
    from dream.rl import LinearPolicy
    from dream.rl.learner import driven

    folder = export.export(str(RENDEZVOUS), tmp_path / "bundle", n=6, seed=0, policy=TRAINED)
    assert (folder / "policy.npz").read_bytes() == TRAINED.read_bytes()
    assert "POLICY = 'policy.npz'" in (folder / "main.py").read_text()
    output, verdict = run_bundle(lab_python, folder, lab_env())
    assert verdict["collisions"] == "0"
    # The robots ran the policy (not the experiment's own rule): the same steps as dream.run of it.
    cls = driven(str(RENDEZVOUS), LinearPolicy.load(TRAINED))
    assert int(re.search(r"steps run +(\d+)", output).group(1)) == dream.run(cls, n=6, seed=0).steps


def test_export_accepts_the_labs_libraries_and_checks_their_versions(tmp_path):
    from dream.lab_libraries import lab_modules, lab_versions

    versions = lab_versions()  # rps 2.1's libraries.txt, as the issue read it
    assert versions["torch"].startswith("2.10.") and versions["scikit-learn"].startswith("1.7.")
    assert versions["gym"].startswith("0.26.") and {"shapely", "networkx", "PyYAML", "opencv-python"} <= set(versions)
    assert {lab_modules()[m] for m in ("sklearn", "cv2", "yaml", "rps")} == {
        "scikit-learn",
        "opencv-python",
        "PyYAML",
        "rps",
    }
    script = tmp_path / "mine.py"
    script.write_text(
        SCRIPT.format(imports="\nimport sklearn\nimport cv2\nimport yaml\nimport gym\nimport torch", body="pass")
    )
    with pytest.warns(export.ExportWarning) as caught:
        export.check_script(script)
    notes = [str(w.message) for w in caught]
    assert any(
        re.search(r"line 6: torch \(torch\) is (not installed here|\S+ here but 2\.10\.0 at the lab)", n) for n in notes
    )
    assert not any("numpy" in note for note in notes)  # DREAM's own dependencies run on the lab's versions


def test_export_refuses_a_missing_policy_file(tmp_path, capsys):
    args = ["export", str(RENDEZVOUS), "-o", str(tmp_path / "out"), "--policy", str(tmp_path / "none.npz")]
    assert cli.main(args) == 2
    assert "--policy" in capsys.readouterr().err and not (tmp_path / "out").exists()
