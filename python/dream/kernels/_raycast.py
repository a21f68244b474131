"""Distance sensors: every robot's infrared rays against line-segment walls and the other robots."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream._checks import FloatArray, as_array, as_poses, check_nonnegative
from dream.kernels._dispatch import implementation
from dream.specs import ONBOARD, OnboardSpec


def distance_rays(poses: Any, walls: Any = None, *, spec: OnboardSpec = ONBOARD, robots: Any = None) -> FloatArray:
    """Noiseless readings ``(k, n)`` of every robot's infrared distance sensors (rps 2.1's model).

    Ray ``j`` starts at ``spec.rays[:2, j]`` in the body frame of a centre ``spec.centre_offset``
    ahead of the pose and points at ``heading + spec.rays[2, j]``; it reads the distance (m) to
    the nearest line-segment wall or other robot (a disc of ``spec.robot_diameter`` around its
    own offset centre) within ``spec.range``, or -1. The arena's edges are not seen; a robot
    whose disc contains a ray's start is not seen by that ray (as in rps 2.1). A grid makes this
    O(n k m) in Rust (m robots within reach), in parallel over robots.

    Parameters
    ----------
    poses : (3, n)
    walls : (w, 2, 2), optional
        Line segments, ``walls[i, 0]`` start and ``walls[i, 1]`` end (rps 2.1's ``obstacles``).
    spec : OnboardSpec
        The sensor head; its noise settings are not used here (see :class:`dream.DistanceSensor`).
    robots : (b,) int, optional
        Cast only these robots' rays (the others' columns read -1); all by default.
    """
    p = as_poses(poses)
    n = p.shape[1]
    segments = np.zeros((0, 4)) if walls is None else as_array(walls, "walls", (None, 2, 2)).reshape(-1, 4)
    rays = as_array(spec.rays, "spec.rays", (3, None))
    check_nonnegative(spec.robot_diameter, "robot_diameter")
    if not (np.isfinite(spec.range) and spec.range > 0):
        raise ValueError(f"`range` must be finite and > 0, got {spec.range}")
    ids = None
    if robots is not None:
        ids = np.ascontiguousarray(np.atleast_1d(robots), dtype=np.int64)
        if ids.ndim != 1 or (len(ids) and (ids.min() < 0 or ids.max() >= n)):
            raise ValueError(f"`robots` must be robot ids in [0, {n}), got {robots!r}")
    options = {"centre_offset": spec.centre_offset, "robot_diameter": spec.robot_diameter, "range": spec.range}
    return implementation("distance_rays")(p, segments, rays, robots=ids, **options)
