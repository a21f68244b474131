"""Record this folder's golden data from the real rps 2.1 (the Robotarium lab's simulator, not on PyPI).

Run it with rps 2.1 installed from its repository, outside DREAM's environment::

    git clone https://github.com/robotarium/robotarium_python_simulator /tmp/rps21src
    python -m venv /tmp/rps21 && /tmp/rps21/bin/pip install /tmp/rps21src
    /tmp/rps21/bin/python tests/data/rps21/record.py            # writes the .npz files and cases.json here
    /tmp/rps21/bin/python tests/data/rps21/record.py --check    # records, and compares with the files here

Every noise constant of 2.1 is set to zero, so the outputs are deterministic. The inputs come
from NumPy's ``default_rng(seed)``: poses drawn one by one in 2.8 x 1.6 m until each is 0.3 m
(start-up cases: 0.4 m) from those kept, then headings; then the commands of every step
(``random``: ``v`` in [-0.25, 0.25] m/s and ``w`` in [-4, 4] rad/s, over the wheels' limits;
``straight``: ``v = 0.15`` m/s and ``w`` in [-0.3, 0.3] rad/s). The start-up phase draws its
charger slots with :mod:`random` and its waypoints with NumPy's global generator: both are
seeded with the case's seed. The tests never import this file (rps 2.1 is no test dependency).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import random
import sys
from pathlib import Path

import numpy as np
from rps.robotarium import Robotarium

HERE = Path(__file__).resolve().parent
STEPS = 300
#: (mode, seed, robots, walls) of the recorded runs, and (seed, robots) of the recorded start-up phases.
RUNS = [("random", 0, 5, True), ("random", 1, 20, True), ("random", 2, 12, False), ("straight", 5, 20, True)]
STARTUPS = [(3, 6), (4, 12)]
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
    if check:
        found = differences(files, table)
        print("\n".join(found) or f"the recording matches the {len(files)} runs and cases.json in {HERE}")
        return 1 if found else 0
    for name, arrays in files.items():
        np.savez_compressed(HERE / name, **arrays)
    (HERE / "cases.json").write_text(json.dumps(table, indent=1) + "\n")
    print(f"wrote {', '.join(files)} and cases.json in {HERE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
