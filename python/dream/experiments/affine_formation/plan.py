"""The affine formation's plan: its stress weights, shapes, tiles, bars and schedule.

See ``docs/experiments/affine-formation.md`` for why each figure is what it is.
"""

from __future__ import annotations

import math

import numpy as np

from dream._checks import Bounds
from dream.obstacles import Obstacle
from dream.specs import ROBOTARIUM, RPS, ArenaSpec

LEADERS = 3
#: Stress weights from the thesis (symmetric; leaders 0-2, followers 3-6).
WEIGHTS = np.array(
    [
        [0, 0.2741, 0.2741, -0.137, -0.137, 0, 0],
        [0.2741, 0, 0, 0.5482, 0, 0, -0.137],
        [0.2741, 0, 0, 0, 0.5482, -0.137, 0],
        [-0.137, 0.5482, 0, 0, 0.0685, 0.2741, 0],
        [-0.137, 0, 0.5482, 0.0685, 0, 0, 0.2741],
        [0, 0, -0.137, 0.2741, 0, 0, 0.137],
        [0, -0.137, 0, 0, 0.2741, 0.137, 0],
    ]
)
#: The nominal configuration, in formation units.
NOMINAL = np.array([[2, 0], [1, 1], [1, -1], [0, 1], [0, -1], [-1, 1], [-1, -1]], dtype=np.float64)
SCALE = 0.3  #: metres per formation unit
GAIN = 8.0  #: the followers' stress gain k (1/s)
LEADER_GAIN = 1.5  #: a leader's gain towards its aim (1/s)
SETTLE = 1200  #: steps for the followers to take their places before the first manoeuvre
#: How far (m) to the right the leaders stand while the followers gather from the corners, until
#: step ``GATHER``: the followers from the right-hand corners, which have the longer way, arrive first.
SHIFT = 0.3
GATHER = 300  #: step at which the leaders return from their gathering places to the nominal ones
MORPH = 75  #: decisions (one every 4 steps: 10 s) over which a leader moves to its next place
LEAD = 600  #: steps between the leaders' change of shape and the bars' entry
RECOVER = 450  #: steps back in the nominal shape between two passes
ENTRY = 0.15  #: the bars enter and leave this far beyond the walls (m)
BAR_SPEED = 0.15  #: bars sweep leftwards at this speed (m/s)
BAR_WIDTH = 0.1  #: thickness of a bar (m)
#: A place closer than this (m) to a crashed robot is taken (a follower's HRVO, safety 0.15 m,
#: would keep it off): the leaders shift the formation along x until no survivor's place is,
#: within the tile less ``WALL`` (m).
CLEAR = 0.2
WALL = 0.15
TOLERANCE = 0.05  #: largest follower error of a formed formation (m)
GAPS = (0.55, 0.3)  #: the wide and the narrow gap between a pair of bars (m)
#: Affine maps (formation units -> formation units) the leaders use: nominal, for the wide gap
#: (compressed), for the narrow gap (collinear: ``x -> 4 a x + a y`` spaces the robots evenly,
#: 2 a = 1.25 units apart, leader 0 further; ``a = 5/6`` left two pairs 0.25 m apart, whose
#: robots met while the followers caught up with the leaders, under rps 2.1's rules in most runs).
SHAPES = {
    "nominal": np.eye(2),
    "compressed": np.diag([1.0, 0.5]),
    "collinear": np.array([[2.5, 0.625], [0.0, 0.0]]),
}


def stress_matrix(weights: np.ndarray = WEIGHTS) -> np.ndarray:
    """Omega: ``Omega_ij = -w_ij`` off the diagonal, row sums on it."""
    return np.diag(weights.sum(axis=1)) - weights


def follower_targets(leaders: np.ndarray, weights: np.ndarray = WEIGHTS) -> np.ndarray:
    """Where the followers converge ``(..., 4, 2)`` for leaders at ``leaders`` ``(..., 3, 2)`` (one
    formation, or a stack of them): ``-Omega_ff^-1 Omega_fl p_l``."""
    omega = stress_matrix(weights)
    # One 4x3 map for every formation (they share Omega), applied to all of them in one product.
    pull = -np.linalg.solve(omega[LEADERS:, LEADERS:], omega[LEADERS:, :LEADERS])
    points = np.asarray(leaders, dtype=np.float64)
    stacked = np.moveaxis(points, -2, 0).reshape(LEADERS, -1)  # (3, ... * 2)
    return np.moveaxis((pull @ stacked).reshape(len(pull), *points.shape[:-2], 2), 0, -2)


def formation(shape: str) -> np.ndarray:
    """World positions ``(7, 2)`` of the formation in ``shape``, centred on the arena's centre."""
    centred = NOMINAL - NOMINAL.mean(axis=0)
    return SCALE * centred @ SHAPES[shape].T


