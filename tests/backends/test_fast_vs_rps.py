"""The Fast backend against the real Robotarium simulator (rps): same poses, same counts."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from rps.robotarium import Robotarium as Rps

from dream.backends import Fast, Robotarium

KEYS = ("boundary", "collision", "actuator")


def new_rps(poses):
    return Rps(
        number_of_robots=poses.shape[1], show_figure=False, sim_in_real_time=False, initial_conditions=poses.copy()
    )


def wrapped(angles):
    """Angles folded into (-pi, pi]: pi and -pi are the same heading."""
    return np.angle(np.exp(1j * angles))


def assert_same_poses(got, expected, atol=1e-9):
    assert_allclose(got[:2], expected[:2], rtol=0, atol=atol)
    assert_allclose(wrapped(got[2] - expected[2]), 0.0, rtol=0, atol=atol)


def random_start(rng, n):
    # Spread out in the arena, some robots close to the walls so that they leave it.
    return np.vstack((rng.uniform(-1.5, 1.5, n), rng.uniform(-0.9, 0.9, n), rng.uniform(-np.pi, np.pi, n)))


def random_commands(rng, n):
    # Up to 1.5x the linear limit and 3x the angular one: rps's thresholding matters.
    return np.vstack((rng.uniform(-0.3, 0.3, n), rng.uniform(-11.0, 11.0, n)))


def rps_counts(sim, before=None):
    """Counts in rps's ``_errors`` (missing key = 0), minus those of ``before``."""
    before = before or {}
    return tuple(sim._errors.get(key, 0) - before.get(key, 0) for key in KEYS)


@pytest.mark.parametrize("n", [1, 5, 20])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fast_reproduces_rps_poses(n, seed):
    rng = np.random.default_rng(seed)
    start = random_start(rng, n)
    sim, fast = new_rps(start), Fast(start.copy())
    ids = np.arange(n)
    travelled = 0.0
    for _ in range(300):
        expected = sim.get_poses().copy()  # rps returns its own array, updated in place later
        got = fast.get_poses()
        assert_same_poses(got, expected)
        commands = random_commands(rng, n)
        sim.set_velocities(ids, commands.copy())  # rps thresholds its argument in place
        fast.set_velocities(ids, commands.copy())
        assert_array_equal(fast.velocities, sim.velocities)
        sim.step()
        fast.step()
        travelled += np.hypot(*(fast.poses[:2] - got[:2])).sum()
    assert_same_poses(fast.poses, sim.poses)
    assert fast.iterations == 300
    assert travelled > 0.5 * n  # the robots did move (about 1.3 m each)


@pytest.mark.parametrize("n", [1, 5, 20])
def test_fast_reproduces_rps_poses_with_gentle_commands_over_long_runs(n):
    # Smooth commands within the limits for 1000 steps: the rounding must not drift.
    rng = np.random.default_rng(100 + n)
    start = random_start(rng, n)
    sim, fast = new_rps(start), Fast(start.copy())
    v = rng.uniform(-0.1, 0.1, n)
    w = rng.uniform(-1.0, 1.0, n)
    for k in range(1000):
        sim.get_poses()
        fast.get_poses()
        commands = np.vstack((v * np.cos(0.01 * k), w))
        sim.set_velocities(np.arange(n), commands.copy())
        fast.set_velocities(np.arange(n), commands.copy())
        sim.step()
        fast.step()
    assert_same_poses(fast.poses, sim.poses)


