"""Unicycle dynamics, the simulators' velocity clipping and validation: poses ``(3, n)``, commands ``(2, n)``."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

import dream._reference as _reference
from dream._checks import FloatArray, all_finite, as_array, as_poses, check_finite
from dream.kernels._dispatch import core_checks, implementation, kernel_input
from dream.specs import GRITSBOT, ROBOTARIUM, RPS, ArenaSpec, RobotSpec, SimulatorSpec


class Violations(NamedTuple):
    """Validation counts of one iteration, by the Robotarium simulator's criteria."""

    boundary: int  #: robots outside the arena (rps 2.1: 1 if any robot is)
    collision: int  #: pairs of robots whose colliders are within one diameter
    actuator: int  #: 1 if any command needs a wheel faster than allowed


def _commands(value: Any, name: str, n: int | None = None) -> FloatArray:
    return as_array(value, name, (2, n))


def unicycle_step(poses: Any, velocities: Any, dt: float = RPS.time_step) -> FloatArray:
    """Poses ``(3, n)`` after one forward-Euler step of the unicycle model (rps's update).

    ``x += dt cos(theta) v``, ``y += dt sin(theta) v``, ``theta += dt w``, then theta is
    wrapped to (-pi, pi] with ``atan2(sin, cos)``.

    Raises
    ------
    ValueError
        A non-finite pose or command, ``dt`` not finite and > 0, or a ``dt`` so large that a
        pose overflows (the message names the robot).
    """
    p = kernel_input(poses, "poses", (3, None))
    u = kernel_input(velocities, "velocities", (2, p.shape[1]))
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"`dt` must be finite and > 0, got {dt}")
    out: FloatArray = implementation("unicycle_step")(p, u, dt)
    if not core_checks() and not all_finite(out):  # the Rust kernel looks for it on every core
        robot = int(np.argwhere(~np.isfinite(out))[0][1])
        raise ValueError(f"`dt` = {dt} overflows: robot {robot}'s pose is no longer finite after the step")
    return out


def threshold_velocities(velocities: Any, spec: SimulatorSpec = RPS) -> FloatArray:
    """Commands ``(2, n)`` clipped as a simulator following ``spec`` clips them.

    rps 0.0.0 (``spec.wheel_thresholding`` off) clips ``v`` and ``w`` to their limits separately;
    rps 2.1 clips each wheel's speed to ``spec.max_wheel`` and converts back to ``(v, w)``.
    """
    u = kernel_input(velocities, "velocities", (2, None))
    if spec.wheel_thresholding:
        return implementation("threshold_wheels")(
            u, wheel_radius=spec.wheel_radius, base_length=spec.base_length, max_wheel=spec.max_wheel
        )
    return implementation("threshold_velocities")(u, spec.max_linear, spec.max_angular)


def wheel_speeds(velocities: Any, spec: SimulatorSpec = RPS) -> FloatArray:
    """Left and right wheel speeds ``(2, n)`` (rad/s) of unicycle commands ``(2, n)`` on ``spec``'s robot.

    Elementwise NumPy (nothing for the Rust core to gain): ``(2v -+ L w) / (2 r)``.
    """
    return _reference.wheel_speeds(_commands(velocities, "velocities"), spec.wheel_radius, spec.base_length)


def validate(poses: Any, velocities: Any, arena: ArenaSpec = ROBOTARIUM, spec: SimulatorSpec = RPS) -> Violations:
    """Boundary, collision and actuator counts for one iteration, as a simulator following ``spec`` counts them.

    Collisions are pairs of colliders (``spec.collider_offset`` ahead of the centres) within
    ``spec.diameter``, found with a grid by the Rust kernel (O(n)); robots outside the arena count
    one each, or once per iteration when ``spec.boundary_per_iteration`` (rps 2.1).
    """
    return validate_each(poses, velocities, arena, spec)[0]


def validate_each(
    poses: Any, velocities: Any, arena: ArenaSpec = ROBOTARIUM, spec: SimulatorSpec = RPS
) -> tuple[Violations, np.ndarray]:
    """:func:`validate`'s counts and the robots in a collision ``(m,)`` int64, ascending (the robots
    of the pairs counted, :func:`colliding`'s), from the same search."""
    p = kernel_input(poses, "poses", (3, None))
    u = kernel_input(velocities, "velocities", (2, p.shape[1]))
    counts = implementation("validate")(
        p,
        u,
        arena.bounds,
        diameter=spec.diameter,
        wheel_radius=spec.wheel_radius,
        base_length=spec.base_length,
        max_wheel=spec.max_wheel,
        collider_offset=spec.collider_offset,
        boundary_per_iteration=spec.boundary_per_iteration,
    )
    return Violations(*counts[:3]), counts[3]


def colliding(poses: Any, spec: SimulatorSpec = RPS) -> np.ndarray:
    """``(n,)`` bool: the robots in a collision as a simulator following ``spec`` counts them
    (:func:`validate`'s pairs: colliders within ``spec.diameter``), found the same way (O(n))."""
    p = as_poses(poses)
    return implementation("colliding")(p, diameter=spec.diameter, collider_offset=spec.collider_offset)


def dxi_to_dxu(dxi: Any, poses: Any, vel_gain: float = 0.8, ang_gain: float = 3.0) -> FloatArray:
    """Unicycle commands ``(2, n)`` from single-integrator velocities ``(2, n)`` at ``poses`` ``(3, n)``.

    ``v = vel_gain (c dx + s dy)``, ``w = ang_gain atan2(-s dx + c dy, v) / (pi/2)``.

    Raises
    ------
    ValueError
        A non-finite velocity, pose or gain (naming it), or shapes that do not match.
    """
    d = kernel_input(dxi, "dxi", (2, None))
    p = kernel_input(poses, "poses", (3, d.shape[1]))
    gains = check_finite(vel_gain, "vel_gain"), check_finite(ang_gain, "ang_gain")
    return implementation("dxi_to_dxu")(d, p, *gains)


def dxu_to_dxi(dxu: Any, headings: Any, projection: float) -> FloatArray:
    """Velocities ``(2, n)`` of the points ``projection`` (m) ahead of robots of ``headings`` ``(n,)``
    driven by unicycle commands ``(2, n)``: the other way from :func:`dxi_to_dxu` (rps's ``uni_to_si``).

    ``dx = v cos(theta) - projection w sin(theta)``, ``dy = v sin(theta) + projection w cos(theta)``.

    Raises
    ------
    ValueError
        A non-finite command, heading or ``projection`` (naming it), or shapes that do not match.
    """
    u = kernel_input(dxu, "dxu", (2, None))
    theta = kernel_input(headings, "headings", (u.shape[1],))
    return implementation("dxu_to_dxi")(u, theta, check_finite(projection, "projection"))


def actuator_limit(dxu: Any, robot: RobotSpec = GRITSBOT) -> FloatArray:
    """Commands ``(2, n)`` within the robot's limits; linear speed is sacrificed before turning."""
    return implementation("actuator_limit")(
        kernel_input(dxu, "dxu", (2, None)),
        max_linear=robot.v_max,
        max_angular=robot.w_max,
        wheel_radius=robot.wheel_radius,
        base_length=robot.base_length,
        max_wheel=robot.ac_max,
    )
