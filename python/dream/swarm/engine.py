"""The engine: the world of a :class:`~dream.swarm.robot.SwarmRobot`, applied to arrays.

Every step, for the robots whose clocks say they decide (``period`` steps on each robot's own
clock, after its start-up delay; crashed robots never), the engine reads their odometry, their
movement sensor and the messages their radio delivers, with the world's faults, calls
:meth:`~dream.swarm.robot.SwarmRobot.decide` and carries the wished velocities through the
HRVO safety layer, the unicycle conversion, the actuator limits and the motion guard
(:mod:`dream.swarm.safety`). The robots that do not decide keep their last command.

What the robots deciding now perceive comes from one pass over their neighbours in the true
poses (:func:`dream.kernels.perceive`, parallel in Rust); every random draw (noise, dropout,
loss, bursts, jitter, lies) is a counter-based hash of who, when and what
(:mod:`dream.swarm.draws`). So the engine runs the
deciding robots one at a time (``one_by_one=True``: robot by robot) or all at once (the swarm)
with the same poses at every step.

Messages are fixed-width records of the radio's declared fields. A message sent at step t is
heard from step ``t + 1 + latency`` on (latency: the radio's, the fault's, its jitter), and a
robot hears the newest message of each sender in range that has arrived; a crashed robot's
messages leave the air.
"""

from __future__ import annotations

import math
import operator
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from functools import cache, partial
from typing import Any

import numpy as np

from dream import kernels
from dream._checks import all_finite, per_robot
from dream.faults import CONSTANT_LIE, DRIFT_PER_STEP, RANDOM_LIE, FaultState
from dream.kernels import Loss, VoronoiCells
from dream.kernels._dispatch import implementation
from dream.kernels._neighbours import Heard, Perceived
from dream.obstacles import sensed
from dream.sensors import seen_velocity
from dream.specs import ArenaSpec, SimulatorSpec
from dream.swarm import byrobot, draws
from dream.swarm.neighbourhood import Deferred, Loaded, Neighbourhood, Summed, summing
from dream.swarm.robot import SwarmRobot, View
from dream.swarm.rows import at_rows, put_all, put_rows, take_all, take_rows
from dream.swarm.safety import drive
from dream.swarm.threads import spread, threads
from dream.traffic import Traffic

#: What robots said: their ids ``(k,)`` and their message's fields (name to ``(k,)``).
Said = tuple[np.ndarray, dict[str, np.ndarray]]
#: A checked decision: the wished velocities, the rows driven direct, the safety radii, the
#: detections heeded (None where not chosen) and what was said.
Settled = tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray | None, Said | None]
#: The fewest robots a block of a swarm decided on a thread of its own holds. NumPy gives the
#: interpreter's lock back while it works on a block's arrays; between two calls each thread waits
#: for it, and on small blocks that wait is most of the time (at a million robots on 16 cores,
#: blocks of 12,000 rows gained less than blocks of 32,768; on 2 cores, blocks of 10,000 nothing).
LEAST_BLOCK = 32768
#: The values a movement sensor measures of each robot it sees, in the order of their noise keys
#: (the offsets ``dx`` and ``dy`` follow from the distance and the bearing).
SENSED = ("distance", "bearing", "vx", "vy")