def _provoking_run(backend_factory, steps=120):
    """A run with every kind of violation: a touching pair, a robot driving out of the arena,
    a robot spinning too fast; returns the backend and a raw rps run on the same commands."""
    start = np.array(
        [
            [0.0, 0.05, 1.5, -1.0, -0.5, 0.7],  # robots 0 and 1 touch; 2 is near the right wall
            [0.0, 0.0, 0.0, 0.5, -0.5, -0.9],  # robot 5 is near the bottom wall
            [0.0, np.pi, 0.0, 0.0, 1.0, -np.pi / 2],
        ]
    )
    n = start.shape[1]
    backend = backend_factory(start.copy())
    sim = new_rps(start)
    before = dict(sim._validate.__defaults__[0]) if sim._validate.__defaults__ else {}
    rng = np.random.default_rng(9)
    for k in range(steps):
        backend.get_poses()
        sim.get_poses()
        commands = np.zeros((2, n))
        commands[:, 2] = 0.2, 0.0  # out through the right wall after ~15 steps
        commands[:, 3] = (0.2, 3.0) if k % 3 else (0.05, 0.5)  # too fast for a wheel two steps in three
        commands[:, 4] = rng.uniform(-0.5, 0.5), rng.uniform(-9.0, 9.0)  # random, beyond limits
        commands[:, 5] = 0.15, 0.0  # out through the bottom wall
        backend.set_velocities(np.arange(n), commands.copy())
        sim.set_velocities(np.arange(n), commands.copy())
        backend.step()
        sim.step()
    return backend, sim, before


@pytest.mark.parametrize("make", [Fast, Robotarium], ids=["fast", "robotarium"])
def test_backend_violations_equal_rps_counts(make):
    backend, sim, before = _provoking_run(make)
    expected = rps_counts(sim, before)
    assert all(count > 0 for count in expected)  # every kind was provoked
    assert tuple(backend.violations) == expected
    assert_same_poses(backend.poses, sim.poses)
    if isinstance(backend, Robotarium):
        # the wrapped rps instance counted the same (in its own, isolated dict)
        assert rps_counts(backend.rps) == expected


def test_fast_and_robotarium_backends_agree_step_by_step(rng):
    start = random_start(rng, 12)
    start[:2, 1] = start[:2, 0] + [0.08, 0.0]  # a collision from the first step
    fast, real = Fast(start.copy()), Robotarium(start.copy())
    for _ in range(200):
        assert_same_poses(fast.get_poses(), real.get_poses())
        commands = random_commands(rng, 12)
        fast.set_velocities(np.arange(12), commands.copy())
        real.set_velocities(np.arange(12), commands.copy())
        fast.step()
        real.step()
        assert fast.violations == real.violations
    assert fast.violations.collision > 0 and fast.violations.actuator > 0


def test_robotarium_backends_do_not_share_counts():
    # rps 0.0.0's `_validate(errors={})` default dict is shared by every instance in a process;
    # DREAM gives each backend its own.
    first, _, _ = _provoking_run(Robotarium, steps=60)
    assert all(count > 0 for count in first.violations)
    assert rps_counts(first.rps) == tuple(first.violations)

    quiet = np.array([[-1.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    second = Robotarium(quiet)
    for _ in range(30):
        second.get_poses()
        second.set_velocities(np.arange(3), np.array([[0.05, 0.05, 0.05], [0.0, 0.0, 0.0]]))
        second.step()
    assert tuple(second.violations) == (0, 0, 0)
    assert rps_counts(second.rps) == (0, 0, 0)
    assert second.rps._errors is not first.rps._errors
    # and the first one kept its own counts
    assert rps_counts(first.rps) == tuple(first.violations)

    third, _, _ = _provoking_run(Robotarium, steps=60)
    assert tuple(third.violations) == tuple(first.violations)  # same run, same counts: no carry-over
    assert rps_counts(third.rps) == tuple(first.violations)


def test_robotarium_backend_does_not_alias_caller_arrays():
    start = np.array([[0.0], [0.0], [0.0]])
    backend = Robotarium(start)
    poses = backend.get_poses()
    commands = np.array([[1.0], [20.0]])
    backend.set_velocities([0], commands)
    assert_array_equal(commands, [[1.0], [20.0]])  # not thresholded in place
    backend.step()
    assert_array_equal(poses, np.zeros((3, 1)))  # a copy, not rps's live array
    assert_array_equal(start, np.zeros((3, 1)))
    assert backend.poses[0, 0] == pytest.approx(0.2 * 0.033)
