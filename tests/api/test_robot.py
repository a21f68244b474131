"""Robot: unicycle conversion, actuator limits, unknown pose, and HRVO on hand-made scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from dream import MovementSensor, OdometrySensor, Robot, RobotHRVO, create_timer, kernels, update_timers
from dream.specs import RobotSpec


def _placed(robot, x=0.0, y=0.0, theta=0.0):
    """``robot`` with its pose set, as its odometry callback would."""
    robot.pos_x, robot.pos_y, robot.rot_w = x, y, theta
    return robot


# v = vel_gain (c dx + s dy), w = ang_gain atan2(-s dx + c dy, v) / (pi/2), worked by hand.
@pytest.mark.parametrize(
    ("theta", "dxi", "gains", "v", "w"),
    [
        (0.0, (0.1, 0.0), (0.8, 3.0), 0.08, 0.0),
        (math.pi / 2, (0.1, 0.0), (0.8, 3.0), 0.0, -3.0),  # target on the right: turn clockwise
        (0.0, (0.0, 0.1), (0.8, 3.0), 0.0, 3.0),  # target on the left
        (0.0, (-0.1, 0.0), (0.8, 3.0), -0.08, 6.0),  # behind: atan2(+0, -0.08) = pi
        (math.pi / 4, (0.1, 0.1), (0.8, 3.0), 0.08 * math.sqrt(2), 0.0),
        (0.0, (0.1, 0.1), (1.0, 2.0), 0.1, 1.0),  # 2 * (pi/4) / (pi/2)
        (math.pi, (0.0, 0.2), (0.5, 1.0), 0.0, -1.0),  # facing -x, target at +y is on the right
        (0.0, (0.0, 0.0), (0.8, 3.0), 0.0, 0.0),
    ],
)
def test_robot_dxi_to_dxu_hand_worked(theta, dxi, gains, v, w):
    robot = _placed(Robot(0, vel_gain=gains[0], ang_gain=gains[1]), theta=theta)
    robot.dxi = np.array(dxi)
    robot.dxi_to_dxu()
    assert robot.dxu[0] == pytest.approx(v, abs=1e-12)
    assert robot.dxu[1] == pytest.approx(w, abs=1e-12)


def test_robot_dxi_to_dxu_ignores_position():
    robot = _placed(Robot(0), x=1.2, y=-0.7, theta=0.0)
    robot.dxi = np.array([0.1, 0.0])
    robot.dxi_to_dxu()
    assert robot.dxu[0] == pytest.approx(0.08)
    assert robot.dxu[1] == pytest.approx(0.0)


# With r = 0.016 and L = 0.105 the wheel test |v|/r + |w| L/(2r) > 12.5 reads |v| + 0.0525|w| > 0.2;
# when it fails, |v| becomes 0.2 - 0.0525|w|.
@pytest.mark.parametrize(
    ("dxu", "expected"),
    [
        ((0.1, 0.0), (0.1, 0.0)),
        ((0.05, 1.0), (0.05, 1.0)),  # 0.05 + 0.0525 < 0.2: untouched
        ((0.5, 0.0), (0.2, 0.0)),  # clamped to v_max
        ((-0.5, 0.0), (-0.2, 0.0)),
        ((0.0, 10.0), (0.0, 3.636363)),  # clamped to w_max, no wheel problem without v
        ((0.0, -10.0), (0.0, -3.636363)),
        ((0.1, 2.0), (0.095, 2.0)),  # 0.1 + 0.105 > 0.2: v = 0.2 - 0.105
        ((-0.1, -2.0), (-0.095, -2.0)),
        ((-0.15, 3.0), (-0.0425, 3.0)),  # v = -(0.2 - 0.1575), sign kept
        ((0.3, 6.0), (0.2 - 0.0525 * 3.636363, 3.636363)),  # both clamps, then the wheels
    ],
)
def test_robot_actuator_limit_hand_worked(dxu, expected):
    robot = Robot(0)
    robot.dxu = np.array(dxu)
    robot.actuator_limit()
    assert robot.dxu[0] == pytest.approx(expected[0], abs=1e-12)
    assert robot.dxu[1] == pytest.approx(expected[1], abs=1e-12)
    # The result never needs a wheel faster than allowed.
    wheel = abs(robot.dxu[0]) / 0.016 + abs(robot.dxu[1]) * 0.105 / (2 * 0.016)
    assert wheel <= 12.5 + 1e-9


def test_robot_actuator_limit_uses_the_robot_spec():
    robot = Robot(0, spec=RobotSpec(v_max=0.1, w_max=1.0))
    robot.dxu = np.array([0.15, -2.0])
    robot.actuator_limit()
    assert robot.dxu[0] == pytest.approx(0.1)
    assert robot.dxu[1] == pytest.approx(-1.0)


def test_robot_conversion_and_limits_are_the_kernels_robot_by_robot(rng):
    """The object robot's own conversion and limits (scalar Python, for speed on one robot) give
    the whole-swarm kernels' commands, on random poses, velocities, gains and limits."""
    n = 300
    poses = np.vstack((rng.uniform(-1, 1, (2, n)), rng.uniform(-4, 4, n)))
    dxi = rng.normal(0, 0.15, (2, n))
    dxi[:, :5] = 0.0  # standing still: atan2(0, 0)
    spec = RobotSpec(v_max=0.15, w_max=2.5)
    for gains in ((0.8, 3.0), (1.3, 0.7)):
        converted = kernels.dxi_to_dxu(dxi, poses, *gains)
        limited = kernels.actuator_limit(converted, spec)
        for i in range(n):
            robot = _placed(Robot(i, vel_gain=gains[0], ang_gain=gains[1], spec=spec), *poses[:, i])
            robot.dxi = dxi[:, i].copy()
            robot.dxi_to_dxu()
            assert_allclose(robot.dxu, converted[:, i], rtol=1e-12, atol=1e-15)
            robot.dxu = converted[:, i].copy()
            robot.actuator_limit()
            assert_allclose(robot.dxu, limited[:, i], rtol=1e-12, atol=1e-15)
    assert (np.abs(limited[0]) < np.abs(converted[0])).any()  # the limits were put to work