def tile_centres(groups: int) -> np.ndarray:
    """Centres ``(groups, 2)`` of the Robotarium-sized tiles, one formation each, in a near-square grid."""
    columns = math.ceil(math.sqrt(groups))
    rows = math.ceil(groups / columns)
    k = np.arange(groups)
    return np.column_stack(
        ((k % columns - (columns - 1) / 2) * ROBOTARIUM.width, (k // columns - (rows - 1) / 2) * ROBOTARIUM.height)
    )


def tile_bounds(centre: np.ndarray) -> Bounds:
    """``(xmin, xmax, ymin, ymax)`` of the Robotarium-sized tile centred at ``centre`` ``(2,)`` (m)."""
    (x, y), half_width, half_height = centre, ROBOTARIUM.width / 2, ROBOTARIUM.height / 2
    return (float(x - half_width), float(x + half_width), float(y - half_height), float(y + half_height))


def tiled_arena(groups: int) -> ArenaSpec:
    """The Robotarium for one formation; for more, the grid of Robotarium-sized tiles."""
    if groups == 1:
        return ROBOTARIUM
    columns = math.ceil(math.sqrt(groups))
    return ArenaSpec.centred(columns * ROBOTARIUM.width, math.ceil(groups / columns) * ROBOTARIUM.height)


def corner_starts(rng: np.random.Generator, centres: np.ndarray | None = None) -> np.ndarray:
    """Initial poses ``(3, 7 g)``: in each tile (centred at ``centres`` ``(g, 2)``, default one tile
    at the origin), leaders in their triangle and followers in the four corners."""
    centres = np.zeros((1, 2)) if centres is None else centres
    tile = np.vstack((formation("nominal")[:LEADERS], [[1.35, 0.75], [1.35, -0.75], [-1.35, 0.75], [-1.35, -0.75]]))
    positions = np.vstack([tile + centre for centre in centres])
    return np.vstack((positions.T, rng.uniform(-math.pi, math.pi, len(positions))))


def bars(gap: float, x: float, centre: np.ndarray | None = None) -> list[Obstacle]:
    """A pair of bars at ``x`` (relative to the tile ``centre``, default the origin) leaving a gap
    of ``gap`` in the middle."""
    centre = np.zeros(2) if centre is None else centre
    height = ROBOTARIUM.ymax - gap / 2
    return [
        Obstacle(centre + (x, gap / 2 + height / 2), (BAR_WIDTH, height), velocity=(-BAR_SPEED, 0.0)),
        Obstacle(centre + (x, -gap / 2 - height / 2), (BAR_WIDTH, height), velocity=(-BAR_SPEED, 0.0)),
    ]


def follower_positions(anchors: np.ndarray) -> np.ndarray:
    """Each formation's follower targets ``(4 g, 2)`` for leaders at ``anchors`` ``(7 g, 2)`` (rows
    of followers unused)."""
    return follower_targets(anchors.reshape(-1, 7, 2)[:, :LEADERS]).reshape(-1, 2)


def affine_image(known: dict[int, np.ndarray], indices: list[int]) -> dict[int, np.ndarray]:
    """Where robots ``indices`` (0-6) belong ``{index: (2,)}`` in the affine image of the nominal
    configuration that the robots ``known`` ``{index: (2,)}`` span: from the three leaders when
    known (three points fix the map), else the least-squares fit to all known (none when those
    do not fix it)."""
    base = {k: known[k] for k in range(LEADERS)} if all(k in known for k in range(LEADERS)) else known
    rows = list(base)
    nominal = np.column_stack((NOMINAL[rows], np.ones(len(rows))))
    if np.linalg.matrix_rank(nominal) < 3:
        return {}
    fit = np.linalg.lstsq(nominal, np.array([base[k] for k in rows]), rcond=None)[0]
    return {k: np.append(NOMINAL[k], 1.0) @ fit for k in indices}


def clearing_shift(places: np.ndarray, crashed: np.ndarray, centre: float) -> float:
    """The shift along x (m) of least size that leaves every place of ``places`` ``(k, 2)`` at least
    :data:`CLEAR` from every crashed robot at ``crashed`` ``(m, 2)`` and within the tile centred at
    x = ``centre`` (less :data:`WALL`); 0 when none does."""
    room = ROBOTARIUM.width / 2 - WALL
    shifts = [0.0]
    for dx, dy in (crashed[:, None, :] - places[None, :, :]).reshape(-1, 2):
        if abs(dy) < CLEAR:
            half = math.sqrt(CLEAR**2 - dy**2)
            shifts += [dx - half, dx + half]
    for shift in sorted(shifts, key=abs):
        x = places[:, 0] + shift
        clear = (
            not len(crashed) or np.hypot(*(crashed[:, None, :] - places[None] - (shift, 0.0)).T).min() >= CLEAR - 1e-9
        )
        if clear and x.min() >= centre - room and x.max() <= centre + room:
            return shift
    return 0.0


def schedule() -> list[tuple[int, int, int, str, float]]:
    """The two bar passes as ``(deform, enter, leave, shape, gap)`` steps: the leaders take the
    shape at ``deform``, the bars enter at the right wall at ``enter`` and have left at the left
    wall at ``leave``, when the leaders return to the nominal shape."""
    crossing = round((ROBOTARIUM.width + 2 * ENTRY) / (BAR_SPEED * RPS.time_step))
    passes, t = [], SETTLE
    for shape, gap in zip(("compressed", "collinear"), GAPS):
        passes.append((t, t + LEAD, t + LEAD + crossing, shape, gap))
        t += LEAD + crossing + RECOVER
    return passes


def tile_places(robots: np.ndarray, shape: str, centres: np.ndarray) -> np.ndarray:
    """The places ``(k, 2)`` (m) of ``robots`` ``(k,)`` (ids) in ``shape`` about their tiles' ``centres``
    ``(g, 2)``, as the per-robot leaders compute them (the formation, then the tile's centre)."""
    return formation(shape)[robots % 7] + centres[robots // 7]


def shape_plan() -> tuple[np.ndarray, list[str], np.ndarray]:
    """What the leaders plan, as ``(steps (e,), shapes, offsets (e, 2))``: from ``steps[i]`` on, the
    formation ``shapes[i]`` moved by ``offsets[i]`` (m) from the tile's centre (to the right while
    the followers gather, then the passes' shapes and back to the nominal)."""
    events = [(0, "nominal", SHIFT), (GATHER, "nominal", 0.0)]
    for deform, _, leave, shape, _ in schedule():
        events += [(deform, shape, 0.0), (leave, "nominal", 0.0)]
    steps, shapes, shifts = zip(*events)
    return np.array(steps), list(shapes), np.column_stack((shifts, np.zeros(len(shifts))))
