"""The World: everything the original DREAM kept in module globals, in one object.

A world owns the radio message board, the registered timers, the clock of the last
``update_timers`` call, a seeded random generator (sensor noise, message loss) and the
neighbour index of the current poses, built once per step for all sensors and radios. Original
scripts use the default world through the module-level functions; ``with World(seed=1):``
makes a fresh world current for the block, so runs in one process never see each other's
messages or timers::

    >>> from dream import World, RangeRadio
    >>> with World(seed=0) as world:
    ...     radio = RangeRadio(0, "radio", callback=lambda messages: None)
    ...     radio.send_data({"state": 1})
    ...     world.messages
    {0: {'state': 1}}
"""

from __future__ import annotations

import copy
import math
import pickle
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from dream import kernels
from dream._checks import as_array, as_poses
from dream.faults import Faults, FaultState
from dream.obstacles import sensed
from dream.timers import Timer

if TYPE_CHECKING:
    from dream.obstacles import Obstacle
    from dream.specs import ArenaSpec, SimulatorSpec


class World:
    """Shared state of one simulation: message board, timers, clock and random generator.

    Parameters
    ----------
    seed : int, optional
        Seed of the world's random generator; the same seed gives the same noise and losses.
    """

    def __init__(self, seed: int | None = None) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.fault_state: FaultState | None = None  #: the run's faults as drawn (see :meth:`inject`)
        self.time: float = 0  #: the ``current_time`` of the last ``update_timers`` call
        self.timers: list[Timer] = []
        #: The arena robots without one of their own keep to, and the limits they tighten theirs to:
        #: the simulator's, given by whoever runs it (:meth:`keep_to`); ``None`` before that.
        self.arena: ArenaSpec | None = None
        self.limits: SimulatorSpec | None = None
        self._board: dict[int, Any] = {}
        self._mutable: set[int] = set()  # senders whose message on the board each reader must copy
        self._in_flight: list[tuple[float, int, Any]] = []  # (visible at, sender, data)
        self._indexed_poses: np.ndarray | None = None  # the pose array the indexes were built for
        self._indexed_xy = b""  # ...and the bytes of its positions then, to notice in-place changes
        self._indexes: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        # Every robot's obstacle reading, by range: the obstacles' layout it was read for, and it.
        self._readings: dict[float, tuple[tuple[Any, ...], np.ndarray]] = {}
        self._checked_input: Any = None  # the last pose array checked, at clock `_checked_time`
        self._checked_time: float = -1
        self._checked = np.zeros((3, 0))
        self._commands_input: Any = None  # the last command array checked as is, at `_commands_time`
        self._commands_time: float = -1

    def keep_to(self, arena: ArenaSpec, limits: SimulatorSpec) -> None:
        """Make the robots of this world keep to ``arena`` (those without one of their own) and to
        ``limits``: the simulator's, which the runner (or :func:`dream.make_robotarium`) gives."""
        self.arena, self.limits = arena, limits

    # -- poses -----------------------------------------------------------------------------
    def checked_poses(self, x: Any) -> np.ndarray:
        """``x`` checked as a ``(3, n)`` pose array (shape, finite values).

        Every sensor and radio of a step receives the same array: it is checked once per
        step of the world's clock, not once per sensor.
        """
        if x is not self._checked_input or self.time != self._checked_time:
            self._checked = as_poses(x, "x")
            self._checked_input, self._checked_time = x, self.time
        return self._checked

    def checked_commands(self, v: Any, n: int) -> np.ndarray:
        """``v`` checked as the ``(2, n)`` unicycle commands of the step (shape, finite values).

        Checked once per step of the world's clock when ``v`` is already a float64 array (robots
        write their columns into it during the step, and every sensor sees that array itself);
        anything else is converted at every call, so that no sensor reads a stale copy.
        """
        if v is self._commands_input and self.time == self._commands_time and v.shape == (2, n):
            return v
        commands = as_array(v, "v", (2, n))
        if commands is v:
            self._commands_input, self._commands_time = v, self.time
        return commands

    # -- neighbours ------------------------------------------------------------------------
    def neighbours_of(
        self,
        poses: np.ndarray,
        robot_id: int,
        radius: float,
        *,
        heading: float | None = None,
        direction: float = 0.0,
        fov: float = 2 * np.pi,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Robot ``robot_id``'s neighbours ``(indices, distances)`` in the checked poses ``(3, n)``.

        Same answer as :func:`dream.kernels.neighbours_of`, but from one whole-swarm index per
        pose array and radius (Rust grid query), shared by every sensor and radio of the step.
        """
        self._fresh(poses)
        if radius not in self._indexes:
            self._indexes[radius] = kernels.neighbours(poses[:2].T, radius)
        indptr, indices, distances = self._indexes[radius]
        row = slice(indptr[robot_id], indptr[robot_id + 1])
        found, dist = indices[row], distances[row]
        # A full circle sees everyone: the wrapped angle below is never beyond pi.
        if heading is None or fov >= 2 * np.pi:
            return found, dist
        dx = poses[0, found] - poses[0, robot_id]
        dy = poses[1, found] - poses[1, robot_id]
        relative = (np.arctan2(dy, dx) - (heading + direction) + np.pi) % (2 * np.pi) - np.pi
        seen = (np.abs(relative) <= fov / 2) | (dist == 0)
        return found[seen], dist[seen]

    def _fresh(self, poses: np.ndarray) -> None:
        """Forget what was found for other poses than ``poses`` (checked, ``(3, n)``)."""
        # The bytes of the positions tell in-place changes (rps moves one array) far faster
        # than an element-wise comparison; the poses are checked finite, so equal bytes are equal values.
        xy = poses[:2].tobytes()
        if poses is not self._indexed_poses or xy != self._indexed_xy:
            self._indexed_poses, self._indexed_xy = poses, xy
            self._indexes, self._readings = {}, {}

    def obstacles_near(
        self, poses: np.ndarray, robot_id: int, obstacles: Sequence[Obstacle], radius: float
    ) -> np.ndarray:
        """What robot ``robot_id``'s obstacle sensor reads in the checked poses ``(3, n)``: the
        closest point of each of ``obstacles`` ``(k, 2)``, NaN beyond ``radius`` or around it.

        Same answer as :func:`dream.obstacles.sensed` for that robot, but from one whole-swarm call
        per pose array, obstacle layout and range, shared by every obstacle sensor of the step.
        """
        self._fresh(poses)
        # The obstacles' layout, not the list's identity: obstacles move between steps. The
        # angle's sign too: -0.0 and 0.0 are equal, but their sines differ in sign.
        layout = tuple((o.center.tobytes(), o.size.tobytes(), o.angle, math.copysign(1.0, o.angle)) for o in obstacles)
        known, reading = self._readings.get(radius, ((), None))
        if reading is None or known != layout:
            reading = sensed(obstacles, poses[:2].T, radius)
            self._readings[radius] = (layout, reading)
        return reading[robot_id]

    # -- faults ----------------------------------------------------------------------------
    def inject(self, faults: Faults | None, n: int) -> FaultState | None:
        """Make ``faults`` happen to this world's ``n`` robots from now on.

        Who fails and when is drawn from a child of the world's generator: the same seed gives
        the same fault events, and a run without faults draws nothing.
        """
        self.fault_state = None if faults is None or not faults.any else FaultState(faults, n, self.rng.spawn(1)[0])
        return self.fault_state

    def _silence(self, robot_id: int) -> None:
        """A crashed robot stops talking: its messages leave the board and the air."""
        self._board.pop(robot_id, None)
        self._mutable.discard(robot_id)
        self._in_flight = [message for message in self._in_flight if message[1] != robot_id]

    # -- radio -----------------------------------------------------------------------------
    def publish(self, robot_id: int, data: Any, latency: int = 0) -> None:
        """Put ``data`` on the board under ``robot_id`` (a later send overwrites an earlier one).

        The board keeps a deep copy, so the sender's later changes reach nobody. With
        ``latency`` > 0 the message becomes visible ``latency`` steps of the world's clock later.
        """
        snapshot = _copy(data)
        state = self.fault_state
        if state is not None:
            if state.crashed[robot_id]:
                return
            if state.byzantine[robot_id]:
                snapshot = state.lie(robot_id, snapshot, int(self.time))
            latency = state.delay(latency)
        if latency > 0:
            self._in_flight.append((self.time + latency, robot_id, snapshot))
        else:
            self._post(robot_id, snapshot)

    def _post(self, sender: int, data: Any) -> None:
        """Make ``data`` the board's message of ``sender``, noting once whether readers must copy
        it (a coverage robot's ``(id, x, y)`` is read by hundreds: checking it for each cost a
        tenth of a 1000-robot step)."""
        self._board[sender] = data
        (self._mutable.discard if _immutable(data) else self._mutable.add)(sender)

    @property
    def messages(self) -> dict[int, Any]:
        """The board ``{robot_id: data}`` as it is visible now."""
        self._deliver()
        return self._board

    def receive(self, senders: Iterable[int], loss: float = 0.0, receiver: int | None = None) -> list[Any]:
        """Copies of the visible messages of ``senders`` (in the given order).

        Robots that have not published are skipped; each message is dropped with probability
        ``loss``, drawn from the world's generator, and by the world's radio faults, if any
        (``receiver`` names the robot listening, for per-link and distance losses).
        """
        board, mutable = self.messages, self._mutable
        state = self.fault_state
        if state is None and loss <= 0:  # nothing lost: the common case, hundreds of senders a call
            return [
                _copy(board[sender]) if sender in mutable else board[sender] for sender in senders if sender in board
            ]
        received = []
        for sender in senders:
            if sender not in board:
                continue
            if state is None:
                through = loss <= 0 or self.rng.random() >= loss
            else:
                through = state.delivered(receiver, sender, loss, self._distance(receiver, sender))
            if through:
                received.append(_copy(board[sender]) if sender in mutable else board[sender])
        return received

    def _distance(self, a: int | None, b: int) -> float:
        """Distance between robots ``a`` and ``b`` in the poses checked last (0 if unknown)."""
        poses = self._checked
        if a is None or max(a, b) >= poses.shape[1]:
            return 0.0
        return float(np.hypot(*(poses[:2, a] - poses[:2, b])))

    def _deliver(self) -> None:
        if not self._in_flight:
            return
        waiting = []
        for visible_at, sender, data in self._in_flight:
            if visible_at <= self.time:
                self._post(sender, data)
            else:
                waiting.append((visible_at, sender, data))
        self._in_flight = waiting

    # -- timers ----------------------------------------------------------------------------
    def create_timer(self, robot_id: int, delay: float, list_of_timers: Sequence[Mapping[str, Any]]) -> Timer:
        """Create a :class:`~dream.timers.Timer` and register it in this world."""
        timer = Timer(robot_id, delay, list_of_timers)
        self.timers.append(timer)
        return timer

    def update_timers(self, current_time: float, param: Mapping[str, Sequence[Any]]) -> None:
        """Advance the clock to ``current_time`` and update every timer of this world.

        Under faults, crashed robots' timers stand still and each robot's timers read its own
        (drifting, jittery) clock.
        """
        self.time = current_time
        state = self.fault_state
        if state is None:
            for timer in self.timers:
                timer.update(current_time, param)
            return
        for crashed in np.flatnonzero(state.advance(int(current_time))):
            self._silence(int(crashed))
        clocked = bool(state.faults.drift or state.faults.clock_jitter)
        for timer in self.timers:
            robot = timer.robot_id
            if robot < state.n and state.crashed[robot]:
                continue
            timer.update(state.clock(robot, current_time) if clocked and robot < state.n else current_time, param)

    # -- current world ---------------------------------------------------------------------
    def __enter__(self) -> World:
        _stack.append(self)
        return self

    def __exit__(self, *exc: object) -> None:
        _stack.remove(self)

    def __repr__(self) -> str:
        return f"World(seed={self.seed}, time={self.time}, timers={len(self.timers)}, messages={len(self._board)})"


#: Types whose values no reader can change: a message of these (or a tuple of them) is shared.
_IMMUTABLE = frozenset({int, float, bool, complex, str, bytes, type(None), np.float64, np.int64, np.bool_})


def _copy(data: Any) -> Any:
    """A deep copy; none for values no reader can change (numbers and strings, alone or in a
    tuple: ``(id, x, y)``, the usual messages of the coverage and consensus robots; copying them
    for each of 300 listeners was most of a 1000-robot coverage step), arrays of numbers, alone
    or in a tuple or list, copied directly, the rest through pickle when possible, which is many
    times faster than ``deepcopy`` for the lists and arrays robots usually send."""
    if _immutable(data):
        return data
    if _plain_array(data):
        return data.copy(order="K")
    if type(data) in (tuple, list) and all(_plain_array(item) for item in data):
        return type(data)(item.copy(order="K") for item in data)
    try:
        return pickle.loads(pickle.dumps(data, protocol=pickle.HIGHEST_PROTOCOL))
    except (pickle.PicklingError, TypeError, AttributeError):
        return copy.deepcopy(data)


def _immutable(data: Any) -> bool:
    """Whether no reader can change ``data``: a number or string, alone or in a tuple of them."""
    kind = type(data)
    return kind in _IMMUTABLE or (kind is tuple and _IMMUTABLE.issuperset(map(type, data)))


def _plain_array(data: Any) -> bool:
    """Whether ``data`` is an ndarray (not a subclass) of numbers, which ``copy`` copies deeply."""
    return type(data) is np.ndarray and not data.dtype.hasobject


_stack: list[World] = [World()]


def current_world() -> World:
    """The innermost world entered with ``with``, or the default world."""
    return _stack[-1]


def reset_default_world(seed: int | None = None) -> World:
    """Replace the default world (for scripts that run several simulations in sequence)."""
    _stack[0] = World(seed)
    return _stack[0]


def create_timer(robot_id: int, delay: float, list_of_timers: Sequence[Mapping[str, Any]]) -> Timer:
    """Create a timer for ``robot_id`` in the current world (see :class:`Timer`)."""
    return current_world().create_timer(robot_id, delay, list_of_timers)


def update_timers(current_time: float, param: Mapping[str, Sequence[Any]]) -> None:
    """Update every timer of the current world; call once per simulation step.

    ``param`` maps each tag to the tuple of arguments of its callbacks, e.g.
    ``{"odom": (x,), "movement": (x, dxu), "robot": (dxu,)}``.
    """
    current_world().update_timers(current_time, param)
