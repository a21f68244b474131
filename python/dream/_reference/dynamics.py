"""Unicycle dynamics and rps validation, written as rps writes them (the Fast backend's oracle).

Poses are ``(3, n)`` (x, y, theta rows), unicycle commands ``(2, n)`` (v, w rows).
"""

from __future__ import annotations

import numpy as np

from dream._checks import FloatArray


def threshold_velocities(velocities: FloatArray, max_linear: float, max_angular: float) -> FloatArray:
    """Commands ``(2, n)`` with |v| and |w| clipped to their limits, signs kept (rps ``set_velocities``)."""
    out = np.array(velocities, dtype=np.float64)
    for row, limit in ((0, max_linear), (1, max_angular)):
        over = np.abs(out[row]) > limit
        out[row, over] = limit * np.sign(out[row, over])
    return out


def wheel_speeds(velocities: FloatArray, wheel_radius: float, base_length: float) -> FloatArray:
    """Left and right wheel speeds ``(2, n)`` (rad/s) of unicycle commands ``(2, n)`` (rps ``_uni_to_diff``)."""
    v, w = velocities[0], velocities[1]
    return np.vstack(
        (1 / (2 * wheel_radius) * (2 * v - base_length * w), 1 / (2 * wheel_radius) * (2 * v + base_length * w))
    )


def threshold_wheels(
    velocities: FloatArray, *, wheel_radius: float, base_length: float, max_wheel: float
) -> FloatArray:
    """Commands ``(2, n)`` whose wheel speeds are clipped to ``max_wheel``, signs kept (rps 2.1)."""
    wheels = wheel_speeds(velocities, wheel_radius, base_length)
    wheels = np.where(np.abs(wheels) > max_wheel, max_wheel * np.sign(wheels), wheels)
    return np.vstack((wheel_radius / 2 * (wheels[0] + wheels[1]), wheel_radius / base_length * (wheels[1] - wheels[0])))


def validate(
    poses: FloatArray,
    velocities: FloatArray,
    bounds: tuple[float, float, float, float],
    *,
    diameter: float,
    wheel_radius: float,
    base_length: float,
    max_wheel: float,
    collider_offset: float = 0.0,
    boundary_per_iteration: bool = False,
) -> tuple[int, int, int, np.ndarray]:
    """``(boundary, collision, actuator)`` counts of one iteration by rps's ``_validate`` criteria,
    and the robots in a collision ``(m,)`` int64, ascending (the robots of the pairs counted).

    boundary: robots outside ``bounds`` (xmin, xmax, ymin, ymax), or 1 if any is when
    ``boundary_per_iteration``; collision: pairs whose colliders (``collider_offset`` ahead of the
    centre along the heading) are within ``diameter`` (inclusive); actuator: 1 if any command
    needs a wheel faster than ``max_wheel``.
    """
    x, y = poses[0], poses[1]
    xmin, xmax, ymin, ymax = bounds
    boundary = int(np.count_nonzero((x < xmin) | (x > xmax) | (y < ymin) | (y > ymax)))
    if boundary_per_iteration:
        boundary = min(boundary, 1)
    pairs = _pairs(poses, diameter, collider_offset)
    actuator = int(np.any(np.abs(wheel_speeds(velocities, wheel_radius, base_length)) > max_wheel))
    robots = np.flatnonzero(pairs.any(axis=0) | pairs.any(axis=1)).astype(np.int64)
    return boundary, int(np.count_nonzero(pairs)), actuator, robots


def colliding(poses: FloatArray, *, diameter: float, collider_offset: float = 0.0) -> np.ndarray:
    """``(n,)`` bool: the robots of the pairs :func:`validate` counts as collisions."""
    pairs = _pairs(poses, diameter, collider_offset)
    return np.logical_or(pairs.any(axis=0), pairs.any(axis=1))


def _pairs(poses: FloatArray, diameter: float, collider_offset: float) -> np.ndarray:
    """``(n, n)`` bool: ``[i, j]`` for ``i < j`` whose colliders (``collider_offset`` ahead of the
    centres along the heading) are within ``diameter`` (inclusive)."""
    x, y = poses[0], poses[1]
    if collider_offset != 0.0:
        x = x + collider_offset * np.cos(poses[2])
        y = y + collider_offset * np.sin(poses[2])
    dx = x[:, None] - x[None, :]
    dy = y[:, None] - y[None, :]
    return np.triu(np.sqrt(dx * dx + dy * dy) <= diameter, k=1)


def unicycle_step(poses: FloatArray, velocities: FloatArray, dt: float) -> FloatArray:
    """Poses ``(3, n)`` after one forward-Euler unicycle step, heading wrapped to (-pi, pi]."""
    out = np.array(poses, dtype=np.float64)
    out[0] = out[0] + dt * np.cos(out[2]) * velocities[0]
    out[1] = out[1] + dt * np.sin(out[2]) * velocities[0]
    turned = out[2] + dt * velocities[1]
    # rps's atan2(sin, cos) gives a heading already in (-pi, pi] back to within a rounding: kept as it is.
    inside = (-np.pi < turned) & (turned <= np.pi)
    out[2] = np.where(inside, turned, np.arctan2(np.sin(turned), np.cos(turned)))
    return out


def dxi_to_dxu(dxi: FloatArray, poses: FloatArray, vel_gain: float, ang_gain: float) -> FloatArray:
    """Unicycle commands ``(2, n)`` from single-integrator velocities ``(2, n)`` at ``poses``.

    ``v = vel_gain (c dx + s dy)`` and ``w = ang_gain atan2(-s dx + c dy, v) / (pi/2)`` with
    ``c, s = cos, sin(theta)``: the original DREAM conversion.
    """
    c, s = np.cos(poses[2]), np.sin(poses[2])
    v = vel_gain * (c * dxi[0] + s * dxi[1])
    w = ang_gain * np.arctan2(-s * dxi[0] + c * dxi[1], v) / (np.pi / 2)
    return np.vstack((v, w))


def dxu_to_dxi(dxu: FloatArray, headings: FloatArray, projection: float) -> FloatArray:
    """Velocities ``(2, n)`` of the points ``projection`` ahead of robots of ``headings`` ``(n,)``
    driven by unicycle commands ``(2, n)`` (rps's ``uni_to_si``; what a movement sensor reports).

    ``dx = v c - projection w s`` and ``dy = v s + projection w c`` with ``c, s = cos, sin(theta)``.
    """
    c, s = np.cos(headings), np.sin(headings)
    ahead = projection * dxu[1]
    return np.vstack((dxu[0] * c - ahead * s, dxu[0] * s + ahead * c))


def actuator_limit(
    dxu: FloatArray,
    *,
    max_linear: float,
    max_angular: float,
    wheel_radius: float,
    base_length: float,
    max_wheel: float,
) -> FloatArray:
    """Commands ``(2, n)`` clipped to the speed limits, then slowed so that no wheel is too fast.

    If ``|v|/r + |w| L/(2r) > max_wheel``, ``|v|`` becomes ``max_wheel r - |w| L/2`` (at least 0),
    keeping its sign and keeping ``w``: turning matters more than advancing.
    """
    out = threshold_velocities(dxu, max_linear, max_angular)
    v, w = out[0], out[1]
    half = base_length / 2
    over = np.abs(v) / wheel_radius + np.abs(w) * half / wheel_radius > max_wheel
    speed = np.maximum(max_wheel * wheel_radius - half * np.abs(w), 0.0)
    out[0] = np.where(over, np.where(v > 0, speed, -speed), v)
    return out