def test_robot_has_the_gritsbot_limits():
    robot = Robot(0)
    assert (robot.v_max, robot.w_max, robot.ac_max, robot.r_wheel, robot.r_length) == (
        0.2,
        3.636363,
        12.5,
        0.016,
        0.105,
    )
    assert robot.dxi.shape == robot.dxu.shape == (2,)


def test_robot_without_pose_commands_zero():
    robot = Robot(0)
    assert not robot.has_pose
    robot.dxi = np.array([0.1, 0.05])
    robot.dxu = np.array([0.3, 0.3])
    robot.dxi_to_dxu()
    assert_array_equal(robot.dxu, [0.0, 0.0])
    _placed(robot)
    assert robot.has_pose


def test_robot_hrvo_without_pose_returns_zero():
    robot = RobotHRVO(0, "robot")
    robot.dxi = np.array([0.1, 0.1])
    result = robot.HRVO(np.array([[0.3, math.pi, 0.0, 0.0]]), np.array([0.2, 0.0]))
    assert_array_equal(result, [0.0, 0.0])
    assert_array_equal(robot.dxi, [0.0, 0.0])


class _SeedStyleRobot(RobotHRVO):
    """A robot written as in the thesis's Appendix B: callbacks set its pose and detections."""

    def __init__(self, robot_id, tag, goal):
        self.goal = np.asarray(goal, dtype=float)
        self.desired_velocity = np.array((0.0, 0.0))
        super().__init__(robot_id, tag)

    def update_sensor(self, detections):
        self.detections = detections

    def update_odom(self, pos):
        self.pos_x = pos[0]
        self.pos_y = pos[1]
        self.rot_w = pos[2]

    def update(self, dxu_):
        delta_x = self.goal[0] - self.pos_x
        delta_y = self.goal[1] - self.pos_y
        dist_error = np.sqrt(delta_x**2 + delta_y**2)
        if dist_error < 0.05:
            self.desired_velocity = np.array((0.0, 0.0))
        else:
            self.desired_velocity[0] = self.v_max * delta_x / dist_error
            self.desired_velocity[1] = self.v_max * delta_y / dist_error
        self.HRVO(self.detections, self.desired_velocity)
        self.dxi_to_dxu()
        self.actuator_limit()
        dxu_[0][self.robot_id] = self.dxu[0]
        dxu_[1][self.robot_id] = self.dxu[1]


