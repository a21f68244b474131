"""Record this folder's golden data from the real rps 2.1 (the Robotarium lab's simulator, not on PyPI).

Run it with rps 2.1 installed from its repository, outside DREAM's environment::

    git clone https://github.com/robotarium/robotarium_python_simulator /tmp/rps21src
    python -m venv /tmp/rps21 && /tmp/rps21/bin/pip install /tmp/rps21src scipy
    /tmp/rps21/bin/python tests/data/rps21/record.py            # writes the .npz files and cases.json here
    /tmp/rps21/bin/python tests/data/rps21/record.py --check    # records, and compares with the files here

Every noise constant of 2.1 is set to zero, so the outputs are deterministic. The inputs come
from NumPy's ``default_rng(seed)``: poses drawn one by one in 2.8 x 1.6 m until each is 0.3 m
(start-up cases: 0.4 m) from those kept, then headings; then the commands of every step
(``random``: ``v`` in [-0.25, 0.25] m/s and ``w`` in [-4, 4] rad/s, over the wheels' limits;
``straight``: ``v = 0.15`` m/s and ``w`` in [-0.3, 0.3] rad/s). The start-up phase draws its
charger slots with :mod:`random` and its waypoints with NumPy's global generator: both are
seeded with the case's seed. The tests never import this file (rps 2.1 is no test dependency).

``lab_startup.json`` holds what 2.1's start-up phase does with the built-in experiments at their lab
size (seed 0): from the experiment's own initial poses, and from those that an exported bundle hands
rps 2.1 (:func:`dream.backends.startup.reachable_starts`); and the last lines of each bundle run on
2.1 as the lab's verifier runs it. This part takes DREAM from this checkout (its pure-Python part).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import random
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from rps.robotarium import Robotarium
from rps.utilities.misc import create_at_pose

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
STEPS = 300
#: (mode, seed, robots, walls) of the recorded runs, and (seed, robots) of the recorded start-up phases.
RUNS = [("random", 0, 5, True), ("random", 1, 20, True), ("random", 2, 12, False), ("straight", 5, 20, True)]
STARTUPS = [(3, 6), (4, 12)]
#: The built-ins at their lab size, the seed of their runs, the seeds of 2.1's start-up draws for each, and
#: the iterations after which a start-up phase counts as stuck.
LAB_CASES = [("hrvo-circle", 10), ("line-consensus", 6), ("voronoi-coverage", 15), ("affine-formation", 7)]
LAB_SEED = 0
LAB_STARTUP_SEEDS = range(5)
STUCK_AFTER = 20_000
#: Three line-segment walls (M, 2, 2) inside the arena, in every run but one.
WALLS = np.array([[[-0.5, -0.6], [-0.5, 0.6]], [[0.4, 0.3], [1.2, 0.3]], [[0.0, -0.9], [0.9, -0.5]]])
#: 2.1's constants as ``cases.json`` holds them, in this order.
CONSTANTS = (
    "TIME_STEP MAX_LINEAR_VELOCITY ROBOT_DIAMETER WHEEL_RADIUS BASE_LENGTH COLLISION_DIAMETER COLLISION_OFFSET "
    "BOUNDARIES CENTER_OFFSET DISTANCE_SENSOR_ERROR DISTANCE_SENSOR_DROPOUT_PROB DISTANCE_SENSOR_OUTLIER_PROB "
    "DISTANCE_SENSOR_RANGE DISTANCE_SENSORS_ORIENTATION ENCODER_COUNTS_PER_REVOLUTION MOTOR_GEAR_RATIO "
    "IMU_ORIENTATION ENCODER_NOISE_STD ACCELEROMETER_NOISE_STDS GYRO_NOISE_STDS MAGNETOMETER_NOISE_STDS "
    "MAGNETOMETER_Z_AVG MAGNETOMETER_XY_AVG ORIENTATION_NOISE_STD MAX_WHEEL_VELOCITY MAX_ANGULAR_VELOCITY"
).split()
#: What each run's file holds after its inputs: the reading of each step, by rps's getter.
READINGS = {
    "distances": "get_distances",
    "encoders": "get_encoders",
    "accelerations": "get_accelerations",
    "gyros": "get_gyros",
    "magnetic_fields": "get_magnetic_fields",
    "orientations": "get_orientations",
}


def silence_noise() -> None:
    """Set 2.1's noise constants to zero (on the class: every instance reads them there)."""
    for name in ("DISTANCE_SENSOR_ERROR", "DISTANCE_SENSOR_DROPOUT_PROB", "DISTANCE_SENSOR_OUTLIER_PROB"):
        setattr(Robotarium, name, 0.0)
    for name in ("ENCODER_NOISE_STD", "ORIENTATION_NOISE_STD"):
        setattr(Robotarium, name, 0.0)
    for name in ("ACCELEROMETER_NOISE_STDS", "GYRO_NOISE_STDS", "MAGNETOMETER_NOISE_STDS"):
        setattr(Robotarium, name, np.zeros(3))


