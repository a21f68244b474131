"""Sensors: detection rows, field of view, range, noise from the world's generator, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from dream import MovementSensor, OdometrySensor, Sensor, World


class _Last:
    """A sensor callback that keeps every reading."""

    def __init__(self):
        self.readings = []

    def __call__(self, values):
        self.readings.append(values)

    @property
    def last(self):
        return self.readings[-1]


def _detect(x, v, robot_id=0, **kwargs):
    got = _Last()
    MovementSensor(robot_id, "movement", got, **kwargs).update(x, v)
    assert len(got.readings) == 1
    return got.last


def test_movement_sensor_row_exact_without_noise():
    # Other robot 0.5 m ahead on +x, heading 0, command (v, w) = (0.1, 2):
    # angle from it towards us = atan2(0 - 0, 0 - 0.5) = pi;
    # vx = 0.1 cos 0 - 0.05 * 2 sin 0 = 0.1; vy = 0.1 sin 0 + 0.05 * 2 cos 0 = 0.1.
    x = np.array([[0.0, 0.5], [0.0, 0.0], [0.0, 0.0]])
    v = np.array([[0.0, 0.1], [0.0, 2.0]])
    assert_array_equal(_detect(x, v), [[0.5, math.pi, 0.1, 0.1]])


def test_movement_sensor_angle_points_from_detected_robot_to_self():
    # Self at (0.1, 0.2), other at (0.4, 0.6): distance 0.5, angle atan2(-0.4, -0.3).
    x = np.array([[0.1, 0.4], [0.2, 0.6], [0.0, 0.0]])
    (row,) = _detect(x, np.zeros((2, 2)))
    assert row[0] == pytest.approx(0.5)
    assert row[1] == pytest.approx(-(math.pi - math.atan(4 / 3)))  # = -2.2143
    assert row[1] == pytest.approx(-2.2142974355881813)


@pytest.mark.parametrize(
    ("theta", "v", "w", "vx", "vy"),
    [
        (0.0, 0.1, 0.0, 0.1, 0.0),
        (math.pi / 2, 0.1, 2.0, -0.1, 0.1),  # vx = -0.05 * 2, vy = 0.1
        (math.pi, 0.2, 0.0, -0.2, 0.0),
        (-math.pi / 2, 0.1, -1.0, -0.05, -0.1),  # vx = -0.05*(-1)*(-1), vy = -0.1
        (math.pi / 4, 0.0, 1.0, -0.05 / math.sqrt(2), 0.05 / math.sqrt(2)),
    ],
)
def test_movement_sensor_velocity_estimate_at_projection_point(theta, v, w, vx, vy):
    x = np.array([[0.0, 0.3], [0.0, 0.0], [0.0, theta]])
    commands = np.array([[0.15, v], [-1.0, w]])  # our own command must not matter
    (row,) = _detect(x, commands)
    assert row[2] == pytest.approx(vx, abs=1e-12)
    assert row[3] == pytest.approx(vy, abs=1e-12)


# Self at the origin facing +y; ahead (0, 0.4), behind (0, -0.5), right (0.6, 0), left (-0.7, 0):
# distinct distances identify who was seen.
_AROUND = np.array([[0.0, 0.0, 0.0, 0.6, -0.7], [0.0, 0.4, -0.5, 0.0, 0.0], [math.pi / 2, 0, 0, 0, 0]])


@pytest.mark.parametrize(
    ("direction", "wide", "seen"),
    [
        (0.0, 2 * math.pi, {0.4, 0.5, 0.6, 0.7}),
        (0.0, math.pi / 2, {0.4}),  # straight ahead only
        (math.pi, math.pi / 2, {0.5}),  # looks backwards
        (math.pi / 2, math.pi / 2, {0.7}),  # counter-clockwise from the heading: left
        (-math.pi / 2, math.pi / 2, {0.6}),
        (0.0, 1.1 * math.pi, {0.4, 0.6, 0.7}),  # just over a half-plane: sideways too
        (0.0, 0.0, {0.4}),  # zero aperture still sees exactly along the axis
    ],
)
def test_movement_sensor_field_of_view(direction, wide, seen):
    found = _detect(_AROUND, np.zeros((2, 5)), direction=direction, wide=wide)
    assert set(np.round(found[:, 0], 12)) == seen


@pytest.mark.parametrize(("bearing_deg", "seen"), [(40.0, True), (-40.0, True), (50.0, False), (-50.0, False)])
def test_movement_sensor_field_of_view_edges(bearing_deg, seen):
    # Heading 0.3 rad, aperture 90 degrees: +-45 degrees around the heading.
    bearing = 0.3 + math.radians(bearing_deg)
    x = np.array([[0.0, 0.5 * math.cos(bearing)], [0.0, 0.5 * math.sin(bearing)], [0.3, 0.0]])
    found = _detect(x, np.zeros((2, 2)), wide=math.pi / 2)
    assert len(found) == (1 if seen else 0)


@pytest.mark.parametrize(("distance", "seen"), [(0.5, True), (0.25, True), (0.5000001, False)])
def test_movement_sensor_range_is_inclusive(distance, seen):
    x = np.array([[0.0, -distance], [0.0, 0.0], [0.0, 0.0]])
    found = _detect(x, np.zeros((2, 2)), range=0.5)
    assert len(found) == (1 if seen else 0)


def test_movement_sensor_never_detects_itself_but_detects_co_located_robot():
    x = np.array([[0.2, 0.2, 1.0], [0.1, 0.1, 0.0], [0.0, 1.0, 0.0]])
    found = _detect(x, np.zeros((2, 3)), robot_id=1)
    # Robot 0 (same spot) at distance 0 and robot 2 at hypot(0.8, 0.1); never robot 1.
    assert found.shape == (2, 4)
    assert sorted(found[:, 0]) == pytest.approx([0.0, math.hypot(0.8, 0.1)])


@pytest.mark.parametrize("noise", [0.0, 0.1])
def test_movement_sensor_empty_detections_have_shape_0_4(noise):
    x = np.array([[0.0, 1.5], [0.0, 0.0], [0.0, 0.0]])
    found = _detect(x, np.zeros((2, 2)), noise=noise)
    assert found.shape == (0, 4)
    alone = _detect(np.zeros((3, 1)), np.zeros((2, 1)), noise=noise)
    assert alone.shape == (0, 4)


def test_movement_sensor_keeps_last_reading():
    x = np.array([[0.0, 0.5], [0.0, 0.0], [0.0, 0.0]])
    sensor = MovementSensor(0, "movement", lambda d: None)
    sensor.update(x, np.zeros((2, 2)))
    assert sensor.ret.shape == (1, 4)
    assert (sensor.pos_x, sensor.pos_y, sensor.rot_w) == (0.0, 0.0, 0.0)


def _noisy_detections(seed):
    x = np.array([[0.0, 0.5, 0.0], [0.0, 0.0, -0.4], [0.0, 0.0, 1.0]])
    v = np.array([[0.0, 0.1, 0.05], [0.0, 2.0, 0.0]])
    with World(seed=seed):
        return _detect(x, v, noise=0.01)


def test_movement_sensor_noise_is_seeded_by_the_world():
    first = _noisy_detections(11)
    assert first.shape == (2, 4)
    assert_array_equal(first, _noisy_detections(11))
    assert not np.array_equal(first, _noisy_detections(12))
    exact = np.array([[0.5, math.pi, 0.1, 0.1], [0.4, math.pi / 2, 0.05 * math.cos(1.0), 0.05 * math.sin(1.0)]])
    assert not np.array_equal(first, exact)
    assert_allclose(first, exact, atol=0.06)  # 6 standard deviations


def test_movement_sensor_noise_never_makes_a_distance_negative():
    # Robots 0.01 m and 0 m away, noise 0.1: half the draws would be below zero unclamped.
    x = np.array([[0.0, 0.01, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    readings = _Last()
    sensor = MovementSensor(0, "movement", readings, noise=0.1)
    for _ in range(200):
        sensor.update(x, np.zeros((2, 3)))
    distances = np.concatenate([reading[:, 0] for reading in readings.readings])
    assert distances.min() == 0.0 and np.mean(distances == 0.0) > 0.3
    vx = np.concatenate([reading[:, 2] for reading in readings.readings])
    assert np.mean(vx < 0) > 0.3  # the other columns keep their noise, of either sign


def test_odometry_sensor_reports_own_pose():
    x = np.array([[0.1, 0.2], [0.3, -0.4], [0.5, 1.0]])
    got = _Last()
    sensor = OdometrySensor(1, "odom", got)
    sensor.update(x)
    assert_array_equal(got.last, [0.2, -0.4, 1.0])
    assert (sensor.pos_x, sensor.pos_y, sensor.rot_w) == (0.2, -0.4, 1.0)


def _noisy_odometry(seed):
    got = _Last()
    with World(seed=seed):
        OdometrySensor(0, "odom", got, noise=0.02).update(np.array([[0.1], [0.3], [0.5]]))
    return got.last


def test_odometry_sensor_noise_is_seeded_by_the_world():
    first = _noisy_odometry(5)
    assert first.shape == (3,)
    assert_array_equal(first, _noisy_odometry(5))
    assert not np.array_equal(first, _noisy_odometry(6))
    assert not np.array_equal(first, [0.1, 0.3, 0.5])
    assert_allclose(first, [0.1, 0.3, 0.5], atol=0.12)


def test_sensor_add_noise_reproducible_and_independent_of_global_rng():
    # SPEC §9: the original drew from np.random, so runs were not reproducible.
    draws = []
    for global_seed in (1, 2):
        np.random.seed(global_seed)
        with World(seed=9):
            draws.append(Sensor(0).add_noise(np.zeros((4, 3)), 0.1))
    assert draws[0].shape == (4, 3)
    assert_array_equal(draws[0], draws[1])
    with World(seed=10):
        assert not np.array_equal(Sensor(0).add_noise(np.zeros((4, 3)), 0.1), draws[0])


def test_sensor_add_noise_draws_from_its_world(world):
    # Two draws from the same world differ: the generator advances.
    sensor = Sensor(0)
    assert not np.array_equal(sensor.add_noise([0.0, 0.0], 0.1), sensor.add_noise([0.0, 0.0], 0.1))


def test_sensor_add_noise_has_the_requested_spread():
    values = Sensor(0).add_noise(np.full(20000, 3.0), 0.1)
    assert values.mean() == pytest.approx(3.0, abs=0.005)
    assert values.std() == pytest.approx(0.1, rel=0.05)


@pytest.mark.parametrize("values", [[1.0, -2.0, 3.5], np.arange(6.0).reshape(2, 3), np.zeros((0, 4))])
def test_sensor_add_noise_zero_leaves_values_unchanged(values):
    out = Sensor(0).add_noise(values, 0.0)
    assert_array_equal(out, np.asarray(values, dtype=float))
    assert out.shape == np.shape(values)


def test_sensor_update_takes_own_pose():
    sensor = Sensor(2)
    sensor.update(np.array([[0.0, 0.0, 0.7], [0.0, 0.0, -0.2], [0.0, 0.0, 3.0]]))
    assert (sensor.pos_x, sensor.pos_y, sensor.rot_w) == (0.7, -0.2, 3.0)


@pytest.mark.parametrize("shape", [(2, 3), (3,), (3, 3, 1)])
def test_movement_sensor_rejects_bad_pose_shape(shape):
    sensor = MovementSensor(0, "movement", lambda d: None)
    with pytest.raises(ValueError, match="`x`"):
        sensor.update(np.zeros(shape), np.zeros((2, 3)))


@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (2,)])
def test_movement_sensor_rejects_bad_velocity_shape(shape):
    sensor = MovementSensor(0, "movement", lambda d: None)
    with pytest.raises(ValueError, match="`v`"):
        sensor.update(np.zeros((3, 3)), np.zeros(shape))


def test_movement_sensor_rejects_nan_velocity():
    v = np.zeros((2, 2))
    v[0, 1] = math.nan
    with pytest.raises(ValueError, match="`v`"):
        MovementSensor(0, "movement", lambda d: None).update(np.zeros((3, 2)), v)


@pytest.mark.parametrize("sensor_class", [Sensor, OdometrySensor])
def test_sensors_reject_bad_pose_shape(sensor_class):
    sensor = Sensor(0) if sensor_class is Sensor else OdometrySensor(0, "odom", lambda p: None)
    with pytest.raises(ValueError, match="`x`"):
        sensor.update(np.zeros((2, 4)))


def test_sensors_reject_nan_pose():
    x = np.zeros((3, 2))
    x[2, 0] = math.nan
    with pytest.raises(ValueError, match="`x`"):
        OdometrySensor(0, "odom", lambda p: None).update(x)


@pytest.mark.parametrize("robot_id", [2, 9, -1])  # -1 would silently be the last robot
def test_sensors_reject_robot_outside_poses(robot_id):
    with pytest.raises(IndexError, match=f"robot id {robot_id}"):
        MovementSensor(robot_id, "movement", lambda d: None).update(np.zeros((3, 2)), np.zeros((2, 2)))
    with pytest.raises(IndexError, match=f"robot id {robot_id}"):
        OdometrySensor(robot_id, "odom", lambda p: None).update(np.zeros((3, 2)))


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"range": -0.1}, "range"),
        ({"range": math.nan}, "range"),
        ({"noise": -0.01}, "noise"),
        ({"wide": -1.0}, "wide"),
    ],
)
def test_movement_sensor_rejects_invalid_parameters(kwargs, name):
    with pytest.raises(ValueError, match=name):
        MovementSensor(0, "movement", lambda d: None, **kwargs)


def test_odometry_sensor_rejects_negative_noise():
    with pytest.raises(ValueError, match="noise"):
        OdometrySensor(0, "odom", lambda p: None, noise=-0.5)


@pytest.mark.parametrize("noise", [-0.1, math.nan])
def test_sensor_add_noise_rejects_invalid_noise(noise):
    with pytest.raises(ValueError, match="noise"):
        Sensor(0).add_noise([1.0, 2.0], noise)


def test_movement_sensor_rejects_non_finite_direction():
    with pytest.raises(ValueError, match="direction"):
        MovementSensor(0, "m", lambda d: None, direction=math.nan)
