"""Sensors: how a robot perceives itself and the others, with optional seeded noise.

Each sensor reads the simulator's pose array ``x`` ``(3, n)``, keeps its own robot's pose as
its origin and reports through a callback. Noise is Gaussian with standard deviation
``noise``, drawn from the world's generator, so a seeded world gives reproducible runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from dream import kernels
from dream._checks import FloatArray, RobotCallback, check_nonnegative, check_robot_id
from dream.world import current_world

if TYPE_CHECKING:
    from dream.obstacles import Obstacle

#: Distance ahead of a robot's centre at which its velocity is estimated (m).
PROJECTION_DISTANCE = 0.05


class Sensor:
    """Base sensor attached to robot ``robot_id``.

    A sensor's ``update`` reads the simulator's arrays and hands the reading to its
    ``callback`` (subclasses take one).

    Attributes
    ----------
    pos_x, pos_y, rot_w : float
        Pose of the robot the sensor is attached to, at the last :meth:`update`.
    ret : any
        The last reading.
    """

    def __init__(self, robot_id: int, tag: str = "Sensor") -> None:
        self.robot_id = robot_id
        self.tag = tag
        self.pos_x = 0.0
        self.pos_y = 0.0
        self.rot_w = 0.0
        self.ret: Any = 0
        self.noise = 0.0  #: standard deviation of the noise on every value of a reading
        self.world = current_world()

    def add_noise(self, values: Any, noise: float) -> FloatArray:
        """``values`` plus Gaussian noise of standard deviation ``noise`` (world's generator)."""
        array = np.array(values, dtype=np.float64)
        if check_nonnegative(noise, "noise") > 0:
            array = array + self.world.rng.normal(0.0, noise, array.shape)
        return array

    callback: Callable[[Any], Any] = RobotCallback()  # type: ignore[assignment]

    def _report(self, values: Any) -> None:
        """Hand a reading to ``self.callback``: with this sensor's noise, and the world's sensor
        faults (a dropped reading never arrives; fault noise adds to the sensor's own)."""
        noise = self.noise
        state = self.world.fault_state
        if state is not None:
            if state.dropped():
                return
            noise = math.hypot(noise, state.faults.sensor_noise)
        # Without noise, the reading is the values as an array of its own: skip the noise checks.
        self.ret = np.array(values, dtype=np.float64) if noise == 0.0 else self.add_noise(values, noise)
        self.callback(self.ret)

    def update(self, x: Any) -> None:
        """Take the attached robot's pose from the pose array ``x`` ``(3, n)``."""
        poses = self.world.checked_poses(x)
        check_robot_id(self.robot_id, poses.shape[1], "x")
        self.pos_x, self.pos_y, self.rot_w = poses[:, self.robot_id].tolist()
        self._poses = poses


def seen_velocity(commands: np.ndarray, headings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(vx, vy)`` ``(k,)`` that a movement sensor reports for robots of last unicycle commands
    ``commands`` ``(2, k)`` and headings ``headings`` ``(k,)``: the velocity of the point
    :data:`PROJECTION_DISTANCE` ahead of each."""
    velocities = kernels.dxu_to_dxi(commands, headings, PROJECTION_DISTANCE)
    return velocities[0], velocities[1]


class MovementSensor(Sensor):
    """Detects the position and velocity of the other robots in range and field of view.

    Parameters
    ----------
    callback : callable
        Receives the detections, an array ``(k, 4)`` of rows ``[distance, angle, vx, vy]``.
    range : float
        Largest distance detected (m, inclusive).
    direction : float
        Sensor axis relative to the robot's heading (rad, counter-clockwise).
    wide : float
        Full aperture (rad); ``2 pi`` sees all around.
    noise : float
        Standard deviation of the noise added to every value (a distance is clamped at 0).

    Notes
    -----
    ``angle`` is the direction *from the detected robot towards this robot*,
    ``atan2(y_self - y_other, x_self - x_other)``: the original DREAM convention, kept so that
    original experiments run unchanged (``RobotHRVO.HRVO`` expects it). ``(vx, vy)`` is the
    detected robot's velocity estimated from its last command ``(v, w)`` and heading ``th`` at
    a point 0.05 m ahead of it: ``vx = v cos th - 0.05 w sin th``,
    ``vy = v sin th + 0.05 w cos th``. A robot never detects itself; robots at the same spot
    detect each other.
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        callback: Callable[[FloatArray], Any],
        range: float = 1.0,  # noqa: A002 (original name)
        direction: float = 0.0,
        wide: float = 2 * np.pi,
        noise: float = 0.0,
    ) -> None:
        super().__init__(robot_id, tag)
        self.callback = callback
        self.range = check_nonnegative(range, "range")
        self.direction = float(direction)
        if not np.isfinite(self.direction):
            raise ValueError(f"`direction` must be finite, got {direction}")
        self.wide = check_nonnegative(wide, "wide")
        self.noise = check_nonnegative(noise, "noise")

    def update(self, x: Any, v: Any) -> None:  # type: ignore[override]
        """Detect from poses ``x`` ``(3, n)`` and last commands ``v`` ``(2, n)``; call the callback."""
        super().update(x)
        poses = self._poses
        commands = self.world.checked_commands(v, poses.shape[1])
        found, distances = self.world.neighbours_of(
            poses, self.robot_id, self.range, heading=self.rot_w, direction=self.direction, fov=self.wide
        )
        detections = np.empty((len(found), 4))  # filled column by column: cheaper than stacking
        detections[:, 0] = distances
        seen = poses[:, found]
        detections[:, 1] = np.arctan2(self.pos_y - seen[1], self.pos_x - seen[0])
        detections[:, 2], detections[:, 3] = seen_velocity(commands[:, found], seen[2])
        self._report(detections)

    def add_noise(self, values: Any, noise: float) -> FloatArray:
        """Detections ``(k, 4)`` plus Gaussian noise, their distances clamped at 0: noise on a robot
        close by must not report it at a negative distance (which HRVO refuses)."""
        noisy = super().add_noise(values, noise)
        np.maximum(noisy[:, 0], 0.0, out=noisy[:, 0])
        return noisy


class OdometrySensor(Sensor):
    """Reports the attached robot's own pose ``[x, y, theta]`` (plus noise) to ``callback``."""

    def __init__(self, robot_id: int, tag: str, callback: Callable[[FloatArray], Any], noise: float = 0.0) -> None:
        super().__init__(robot_id, tag)
        self.callback = callback
        self.noise = check_nonnegative(noise, "noise")

    def update(self, x: Any) -> None:
        """Read the pose from ``x`` ``(3, n)`` and call the callback."""
        super().update(x)
        self._report([self.pos_x, self.pos_y, self.rot_w])


class ObstacleSensor(Sensor):
    """Measures the closest point of every obstacle within ``range`` (m, inclusive).

    The callback receives an array ``(k, 2)`` of closest points in world coordinates, obstacles
    in the given order (noise, if any, is added to every coordinate). An obstacle the robot is
    inside of is not reported. The sensor reads the obstacles' current positions, so moving
    obstacles are seen where they are.
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        callback: Callable[[FloatArray], Any],
        obstacles: Sequence[Obstacle],
        range: float = 1.0,  # noqa: A002 (as the other sensors)
        noise: float = 0.0,
    ) -> None:
        super().__init__(robot_id, tag)
        self.callback = callback
        self.obstacles = obstacles
        self.range = check_nonnegative(range, "range")
        self.noise = check_nonnegative(noise, "noise")

    def update(self, x: Any) -> None:
        """Measure from the attached robot's pose in ``x`` ``(3, n)`` and call the callback."""
        super().update(x)
        found = self.world.obstacles_near(self._poses, self.robot_id, self.obstacles, self.range)
        self._report(found[~np.isnan(found[:, 0])])
