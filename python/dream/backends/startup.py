"""rps 2.1's start-up phase for the Fast backend: robots drive from the chargers to their poses.

rps 2.1 places each robot on one of 22 charger slots along the top and bottom edges of the
arena (facing inwards) and drives it to ``initial_conditions`` with a pose controller and
barrier certificates before the experiment begins; validation is off meanwhile. This module
does the same with its own controller. Far from its goal a robot steers a point ``LOOKAHEAD``
ahead of itself (which a unicycle can steer exactly) towards the goal, and HRVO keeps those
points ``SAFETY`` apart; within ``NEAR`` of the goal it closes in with a plain unicycle
position controller (forwards or backwards, whichever faces the goal), and once in position
it turns on the spot to its heading. HRVO can deadlock (robots waiting on each other): a
robot that has not moved ``UNSTUCK_DISTANCE`` in ``STALL_STEPS`` heads for a random detour
point nearby until it gets there or stalls again (rps 2.1 breaks deadlocks the same way).
Start-up ends when every robot is within ``POSITION_TOLERANCE`` of its position and
``HEADING_TOLERANCE`` of its heading.

:func:`reachable_starts` moves initial conditions that rps 2.1's own start-up phase cannot
reach to nearby ones that it can (see there).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from dream import kernels
from dream._checks import FloatArray
from dream.specs import GRITSBOT, ROBOTARIUM, RPS2, ArenaSpec, SimulatorSpec

if TYPE_CHECKING:
    from dream.obstacles import Obstacle

#: Charger slots per edge (rps 2.1: 11 on the top edge and 11 on the bottom one).
SLOTS_PER_EDGE = 11
LOOKAHEAD = 0.05  #: m: the steered point ahead of the axle centre
SAFETY = 0.2  #: m: HRVO's combined radius for two steered points (colliders stay > 0.135 m apart)
SPEED = 0.1  #: m/s: cruise speed of the steered point
GAIN = 1.0  #: 1/s: speed per metre of remaining distance near the goal
NEAR = 0.1  #: m: closer than this a robot leaves HRVO for the position controller
TURN_GAIN = 2.0  #: 1/s: turning rate per radian of heading error
STALL_STEPS = 150  #: steps without progress before a detour
UNSTUCK_DISTANCE = 0.1  #: m: progress that ends a stall or a detour
DETOUR = 0.4  #: m: half-size of the square a detour point is drawn from
POSITION_TOLERANCE = 0.015  #: m: arrival, with margin for rps 2.1's 0.02
HEADING_TOLERANCE = 0.05  #: rad: aligned, with margin for rps 2.1's 0.18
MAX_ITERATIONS = 20_000
#: m: rps 2.1's start-up keeps points 0.05 m ahead of the robots 0.15 + 2 x 0.05 m apart (its unicycle
#: barrier certificate's defaults); two initial conditions whose points are closer are never both reached.
RPS2_BARRIER_SPACING = 0.25
RPS2_PROJECTION = 0.05  #: m: how far ahead of a robot that point lies
#: m: the spacing :func:`reachable_starts` keeps: the barrier's whatever the two headings (0.25 + 2 x 0.05),
#: plus a 0.05 m margin.
START_SPACING = 0.4
START_GRID = 0.05  #: m: the grid of points a start that is too close moves to
START_CLEARANCE = GRITSBOT.radius + 0.05  #: m: how far from an obstacle a moved start's centre stays


class StartUp(NamedTuple):
    """What the start-up phase did."""

    chargers: FloatArray  #: (3, n) the poses it started from
    poses: FloatArray  #: (3, n) the poses it ended at
    iterations: int
    violations: kernels.Violations  #: counted by the simulator's rules although rps does not


def charger_poses(
    n: int, rng: np.random.Generator, arena: ArenaSpec = ROBOTARIUM, diameter: float = 0.11
) -> FloatArray:
    """``n`` distinct charger slots ``(3, n)`` drawn from ``rng``, facing into the arena.

    The slots are ``SLOTS_PER_EDGE`` evenly spaced points along the top and bottom edges,
    inset by half a robot ``diameter``, as in rps 2.1.
    """
    slots = 2 * SLOTS_PER_EDGE
    if n > slots:
        raise ValueError(f"the start-up phase has {slots} charger slots, got {n} robots: use skip_initialization")
    half_width, half_height = (arena.width - diameter) / 2, (arena.height - diameter) / 2
    cx, cy = (arena.xmin + arena.xmax) / 2, (arena.ymin + arena.ymax) / 2
    chosen = rng.choice(slots, size=n, replace=False)
    bottom = chosen % 2 == 0
    poses = np.empty((3, n))
    poses[0] = cx + np.linspace(-half_width, half_width, SLOTS_PER_EDGE)[chosen // 2]
    poses[1] = np.where(bottom, cy - half_height, cy + half_height)
    poses[2] = np.where(bottom, np.pi / 2, -np.pi / 2)
    return poses


def reachable_starts(
    poses: FloatArray,
    arena: ArenaSpec = ROBOTARIUM,
    spacing: float = START_SPACING,
    obstacles: Sequence[Obstacle] = (),
) -> FloatArray:
    """``poses`` ``(3, n)`` with no two positions closer than ``spacing``: a copy in which rps 2.1's
    start-up phase reaches every pose.

    That phase never ends when two initial conditions lie closer than its barrier certificate
    lets the robots come (:data:`RPS2_BARRIER_SPACING` between points :data:`RPS2_PROJECTION`
    ahead of them): the two robots jostle near their poses for ever, too close to them for its
    deadlock breaker to act. Robots are kept in order while they are ``spacing`` from those kept;
    each other robot moves to the nearest point of a :data:`START_GRID` grid, in the central part
    of ``arena`` where :func:`dream.backends.initial_poses` draws, that is ``spacing`` from every
    robot placed and :data:`START_CLEARANCE` from ``obstacles``. Headings are kept.

    Raises
    ------
    ValueError
        If the robots do not all fit ``spacing`` apart there.
    """
    width, height = arena.width * 2.5 / 3.2, arena.height * 1.5 / 2.0
    cx, cy = (arena.xmin + arena.xmax) / 2, (arena.ymin + arena.ymax) / 2
    xs = cx + np.arange(-width / 2, width / 2 + START_GRID / 2, START_GRID)
    ys = cy + np.arange(-height / 2, height / 2 + START_GRID / 2, START_GRID)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    for obstacle in obstacles:
        grid = grid[obstacle.distances(grid) >= START_CLEARANCE]
    starts = np.array(poses, dtype=np.float64)
    placed: list[int] = []
    moved: list[int] = []
    for i in range(starts.shape[1]):
        close = np.hypot(*(starts[:2, placed] - starts[:2, i : i + 1])) < spacing
        (moved if close.any() else placed).append(i)
    for i in moved:
        free = np.all(np.hypot(*(grid.T[:, :, None] - starts[:2, None, placed])) >= spacing, axis=1)
        if not free.any():
            raise ValueError(
                f"{starts.shape[1]} robots do not fit {spacing} m apart in the central {width:.2f} x {height:.2f} m "
                "of the arena (off its obstacles), as rps 2.1's start-up phase needs"
            )
        options = grid[free]
        starts[:2, i] = options[np.argmin(np.hypot(*(options.T - starts[:2, i : i + 1])))]
        placed.append(i)
    return starts


def _heading_errors(poses: FloatArray, targets: FloatArray) -> FloatArray:
    error = targets[2] - poses[2]
    return np.arctan2(np.sin(error), np.cos(error))


def start_up(
    targets: FloatArray,
    rng: np.random.Generator,
    arena: ArenaSpec = ROBOTARIUM,
    spec: SimulatorSpec = RPS2,
) -> StartUp:
    """Drive ``n`` robots from random charger slots to ``targets`` ``(3, n)`` (see module docs).

    Raises
    ------
    RuntimeError
        If the robots are not all in place after ``MAX_ITERATIONS`` steps (targets closer to
        each other than ``SAFETY`` cannot all be reached).
    """
    n = targets.shape[1]
    chargers = charger_poses(n, rng, arena)
    robot = GRITSBOT.within(spec)
    bounds = arena.shrunk(LOOKAHEAD)
    poses = chargers.copy()
    velocity = np.zeros((n, 2))
    near = np.zeros(n, dtype=bool)
    placed = np.zeros(n, dtype=bool)
    anchors, stalled_since = poses[:2].T.copy(), np.zeros(n, dtype=int)
    detours = np.full((n, 2), np.nan)
    inner = np.array(arena.shrunk(3 * LOOKAHEAD)).reshape(2, 2)
    violations = kernels.Violations(0, 0, 0)
    for iteration in range(MAX_ITERATIONS):
        heading_error = _heading_errors(poses, targets)
        offset = targets[:2] - poses[:2]
        distance = np.hypot(*offset)
        placed |= distance <= POSITION_TOLERANCE
        if np.all(placed & (np.abs(heading_error) <= HEADING_TOLERANCE)):
            return StartUp(chargers, poses, iteration, violations)
        near |= distance < NEAR
        moved = np.linalg.norm(poses[:2].T - anchors, axis=1) > UNSTUCK_DISTANCE
        anchors[moved], stalled_since[moved] = poses[:2].T[moved], iteration
        detours[np.linalg.norm(poses[:2].T - detours, axis=1) < NEAR] = np.nan
        stuck = ~near & (iteration - stalled_since > STALL_STEPS)
        for i in np.flatnonzero(stuck):
            detours[i] = np.clip(poses[:2, i] + rng.uniform(-DETOUR, DETOUR, 2), inner[:, 0], inner[:, 1])
            stalled_since[i] = iteration
        c, s = np.cos(poses[2]), np.sin(poses[2])
        points = poses[:2].T + LOOKAHEAD * np.column_stack((c, s))
        to_goal = np.where(np.isnan(detours), targets[:2].T, detours) - points
        remaining = np.linalg.norm(to_goal, axis=1, keepdims=True)
        preferred = to_goal * np.minimum(GAIN, SPEED / np.maximum(remaining, 1e-12))
        preferred[near] = 0.0
        velocity = kernels.hrvo(points, velocity, preferred, safety=SAFETY, v_max=SPEED, bounds=bounds)
        velocity[near] = 0.0
        # The point LOOKAHEAD ahead moves exactly with (v, w) = (c dx + s dy, (-s dx + c dy) / LOOKAHEAD).
        commands = np.vstack(
            (c * velocity[:, 0] + s * velocity[:, 1], (-s * velocity[:, 0] + c * velocity[:, 1]) / LOOKAHEAD)
        )
        # Bearing of the goal folded into (-pi/2, pi/2]: a goal behind is reached backwards.
        bearing = np.arctan(np.tan(np.arctan2(offset[1], offset[0]) - poses[2]))
        closing = np.vstack((GAIN * (c * offset[0] + s * offset[1]), TURN_GAIN * bearing))
        commands[:, near] = closing[:, near]
        commands[:, placed] = np.vstack((np.zeros(n), TURN_GAIN * heading_error))[:, placed]
        commands = kernels.actuator_limit(commands, robot)
        found = kernels.validate(poses, commands, arena, spec)
        violations = kernels.Violations(*(a + b for a, b in zip(violations, found)))
        poses = kernels.unicycle_step(poses, kernels.threshold_velocities(commands, spec), spec.time_step)
    raise RuntimeError(f"the start-up phase did not bring every robot to its pose within {MAX_ITERATIONS} steps")
