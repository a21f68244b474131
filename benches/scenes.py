"""The swarms every benchmark runs on, in one place so that all benches time the same scenes.

Each scene gives positions, previous velocities and preferred velocities, all ``(n, 2)`` in
m and m/s, with about ``DENSITY`` robots within ``RANGE`` of each robot (the sensing range of
the experiments) unless said otherwise. The easy lattice alone flatters a kernel (robots are
spread evenly, preferred velocities are mostly free); the other three are the hard cases:

- ``lattice``: a jittered square lattice (robots stay >= 0.28 m apart), random velocities and
  preferred directions. The oldest figures of docs/benchmarks.md use it.
- ``uniform``: robots uniformly at random in a square, so some are closer than the safety
  radius (0.24 m) to each other or overlap; random velocities and preferred directions.
- ``crossing``: a disc twice as dense (about 20 within RANGE), every robot heading for its
  antipodal point ``-p`` at full speed, its previous velocity that heading turned by up to
  +-30 degrees: converging streams and head-on pairs across the centre.
- ``blocked``: a standing crowd (zero velocities, uniform positions) in which every robot
  wants to drive straight into its nearest neighbour, so no preferred velocity is ever free
  and every robot searches the candidate grid.
- ``ring``: hrvo-circle's swarm parked on its ring (goals 0.34 m apart around an ellipse of
  the Robotarium's shape, a few centimetres off), about 5 within RANGE: a swarm spread thin
  over an arena hundreds of metres wide at large n, where the grids' cell tables are sparse.
  (Up to n = 10 the thesis's circle of 0.85 m: use it from n = 100.)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from dream import kernels
from dream.experiments.hrvo_circle import circle_layout

RANGE = 1.0  #: sensing range (m) of the neighbour search and of HRVO
DENSITY = 10  #: robots within RANGE of a robot, on average
V_MAX = 0.2  #: GRITSbot top speed (m/s)


class Scene(NamedTuple):
    """One swarm: positions, previous velocities and preferred velocities, each ``(n, 2)``."""

    positions: np.ndarray
    velocities: np.ndarray
    preferred: np.ndarray


def _side(n: int, density: float = DENSITY) -> float:
    """Side (m) of the square that holds ``n`` robots with ``density`` within RANGE of each."""
    return math.sqrt(n * math.pi * RANGE**2 / density)


def _headings(rng: np.random.Generator, n: int, speed: float) -> np.ndarray:
    angle = rng.uniform(-np.pi, np.pi, n)
    return speed * np.column_stack((np.cos(angle), np.sin(angle)))


def lattice(n: int, seed: int = 0) -> Scene:
    """Jittered square lattice, spacing ``sqrt(pi / DENSITY)``, jitter +-1/4 of it."""
    spacing = RANGE * math.sqrt(math.pi / DENSITY)
    columns = math.ceil(math.sqrt(n))
    points = np.column_stack(np.divmod(np.arange(n), columns)).astype(np.float64) * spacing
    points += np.random.default_rng(seed).uniform(-spacing / 4, spacing / 4, (n, 2))
    rng = np.random.default_rng(seed + 2)
    return Scene(points, rng.uniform(-0.7 * V_MAX, 0.7 * V_MAX, (n, 2)), _headings(rng, n, V_MAX))


def uniform(n: int, seed: int = 0) -> Scene:
    """Uniformly random positions in a square (overlaps included), random velocities and goals."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0.0, _side(n), (n, 2))
    return Scene(points, rng.uniform(-0.7 * V_MAX, 0.7 * V_MAX, (n, 2)), _headings(rng, n, V_MAX))


def crossing(n: int, seed: int = 0) -> Scene:
    """A dense disc in which every robot heads for its antipodal point through the centre."""
    rng = np.random.default_rng(seed)
    radius = _side(n, 2 * DENSITY) / math.sqrt(math.pi)  # the disc of the square's area
    r = radius * np.sqrt(rng.uniform(0.0, 1.0, n))
    angle = rng.uniform(-np.pi, np.pi, n)
    points = np.column_stack((r * np.cos(angle), r * np.sin(angle)))
    preferred = -V_MAX * np.column_stack((np.cos(angle), np.sin(angle)))
    turn = rng.uniform(-np.pi / 6, np.pi / 6, n)
    c, s = np.cos(turn), np.sin(turn)
    velocities = np.column_stack((c * preferred[:, 0] - s * preferred[:, 1], s * preferred[:, 0] + c * preferred[:, 1]))
    return Scene(points, velocities, preferred)


def blocked(n: int, seed: int = 0) -> Scene:
    """A standing crowd in which each robot's preferred velocity points at its nearest neighbour.

    With zero velocities both apexes are the origin and the direction to a neighbour lies
    strictly inside its cone, so every preferred velocity is forbidden.
    """
    rng = np.random.default_rng(seed)
    points = rng.uniform(0.0, _side(n), (n, 2))
    indptr, indices, distances = kernels.neighbours(points, 2 * RANGE)
    preferred = np.zeros((n, 2))
    for i in range(n):
        row = slice(indptr[i], indptr[i + 1])
        if indptr[i + 1] > indptr[i] and distances[row].min() > 0:
            j = indices[row][np.argmin(distances[row])]
            offset = points[j] - points[i]
            preferred[i] = V_MAX * offset / np.hypot(offset[0], offset[1])
    return Scene(points, np.zeros((n, 2)), preferred)


def ring(n: int, seed: int = 0) -> Scene:
    """hrvo-circle's goals for ``n`` robots on Fast, each robot within 3 cm of its goal, heading
    around the ring or across it."""
    rng = np.random.default_rng(seed)
    points = circle_layout(n).goals + rng.uniform(-0.03, 0.03, (n, 2))
    return Scene(points, rng.uniform(-0.7 * V_MAX, 0.7 * V_MAX, (n, 2)), _headings(rng, n, V_MAX))


#: Every scene by name, in the order the benches print them.
SCENES: dict[str, Callable[[int, int], Scene]] = {
    "lattice": lattice,
    "uniform": uniform,
    "crossing": crossing,
    "blocked": blocked,
    "ring": ring,
}
