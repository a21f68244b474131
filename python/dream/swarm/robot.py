"""A swarm robot: a robot whose decision is written once, on arrays with a leading robot axis.

A :class:`SwarmRobot` declares what a robot has (a movement sensor, a radio and the fields of its
messages, a memory, an optional HRVO safety layer) and how often it decides; its :meth:`decide`
turns what the robots deciding now know (a :class:`View`) into the velocities they want. The
engine (:mod:`dream.swarm.engine`) runs the same class robot by robot or as one swarm, with the
world's faults applied to the arrays, and both give the same poses at every step::

    class Meet(SwarmRobot):
        period = 10
        movement = Movement(range=0.5)
        radio = Radio(range=1.0, fields=("x", "y"))
        avoid = Avoid(safety=0.2)

        def decide(self, view):
            here = view.pose[:, :2]
            view.send(x=here[:, 0], y=here[:, 1])
            heard = view.heard.sum(["x", "y"]) + here
            centre = heard / (view.heard.count + 1)[:, None]
            return 0.5 * (centre - here)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from dream import rules
from dream._checks import Bounds, as_offsets, check_nonnegative
from dream.kernels import VoronoiCells
from dream.obstacles import Obstacle
from dream.robot import GUARD_HORIZON
from dream.specs import GRITSBOT, RobotSpec
from dream.swarm.cells import known_cells
from dream.swarm.neighbourhood import Neighbourhood

#: CSR rows of points, one row per deciding robot: ``(offsets (k + 1,), points (m, 2))``.
Rows = tuple[Any, Any]


@dataclass(frozen=True)
class Movement:
    """A movement sensor: the robots within ``range`` (m) and the field of view ``fov`` (rad,
    about the heading turned by ``direction``), seen with Gaussian ``noise`` on every value."""

    range: float = 0.5
    fov: float = 2 * math.pi
    direction: float = 0.0
    noise: float = 0.0

    def __post_init__(self) -> None:
        for name in ("range", "fov", "noise"):
            check_nonnegative(getattr(self, name), f"Movement {name}")
        if not math.isfinite(self.direction):
            raise ValueError(f"`Movement direction` must be finite, got {self.direction!r}")


@dataclass(frozen=True)
class Radio:
    """A radio: hears the robots within ``range`` (m), or linked to it in ``graph``, that have
    said something.

    ``fields`` names the message's fields (floats), or maps each to ``float`` or ``int`` (ints,
    such as ids, are never falsified by a Byzantine sender). ``loss`` drops each message with that
    probability; ``latency`` delays a message by that many steps (at least one). ``graph``, a
    communication graph as CSR ``(indptr (n + 1,), indices)`` (robot i hears the robots
    ``indices[indptr[i]:indptr[i + 1]]``, whatever their distance), replaces the range.
    """

    range: float = 1.0
    fields: tuple[str, ...] | Mapping[str, type] = ()
    loss: float = 0.0
    latency: int = 0
    graph: tuple[np.ndarray, np.ndarray] | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        check_nonnegative(self.range, "Radio range")
        if not 0.0 <= self.loss <= 1.0:
            raise ValueError(f"Radio loss is a probability in [0, 1], got {self.loss!r}")
        if isinstance(self.latency, bool) or not isinstance(self.latency, (int, np.integer)) or self.latency < 0:
            raise ValueError(f"Radio latency must be a whole number of steps >= 0, got {self.latency!r}")
        if self.graph is not None:
            indices = np.ascontiguousarray(self.graph[1], dtype=np.int64)
            indptr = as_offsets(self.graph[0], "Radio graph", len(indices), part="indptr")
            if len(indices) and (indices.min() < 0 or indices.max() >= len(indptr) - 1):
                raise ValueError(f"`Radio graph` indices must be robot ids in [0, {len(indptr) - 1})")
            object.__setattr__(self, "graph", (indptr, indices))
        for name, kind in self.kinds.items():
            if not name.isidentifier() or name in ("sender", "where"):
                raise ValueError(f"Radio field {name!r} must be an identifier other than 'sender' and 'where'")
            if kind not in (float, int):
                raise ValueError(f"Radio field {name!r} must be float or int, got {kind!r}")

    @property
    def kinds(self) -> dict[str, type]:
        """Each field's type."""
        if isinstance(self.fields, Mapping):
            return dict(self.fields)
        return {name: float for name in self.fields}


