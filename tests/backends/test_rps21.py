"""rps 2.1's rules: the Fast backend against poses and counts recorded from 2.1, both rps generations
behind the Robotarium backend, and 2.1's start-up phase from the chargers."""

from __future__ import annotations

import json
import sys
import types
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from dream import _reference, cli, kernels
from dream.backends import Fast, Robotarium, make_robotarium, rps_generation
from dream.backends.startup import RPS2_BARRIER_SPACING, RPS2_PROJECTION, START_SPACING, charger_poses, reachable_starts
from dream.specs import ROBOTARIUM, RPS0, RPS2, RULES

GOLDEN = Path(__file__).parents[1] / "data" / "rps21"  # recorded from rps 2.1 by its record.py
CASES = json.loads((GOLDEN / "cases.json").read_text())
FILES = [case["file"] for case in CASES["random_command_cases"]]
#: rps 2.1's `_errors` keys in the order of DREAM's Violations.
ERROR_KEYS = ("robots_outside_boundaries", "robots_too_close", "exceeded_actuator_limits")


def wrapped(angles):
    return np.angle(np.exp(1j * angles))


def replay(data):
    """Runs the recorded commands on Fast with rps 2.1's rules; returns the poses before each step."""
    sim = Fast(data["initial_conditions"], spec=RPS2, obstacles=data["obstacles"])
    n = sim.number_of_robots
    poses = []
    for commands in data["commands"]:
        poses.append(sim.get_poses())
        sim.set_velocities(np.arange(n), commands)
        sim.step()
    return sim, np.array(poses)


# -- the constants ---------------------------------------------------------------------------------
def test_rps2_rules_hold_the_recorded_constants():
    c = CASES["constants"]
    assert RPS2.time_step == c["TIME_STEP"] and RPS2.max_linear == c["MAX_LINEAR_VELOCITY"]
    assert (RPS2.wheel_radius, RPS2.base_length) == (c["WHEEL_RADIUS"], c["BASE_LENGTH"])
    assert (RPS2.diameter, RPS2.collider_offset) == (c["COLLISION_DIAMETER"], c["COLLISION_OFFSET"])
    assert RPS2.max_wheel == pytest.approx(c["MAX_WHEEL_VELOCITY"], abs=1e-12)
    assert ROBOTARIUM.bounds == tuple(c["BOUNDARIES"])
    assert RULES == {"rps0": RPS0, "rps2": RPS2} and RPS0.base_length == 0.105


# -- parity with the recorded runs -----------------------------------------------------------------
@pytest.mark.parametrize("name", FILES)
def test_fast_with_rps2_rules_reproduces_recorded_poses_and_counts(name):
    data = np.load(GOLDEN / name)
    sim, poses = replay(data)
    expected = data["poses"]
    assert poses.shape == expected.shape
    assert_allclose(poses[:, :2], expected[:, :2], rtol=0, atol=1e-9)
    assert_allclose(wrapped(poses[:, 2] - expected[:, 2]), 0.0, rtol=0, atol=1e-9)
    errors = next(case["errors"] for case in CASES["random_command_cases"] if case["file"] == name)
    assert tuple(sim.violations) == tuple(errors.get(key, 0) for key in ERROR_KEYS)
    assert sim.iterations == len(data["commands"])


def test_recorded_cases_tell_the_generations_apart():
    # The straight case collides and leaves the arena: rps 0.0.0's rules count it differently, and
    # the random cases' spins are within 0.0.0's separate v/w limits far more often.
    for name in FILES:
        data = np.load(GOLDEN / name)
        old = Fast(data["initial_conditions"], spec=RPS0)
        for commands in data["commands"]:
            old.get_poses()
            old.set_velocities(np.arange(old.number_of_robots), commands)
            old.step()
        assert np.abs(old.poses[:2] - data["poses"][-1][:2]).max() > 1e-3


# -- validation and thresholding kernels: Rust against the NumPy reference --------------------------
@pytest.mark.parametrize("n", [0, 1, 2, 17, 200])
def test_validate_with_rps2_rules_matches_reference(rng, n):
    for _ in range(20):
        poses = np.vstack((rng.uniform(-1.8, 1.8, n), rng.uniform(-1.2, 1.2, n), rng.uniform(-np.pi, np.pi, n)))
        commands = np.vstack((rng.uniform(-0.25, 0.25, n), rng.uniform(-4.0, 4.0, n)))
        rules = {
            "diameter": RPS2.diameter,
            "wheel_radius": RPS2.wheel_radius,
            "base_length": RPS2.base_length,
            "max_wheel": RPS2.max_wheel,
            "collider_offset": RPS2.collider_offset,
            "boundary_per_iteration": True,
        }
        expected = _reference.validate(poses, commands, ROBOTARIUM.bounds, **rules)[:3]
        assert tuple(kernels.validate(poses, commands, spec=RPS2)) == expected
        assert expected[0] in (0, 1)