class Engine:
    """Runs ``n`` robots of one :class:`SwarmRobot` (see the module docs).

    Parameters
    ----------
    robot : SwarmRobot
        The robots' declarations and decision rule.
    n : int
        Number of robots.
    seed : int
        Keys every random draw.
    arena : ArenaSpec
        The arena HRVO keeps the robots in.
    one_by_one : bool
        Robot by robot (each deciding robot on its own view) instead of the whole swarm at once.
    """

    def __init__(self, robot: SwarmRobot, n: int, seed: int, arena: ArenaSpec, *, one_by_one: bool = False) -> None:
        self.robot, self.n, self.seed, self.arena, self.one_by_one = robot, n, seed, arena, one_by_one
        name = type(robot).__name__
        period = robot.period
        if isinstance(period, bool) or not isinstance(period, (int, np.integer)) or period < 0:
            raise ValueError(f"{name}.period must be a whole number of steps >= 0, got {period!r}")
        self.start = np.asarray(robot.start(np.arange(n)), dtype=np.int64)
        if self.start.shape != (n,):
            raise ValueError(f"{name}.start(ids) returned shape {self.start.shape}, expected (n,) = ({n},)")
        self.limits = robot.spec
        self.last = np.zeros(n)  #: each robot's clock at its last decision
        self.belief = np.full((n, 3), np.nan)  #: each robot's odometry, NaN until its first reading
        self.dxi = np.zeros((n, 2))  #: each robot's last chosen velocity (m/s)
        #: each robot's memory, ``(n, *shape)`` per field (a field declared as an array keeps one per robot)
        self.memory = {key: np.full((n, *np.shape(value)), value) for key, value in robot.memory.items()}
        self.silenced = np.zeros(n, dtype=bool)  #: crashed robots whose messages left the air
        self.sidestep = np.zeros(n, dtype=np.int64)
        self.side = np.ones(n)
        kinds = {} if robot.radio is None else robot.radio.kinds
        self.kinds = {key: np.dtype(np.float64 if kind is float else np.int64) for key, kind in kinds.items()}
        self.board = {key: np.zeros(n, dtype=kind) for key, kind in self.kinds.items()}
        self.sent_at = np.full(n, -1, dtype=np.int64)  #: step of each sender's message on the board
        # Messages in the air: when each is heard, its sender, when it was sent, and its fields.
        self.air: dict[str, np.ndarray] = {
            "visible": np.zeros(0, dtype=np.int64),
            "sender": np.zeros(0, dtype=np.int64),
            "sent": np.zeros(0, dtype=np.int64),
            **{key: np.zeros(0, dtype=kind) for key, kind in self.kinds.items()},
        }
        self.lossy = np.zeros(0, dtype=np.int64)  #: links (receiver * n + sender) in a loss burst
        self.traffic = Traffic(n)  #: each robot's messages sent, heard and lost so far
        #: whether to count them (the runner counts only for an output that reads them: the
        #: trajectory log, a recording; without, a range radio's inbox is found only when read)
        self.count_traffic = True
        #: whether a decision has read a deferred inbox: from then on it is found with the robots
        #: seen, in the same neighbour query (one pass where two would be made)
        self.inbox_read = False
        #: whether a decision has read a deferred inbox for its count, sums or means only: from
        #: then on those are found in the perception's pass, without the inbox's rows, until a
        #: decision reads more of it (then it is read, as above)
        self.inbox_summed = False
        #: whether a decision has read the velocities of the robots seen: from then on they are
        #: carried to them in the perception's pass
        self.velocities_read = False
        self.focus: int | None = None  #: a robot whose last readings and inbox to keep (for a recording)
        #: robot :attr:`focus`'s last decision: its ``step``, and the columns of what it ``seen`` and ``heard``
        self.focus_view: dict[str, Any] = {}
        #: robot by robot, the view of every robot deciding now and the views cut from it
        self._cut: tuple[View | None, list[View], Sequence[int]] = (None, [], [])
        self._handed: list[dict[str, np.ndarray]] = []  #: the memory rows each of those views was handed

    def attach(self, simulator: SimulatorSpec) -> None:
        """Keep to the limits of the simulator the robots run on."""
        self.limits = self.robot.spec.within(simulator)

    # -- the step --------------------------------------------------------------------------
    def step(self, t: int, x: np.ndarray, commands: np.ndarray, faults: FaultState | None = None) -> np.ndarray:
        """Decide at step ``t`` from the poses ``x`` ``(3, n)``: ``commands`` ``(2, n)`` (the last
        ones, which the movement sensors see) with the deciding robots' columns replaced."""
        views = self.perceive(t, x, commands, faults)
        bounds = None
        if len(views) == 1 and not self.one_by_one and self.robot.threaded:
            bounds = byrobot.blocks(len(views[0]), threads(), LEAST_BLOCK)
        if bounds is None:
            return self.act(t, views, [self.robot.decide(view) for view in views], commands, faults)
        pieces = self._pieces(views[0], bounds)
        return self.act(t, pieces, list(_pool().map(self.robot.decide, pieces)), commands, faults)

    def perceive(self, t: int, x: np.ndarray, commands: np.ndarray, faults: FaultState | None = None) -> list[View]:
        """What the robots due to decide at step ``t`` know: one :class:`View` per robot robot by
        robot, else one for all of them (none if no robot decides). :meth:`step` is this, each
        view's :meth:`~SwarmRobot.decide`, then :meth:`act`; a learner (:mod:`dream.rl`) decides
        in between."""
        if faults is not None and (faults.crashed & ~self.silenced).any():
            self._silence(faults.crashed & ~self.silenced)
        self._deliver(t)
        clock = self._clock(t, faults)
        due = (clock > self.start) & (clock - self.last >= self.robot.period)
        if faults is not None:
            due &= ~faults.crashed
        rows = np.flatnonzero(due)
        self.last[rows] = _clocks(clock, rows)
        known = self._odometry(t, rows, x, faults)
        if not known.all():
            rows = rows[known]
        if self.robot.movement is not None:  # a robot whose sensor reading is lost holds its command
            rows = rows[self._kept(t, rows, np.full(len(rows), -2), faults)]
        if self.robot.obstacles is not None:  # so does one whose obstacle reading is lost
            rows = rows[self._kept(t, rows, np.full(len(rows), -3), faults)]
        self._cut = (None, [], [])
        if not len(rows):
            return []
        talking = self.sent_at >= 0
        whole = self._view(t, rows, _clocks(clock, rows), x, commands, talking, faults)
        if not self.one_by_one:
            return [whole]
        return self._pieces(whole, range(len(whole) + 1))  # perceived at once, decided one by one

    def _pieces(self, whole: View, bounds: Sequence[int]) -> list[View]:
        """``whole`` cut into the pieces of rows ``bounds`` (:func:`~dream.swarm.byrobot.cut`), kept
        with the memory each was handed until :meth:`act` carries them out."""
        pieces = byrobot.cut(whole, bounds)
        self._cut, self._handed = (whole, pieces, bounds), [dict(view.memory) for view in pieces]
        return pieces

    def act(
        self,
        t: int,
        views: list[View],
        wishes: list[np.ndarray],
        commands: np.ndarray,
        faults: FaultState | None = None,
    ) -> np.ndarray:
        """Carry out the velocities ``wishes`` (one ``(k, 2)`` per view of :meth:`perceive`) and
        what the views remember and send: ``commands`` ``(2, n)`` with the deciding robots' columns
        replaced."""
        out = commands.copy()
        whole, pieces, bounds = self._cut
        if whole is not None and len(views) == len(pieces) and all(map(operator.is_, views, pieces)):
            said = self._apply_pieces(whole, views, list(wishes), bounds, out)
        else:
            said = [self._apply(view, wished, out) for view, wished in zip(views, wishes)]
        self._cut, self._handed = (None, [], []), []  # the step's views are done with (a checkpoint keeps none)
        if self.robot.radio is not None:
            self._publish(t, [s for s in said if s is not None], faults)
        return out

    def _view(
        self,
        t: int,
        rows: np.ndarray,
        clock: np.ndarray,
        x: np.ndarray,
        commands: np.ndarray,
        talking: np.ndarray,
        faults: FaultState | None,
    ) -> View:
        """What the robots ``rows`` perceive and hear."""
        movement, radio = self.robot.movement, self.robot.radio
        # What the sensors see of the others' motion: their commands before anyone decides now,
        # every robot's, carried to the robots seen or worked out when first read (see
        # _velocities_carried).
        reported = partial(seen_velocity, commands, x[2])
        carried = movement is not None and self._velocities_carried(faults)
        velocities = reported() if carried else ()
        # A range radio's losses are drawn where the kernels find the messages, but for bursty
        # links': a link's chain steps on every message offered, listed for _hear.
        by_range = radio is not None and radio.graph is None
        found = by_range and (faults is None or faults.faults.burst is None)
        loss = self._loss(t, faults) if found else None
        # Without counts to keep, the inbox is found only if the decision reads it (View.cells
        # need not: a robot in a crowd hears hundreds of messages), until one does; a decision
        # that has only counted or summed it gets those from the perception's pass, as do the
        # world's fault counts the messages lost (then counted there, for every inbox).
        deferred = found and not self.count_traffic and not self.inbox_read
        floats = [name for name, kind in self.kinds.items() if kind.kind == "f"]
        counted = loss is not None and faults is not None
        in_pass = deferred and ((self.inbox_summed and bool(floats)) or counted)
        summed = (floats if self.inbox_summed else []) if in_pass else None
        listened = by_range and (not deferred or in_pass)
        seen, heard = kernels.perceive(
            x[:2].T,
            x[2],
            rows,
            sight=None if movement is None else (movement.range, movement.fov, movement.direction),
            radio_range=radio.range if radio is not None and listened else None,
            talking=talking if listened else None,
            carried=velocities,  # read at the robots seen, in the same pass
            bearings=self._bearings_read(faults),
            summed=None if summed is None else [self.board[name] for name in summed],
            loss=loss if listened else None,
        )
        if counted:  # listened to, deferred or not
            assert faults is not None
            faults.messages_lost += int(heard[3].sum())
        if radio is not None and radio.graph is not None:
            heard = _linked(
                radio.graph, rows, x, talking, measured=faults is not None and faults.faults.distance_loss > 0
            )
        inbox: Neighbourhood
        lost = None  # what gives the links whose messages were lost as the inbox was listed (bursts)
        if deferred:
            assert radio is not None
            sums = Summed(np.diff(heard[0]), dict(zip(summed or [], heard[4:], strict=True))) if in_pass else None

            def load() -> Neighbourhood:
                if summing() and not (sums is not None and sums.sums):  # counted or summed only, so far
                    self.inbox_summed = True
                else:
                    self.inbox_read = True
                heard = kernels.perceive(x[:2].T, x[2], rows, radio_range=radio.range, talking=talking, loss=loss)[1]
                return self._hear(t, rows, heard, faults, drawn=loss is not None)[0].frozen()

            inbox = Deferred(load, sums)
        else:
            inbox, lost = self._hear(t, rows, heard, faults, drawn=loss is not None)
            inbox = inbox.frozen()
        ids, command = rows.copy(), commands.T[rows]  # (k, 2) rows of their own
        ids.flags.writeable = command.flags.writeable = False
        at = at_rows(rows, self.n)
        view = View(
            ids,
            clock.copy(),
            take_rows(self.belief, at),
            self._sense(t, rows, seen, faults, reported).frozen(),
            inbox,
            take_all(self.memory, at),
            self._obstacles(t, rows, x, faults).frozen(),
            command,
        )
        if by_range:
            view.board_cells = partial(self._board_cells, x[:2].T, talking, loss, lost)
        if self.focus is not None:
            self._keep_focus(t, rows, view, self.focus)
        return view

    def _apply(self, view: View, wished: Any, out: np.ndarray) -> Said | None:
        """Check a view's decision, keep its memory and put its commands into ``out``. Returns what
        its robots said (their ids and fields), if anything."""
        rows = np.asarray(view.ids)
        at = at_rows(rows, self.n)
        wished, straight, safety, heeded, said = self._settle(view, wished)
        seen = view.seen if heeded is None else view.seen.where(heeded)
        out[:, at] = drive(self, rows, wished, take_rows(self.belief, at), seen, straight, safety)
        return said

    def _apply_pieces(
        self, whole: View, views: list[View], wishes: list[Any], bounds: Sequence[int], out: np.ndarray
    ) -> list[Said | None]:
        """:meth:`_apply` of the views :func:`~dream.swarm.byrobot.cut` made of ``whole`` (rows
        ``bounds``): each decision checked and kept on its own, all of them driven at once."""
        pieces = zip(views, wishes, self._handed, bounds[:-1], bounds[1:])
        settled = [self._settle(view, wish, (whole.memory, slice(a, b), kept)) for view, wish, kept, a, b in pieces]
        rows = np.asarray(whole.ids)
        at = at_rows(rows, self.n)
        put_all(self.memory, at, whole.memory)  # every robot's memory row, changed or not
        wished, straight, safety, seen = byrobot.merged(whole, settled, self.robot.avoid, bounds)
        out[:, at] = drive(self, rows, wished, take_rows(self.belief, at), seen, straight, safety)
        return [said for *_, said in settled]

    def _settle(
        self, view: View, wished: Any, piece: tuple[dict[str, np.ndarray], slice, dict[str, np.ndarray]] | None = None
    ) -> Settled:
        """Check a view's decision and keep its memory and its side to step aside to. A view
        :func:`~dream.swarm.byrobot.cut` from all the robots' (``piece``: that one's memory, this
        view's row of it, the memory it was handed) keeps its memory in that row (a row handed
        holds its changes already)."""
        rows = np.asarray(view.ids)
        wished = np.asarray(wished, dtype=np.float64)
        name = type(self.robot).__name__
        if wished.shape != (len(rows), 2) or not all_finite(wished):
            raise ValueError(
                f"{name}.decide must return finite velocities of shape (k, 2) = ({len(rows)}, 2), "
                f"got shape {wished.shape}" + ("" if wished.shape != (len(rows), 2) else " with NaN or inf")
            )
        into, at, handed = (self.memory, at_rows(rows, self.n), {}) if piece is None else piece
        kept = {}
        for key, values in view.memory.items():
            if key in handed and values is handed[key]:
                continue
            if key not in self.memory:
                raise ValueError(f"{name} remembers {key!r}, which its memory does not declare: add it to `memory`")
            memory = self.memory[key]
            kept[key] = per_robot(values, len(rows), memory.dtype, f"{name} memory {key!r}", memory.shape[1:])
        put_all(into, at, kept)  # every field checked first: a bad one leaves the memory as it was
        for key in handed.keys() - view.memory.keys():  # a field forgotten: kept as it was
            into[key][at] = self.memory[key][rows]
        straight = safety = None
        if view.straight is not None:
            straight = per_robot(view.straight, len(rows), np.dtype(bool), f"{name}'s rows driven direct")
        if view.safety is not None:
            safety = per_robot(view.safety, len(rows), np.dtype(np.float64), f"{name}'s safety radii")
            if not (np.isfinite(safety).all() and (safety >= 0).all()):
                raise ValueError(f"{name}'s safety radii must be finite and >= 0")
        if view.turn is not None:
            side = per_robot(view.turn[0], len(rows), np.dtype(np.float64), f"{name}'s sides to step aside to")
            stop = per_robot(view.turn[1], len(rows), np.dtype(bool), f"{name}'s rows that stop stepping aside")
            self.side[rows] = np.where(side != 0.0, np.sign(side), self.side[rows])
            self.sidestep[rows[stop]] = 0
        heeded = None
        if view.heeded is not None:
            heeded, detections = np.asarray(view.heeded), view.seen.offsets[-1]
            if heeded.shape != (detections,) or heeded.dtype != bool:
                raise ValueError(
                    f"{name}'s heeded detections must be one bool per detection, shape ({detections},), "
                    f"got {heeded.dtype} of shape {heeded.shape}"
                )
        if view.said is None:
            return wished, straight, safety, heeded, None
        message = self._message(view.said, len(rows))
        if view.saying is None:
            return wished, straight, safety, heeded, (rows, message)
        saying = per_robot(view.saying, len(rows), np.dtype(bool), f"{name}'s senders (`where`)")
        said = rows[saying], {key: values[saying] for key, values in message.items()}
        return wished, straight, safety, heeded, said

    def _keep_focus(self, t: int, rows: np.ndarray, view: View, focus: int) -> None:
        """Keep what robot ``focus`` reads and hears now, if it is among ``rows`` (increasing)."""
        at = int(np.searchsorted(rows, focus))
        if at == len(rows) or rows[at] != focus:
            return

        def own(hood: Neighbourhood) -> dict[str, np.ndarray]:
            cut = slice(hood.offsets[at], hood.offsets[at + 1])
            found = {name: values[cut].copy() for name, values in hood.columns.items()}
            found.update({name: hood[name][cut].copy() for name in hood.derived if name not in found})
            if hood.index is not None:  # the fields still on the board: this robot's entries only
                found.update(
                    {name: source[hood.index[cut]] for name, source in hood.sources.items() if name not in found}
                )
            return found

        self.focus_view = {"step": t, "seen": own(view.seen), "heard": own(view.heard)}

    # -- time --------------------------------------------------------------------------------
    def _clock(self, t: int, faults: FaultState | None) -> float | np.ndarray:
        """Each robot's clock at the world's step ``t``: drifting and jittery under those faults, else
        the world's step itself (one number: no array of a million copies of it to compare)."""
        if faults is None or not (faults.faults.drift or faults.faults.clock_jitter):
            return float(t)
        clock = faults.rates * t
        jitter = faults.faults.clock_jitter
        if jitter:
            clock = clock + draws.integers(-jitter, jitter, self.seed, draws.CLOCK_JITTER, t, np.arange(self.n))
        return np.maximum(clock, 0.0)

    # -- sensors -----------------------------------------------------------------------------
    def _odometry(self, t: int, rows: np.ndarray, x: np.ndarray, faults: FaultState | None) -> np.ndarray:
        """Read the odometry of ``rows`` into :attr:`belief`; a dropped reading leaves the belief as
        it was. Returns which of ``rows`` know their pose (``(k,)`` bool)."""
        at = at_rows(rows, self.n)
        reading = x.T[at]  # (k, 3) C-ordered, as the belief's rows
        sigma = math.hypot(self.robot.odometry_noise, 0.0 if faults is None else faults.faults.sensor_noise)
        if sigma > 0:
            reading = reading + sigma * draws.normal(self.seed, draws.ODOMETRY_NOISE, t, rows[:, None], np.arange(3))
        kept = self._kept(t, rows, np.full(len(rows), -1), faults)
        if kept.all():
            put_rows(self.belief, at, reading)
            return np.isfinite(reading[:, 0])
        self.belief[rows[kept]] = reading[kept]
        return np.isfinite(self.belief[at, 0])

    def _kept(self, t: int, me: np.ndarray, others: np.ndarray, faults: FaultState | None) -> np.ndarray:
        """Which readings of robots ``me`` the dropout fault keeps (``others``: -1 for the odometry,
        -2 for the movement sensor's reading and -3 for the obstacle sensor's, each lost whole, as
        an object sensor's is)."""
        if faults is None or not faults.faults.sensor_dropout:
            return np.ones(len(me), dtype=bool)
        kept = draws.uniform(self.seed, draws.DROPOUT, t, me, others) >= faults.faults.sensor_dropout
        faults.readings_dropped += int((~kept).sum())
        return kept

    def _sense(
        self,
        t: int,
        rows: np.ndarray,
        seen: Perceived,
        faults: FaultState | None,
        reported: Callable[[], tuple[np.ndarray, np.ndarray]],
    ) -> Neighbourhood:
        """The movement sensor's detections (what :func:`dream.kernels.perceive` found ``rows``
        see, with the velocities the sensor reports for them), with the sensor's noise and the
        world's sensor faults. The velocities come carried in ``seen`` (see
        :meth:`_velocities_carried`), or else from ``reported()``, every robot's, the first time
        the decision reads them."""
        sensor = self.robot.movement
        offsets, others, gaps, bearing, dx, dy, *moving = seen
        if sensor is None:
            return Neighbourhood(offsets, {name: np.zeros(0) for name in (*SENSED, "dx", "dy")})
        if not self._bearings_read(faults):  # worked out only if the decision reads them
            if not moving:
                velocities = Loaded(("vx", "vy"), partial(self._reported, reported))
                columns = {"distance": gaps, "dx": dx, "dy": dy}
                return Neighbourhood(offsets, columns, (others, velocities), derived={"bearing": _bearings})
            columns = {"distance": gaps, "vx": moving[0], "vy": moving[1], "dx": dx, "dy": dy}
            return Neighbourhood(offsets, columns, derived={"bearing": _bearings})
        columns = {"distance": gaps, "bearing": bearing, "vx": moving[0], "vy": moving[1]}
        sigma = self._sensor_noise(faults)
        if sigma > 0:
            me = np.repeat(rows, np.diff(offsets))
            noise = draws.normal(self.seed, draws.DETECTION_NOISE, t, me[:, None], others[:, None], np.arange(4))
            columns = {name: columns[name] + sigma * noise[:, k] for k, name in enumerate(SENSED)}
            columns["distance"] = np.maximum(columns["distance"], 0.0)  # never negative, noisy or not
            dx, dy = _offsets(columns["distance"], columns["bearing"])
        columns["dx"], columns["dy"] = dx, dy
        return Neighbourhood(offsets, columns)

    def _sensor_noise(self, faults: FaultState | None) -> float:
        """The movement sensor's noise with the world's (standard deviation of each value)."""
        assert self.robot.movement is not None
        return math.hypot(self.robot.movement.noise, 0.0 if faults is None else faults.faults.sensor_noise)

    def _reported(self, reported: Callable[[], tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
        """``reported()``, read by a decision: from the next step on, carried."""
        self.velocities_read = True
        return reported()

    def _velocities_carried(self, faults: FaultState | None) -> bool:
        """Whether the step reads the velocities of the robots seen whatever the decision does
        (HRVO steers by them; a noisy sensor adds its noise to them), or the decision has read
        them before: then every robot's is worked out and carried to the robots seen in the
        perception's pass. Otherwise only if the decision reads them (voronoi-coverage never
        does: a conversion of every robot's command, 2 ms a step at 100,000 robots)."""
        avoids = self.robot.avoid is not None
        return avoids or self.velocities_read or self._sensor_noise(faults) > 0

    def _bearings_read(self, faults: FaultState | None) -> bool:
        """Whether the step reads the bearings of the robots seen whatever the decision does: a
        noisy sensor's offsets come from them. Otherwise they are worked out only if the decision
        reads them (an ``atan2`` each: 15-20 % of a crowd's perception; HRVO steers by the offsets)."""
        return self.robot.movement is not None and self._sensor_noise(faults) > 0

    def _obstacles(self, t: int, rows: np.ndarray, x: np.ndarray, faults: FaultState | None) -> Neighbourhood:
        """The obstacle sensor's reading of ``rows`` (:class:`~dream.swarm.robot.Obstacles`): the
        obstacles sensed, with the sensor's noise and the world's."""
        sensor = self.robot.obstacles
        if sensor is None:
            return Neighbourhood(np.zeros(len(rows) + 1, dtype=np.int64), {"dx": np.zeros(0), "dy": np.zeros(0)})
        here = x[:2, rows].T
        closest = sensed(sensor.obstacles, here, sensor.range)  # (k, obstacles, 2), NaN: not sensed
        found = ~np.isnan(closest[..., 0])
        owners, which = np.nonzero(found)
        dx, dy = (closest[found] - here[owners]).T
        sigma = math.hypot(sensor.noise, 0.0 if faults is None else faults.faults.sensor_noise)
        if sigma > 0:
            noise = draws.normal(self.seed, draws.OBSTACLE_NOISE, t, rows[owners, None], which[:, None], np.arange(2))
            dx, dy = dx + sigma * noise[:, 0], dy + sigma * noise[:, 1]
        offsets = np.concatenate(([0], np.cumsum(found.sum(axis=1))))
        return Neighbourhood(offsets, {"dx": dx, "dy": dy, "distance": np.hypot(dx, dy)})

    # -- radio -------------------------------------------------------------------------------
    def _hear(
        self, t: int, rows: np.ndarray, heard: Heard, faults: FaultState | None, drawn: bool = False
    ) -> tuple[Neighbourhood, Callable[[], np.ndarray] | None]:
        """The messages delivered to ``rows`` by the talking robots in range or linked (what
        :func:`dream.kernels.perceive` or :func:`~dream.kernels.linked` found), with the radio's
        and the world's losses: ``drawn`` where the perception drew them (``heard[3]``: each row's
        messages lost, counted in the faults already), else drawn here. Returns the inbox and,
        under loss bursts, what gives the links of the messages lost (``i * n + j``: increasing
        for a range radio, whose rows list their senders in order; worked out once, and only if
        the cells read them), else ``None``."""
        offsets, senders, gaps = heard[:3]
        radio = self.robot.radio
        if radio is None:
            return Neighbourhood(offsets, {"sender": senders}), None
        inbox = Neighbourhood(offsets, {"sender": senders}, (senders, self.board))
        loss = None if drawn else self._loss(t, faults)
        burst = None if faults is None else faults.faults.burst
        if loss is None and burst is None:
            if self.count_traffic:
                self.traffic.received(rows, offsets, lost=heard[3] if drawn else None)
            return inbox, None
        me = np.repeat(rows, np.diff(offsets))
        through = np.ones(len(senders), dtype=bool)
        if loss is not None:  # a draw for every message: one kept for sure passes too (a draw is below 1)
            through = draws.delivered(loss, me, senders, gaps)
        links = None
        if burst is not None:
            links = me * self.n + senders
            through &= ~self._burst(t, me, senders, links, burst)
        if faults is not None:
            faults.messages_lost += int((~through).sum())
        if self.count_traffic:
            self.traffic.received(rows, offsets, through)
        return inbox.where(through), None if links is None else cache(lambda: links[~through])

    def _loss(self, t: int, faults: FaultState | None) -> Loss | None:
        """The radio's and the world's message losses at step ``t`` (``None``: every message in
        range or linked gets through, unless a burst takes it)."""
        keep = 1.0 - (0.0 if self.robot.radio is None else self.robot.radio.loss)
        per_metre = 0.0
        if faults is not None:  # a graph radio measures the distances for this loss only
            keep, per_metre = keep * (1.0 - faults.faults.loss), faults.faults.distance_loss
        if keep == 1.0 and per_metre == 0:
            return None
        return Loss(self.seed, draws.LOSS, t, keep, per_metre)

    def _board_cells(
        self,
        positions: np.ndarray,
        talking: np.ndarray,
        loss: Loss | None,
        lost: Callable[[], np.ndarray] | None,
        rows: np.ndarray,
        here: np.ndarray,
        fields: tuple[str, str],
        seen: tuple[Any, Any],
        same: float,
        virtual: tuple[Any, Any],
        **shape: Any,
    ) -> VoronoiCells:
        """:meth:`View.cells` of ``rows`` for a range radio: what each hears is what the talking
        robots within range of it (``positions`` ``(n, 2)``) have on the board, less the messages
        ``loss`` takes and those of the links ``lost`` (found as the inbox was listed: a
        burst's), and :func:`dream.kernels.heard_cells` looks only at the messages near each cell
        (drawing the loss of those alone, as the perception draws it)."""
        missing = [name for name in fields if name not in self.board]
        if missing:
            raise KeyError(f"no field {missing[0]!r} in the radio's messages (its fields: {', '.join(self.board)})")
        said = np.empty((len(talking), len(fields)))
        for column, name in enumerate(fields):
            said[:, column] = self.board[name]
        said[~talking] = np.nan  # a robot that has said nothing yet
        assert self.robot.radio is not None  # a range radio
        links = None if lost is None else lost()
        if links is not None and len(rows):  # the rows asked for only: robot by robot, a robot's own
            first, last = np.searchsorted(links, (rows[0] * self.n, (rows[-1] + 1) * self.n))
            links = links[first:last]
        radio: dict[str, Any] = {"range": self.robot.radio.range, "loss": loss, "lost": links}
        return kernels.heard_cells(here, rows, positions, said, seen=seen, same=same, virtual=virtual, **radio, **shape)

    def _burst(
        self, t: int, me: np.ndarray, others: np.ndarray, links: np.ndarray, burst: tuple[float, float]
    ) -> np.ndarray:
        """Each link's Gilbert-Elliott state after this message (True: in a loss burst): the
        messages from ``others`` to ``me``, on the ``links`` ``me * n + others``."""
        flips = draws.uniform(self.seed, draws.BURST, t, me, others)
        now, self.lossy = implementation("bursts")(self.lossy, links, flips, *burst)
        return now

    def _message(self, said: dict[str, np.ndarray], k: int) -> dict[str, np.ndarray]:
        """The deciding robots' message, checked against the radio's fields: one value per robot
        (or one for all), of the field's kind."""
        name = type(self.robot).__name__
        if self.robot.radio is None:
            raise ValueError(f"{name} sent a message but declares no radio")
        if set(said) != set(self.kinds):
            raise ValueError(
                f"{name} sent fields {sorted(said)}, but its radio declares {sorted(self.kinds)}: send every field"
            )
        return {key: per_robot(said[key], k, kind, f"{name} message field {key!r}") for key, kind in self.kinds.items()}

    def _publish(self, t: int, said: list[Said], faults: FaultState | None) -> None:
        """Put what the robots said this step in the air: lies from Byzantine senders, each
        message heard from ``t + 1 + latency`` on."""
        if not said:
            return
        senders = np.concatenate([rows for rows, _ in said])
        if self.count_traffic:
            np.add.at(self.traffic.sent, senders, 1)
        fields = {key: np.concatenate([message[key] for _, message in said]) for key in self.kinds}
        delay = np.full(len(senders), self.robot.radio.latency if self.robot.radio is not None else 0)
        if faults is not None:
            f = faults.faults
            liars = faults.byzantine[senders]
            if liars.any():
                self._lie(t, senders, liars, fields, f.lie)
            delay += f.latency
            if f.jitter:
                delay += draws.integers(-f.jitter, f.jitter, self.seed, draws.LATENCY_JITTER, t, senders)
        # Heard `latency` steps after it was sent, as in the object world, but never in the step it
        # was sent: robots deciding together cannot hear each other (the order they decide in is
        # no one's business).
        air = {"visible": t + np.maximum(delay, 1), "sender": senders, "sent": np.full(len(senders), t), **fields}
        if len(self.air["visible"]):
            air = {key: np.concatenate((self.air[key], air[key])) for key in self.air}
        self.air = air

    def _lie(self, t: int, senders: np.ndarray, liars: np.ndarray, fields: dict[str, np.ndarray], rule: str) -> None:
        """Replace the float fields of the liars' messages by the adversary ``rule`` (ints kept)."""
        for number, values in enumerate(fields.values()):
            if values.dtype.kind != "f":
                continue
            if rule == "constant":
                values[liars] = CONSTANT_LIE
            elif rule == "random":
                u = draws.uniform(self.seed, draws.LIE, t, senders[liars], number)
                values[liars] = (2.0 * u - 1.0) * RANDOM_LIE
            else:
                values[liars] += DRIFT_PER_STEP * t

    def _deliver(self, t: int) -> None:
        """Move the messages heard from step ``t`` on to the board: each sender's newest (by when it
        was sent: with jitter, an older message can arrive after a newer one, and is dropped)."""
        air = self.air
        arriving = air["visible"] <= t
        if not arriving.any():
            return
        # Without latency every message in the air arrives, one from each sender, in order:
        # read in place then, not gathered.
        arrived: slice | np.ndarray = slice(None) if arriving.all() else np.flatnonzero(arriving)
        senders = air["sender"][arrived]
        if len(senders) > 1 and (senders[1:] <= senders[:-1]).any():
            # The newest per sender: sort by (sender, sent), keep each sender's last.
            index = np.flatnonzero(arriving)
            order = index[np.lexsort((air["sent"][index], air["sender"][index]))]
            last = np.r_[air["sender"][order][1:] != air["sender"][order][:-1], True]
            arrived = order[last]
            senders = air["sender"][arrived]
        sent = air["sent"][arrived]
        newer = sent > self.sent_at[senders]
        if not newer.all():
            arrived = np.flatnonzero(newer) if isinstance(arrived, slice) else arrived[newer]
            senders, sent = senders[newer], sent[newer]
        # The senders increase: the board's rows written on every core.
        put_rows(self.sent_at, senders, sent)
        put_all(self.board, senders, {key: air[key][arrived] for key in self.kinds})
        self.air = {key: values[~arriving] for key, values in air.items()}

    def _silence(self, crashed: np.ndarray) -> None:
        """The messages of robots that have just crashed leave the board and the air."""
        self.silenced |= crashed
        self.sent_at[crashed] = -1
        gone = crashed[self.air["sender"]]
        if gone.any():
            self.air = {key: values[~gone] for key, values in self.air.items()}


def _linked(
    graph: tuple[np.ndarray, np.ndarray], rows: np.ndarray, x: np.ndarray, talking: np.ndarray, measured: bool
) -> Heard:
    """What ``rows`` hear over the communication ``graph`` (:func:`dream.kernels.linked`), as
    :func:`dream.kernels.perceive` gives a range radio's; the distances only if ``measured``."""
    if len(graph[0]) - 1 != x.shape[1]:
        raise ValueError(f"the radio's graph links {len(graph[0]) - 1} robots, but the run has {x.shape[1]}")
    return kernels.linked(rows, graph, talking, positions=x[:2].T if measured else None)


def _clocks(clock: float | np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The clocks ``(k,)`` of robots ``rows`` from :meth:`Engine._clock`'s answer."""
    return np.full(len(rows), clock) if isinstance(clock, float) else clock[rows]


def _offsets(distance: np.ndarray, bearing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``distance * cos(bearing)`` and ``distance * sin(bearing)``, worked out in pieces on every
    thread (:func:`~dream.swarm.threads.spread`, the same bits): a cosine and a sine a noisy
    detection."""
    dx, dy = np.empty_like(distance), np.empty_like(distance)

    def polar(piece: slice) -> None:
        x, y = dx[piece], dy[piece]
        np.cos(bearing[piece], out=x)
        x *= distance[piece]
        np.sin(bearing[piece], out=y)
        y *= distance[piece]

    spread(polar, len(distance))
    return dx, dy


def _bearings(seen: Neighbourhood) -> np.ndarray:
    """The bearings of the robots seen, from their offsets (world frame, towards them)."""
    return np.arctan2(seen["dy"], seen["dx"])


@cache
def _pool() -> ThreadPoolExecutor:
    return ThreadPoolExecutor(threads(), thread_name_prefix="dream-decide")


# A forked child (multiprocessing's default on Linux) has none of its parent's threads: a new pool.
os.register_at_fork(after_in_child=_pool.cache_clear)
