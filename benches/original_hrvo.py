"""The prototype's per-robot HRVO cost, for comparison only: plain Python loops over the
candidate velocities, one neighbour at a time, as the thesis's listing does (rewritten here;
not used by DREAM).
"""

from __future__ import annotations

import math

import numpy as np


def original_style_hrvo(detections, velocity, desired, position, bounds, safety=0.24, v_max=0.2):
    """Velocity chosen by the prototype's procedure: sequential filtering, then nearest."""
    rows = []
    for distance, angle, vx, vy in detections:
        distance = max(distance, safety)
        phi = math.asin(safety / distance)
        left, right = angle + phi, angle - phi
        # Half-plane coefficients (a, b, c) of the VO's and the RVO's edges.
        edges = []
        for apex in ((vx, vy), ((vx + velocity[0]) / 2, (vy + velocity[1]) / 2)):
            line_l = np.array([-math.sin(left), math.cos(left), math.sin(left) * apex[0] - math.cos(left) * apex[1]])
            line_r = np.array(
                [-math.sin(right), math.cos(right), math.sin(right) * apex[0] - math.cos(right) * apex[1]]
            )
            edges.append((line_l, line_r))
        (vo_l, vo_r), (rvo_l, rvo_r) = edges
        to_l = abs(rvo_l[0] * velocity[0] + rvo_l[1] * velocity[1] + rvo_l[2])
        to_r = abs(rvo_r[0] * velocity[0] + rvo_r[1] * velocity[1] + rvo_r[2])
        line_l = rvo_l if to_l < to_r else vo_l
        line_r = rvo_r if to_l > to_r else vo_r
        rows.append((np.array([-line_l[:2], line_r[:2]]), np.array([line_l[2], -line_r[2]])))
    speeds, angles = np.meshgrid(np.linspace(0.0, v_max, 10), np.linspace(0, 2 * np.pi, 20))
    samples = np.vstack(
        (np.append((speeds * np.cos(angles)).ravel(), 0), np.append((speeds * np.sin(angles)).ravel(), 0))
    )
    for matrix, vector in rows:
        kept = []
        for k in range(samples.shape[1]):
            if not (matrix @ samples[:, k] < vector).all():
                kept.append(samples[:, k])
        samples = np.array(kept).T if kept else np.zeros((2, 1))
    kept = []
    for k in range(samples.shape[1]):
        x, y = samples[0, k] + position[0], samples[1, k] + position[1]
        if bounds[0] < x < bounds[1] and bounds[2] < y < bounds[3]:
            kept.append(samples[:, k])
    samples = np.array(kept).T if kept else np.zeros((2, 1))
    gaps = np.linalg.norm(samples - np.asarray(desired).reshape(2, 1), axis=0)
    return samples[:, int(np.argmin(gaps))]
