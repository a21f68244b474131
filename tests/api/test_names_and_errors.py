"""The original names, the specs constants, and an original-style script that runs unchanged."""

from __future__ import annotations

import dataclasses
import math
import textwrap

import numpy as np
import pytest

import dream
from dream import specs
from dream.specs import ArenaSpec, RobotSpec

ORIGINAL_NAMES = [
    "Robot",
    "Robot_hrvo",
    "Sensor",
    "Movement_sensor",
    "Odometry_sensor",
    "Radio",
    "Radio_range",
    "Timer",
    "create_timer",
    "update_timers",
]

SPEC_CONSTANTS = [
    "R_V_MAX",
    "R_W_MAX",
    "R_AC_MAX",
    "R_R_WHEEL",
    "R_R_LENGTH",
    "T_WIDTH",
    "T_HEIGHT",
    "T_ORIGIN_X",
    "T_ORIGIN_Y",
    "T_MAX_WIDTH",
    "T_MIN_WIDTH",
    "T_MAX_HEIGHT",
    "T_MIN_HEIGHT",
]


def _star_namespace():
    namespace = {}
    exec("from dream import *", namespace)
    return namespace


@pytest.mark.parametrize("name", ORIGINAL_NAMES + SPEC_CONSTANTS + ["GraphRadio", "World"])
def test_star_import_provides_name(name):
    namespace = _star_namespace()
    assert name in namespace
    assert namespace[name] is getattr(dream, name)


@pytest.mark.parametrize(
    ("original", "pep8"),
    [
        ("Robot_hrvo", "RobotHRVO"),
        ("Movement_sensor", "MovementSensor"),
        ("Odometry_sensor", "OdometrySensor"),
        ("Radio_range", "RangeRadio"),
    ],
)
def test_original_and_pep8_names_are_the_same_object(original, pep8):
    assert getattr(dream, original) is getattr(dream, pep8)
    assert _star_namespace()[original] is getattr(dream, pep8)


def test_original_class_hierarchy():
    assert issubclass(dream.Robot_hrvo, dream.Robot)
    assert issubclass(dream.Movement_sensor, dream.Sensor)
    assert issubclass(dream.Odometry_sensor, dream.Sensor)
    assert issubclass(dream.Radio_range, dream.Radio)
    assert issubclass(dream.GraphRadio, dream.Radio)


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("R_V_MAX", 0.2),
        ("R_W_MAX", 3.636363),
        ("R_AC_MAX", 12.5),
        ("R_R_WHEEL", 0.016),
        ("R_R_LENGTH", 0.105),
        ("T_WIDTH", 3.2),
        ("T_HEIGHT", 2.0),
        ("T_ORIGIN_X", 0.0),
        ("T_ORIGIN_Y", 0.0),
        ("T_MAX_WIDTH", 1.6),
        ("T_MIN_WIDTH", -1.6),
        ("T_MAX_HEIGHT", 1.0),
        ("T_MIN_HEIGHT", -1.0),
    ],
)
def test_specs_constant_has_thesis_value(name, value):
    assert getattr(specs, name) == pytest.approx(value, abs=1e-15)
    assert getattr(dream, name) == getattr(specs, name)


def test_specs_dataclasses_default_to_the_constants():
    robot = RobotSpec()
    assert (robot.v_max, robot.w_max, robot.ac_max, robot.wheel_radius, robot.base_length) == (
        0.2,
        3.636363,
        12.5,
        0.016,
        0.105,
    )
    assert robot.radius == pytest.approx(0.055)
    assert ArenaSpec().bounds == pytest.approx((-1.6, 1.6, -1.0, 1.0))


def test_arena_spec_centred_and_shrunk():
    arena = ArenaSpec.centred(width=32.0, height=20.0)
    assert arena.bounds == (-16.0, 16.0, -10.0, 10.0)
    assert (arena.width, arena.height) == (32.0, 20.0)
    assert arena.shrunk(0.5) == (-15.5, 15.5, -9.5, 9.5)


@pytest.mark.parametrize(
    "bounds",
    [
        (1.0, 1.0, -1.0, 1.0),  # xmin == xmax
        (2.0, 1.0, -1.0, 1.0),  # xmin > xmax
        (-1.0, 1.0, 0.5, 0.5),
        (-1.0, 1.0, 1.0, -1.0),
        (-math.inf, 1.0, -1.0, 1.0),
        (-1.0, math.nan, -1.0, 1.0),
    ],
)
def test_arena_spec_rejects_invalid_bounds(bounds):
    with pytest.raises(ValueError, match="arena"):
        ArenaSpec(*bounds)


@pytest.mark.parametrize(("spec", "field"), [(RobotSpec(), "v_max"), (ArenaSpec(), "xmin"), (specs.RPS, "time_step")])
def test_specs_are_frozen(spec, field):
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(spec, field, 1.0)