def spaced_poses(rng: np.random.Generator, n: int, spacing: float) -> np.ndarray:
    """Poses (3, n): positions drawn one at a time, kept when ``spacing`` (m) from those kept; then headings."""
    kept: list[np.ndarray] = []
    while len(kept) < n:
        candidate = rng.uniform([-1.4, -0.8], [1.4, 0.8])
        if all(np.hypot(*(candidate - other)) >= spacing for other in kept):
            kept.append(candidate)
    return np.vstack((np.array(kept).T, rng.uniform(-np.pi, np.pi, n)))


def commands(rng: np.random.Generator, mode: str, n: int) -> np.ndarray:
    """The ``[v; w]`` (STEPS, 2, n) of every step."""
    if mode == "random":
        return rng.uniform([[-0.25], [-4.0]], [[0.25], [4.0]], size=(STEPS, 2, n))
    turns = rng.uniform(-0.3, 0.3, size=(STEPS, n))
    return np.stack((np.full((STEPS, n), 0.15), turns), axis=1)


def record_run(mode: str, seed: int, n: int, walls: bool) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    """One run of 2.1 without its start-up phase (among :data:`WALLS`, or none): the arrays of its
    file, and its final ``_errors``."""
    obstacles = WALLS if walls else np.zeros((0, 2, 2))
    rng = np.random.default_rng(seed)
    start = spaced_poses(rng, n, 0.3)
    sent = commands(rng, mode, n)
    sim = Robotarium(
        number_of_robots=n, show_figure=False, initial_conditions=start, use_distance_sensors=True,
        obstacles=obstacles, sim_in_real_time=False, skip_initialization=True,
    )  # fmt: skip
    poses, readings = [], {name: [] for name in READINGS}
    for step in sent:
        poses.append(sim.get_poses())
        sim.set_velocities(np.arange(n), step)
        sim.step()
        for name, getter in READINGS.items():
            readings[name].append(getattr(sim, getter)())
    arrays = {"initial_conditions": start, "commands": sent, "obstacles": obstacles, "poses": np.array(poses)}
    arrays.update({name: np.array(values) for name, values in readings.items()})
    return arrays, dict(sim._errors)


def record_startup(seed: int, n: int) -> dict:
    """2.1's start-up phase from the chargers to spaced poses: where it ends, after how many iterations."""
    targets = spaced_poses(np.random.default_rng(seed), n, 0.4)
    random.seed(seed)
    np.random.seed(seed)
    with contextlib.redirect_stdout(io.StringIO()):  # its progress lines
        sim = Robotarium(number_of_robots=n, show_figure=False, initial_conditions=targets, sim_in_real_time=False)
    return {
        "seed": seed,
        "n": n,
        "initial_conditions": targets.tolist(),
        "poses_after_startup": sim.get_poses().tolist(),
        "startup_iterations": sim._iteration,
        "errors": dict(sim._errors),
    }


def startup_from(targets: np.ndarray, seed: int) -> dict:
    """2.1's start-up phase to ``targets`` with its draws seeded: its iterations (``None`` when stuck
    after :data:`STUCK_AFTER`) and which robots were at their poses (by its own test) when it ended."""

    class Bounded(Robotarium):
        def step(self) -> None:
            super().step()
            if self.initializing and self._iteration >= STUCK_AFTER:
                raise TimeoutError

    random.seed(seed)
    np.random.seed(seed)
    simulator = Bounded.__new__(Bounded)  # built apart from __init__, so that a stuck phase leaves it to read
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            simulator.__init__(number_of_robots=targets.shape[1], show_figure=False, initial_conditions=targets,
                               sim_in_real_time=False)  # fmt: skip
        iterations = simulator._iteration
    except TimeoutError:
        iterations = None
    at_pose = create_at_pose(position_error=0.05, rotation_error=0.2)(simulator._poses, targets)[1]
    return {"seed": seed, "iterations": iterations, "at_pose": at_pose.tolist()}