def test_validate_counts_offset_colliders_that_centres_would_miss():
    # 0.15 m apart, facing each other: colliders 0.10 m apart (rps 2.1 counts), centres 0.15 (0.0.0 does not).
    poses = np.array([[0.0, 0.15], [0.0, 0.0], [0.0, np.pi]])
    assert kernels.validate(poses, np.zeros((2, 2)), spec=RPS2).collision == 1
    assert kernels.validate(poses, np.zeros((2, 2)), spec=RPS0).collision == 0
    # Back to back 0.12 m apart: the colliders are 0.17 m apart, so rps 2.1 counts nothing.
    back = np.array([[0.0, 0.12], [0.0, 0.0], [np.pi, 0.0]])
    assert kernels.validate(back, np.zeros((2, 2)), spec=RPS2).collision == 0


def test_validate_counts_the_boundary_once_per_iteration_with_rps2_rules():
    poses = np.array([[1.7, -1.7, 0.0], [0.0, 0.0, 1.2], [0.0, 0.0, 0.0]])
    assert kernels.validate(poses, np.zeros((2, 3)), spec=RPS2).boundary == 1
    assert kernels.validate(poses, np.zeros((2, 3)), spec=RPS0).boundary == 3


@pytest.mark.parametrize("n", [0, 1, 5, 300])
def test_threshold_wheels_matches_reference_and_respects_the_wheel_limit(rng, n):
    commands = np.vstack((rng.uniform(-0.4, 0.4, n), rng.uniform(-8.0, 8.0, n)))
    got = kernels.threshold_velocities(commands, RPS2)
    wheels = {"wheel_radius": RPS2.wheel_radius, "base_length": RPS2.base_length, "max_wheel": RPS2.max_wheel}
    assert_allclose(got, _reference.threshold_wheels(commands, **wheels), rtol=0, atol=1e-15)
    assert np.all(np.abs(kernels.wheel_speeds(got, RPS2)) <= RPS2.max_wheel + 1e-9)
    inside = np.all(np.abs(kernels.wheel_speeds(commands, RPS2)) <= RPS2.max_wheel, axis=0)
    assert_allclose(got[:, inside], commands[:, inside], rtol=0, atol=1e-15)


def test_validate_rejects_a_non_finite_collider_offset():
    from dataclasses import replace

    with pytest.raises(ValueError, match="collider_offset"):
        kernels.validate(np.zeros((3, 2)), np.zeros((2, 2)), spec=replace(RPS2, collider_offset=float("nan")))


# -- the backend protocol: both report names, and make_robotarium's rules ---------------------------
def test_debug_and_call_at_scripts_end_print_the_same_report(capsys):
    sim = Fast(np.array([[0.0, 1.7], [0.0, 0.0], [0.0, 0.0]]), spec=RPS2)
    sim.get_poses()
    sim.set_velocities(np.arange(2), np.array([[0.1, 0.0], [9.0, 0.0]]))
    sim.step()
    sim.debug()
    first = capsys.readouterr().out
    sim.call_at_scripts_end()
    assert capsys.readouterr().out == first
    assert "1 iteration(s) with robots outside" in first and "actuator" in first


def test_make_robotarium_follows_the_installed_rps_by_default_and_takes_rules():
    assert make_robotarium(3, backend="fast", seed=0).spec == RULES[rps_generation() or "rps0"]
    sim = make_robotarium(3, seed=0, rules="rps2")
    assert type(sim) is Fast and sim.spec == RPS2
    with pytest.raises(ValueError, match="'rps1'"):
        make_robotarium(3, seed=0, rules="rps1")


def test_fast_takes_the_rules_by_name():
    assert Fast(np.zeros((3, 1)), rules="rps2").spec == RPS2
    assert Fast(np.zeros((3, 1)), rules="rps0").spec == RPS0
    with pytest.raises(ValueError, match="'rps3'"):
        Fast(np.zeros((3, 1)), rules="rps3")
    with pytest.raises(ValueError, match="disagree"):
        Fast(np.zeros((3, 1)), spec=RPS2, rules="rps0")


@pytest.mark.skipif(rps_generation() != "rps0", reason="needs rps 0.0.0 installed")
def test_make_robotarium_refuses_other_rules_on_the_installed_rps():
    with pytest.raises(ValueError, match="rps2"):
        make_robotarium(3, backend="robotarium", seed=0, rules="rps2")
    with pytest.raises(ValueError, match="skip_initialization"):
        Robotarium(np.zeros((3, 1)), skip_initialization=False)


