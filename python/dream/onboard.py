"""The GRITSbot's onboard sensors, as rps 2.1 models them: infrared distance sensors, wheel
encoders and an IMU (accelerometer, gyro, magnetometer, compass).

Each sensor follows DREAM's pattern: built with ``(robot_id, tag, callback, ...)``, updated by
a timer with the simulator's arrays, it calls ``callback(reading)``. Their constants and noise
model are :class:`dream.specs.OnboardSpec` (:data:`dream.specs.ONBOARD`); noise is drawn from
the world's seeded generator, so a seeded world gives reproducible readings. With
``noise=False`` the readings equal rps 2.1's recorded ones.

For a whole swarm at once, call :func:`dream.kernels.distance_rays` and :func:`distance_noise`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from dream import kernels
from dream._checks import FloatArray, as_array
from dream.sensors import Sensor
from dream.specs import ONBOARD, RPS2, OnboardSpec, SimulatorSpec

__all__ = ["DistanceSensor", "EncoderSensor", "ImuReading", "ImuSensor", "distance_noise"]


def distance_noise(readings: Any, rng: np.random.Generator, spec: OnboardSpec = ONBOARD) -> FloatArray:
    """Noisy copies of noiseless distance readings (any shape; -1 = nothing), rps 2.1's model.

    A reading that saw something is dropped (-1) with probability ``spec.dropout``; otherwise
    it is replaced by a uniform value in ``[0, spec.range)`` with probability ``spec.outlier``;
    otherwise Gaussian noise of std ``spec.distance_error`` times the distance is added and the
    result clipped to ``[0, spec.range]``. -1 stays -1. The same number of draws is taken
    whatever the readings, so runs stay aligned.
    """
    values = np.array(readings, dtype=np.float64)
    dropped = rng.random(values.shape) < spec.dropout
    outlier = rng.random(values.shape) < spec.outlier
    uniform = rng.uniform(0.0, spec.range, values.shape)
    noisy = np.clip(values + spec.distance_error * values * rng.standard_normal(values.shape), 0.0, spec.range)
    seen = values >= 0
    return np.where(~seen | dropped, -1.0, np.where(outlier, uniform, noisy))


class DistanceSensor(Sensor):
    """The robot's seven infrared distance sensors.

    Parameters
    ----------
    callback : callable
        Receives the readings ``(k,)`` (m; -1 where nothing is within range), one per ray of
        ``spec.rays`` (the GRITSbot's: rear left, left, front left, front, front right, right,
        rear right).
    walls : (m, 2, 2) array_like, optional
        Line-segment walls (``[i, 0]`` start, ``[i, 1]`` end). Other robots are always seen,
        as discs of ``spec.robot_diameter``; the arena's edges are not (rps 2.1 does not).
    noise : bool
        Apply the documented noise model (:func:`distance_noise`); off, the readings are exact.
    spec : OnboardSpec
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        callback: Callable[[FloatArray], Any],
        walls: Any = None,
        noise: bool = True,
        spec: OnboardSpec = ONBOARD,
    ) -> None:
        super().__init__(robot_id, tag)
        self.callback = callback
        self.walls = np.zeros((0, 2, 2)) if walls is None else as_array(walls, "walls", (None, 2, 2))
        self.noise = bool(noise)
        self.spec = spec

    def update(self, x: Any) -> None:
        """Cast the rays from the poses ``x`` ``(3, n)``; call the callback with the readings."""
        super().update(x)
        exact = kernels.distance_rays(self._poses, self.walls, spec=self.spec, robots=[self.robot_id])
        readings = exact[:, self.robot_id]
        if self.noise:
            readings = distance_noise(readings, self.world.rng, self.spec)
        self.ret = readings
        self.callback(readings)


