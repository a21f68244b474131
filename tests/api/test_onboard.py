"""The GRITSbot's onboard sensors (rps 2.1's model): recorded readings, ray casting against its
reference, and the documented noise model."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

import dream
from dream import World, _reference, kernels
from dream.backends import Fast
from dream.onboard import DistanceSensor, EncoderSensor, ImuReading, ImuSensor, distance_noise
from dream.specs import ONBOARD, RPS2

GOLDEN = Path(__file__).parents[1] / "data" / "rps21"  # recorded from rps 2.1 by its record.py
FILES = sorted(path.name for path in GOLDEN.glob("*.npz"))
EXACT = ONBOARD.noiseless()


def replay(data):
    """Yields the Fast backend (rps 2.1 rules) after each recorded step."""
    sim = Fast(data["initial_conditions"], spec=RPS2, obstacles=data["obstacles"])
    for commands in data["commands"]:
        sim.get_poses()
        sim.set_velocities(np.arange(sim.number_of_robots), commands)
        sim.step()
        yield sim


def reference_rays(poses, walls, robots=None):
    return _reference.distance_rays(
        poses,
        np.asarray(walls, dtype=float).reshape(-1, 4),
        np.array(ONBOARD.rays),
        centre_offset=ONBOARD.centre_offset,
        robot_diameter=ONBOARD.robot_diameter,
        range=ONBOARD.range,
        robots=robots,
    )


def test_onboard_sensors_are_exported():
    assert dream.DistanceSensor is DistanceSensor and dream.EncoderSensor is EncoderSensor
    assert dream.ImuSensor is ImuSensor


# -- noiseless readings against the recordings of rps 2.1 ---------------------------------------------
@pytest.mark.parametrize("name", FILES)
def test_sensors_without_noise_reproduce_the_recorded_readings(name):
    data = np.load(GOLDEN / name)
    n = data["initial_conditions"].shape[1]
    readings: dict[str, list] = {"distances": [], "encoders": [], "imu": []}
    watched = [0, n - 1]
    distance = [DistanceSensor(i, "ir", readings["distances"].append, data["obstacles"], noise=False) for i in watched]
    encoders = [EncoderSensor(i, "enc", readings["encoders"].append, noise=False) for i in range(n)]
    imus = [ImuSensor(i, "imu", readings["imu"].append, noise=False) for i in range(n)]
    for step, sim in enumerate(replay(data)):
        poses, applied = sim.poses, sim.velocities
        swarm = kernels.distance_rays(poses, data["obstacles"], spec=EXACT)
        assert_allclose(swarm, data["distances"][step], rtol=0, atol=1e-9)
        for sensor in distance:
            sensor.update(poses)
        assert_allclose(np.column_stack(readings["distances"]), data["distances"][step][:, watched], atol=1e-9)
        for sensor in encoders:
            sensor.update(poses, applied)
        assert_array_equal(np.column_stack(readings["encoders"]), data["encoders"][step])
        for sensor in imus:
            sensor.update(poses, applied)
        imu = readings["imu"]
        assert_allclose(np.column_stack([r.acceleration for r in imu]), data["accelerations"][step], atol=1e-9)
        assert_allclose(np.column_stack([r.gyro for r in imu]), data["gyros"][step], atol=1e-9)
        assert_allclose(np.column_stack([r.magnetic_field for r in imu]), data["magnetic_fields"][step], atol=1e-9)
        assert_allclose([r.orientation for r in imu], data["orientations"][step], atol=1e-9)
        for values in readings.values():
            values.clear()
    assert np.mean(data["distances"] >= 0) > 0.1  # the recordings do see walls and robots


# -- ray casting: Rust against the NumPy reference ------------------------------------------------------
@pytest.mark.parametrize("n", [0, 1, 2, 40, 300])
@pytest.mark.parametrize("m", [0, 1, 12])
def test_distance_rays_match_reference(rng, n, m):
    side = 1.0 + np.sqrt(n) * 0.3  # crowded enough that rays hit robots
    poses = np.vstack((rng.uniform(-side, side, (2, n)), rng.uniform(-np.pi, np.pi, n)))
    walls = rng.uniform(-side, side, (m, 2, 2))
    got = kernels.distance_rays(poses, walls)
    assert got.shape == (7, n)
    assert_allclose(got, reference_rays(poses, walls), rtol=0, atol=1e-12)
    assert np.all((got == -1) | ((got >= 0) & (got < ONBOARD.range)))
    if n:
        some = rng.choice(n, size=min(n, 3), replace=False)
        subset = kernels.distance_rays(poses, walls, robots=some)
        assert_allclose(subset[:, some], got[:, some], rtol=0, atol=0)
        assert np.all(np.delete(subset, some, axis=1) == -1)


def test_distance_rays_see_a_wall_and_a_robot_ahead():
    # Robot 0 faces +x; its front ray starts 0.01 + 0.05 m ahead of the pose.
    poses = np.array([[0.0, 0.5], [0.0, 0.0], [0.0, np.pi]])
    walls = np.array([[[1.0, -1.0], [1.0, 1.0]]])
    got = kernels.distance_rays(poses, walls)
    assert got[3, 0] == pytest.approx((0.5 - 0.01) - 0.06 - 0.055)  # robot 1's disc, around its offset centre
    # Robot 1 faces -x: its rear ray (angle pi) looks towards +x, at the wall.
    assert got[0, 1] == pytest.approx(1.0 - (0.5 - 0.01 + 0.04))
    lonely = kernels.distance_rays(poses[:, :1])  # no walls, no robots: the arena's edges are not seen
    assert np.all(lonely == -1)


def test_distance_rays_reject_bad_input():
    with pytest.raises(ValueError, match="walls"):
        kernels.distance_rays(np.zeros((3, 2)), np.zeros((2, 4)))
    with pytest.raises(ValueError, match="robots"):
        kernels.distance_rays(np.zeros((3, 2)), robots=[2])
    with pytest.raises(ValueError, match="poses"):
        kernels.distance_rays(np.full((3, 2), np.nan))


# -- the noise model ------------------------------------------------------------------------------------
def test_distance_noise_follows_the_documented_model():
    rng = np.random.default_rng(5)
    true = np.where(np.arange(200_000) % 10 == 0, -1.0, 0.6)
    noisy = distance_noise(true, rng)
    assert np.all(noisy[true < 0] == -1)
    hits = noisy[true > 0]
    size = hits.size
    dropped = np.mean(hits == -1)
    assert abs(dropped - ONBOARD.dropout) < 5 * np.sqrt(ONBOARD.dropout / size)
    kept = hits[hits >= 0]
    assert np.all((kept >= 0) & (kept <= ONBOARD.range))
    # Beyond 8 sigma of 0.6 m only the uniform outliers land, on 1 - 2 band / range of their range.
    band = 8 * ONBOARD.distance_error * 0.6
    expected = ONBOARD.outlier * (1 - 2 * band / ONBOARD.range)
    outliers = np.abs(kept - 0.6) > band
    assert abs(outliers.mean() - expected) < 5 * np.sqrt(expected / kept.size)
    # Without dropouts and outliers, the spread is 3 % of the distance.
    gaussian = distance_noise(np.full(100_000, 0.6), rng, replace(ONBOARD, dropout=0.0, outlier=0.0))
    assert gaussian.std() / 0.6 == pytest.approx(ONBOARD.distance_error, rel=0.02)
    assert gaussian.mean() == pytest.approx(0.6, abs=5 * 0.018 / np.sqrt(100_000))


def test_noise_comes_from_the_world_generator():
    poses = np.array([[0.0, 0.4], [0.0, 0.0], [0.0, 0.0]])

    def readings(seed):
        out: list = []
        with World(seed=seed):
            sensor = DistanceSensor(0, "ir", out.append)
            for _ in range(50):
                sensor.update(poses)
        return np.array(out)

    assert_array_equal(readings(3), readings(3))
    assert not np.array_equal(readings(3), readings(4))


def test_encoder_noise_has_the_documented_spread():
    counts: list = []
    sensor = EncoderSensor(0, "enc", counts.append)
    poses = np.zeros((3, 1))
    # Standing still: each step's count is round(N(0, 0.25)), nonzero when |noise| > 0.5 (2 sigma).
    for _ in range(20_000):
        sensor.update(poses, np.zeros((2, 1)))
    steps = np.diff(np.array(counts), axis=0, prepend=0)
    assert np.mean(steps != 0) == pytest.approx(0.0455, abs=0.006)
    # Driving: ~4.4 counts per step per wheel at 0.1 m/s, std 0.25 sqrt(4.4) before rounding.
    fast: list = []
    moving = EncoderSensor(0, "enc", fast.append)
    for _ in range(20_000):
        moving.update(poses, np.array([[0.1], [0.0]]))
    deltas = np.diff(np.array(fast), axis=0, prepend=0)
    expected = 0.1 / 0.016 * 0.033 * 28 * 100.37 / (2 * np.pi)
    assert deltas.mean() == pytest.approx(expected, abs=0.02)
    assert deltas.std() == pytest.approx(np.sqrt(0.25**2 * expected + 1 / 12), rel=0.06)


def test_imu_noise_has_the_documented_stds():
    out: list[ImuReading] = []
    sensor = ImuSensor(0, "imu", out.append)
    for _ in range(10_000):
        sensor.update(np.array([[0.0], [0.0], [1.0]]), np.array([[0.0], [2.0]]))
    acceleration = np.array([r.acceleration for r in out])
    assert_allclose(acceleration.std(axis=0), ONBOARD.accelerometer_noise, rtol=0.05)
    assert_allclose(np.array([r.gyro for r in out]).std(axis=0), ONBOARD.gyro_noise, rtol=0.05)
    assert_allclose(np.array([r.magnetic_field for r in out]).std(axis=0), ONBOARD.magnetometer_noise, rtol=0.05)
    assert np.std([r.orientation for r in out]) == pytest.approx(ONBOARD.compass_noise, rel=0.05)
    assert_allclose(
        acceleration.mean(axis=0), [-4 * ONBOARD.imu_position[0], -4 * ONBOARD.imu_position[1], -9.81], atol=2e-3
    )


def test_encoder_rejects_bad_steps_and_commands():
    sensor = EncoderSensor(0, "enc", lambda counts: None)
    with pytest.raises(ValueError, match="steps"):
        sensor.update(np.zeros((3, 1)), np.zeros((2, 1)), steps=0)
    with pytest.raises(ValueError, match="`v`"):
        sensor.update(np.zeros((3, 1)), np.zeros((2, 3)))