class FakeRps2:
    """Stands in for rps 2.x's Robotarium: keyword-only construction, `_poses`, `debug()`."""

    made: ClassVar[list[dict]] = []

    stuck = False  #: whether the start-up phase deadlocks

    def __init__(self, **kwargs):
        FakeRps2.made.append(kwargs)
        self._poses = kwargs["initial_conditions"].copy()
        self._velocities = np.zeros((2, kwargs["number_of_robots"]))
        self._iteration = 0
        self.initializing = True
        if not kwargs["skip_initialization"]:
            self.step()
            while self.stuck:
                self.step()
            self._poses[:2] += 0.01  # the start-up phase ends near, not at, the initial conditions
        self.initializing = False

    def _validate(self, errors):
        return errors

    def get_poses(self):
        return self._poses.copy()

    def set_velocities(self, ids, velocities):
        self._velocities[:, ids] = velocities

    def step(self):
        self._iteration += 1
        self._poses[0] += 0.033 * self._velocities[0] * np.cos(self._poses[2])

    def debug(self):
        pass


@pytest.fixture
def fake_rps2(monkeypatch):
    package, module = types.ModuleType("rps"), types.ModuleType("rps.robotarium")
    module.Robotarium = FakeRps2
    package.robotarium = module
    monkeypatch.setitem(sys.modules, "rps", package)
    monkeypatch.setitem(sys.modules, "rps.robotarium", module)
    FakeRps2.made.clear()
    return FakeRps2


def test_robotarium_backend_drives_rps2_without_throttling_and_passes_its_options(fake_rps2):
    assert rps_generation() == "rps2"
    walls = np.array([[[-0.5, -0.6], [-0.5, 0.6]]])
    start = np.array([[0.0, 0.5], [0.0, 0.0], [0.0, 0.0]])
    assert Robotarium(start).iterations == 0  # DREAM's default: start at the initial conditions
    assert fake_rps2.made[-1]["skip_initialization"] is True
    sim = Robotarium(start, obstacles=walls, use_distance_sensors=True, skip_initialization=False)
    options = fake_rps2.made[-1]
    assert options["sim_in_real_time"] is False and options["skip_initialization"] is False
    assert_array_equal(options["obstacles"], walls) and options["use_distance_sensors"] is True
    assert sim.spec == RPS2
    assert_allclose(sim.get_poses()[:2], start[:2] + 0.01)  # poses where rps's start-up left them
    sim.set_velocities(np.arange(2), np.array([[0.1, 0.1], [0.0, 0.0]]))
    sim.step()
    assert_allclose(sim.poses[0], start[0] + 0.01 + 0.0033)
    Robotarium(start, skip_initialization=True, sim_in_real_time=True)
    assert fake_rps2.made[-1]["skip_initialization"] is True and fake_rps2.made[-1]["sim_in_real_time"] is True
    assert make_robotarium(2, initial_conditions=start).spec == RPS2  # auto: the installed generation


def test_make_robotarium_runs_rps2s_start_up_phase_to_starts_it_reaches_unless_told_not_to(fake_rps2):
    close = np.array([[0.0, 0.2, -1.0], [0.0, 0.0, 0.5], [0.0, 3.0, 1.0]])  # the first two block each other
    sim = make_robotarium(3, backend="robotarium", initial_conditions=close)
    options = fake_rps2.made[-1]
    assert options["skip_initialization"] is False
    assert_array_equal(options["initial_conditions"], reachable_starts(close))
    assert np.hypot(*(options["initial_conditions"][:2, 0] - options["initial_conditions"][:2, 1])) >= START_SPACING
    assert_allclose(sim.poses[:2], options["initial_conditions"][:2] + 0.01)  # where the phase left them
    make_robotarium(3, backend="robotarium", initial_conditions=close, startup=False)
    assert fake_rps2.made[-1]["skip_initialization"] is True
    assert_array_equal(fake_rps2.made[-1]["initial_conditions"], close)