def test_robot_hrvo_controller_before_sensors_on_first_tick_commands_zero():
    # SPEC §9: timers fire in list order, so on the first tick the controller runs before
    # the odometry; the original then steered from pose (0, 0, 0).
    x = np.array([[0.5, -0.5], [0.3, -0.3], [2.0, -1.0]])
    dxu = np.full((2, 2), 0.07)
    robots = []
    for i in range(2):
        robot = _SeedStyleRobot(i, f"robot_{i}", goal=(1.0, -0.8))
        mov = MovementSensor(i, f"movement_{i}", robot.update_sensor)
        odo = OdometrySensor(i, f"odom_{i}", robot.update_odom)
        create_timer(
            i,
            0,
            [
                {"delay": 2, "tag": "robot", "call": robot.update},  # the controller first
                {"delay": 1, "tag": "movement", "call": mov.update},
                {"delay": 1, "tag": "odom", "call": odo.update},
            ],
        )
        robots.append(robot)
    params = {"movement": (x, dxu), "odom": (x,), "robot": (dxu,)}

    update_timers(2, params)
    assert dxu.tolist() == [[0.0, 0.0], [0.0, 0.0]]  # exactly zero, not merely small
    assert all(robot.has_pose for robot in robots)  # the sensors did run after it

    update_timers(4, params)  # now the pose is known: the robots move
    assert np.all(np.abs(dxu) > 0)


def test_robot_hrvo_no_detections_returns_desired_velocity():
    robot = _placed(RobotHRVO(0, "robot"))
    result = robot.HRVO(np.zeros((0, 4)), np.array([0.1, 0.05]))
    assert_array_equal(result, [0.1, 0.05])
    assert_array_equal(robot.dxi, [0.1, 0.05])


def test_robot_hrvo_accepts_empty_list_of_detections():
    robot = _placed(RobotHRVO(0, "robot"))
    assert_array_equal(robot.HRVO([], [-0.02, 0.03]), [-0.02, 0.03])


def test_robot_hrvo_clamps_desired_velocity_to_v_max():
    robot = _placed(RobotHRVO(0, "robot"))
    result = robot.HRVO(np.zeros((0, 4)), np.array([0.3, 0.4]))  # norm 0.5 -> 0.2
    assert result == pytest.approx([0.12, 0.16])
    assert np.hypot(*robot.dxi) <= 0.2 + 1e-12


@pytest.mark.parametrize("other_velocity", [(0.0, 0.0), (-0.1, 0.0)])
def test_robot_hrvo_avoids_robot_straight_ahead(other_velocity):
    # The other robot is 0.3 m ahead on +x; the seed's angle points from it to us: pi.
    robot = _placed(RobotHRVO(0, "robot"))
    detections = np.array([[0.3, math.pi, *other_velocity]])
    result = robot.HRVO(detections, np.array([0.2, 0.0]))
    assert not np.allclose(result, [0.2, 0.0])
    speed = np.hypot(*result)
    assert speed > 0  # there is room to move sideways
    # Not strictly inside the reciprocal velocity obstacle: the cone of half-angle
    # asin(0.24/0.3) around +x with its apex at (own previous velocity 0 + other's) / 2. (The
    # HRVO moves one edge's apex out to the other's velocity, which only widens the cone.)
    relative = result - np.asarray(other_velocity) / 2
    half_angle = math.asin(0.24 / 0.3)
    assert abs(math.atan2(relative[1], relative[0])) >= half_angle - 1e-9


def test_robot_hrvo_ignores_robot_behind():
    # The other robot is behind us (angle from it to us is 0 = +x): the way ahead is free.
    robot = _placed(RobotHRVO(0, "robot"))
    result = robot.HRVO(np.array([[0.3, 0.0, 0.0, 0.0]]), np.array([0.2, 0.0]))
    assert_array_equal(result, [0.2, 0.0])