def test_robot_spec_override_is_a_new_value():
    fast = dataclasses.replace(RobotSpec(), v_max=0.5)
    assert fast.v_max == 0.5
    assert RobotSpec().v_max == 0.2


# A script in the style of the thesis's Appendix B, against DREAM's Fast backend instead of
# rps: subclass of Robot_hrvo with callbacks, sensors, range radio, timers, explicit loop.
ORIGINAL_SCRIPT = textwrap.dedent(
    """
    import numpy as np
    import dream
    from dream import *

    class Robot_c(Robot_hrvo):
        def __init__(self, robot_id, tag, goal, vel_gain=0.8, ang_gain=3, safety=0.24):
            self.robot_id = robot_id
            self.tag = tag
            self.goal = goal
            self.desired_velocity = np.array((0.0, 0.0))
            self.heard = []
            super().__init__(self.robot_id, self.tag, vel_gain=vel_gain, ang_gain=ang_gain, safety=safety)

        def update_radio(self, radio_data):
            self.heard.append(len(radio_data))
            return [self.robot_id, self.pos_x, self.pos_y]

        def update_sensor(self, detections):
            self.detections = detections

        def update_odom(self, pos):
            self.pos_x = pos[0]
            self.pos_y = pos[1]
            self.rot_w = pos[2]

        def update(self, dxu_):
            self.delta_x = self.goal[0] - self.pos_x
            self.delta_y = self.goal[1] - self.pos_y
            dist_error = np.sqrt(self.delta_x ** 2 + self.delta_y ** 2)
            if dist_error < 0.05:
                self.desired_velocity = np.array((0.0, 0.0))
            else:
                self.desired_velocity[0] = self.v_max * self.delta_x / dist_error
                self.desired_velocity[1] = self.v_max * self.delta_y / dist_error
            self.HRVO(self.detections, self.desired_velocity)
            self.dxi_to_dxu()
            self.actuator_limit()
            dxu_[0][self.robot_id] = self.dxu[0]
            dxu_[1][self.robot_id] = self.dxu[1]

    N = 4
    iterations = 200
    goals = np.array([[0.6, -0.6, -0.6, 0.6], [0.5, 0.5, -0.5, -0.5]])

    r = dream.make_robotarium(N, backend="fast", seed=1)

    robot_tag = 'robot'
    movement_tag = 'movement'
    odometry_tag = 'odom'
    radio_tag = 'radio'

    robots = []
    for i in range(N):
        rob = Robot_c(i, f'{robot_tag}_{i}', goal=goals[:, i])
        mov = Movement_sensor(i, f'{movement_tag}_{i}', rob.update_sensor)
        odo = Odometry_sensor(i, f'{odometry_tag}_{i}', rob.update_odom)
        rad = Radio_range(i, f'{radio_tag}_{i}', rob.update_radio, range=5.0)
        list_timers = [
            {'delay': 4 + (i % 2), 'tag': robot_tag, 'call': rob.update},
            {'delay': 3 + (i % 2), 'tag': movement_tag, 'call': mov.update},
            {'delay': 2 + (i % 2), 'tag': odometry_tag, 'call': odo.update},
            {'delay': 30, 'tag': radio_tag, 'call': rad.update},
        ]
        create_timer(i, 20 + i, list_timers)
        robots.append(rob)

    dxu = np.zeros((2, N))
    x = r.get_poses()
    start = x.copy()
    r.step()

    for i in range(iterations):
        x = r.get_poses()
        params = {movement_tag: (x, dxu), odometry_tag: (x,), radio_tag: (x,), robot_tag: (dxu,)}
        update_timers(i, params)
        r.set_velocities(np.arange(N), dxu)
        r.step()

    final = r.poses
    """
)


def test_original_style_script_runs_unchanged_and_moves_robots_to_goals(world):
    namespace = {"__name__": "original_script"}
    exec(compile(ORIGINAL_SCRIPT, "original_script.py", "exec"), namespace)
    goals, start, final = namespace["goals"], namespace["start"], namespace["final"]
    before = np.linalg.norm(start[:2] - goals, axis=0)
    after = np.linalg.norm(final[:2] - goals, axis=0)
    # ~175 active steps at up to 0.8 * 0.2 m/s x 0.033 s: at most ~0.9 m each. Every robot
    # either arrived (tolerance 0.05) or covered a good part of the way.
    assert np.all(after < before)
    assert np.all((after < 0.1) | (after < before - 0.3))
    assert after.sum() < 0.5 * before.sum()
    # Everything went through the test's world: its timers and the radios' board.
    assert len(world.timers) == 4
    assert sorted(world.messages) == [0, 1, 2, 3]
    assert all(robot.heard and robot.heard[-1] == 3 for robot in namespace["robots"])
    r = namespace["r"]
    assert r.iterations == 201
    assert r.violations.collision == 0