@dataclass(frozen=True)
class Avoid:
    """The HRVO safety layer between a robot's wish and its wheels (see :class:`dream.RobotHRVO`).

    HRVO picks the velocity closest to the wished one that no detected robot forbids within
    ``safety`` (m, centre to centre), and that keeps the robot ``margin`` (m, default its radius)
    inside the arena when ``check_boundaries``; a robot HRVO stops while it wants to move steps
    aside for ``sidestep`` decisions; the motion guard (``guard``) stops a unicycle whose turn
    would close in on a detected robot's body within ``horizon`` (s).
    """

    safety: float = 0.24
    check_boundaries: bool = True
    margin: float | None = None
    sidestep: int = 10
    guard: bool = True
    horizon: float = GUARD_HORIZON
    n_angles: int = 20
    n_speeds: int = 10
    include_preferred: bool = True

    def __post_init__(self) -> None:
        check_nonnegative(self.safety, "Avoid safety")
        check_nonnegative(self.horizon, "Avoid horizon")
        if self.margin is not None:
            check_nonnegative(self.margin, "Avoid margin")
        for name in ("sidestep", "n_angles", "n_speeds"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < (name != "sidestep"):
                raise ValueError(f"Avoid {name} must be a whole number >= {int(name != 'sidestep')}, got {value!r}")


@dataclass(frozen=True)
class Obstacles:
    """An obstacle sensor: the closest point of each of ``obstacles`` (the world's
    :class:`~dream.obstacles.Obstacle` list, read where they are now, moving ones too) within
    ``range`` (m, inclusive), none for an obstacle the robot is inside of, with Gaussian ``noise``
    on every coordinate."""

    obstacles: Sequence[Obstacle] = field(default=(), compare=False)
    range: float = 1.0
    noise: float = 0.0

    def __post_init__(self) -> None:
        for name in ("range", "noise"):
            check_nonnegative(getattr(self, name), f"Obstacles {name}")
        if not all(isinstance(o, Obstacle) for o in self.obstacles):
            raise ValueError("`Obstacles obstacles` must be a sequence of dream.Obstacle")


@dataclass(frozen=True)
class Guard:
    """The motion guard with a distance of its own: a unicycle whose drive along its heading
    would bring it within ``near`` (m, centre to centre) of a robot it sees in the next
    :data:`~dream.robot.GUARD_HORIZON` seconds gets no linear speed (it still turns). Without
    :class:`Avoid` it is the robot's only safety layer (no HRVO); with it, it replaces the
    distance :class:`Avoid` derives from its safety radius."""

    near: float

    def __post_init__(self) -> None:
        check_nonnegative(self.near, "Guard near")


@dataclass
class View:
    """What the robots deciding now know, one row per robot (``k`` of them).

    Attributes
    ----------
    ids : (k,) int
        Their ids (a robot knows its own name).
    clock : (k,) float
        Each robot's own clock (steps): the world's step, unless drift or jitter put it off.
    pose : (k, 3)
        Their odometry ``[x, y, theta]`` (m, m, rad), as noisy as the sensor.
    seen : Neighbourhood
        (read-only, as ``ids``) The movement sensor's detections, columns ``distance``,
        ``bearing`` (world frame, from the robot towards the other), ``dx``, ``dy`` (the other's
        position less the robot's), ``vx``, ``vy`` (the other's velocity); empty rows without a
        movement sensor.
    heard : Neighbourhood
        The messages the radio delivered: ``sender`` and the declared fields.
    memory : dict of (k,) arrays
        The robots' memory (:attr:`SwarmRobot.memory`); change it in place or assign new arrays.
    obstacles : Neighbourhood
        (read-only) The obstacle sensor's reading (:class:`Obstacles`), one entry per obstacle
        sensed, in the sensor's order: columns ``dx``, ``dy`` (the closest point less the
        robot's position) and ``distance``; empty rows without an obstacle sensor.
    command : (k, 2)
        (read-only) The command ``[v, w]`` (m/s, rad/s) each robot last gave its wheels, after
        the safety layer: held against its odometry, it tells a robot whether its wheels obey.
    """

    ids: np.ndarray
    clock: np.ndarray
    pose: np.ndarray
    seen: Neighbourhood
    heard: Neighbourhood
    memory: dict[str, np.ndarray]
    obstacles: Neighbourhood | None = None
    command: Any = None
    said: dict[str, np.ndarray] | None = field(default=None, repr=False)
    saying: Any = field(default=None, repr=False)  #: which rows send (``where`` of :meth:`send`)
    straight: Any = field(default=None, repr=False)  #: which rows skip HRVO (:meth:`direct`)
    heeded: Any = field(default=None, repr=False)  #: which detections the safety layer heeds (:meth:`heed`)
    safety: Any = field(default=None, repr=False)  #: each row's safety radius (:meth:`keep_apart`)
    turn: Any = field(default=None, repr=False)  #: each row's side and stop (:meth:`aside`)
    #: The engine's way to :meth:`cells` of robots ``ids`` from the board, for a range radio
    #: (None: the rows').
    board_cells: Any = field(default=None, repr=False)

    def __len__(self) -> int:
        return len(self.ids)

    def send(self, where: Any = None, **fields: Any) -> None:
        """Broadcast a message from the robots deciding now: one ``(k,)`` array (or one value for
        all) per declared field of the radio. ``where`` ``(k,)`` bool, optional, picks the robots
        that send (the others say nothing this time, and are heard saying what they said last).
        A later call replaces an earlier one."""
        self.said, self.saying = dict(fields), where

    def direct(self, rows: Any) -> None:
        """Drive the wishes of the robots flagged in ``rows`` ``(k,)`` bool as they are, without the
        HRVO layer (and without stepping aside): for a robot settling its last centimetres, whose
        neighbours' velocity obstacles would forbid the very direction of its place. The motion
        guard still checks them. A later call replaces an earlier one."""
        self.straight = rows

    def heed(self, detections: Any) -> None:
        """Let the HRVO layer and the motion guard heed only the detections flagged in
        ``detections`` (one bool per entry of :attr:`seen`): for a robot that sees farther than
        it avoids, or avoids only some of the robots it sees (a leader that ignores its
        followers). A later call replaces an earlier one."""
        self.heeded = detections

    def keep_apart(self, safety: Any) -> None:
        """Plan the rows' HRVO and motion guard with their own combined safety radii ``safety``
        ``(k,)`` (m) instead of :attr:`Avoid.safety`: for a robot that squeezes through a gap, say.
        A later call replaces an earlier one."""
        self.safety = safety

    def aside(self, side: Any = 0.0, stop: Any = False) -> None:
        """Choose how the rows step aside when HRVO blocks them: ``side`` ``(k,)`` (1.0: to the
        right, -1.0: to the left, 0.0: as before) and ``stop`` ``(k,)`` bool (stop stepping aside
        now). A later call replaces an earlier one."""
        self.turn = (side, stop)

    def cells(
        self,
        x: str = "x",
        y: str = "y",
        *,
        seen: Rows | None = None,
        same: float = 0.0,
        virtual: Rows | None = None,
        radius: float,
        bounds: Bounds,
        resolution: int = 64,
        polygons: bool = False,
    ) -> VoronoiCells:
        """Each deciding robot's Voronoi cell from what it alone knows (:func:`dream.swarm.known_cells`):
        the disc of ``radius`` (m) around its odometry position within ``bounds``, clipped by the
        positions its messages give (fields ``x`` and ``y``), then by the positions it sees,
        ``seen`` (CSR rows ``(offsets (k + 1,), points (m, 2))``), that lie farther than ``same``
        (m) from every one of those (a robot seen that no message accounts for, a crashed one
        say), then by its ``virtual`` agents (CSR rows; :func:`dream.kernels.obstacle_agents`).

        For a range radio, the engine looks only at the messages near each cell
        (:func:`dream.kernels.heard_cells`, drawing their losses as the perception does, or
        leaving out those a loss burst took as the inbox was listed): a robot in a crowd hears
        hundreds, of which a dozen shape its cell. The cells are the same, to the bit.
        """
        empty: Rows = (np.zeros(len(self) + 1, dtype=np.int64), np.zeros((0, 2)))
        seen, virtual = seen or empty, virtual or empty
        here = self.pose[:, :2]
        shape: dict[str, Any] = {"radius": radius, "bounds": bounds, "resolution": resolution, "polygons": polygons}
        if self.board_cells is not None:
            cells: VoronoiCells = self.board_cells(np.asarray(self.ids), here, (x, y), seen, same, virtual, **shape)
            return cells
        heard = self.heard
        messages = np.column_stack((heard[x], heard[y])).reshape(-1, 2)
        far = rules.far_from(seen[1], messages, same, offsets=(seen[0], heard.offsets))
        silent = (np.concatenate(([0], np.cumsum(far)))[np.asarray(seen[0])], np.asarray(seen[1])[far])
        return known_cells(here, (heard.offsets, messages), silent, virtual, **shape)


class SwarmRobot:
    """Base class of a robot written on arrays (see the module docs).

    Class attributes (or instance attributes set in ``__init__``)
    --------------------------------------------------------------
    period : int
        Steps between two decisions of a robot, on its own clock.
    movement : Movement or None
        The movement sensor.
    radio : Radio or None
        The radio and its message fields.
    avoid : Avoid or None
        The HRVO safety layer on the wished velocities.
    obstacles : Obstacles or None
        The obstacle sensor.
    guard : Guard or None
        The motion guard at a distance of its own (with or without :attr:`avoid`).
    halts : bool
        A robot that wishes no velocity gets no command at all (default False: the unicycle
        conversion's, which for a zero wish turns a robot heading between -pi and -pi/2 at full
        speed, ``atan2(+0, -0) = pi``).
    threaded : bool
        :meth:`decide` reads nothing but its view and keeps nothing of its own (no state on
        ``self``, no random draws of its own), so that each robot's result depends on its own row
        alone, as robot by robot. A swarm of such robots then decides in blocks of at least
        :data:`~dream.swarm.engine.LEAST_BLOCK` rows on several threads at once (one per core of
        the Rust kernels' pool), with the same bits: NumPy gives the thread back while it works
        on a block's arrays. Work a decision does once a call for the whole swarm (``cells`` of
        a range radio looks up the whole board) is then done once a block. Default False: one
        call for all the rows.
    memory : dict
        Each memory field's initial value (a float or an int, or an array of them: each robot then
        keeps one of that shape), kept per robot between decisions.
    odometry_noise : float
        Standard deviation of the noise on every odometry value.
    vel_gain, ang_gain : float
        The single-integrator to unicycle conversion's gains (:meth:`dream.Robot.dxi_to_dxu`).
    spec : RobotSpec
        The robot's limits (default: GRITSbot).
    """

    period: int = 10
    movement: Movement | None = None
    radio: Radio | None = None
    avoid: Avoid | None = None
    obstacles: Obstacles | None = None
    guard: Guard | None = None
    halts: bool = False
    threaded: bool = False
    memory: ClassVar[dict[str, Any]] = {}
    odometry_noise: float = 0.0
    vel_gain: float = 0.8
    ang_gain: float = 3.0
    spec: RobotSpec = GRITSBOT

    def start(self, ids: np.ndarray) -> np.ndarray:
        """Each robot's start-up delay (steps, ``(n,)`` ints): it decides first after it (default 0)."""
        return np.zeros(len(ids), dtype=np.int64)

    def decide(self, view: View) -> np.ndarray:
        """The velocities ``(k, 2)`` (m/s, world frame) the deciding robots want; call
        ``view.send(...)`` to broadcast and change ``view.memory`` to remember."""
        raise NotImplementedError(f"{type(self).__name__} must define decide(self, view)")