def record_lab() -> list[dict]:
    """For each of :data:`LAB_CASES`: 2.1's start-up phase from the experiment's poses (seed 0) and from
    the bundle's (every seed of :data:`LAB_STARTUP_SEEDS`), and the last lines of the bundle's run."""
    sys.path.insert(0, str(ROOT / "python"))
    from dream import export
    from dream.experiments import find

    cases = []
    for name, n in LAB_CASES:
        lab = export.LabRun(name, n, LAB_SEED, find(name)().params)
        own, starts = lab.stepper.requested, lab.initial_conditions  # 2.1 installed: the bundle's
        with tempfile.TemporaryDirectory() as folder:
            bundle = export.export(name, Path(folder) / "bundle", n=n, seed=LAB_SEED)
            seeded = (
                "import random, runpy, numpy; random.seed(0); numpy.random.seed(0); "
                f"runpy.run_path({str(bundle / 'main.py')!r}, run_name='__main__')"
            )
            env = {**os.environ, "DREAM_HEADLESS": "1", "MPLBACKEND": "Agg"}  # the bundle's dream/ comes first
            done = subprocess.run([sys.executable, "-c", seeded], env=env, cwd=folder, capture_output=True, text=True)
        kept = ("At initial", "No ", "Errors", "dream:")  # start-up done, rps's verdict, DREAM's
        cases.append({
            "experiment": name, "n": n, "seed": LAB_SEED,
            "own_starts": own.tolist(), "own_startup": startup_from(own, 0),
            "bundle_starts": starts.tolist(),
            "bundle_startups": [startup_from(starts, seed) for seed in LAB_STARTUP_SEEDS],
            "bundle_exit": done.returncode,
            "bundle_lines": [line for line in done.stdout.splitlines() if line.startswith(kept)],
        })  # fmt: skip
    return cases


def record() -> tuple[dict[str, dict[str, np.ndarray]], dict]:
    """Every run's arrays by file name, and the contents of ``cases.json``."""
    silence_noise()
    constants = {}
    for name in CONSTANTS:
        value = getattr(Robotarium, name)
        constants[name] = value.tolist() if isinstance(value, np.ndarray) else value
    files, cases = {}, []
    for mode, seed, n, walls in RUNS:
        name = f"{mode}_commands_seed{seed}_n{n}.npz"
        files[name], errors = record_run(mode, seed, n, walls)
        cases.append({"file": name, "mode": mode, "n": n, "steps": STEPS, "errors": errors})
    startups = [record_startup(seed, n) for seed, n in STARTUPS]
    table = {"rps_version": "2.1.0", "constants": constants, "random_command_cases": cases, "startup_cases": startups}
    return files, table


def differences(files: dict[str, dict[str, np.ndarray]], table: dict) -> list[str]:
    """Where the recording differs from the files here: runs exactly, start-up poses beyond 1e-9 m
    (its QP solver's rounding depends on the BLAS)."""
    found = []
    for name, arrays in files.items():
        with np.load(HERE / name) as stored:
            if sorted(stored.files) != sorted(arrays):
                found.append(f"{name}: arrays {sorted(stored.files)}, recorded {sorted(arrays)}")
            found += [f"{name}: {key} differs" for key in arrays if not np.array_equal(stored[key], arrays[key])]
    stored_table = json.loads((HERE / "cases.json").read_text())
    for key in ("rps_version", "constants", "random_command_cases"):
        if stored_table[key] != table[key]:
            found.append(f"cases.json: {key} differs")
    for old, new in zip(stored_table["startup_cases"], table["startup_cases"]):
        poses = np.abs(np.array(old.pop("poses_after_startup")) - new.pop("poses_after_startup")).max()
        if old != new or poses > 1e-9:
            found.append(f"cases.json: start-up case of seed {new['seed']} differs (poses by {poses:.1e} m)")
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with the files here instead of writing them")
    check = parser.parse_args().check
    files, table = record()
    lab = record_lab()
    if check:
        found = differences(files, table)
        stored = json.loads((HERE / "lab_startup.json").read_text())
        found += [f"lab_startup.json: {case['experiment']} differs" for case, old in zip(lab, stored) if case != old]
        print("\n".join(found) or f"the recording matches the {len(files)} runs, cases.json and lab_startup.json")
        return 1 if found else 0
    for name, arrays in files.items():
        np.savez_compressed(HERE / name, **arrays)
    (HERE / "cases.json").write_text(json.dumps(table, indent=1) + "\n")
    (HERE / "lab_startup.json").write_text(json.dumps(lab, indent=1) + "\n")
    print(f"wrote {', '.join(files)}, cases.json and lab_startup.json in {HERE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