@pytest.mark.parametrize(
    ("position", "desired", "axis", "limit"),
    [
        ((1.5, 0.0), (0.2, 0.0), 0, 1.6 - 0.055),
        ((-1.5, 0.0), (-0.2, 0.0), 0, -(1.6 - 0.055)),
        ((0.0, 0.92), (0.0, 0.2), 1, 1.0 - 0.055),
        ((0.0, -0.92), (0.0, -0.2), 1, -(1.0 - 0.055)),
    ],
)
def test_robot_hrvo_check_boundaries_keeps_body_inside(position, desired, axis, limit):
    robot = _placed(RobotHRVO(0, "robot"), *position)
    result = robot.HRVO(np.zeros((0, 4)), np.array(desired))
    ahead = np.asarray(position) + result
    assert abs(ahead[axis]) < abs(limit)  # strictly inside the arena shrunk by the radius
    assert abs(ahead[1 - axis]) < 0.945
    # Among what stays inside it still heads out as far as it may.
    assert np.sign(result[axis]) == np.sign(desired[axis])


def test_robot_hrvo_check_boundaries_corner():
    robot = _placed(RobotHRVO(0, "robot"), 1.5, 0.9)
    result = robot.HRVO(np.zeros((0, 4)), np.array([0.15, 0.1]))
    assert 1.5 + result[0] < 1.545
    assert 0.9 + result[1] < 0.945


def test_robot_hrvo_without_boundary_check_may_leave():
    robot = _placed(RobotHRVO(0, "robot", check_boundaries=False), 1.5)
    result = robot.HRVO(np.zeros((0, 4)), np.array([0.2, 0.0]))
    assert_array_equal(result, [0.2, 0.0])
    assert 1.5 + result[0] > 1.6


@pytest.mark.parametrize("shape", [(1, 3), (2, 5), (4,)])
def test_robot_hrvo_rejects_bad_detections_shape(shape):
    robot = _placed(RobotHRVO(0, "robot"))
    with pytest.raises(ValueError, match="`detections`"):
        robot.HRVO(np.ones(shape), np.array([0.1, 0.0]))


def test_robot_hrvo_rejects_nan_detections():
    robot = _placed(RobotHRVO(0, "robot"))
    with pytest.raises(ValueError, match="`detections`"):
        robot.HRVO(np.array([[0.3, math.nan, 0.0, 0.0]]), np.array([0.1, 0.0]))


@pytest.mark.parametrize("desired", [(math.nan, 0.0), (0.1, math.inf), (0.1, 0.0, 0.0)])
def test_robot_hrvo_rejects_bad_desired_velocity(desired):
    robot = _placed(RobotHRVO(0, "robot"))
    with pytest.raises(ValueError, match="`desired_velocity`"):
        robot.HRVO(np.zeros((0, 4)), np.array(desired))


@pytest.mark.parametrize("robot_id", [-1, 1.5, "3", True, None])
@pytest.mark.parametrize("robot_class", [Robot, RobotHRVO])
def test_robot_rejects_invalid_robot_id(robot_class, robot_id):
    with pytest.raises(ValueError, match="robot_id"):
        robot_class(robot_id, "robot")


def test_robot_accepts_numpy_integer_id():
    assert Robot(np.int64(4)).robot_id == 4


@pytest.mark.parametrize("safety", [-0.1, math.nan])
def test_robot_hrvo_rejects_invalid_safety(safety):
    with pytest.raises(ValueError, match="safety"):
        RobotHRVO(0, "robot", safety=safety)


@pytest.mark.parametrize("empty", [[], np.zeros(0), np.zeros((0, 4))])
def test_robot_hrvo_treats_empty_detections_as_nobody_around(empty):
    # The original sensor reported "nothing" as an empty 1-D array; both forms mean free space.
    robot = RobotHRVO(0, "r", check_boundaries=False)
    robot.pos_x, robot.pos_y, robot.rot_w = 0.0, 0.0, 0.0
    assert_array_equal(robot.HRVO(empty, np.array([0.1, 0.0])), [0.1, 0.0])


def test_robot_hrvo_rejects_empty_detections_of_the_wrong_width():
    robot = RobotHRVO(0, "r")
    robot.pos_x, robot.pos_y, robot.rot_w = 0.0, 0.0, 0.0
    with pytest.raises(ValueError, match="detections"):
        robot.HRVO(np.zeros((0, 3)), np.array([0.1, 0.0]))