class EncoderSensor(Sensor):
    """The wheel encoders: counts ``[left, right]`` since the sensor was built.

    Each update adds the counts of ``steps`` time steps at the robot's applied command:
    ``wheel speed (rad/s) * dt * counts_per_revolution * gear_ratio / 2 pi``, plus Gaussian noise
    of std ``encoder_noise * sqrt(max(|counts|, 1))``, rounded to whole counts (rps 2.1 rounds
    every step: update every step, ``steps=1``, to reproduce its counts exactly).

    Parameters
    ----------
    callback : callable
        Receives the counts, an int64 array ``(2,)``.
    noise : bool
    spec : OnboardSpec
    simulator_spec : SimulatorSpec
        The wheels (radius, base) and time step; rps 2.1's by default.
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        callback: Callable[[np.ndarray], Any],
        noise: bool = True,
        spec: OnboardSpec = ONBOARD,
        simulator_spec: SimulatorSpec = RPS2,
    ) -> None:
        super().__init__(robot_id, tag)
        self.callback = callback
        self.noise = bool(noise)
        self.spec = spec
        self.simulator_spec = simulator_spec
        self.counts = np.zeros(2, dtype=np.int64)

    def update(self, x: Any, v: Any, steps: int = 1) -> None:  # type: ignore[override]
        """Count ``steps`` steps of the applied commands ``v`` ``(2, n)`` (e.g. the backend's
        ``velocities``); call the callback with the counts."""
        super().update(x)
        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
            raise ValueError(f"`steps` must be an integer >= 1, got {steps!r}")
        command = as_array(v, "v", (2, self._poses.shape[1]))[:, [self.robot_id]]
        per_radian = self.spec.counts_per_revolution * self.spec.gear_ratio / (2 * np.pi)
        wheels = self.simulator_spec
        delta = kernels.wheel_speeds(command, wheels)[:, 0] * (wheels.time_step * steps) * per_radian
        if self.noise:
            spread = self.spec.encoder_noise * np.sqrt(np.maximum(np.abs(delta), 1.0))
            delta = delta + spread * self.world.rng.standard_normal(2)
        self.counts = self.counts + np.round(delta).astype(np.int64)
        self.ret = self.counts.copy()
        self.callback(self.ret)


class ImuReading(NamedTuple):
    """One IMU reading, in the robot's frame."""

    acceleration: FloatArray  #: (3,) m/s^2
    gyro: FloatArray  #: (3,) rad/s
    magnetic_field: FloatArray  #: (3,) uT
    orientation: float  #: compass heading, degrees in [0, 360)


class ImuSensor(Sensor):
    """Accelerometer, gyro, magnetometer and compass of the robot.

    From the robot's heading ``th`` and applied angular velocity ``w``: acceleration
    ``[-w^2 px, -w^2 py, -g]`` (centripetal at the IMU's position ``(px, py)`` plus gravity),
    gyro ``[0, 0, w]``, magnetic field ``[B cos th, -B sin th, Bz]`` and compass ``th`` in
    degrees modulo 360, each with Gaussian noise of the documented std.

    rps 2.1 also writes linear and tangential acceleration terms, but computes them from the
    command minus itself, so they are always zero; its recordings show it, and this sensor
    reads as rps 2.1 does.

    Parameters
    ----------
    callback : callable
        Receives an :class:`ImuReading`.
    noise : bool
    spec : OnboardSpec
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        callback: Callable[[ImuReading], Any],
        noise: bool = True,
        spec: OnboardSpec = ONBOARD,
    ) -> None:
        super().__init__(robot_id, tag)
        self.callback = callback
        self.noise = bool(noise)
        self.spec = spec

    def update(self, x: Any, v: Any) -> None:  # type: ignore[override]
        """Read the IMU at poses ``x`` ``(3, n)`` with applied commands ``v`` ``(2, n)``; call the callback."""
        super().update(x)
        w = float(as_array(v, "v", (2, self._poses.shape[1]))[1, self.robot_id])
        spec, theta = self.spec, self.rot_w
        px, py = spec.imu_position
        acceleration = np.array([-w * w * px, -w * w * py, -spec.gravity])
        gyro = np.array([0.0, 0.0, w])
        field = np.array([spec.magnetic_xy * np.cos(theta), -spec.magnetic_xy * np.sin(theta), spec.magnetic_z])
        degrees = np.degrees(theta)
        if self.noise:
            rng = self.world.rng
            acceleration = acceleration + np.asarray(spec.accelerometer_noise) * rng.standard_normal(3)
            gyro = gyro + np.asarray(spec.gyro_noise) * rng.standard_normal(3)
            field = field + np.asarray(spec.magnetometer_noise) * rng.standard_normal(3)
            degrees = degrees + spec.compass_noise * rng.standard_normal()
        self.ret = ImuReading(acceleration, gyro, field, float(np.mod(degrees, 360.0)))
        self.callback(self.ret)