def test_run_on_rps2_goes_through_its_start_up_phase_unless_told_not_to(fake_rps2):
    import dream

    dream.run("hrvo-circle", n=10, seed=0, backend="robotarium", steps=1)
    started = fake_rps2.made[-1]
    assert started["skip_initialization"] is False and started["number_of_robots"] == 10
    dream.run("hrvo-circle", n=10, seed=0, backend="robotarium", steps=1, startup=False)
    skipped = fake_rps2.made[-1]
    assert skipped["skip_initialization"] is True
    # hrvo-circle's own starts are 0.2 m apart, which 2.1's start-up never reaches: those are moved.
    assert_array_equal(started["initial_conditions"], reachable_starts(skipped["initial_conditions"]))
    assert not np.array_equal(started["initial_conditions"], skipped["initial_conditions"])
    # The command line: the phase unless --skip-startup.
    run = ["run", "line-consensus", "--backend", "robotarium", "--steps", "1", "--no-progress"]
    assert cli.main(run) == 0 and fake_rps2.made[-1]["skip_initialization"] is False
    assert cli.main([*run, "--skip-startup"]) == 0 and fake_rps2.made[-1]["skip_initialization"] is True


def test_robotarium_backend_stops_a_deadlocked_rps2_start_up_with_an_error(fake_rps2, monkeypatch):
    monkeypatch.setattr(fake_rps2, "stuck", True)
    with pytest.raises(RuntimeError, match="skip_initialization=True"):
        Robotarium(np.zeros((3, 1)), skip_initialization=False)
    assert Robotarium(np.zeros((3, 1)), skip_initialization=True).iterations == 0


# -- the start-up phase ------------------------------------------------------------------------------
def test_charger_poses_are_distinct_slots_on_the_edges_facing_inwards(rng):
    poses = charger_poses(22, rng)
    assert len({(x, y) for x, y in poses[:2].T.round(9)}) == 22
    assert_allclose(np.abs(poses[1]), 0.945)
    assert_allclose(poses[2], np.where(poses[1] < 0, np.pi / 2, -np.pi / 2))
    with pytest.raises(ValueError, match="22 charger slots"):
        charger_poses(23, rng)


def _gaps(points):
    gaps = np.hypot(*(points[:, :, None] - points[:, None, :]))
    return gaps[~np.eye(points.shape[1], dtype=bool)]


def test_reachable_starts_moves_only_starts_too_close_and_keeps_headings(rng):
    # A cluster 0.2 m apart in a corner, and robots already far apart elsewhere.
    cluster = np.array([[x, y] for x in (-1.1, -0.9, -0.7) for y in (-0.6, -0.4)]).T
    spread = np.array([[0.5, 1.0, 0.5], [0.5, 0.0, -0.5]])
    poses = np.vstack((np.hstack((cluster, spread)), rng.uniform(-np.pi, np.pi, 9)))
    starts = reachable_starts(poses)
    assert _gaps(starts[:2]).min() >= START_SPACING - 1e-12
    assert_array_equal(starts[2], poses[2])
    assert_array_equal(starts[:, 6:], poses[:, 6:])  # already far apart: kept
    assert_array_equal(starts[:, 0], poses[:, 0])  # the first of the cluster stays, the next moves
    assert np.hypot(*(starts - poses)[:2]).max() < 1.0  # moved to nearby free points
    assert np.all(np.abs(starts[0]) <= 1.25 + 1e-9) and np.all(np.abs(starts[1]) <= 0.75 + 1e-9)
    # Whatever the headings, the points rps 2.1's barrier keeps apart are then far enough apart.
    for headings in rng.uniform(-np.pi, np.pi, (50, 9)):
        ahead = starts[:2] + RPS2_PROJECTION * np.vstack((np.cos(headings), np.sin(headings)))
        assert _gaps(ahead).min() >= RPS2_BARRIER_SPACING
    assert_array_equal(reachable_starts(starts), starts)
    with pytest.raises(ValueError, match="20 robots do not fit 1.0 m apart"):
        reachable_starts(np.zeros((3, 20)), spacing=1.0)


@pytest.mark.parametrize("case", CASES["startup_cases"], ids=lambda case: f"n={case['n']}")
def test_start_up_reaches_the_recorded_initial_conditions_without_violations(case):
    targets = np.array(case["initial_conditions"])
    sim = Fast(targets, spec=RPS2, start_up=True, rng=np.random.default_rng(case["seed"]))
    report = sim.startup
    assert report is not None
    assert np.all(np.isin(report.chargers[1], [-0.945, 0.945]))
    reached = sim.get_poses()
    assert np.hypot(*(reached[:2] - targets[:2])).max() <= 0.02
    assert np.abs(wrapped(reached[2] - targets[2])).max() <= 0.18
    assert tuple(report.violations) == (0, 0, 0)
    # Comparable to rps 2.1's own start-up (570 and 1085 iterations), not counted in the experiment.
    assert 0 < report.iterations < 3 * case["startup_iterations"]
    assert sim.iterations == 0 and tuple(sim.violations) == (0, 0, 0)
