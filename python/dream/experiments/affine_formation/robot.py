"""The affine formation's robot: leaders and followers, two roles of one swarm robot.

Robot ``i`` holds place ``i % 7`` of formation ``i // 7``: places 0-2 lead, 3-6 follow. Each robot
hears the six others of its formation, keeps what each claimed last and when it last heard it (a
failure detector), and decides from its own odometry, sensor, radio and clock; see
``docs/experiments/affine-formation.md`` for the rules and the failures they answer.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream import rules, timers
from dream.experiments.affine_formation.plan import (
    GAIN,
    LEADER_GAIN,
    LEADERS,
    MORPH,
    NOMINAL,
    WEIGHTS,
    affine_image,
    clearing_shift,
    formation,
    shape_plan,
    tile_bounds,
)
from dream.robot import SIDESTEP_UPDATES
from dream.swarm import Avoid, Movement, Neighbourhood, Radio, SwarmRobot, View, put_all, take_all

MEMBERS = len(NOMINAL)  #: robots in a formation
SAFETY = 0.15  #: the HRVO safety radius (m): the formation's robots are 0.3 m apart
FINE = 0.03  #: below this desired speed (m/s) a follower moves without HRVO
RANGE = 0.6  #: robots within this distance (m) are the ones a follower's HRVO avoids
VERIFY = 1.0  #: the movement sensor sees this far (m), to check claimed positions
MATCH = 0.15  #: a claimed position this close (m) to a robot seen matches it (radio lag, latency)
STRIKES = 3  #: decisions in a row whose claims match no robot seen make a liar
PLAN_SLACK = 0.5  #: a leader claiming to be this far (m) from every place the other leaders plan for it lies
SILENCE = 20  #: radio rounds without a message after which a robot is taken for crashed
#: Decisions in a row a robot's odometry stands still while its wheels are told to move, after
#: which it takes them for stuck for good: it stops driving them and says so, and its formation
#: takes it for crashed (fail-stop).
STILL = 3
DRIVE = 1e-3  #: a forward speed (m/s) that moves a robot by more than its odometry's last bit
START_DELAY = 10  #: start-up delay of robot i: this plus its place in its formation (i % 7) steps
CONTROL_GAP = 4  #: steps between two decisions (and radio rounds) of a robot
#: The message's fields beyond the position: where the plan has each leader head now (leaders only).
AIMS = tuple(f"{axis}{m}" for m in range(LEADERS) for axis in ("ax", "ay"))


def formation_graph(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Every robot linked to the six others of its formation, as CSR ``(indptr, indices)``."""
    ids = np.arange(n)
    others = (ids - ids % MEMBERS)[:, None] + np.arange(MEMBERS)
    indices = others[others != ids[:, None]]
    return np.arange(n + 1, dtype=np.int64) * (MEMBERS - 1), indices.astype(np.int64)


class FormationRobot(SwarmRobot):
    """A leader or a follower of an affine formation, by its place (see the module docs).

    A leader takes each shape of the plan (:func:`~dream.experiments.affine_formation.plan.shape_plan`)
    when the operator orders it: the experiment sets the memory field ``order`` to the plan's step
    at the world's time, so that clocks that drift do not split a formation. The aims of its
    formation's leaders then move to the new places at a steady pace over ``MORPH`` decisions
    (:func:`dream.rules.morph`), shifted clear of the robots it takes for crashed (which alone it
    avoids), and it sends them with its position. A follower obeys the stress law on where it
    takes its formation to be (:func:`positions`), through HRVO, checking the claims it hears
    against what it sees (:func:`judge`).
    """

    period = CONTROL_GAP
    threaded = True  # decide reads its view alone: blocks of a swarm decide on several threads
    movement = Movement(range=VERIFY)
    memory = {
        "heard": np.full((MEMBERS, 2), np.nan),  # the last position each robot of its formation claimed
        # Its tables of the formation in the narrowest types that hold them: copied out and back
        # for every robot deciding, each step.
        "news": np.zeros(MEMBERS, dtype=np.int32),  # its round in which it last heard each (0: never)
        "rounds": 0,  # its radio rounds so far
        "plans": np.full((LEADERS, LEADERS, 2), np.nan),  # each leader's last word on the leaders' aims (followers)
        "strikes": np.zeros(MEMBERS, dtype=np.int8),  # decisions in a row each one's claim was blamed (<= STRIKES)
        "liar": np.zeros(MEMBERS, dtype=bool),  # robots taken for liars
        "liar_at": np.full((MEMBERS, 2), np.nan),  # where a liar was seen last (NaN: not located)
        "order": 0,  # the step of the plan the operator has ordered last (set by the experiment)
        "phase": -1,  # the leader's step of the plan
        "start": np.full((LEADERS, 2), np.nan),  # the leaders' places its aims left from
        "goals": np.full((LEADERS, 2), np.nan),  # and the places they go to
        "decisions": MORPH,  # its decisions since then
        "shift": 0.0,  # how far (m) along x it shifts the plan clear of crashed robots
        "silent": np.zeros(MEMBERS, dtype=bool),  # the robots it takes for crashed
        "was": np.full(2, np.nan),  # its position by odometry at its last decision
        "still": 0,  # its decisions in a row without moving while its wheels were told to
    }

    def __init__(self, n: int, centres: np.ndarray) -> None:
        self.radio = Radio(graph=formation_graph(n), fields=("x", "y", "stuck", *AIMS))
        self.avoid = Avoid(safety=SAFETY, sidestep=SIDESTEP_UPDATES)
        self.centres = centres  #: the centres ``(n / 7, 2)`` of the formations' tiles
        self.tiles = np.array([tile_bounds(centre) for centre in centres]).reshape(-1, 4)  #: and their bounds
        self.nominal = formation("nominal")  #: the nominal shape about a tile's centre
        _, shapes, offsets = shape_plan()
        self.plan_places = np.array([formation(shape) for shape in shapes]) + offsets[:, None, :]

    def start(self, ids: np.ndarray) -> np.ndarray:
        return timers.staggered(ids, START_DELAY, MEMBERS)

    # -- the decision --------------------------------------------------------------------------
    def decide(self, view: View) -> np.ndarray:
        memory, here, place = view.memory, view.pose[:, :2], view.ids % MEMBERS
        listen(view)
        alive = (memory["news"] == 0) | (memory["rounds"][:, None] - memory["news"] <= SILENCE)
        lead = place < LEADERS
        seen = view.seen
        spotted = seen.points(here)  # where it sees each robot
        desired, heeded = np.zeros((len(view), 2)), seen["distance"] <= RANGE
        rows = np.flatnonzero(lead)
        aims = np.zeros((0, LEADERS, 2))
        if len(rows):
            self.plan(view, rows, alive[rows])
            mine = {key: memory[key][rows] for key in ("start", "goals", "decisions")}
            aims = self.aims(view.ids[rows], mine)
        stuck = wheels_stuck(view)
        view.send(x=here[:, 0], y=here[:, 1], stuck=stuck.astype(float), **self.said(lead, aims))
        if len(rows):
            memory["decisions"][rows] += 1
            mine["decisions"] = mine["decisions"] + 1
            aim = self.aims(view.ids[rows], mine)[np.arange(len(rows)), place[rows]]
            desired[rows] = rules.toward(here[rows], aim, LEADER_GAIN, self.spec.v_max)
            # A leader heeds only the robots it takes for crashed, where they were heard last.
            heeded = heeded & ~lead[seen.owner]
            if memory["silent"][rows].any():
                crashed = seen.broadcast(np.where(memory["silent"][:, :, None], memory["heard"], np.nan))
                heeded |= lead[seen.owner] & rules.each_any(_squared_gaps(spotted, crashed) <= MATCH**2)
        if (~lead).any():
            rows = np.flatnonzero(~lead)
            desired[rows] = self.follow(view, rows, alive[rows], spotted)
        desired[stuck] = 0.0  # a robot seen driving its stuck wheels would pass for a moving one
        view.heed(heeded)
        memory["was"] = here
        # Close to its place HRVO would forbid a follower the last centimetres towards a neighbour.
        view.direct(~lead & rules.settles(desired, np.inf, FINE, 0.0))
        return desired

    @staticmethod
    def said(lead: np.ndarray, aims: np.ndarray) -> dict[str, np.ndarray]:
        """The aims fields of the message: the leaders' ``aims`` ``(l, 3, 2)``, NaN from followers."""
        fields = np.full((len(lead), LEADERS, 2), np.nan)
        fields[lead] = aims
        flat = fields.reshape(len(lead), -1)
        return {name: flat[:, column] for column, name in enumerate(AIMS)}

    # -- leaders -------------------------------------------------------------------------------
    def aims(self, ids: np.ndarray, memory: dict[str, np.ndarray]) -> np.ndarray:
        """The points ``(k, 3, 2)`` (m) where the plan has the formation's leaders head now, for the
        leaders ``ids`` ``(k,)`` whose memory rows ``memory`` holds (before its first plan: their
        nominal places)."""
        start, goals = memory["start"], memory["goals"]
        if np.isnan(start).any() or np.isnan(goals).any():  # some leader has not planned yet
            nominal = self.nominal[:LEADERS] + np.take(self.centres, ids // MEMBERS, axis=0)[:, None, :]
            start, goals = np.where(np.isnan(start), nominal, start), np.where(np.isnan(goals), nominal, goals)
        return rules.morph(start, goals, memory["decisions"], MORPH)

    def plan(self, view: View, rows: np.ndarray, alive: np.ndarray) -> None:
        """The leaders ``rows`` take the shape the operator ordered last, or a new shift clear of
        the robots they now take for crashed: their aims set off for the new places."""
        memory, ids = view.memory, view.ids[rows]
        phase = memory["order"][rows]
        silent = ~alive & (memory["news"][rows] > 0)
        moved = phase > memory["phase"][rows]
        changed = rules.each_any(silent != memory["silent"][rows])
        memory["phase"][rows], memory["silent"][rows] = np.maximum(phase, memory["phase"][rows]), silent
        places = (
            np.take(self.plan_places, memory["phase"][rows], axis=0)
            + np.take(self.centres, ids // MEMBERS, axis=0)[:, None, :]
        )
        shift = np.where(moved | changed, 0.0, memory["shift"][rows])
        for r in np.flatnonzero((moved | changed) & rules.each_any(silent)):
            shift[r] = self.clearing(places[r], silent[r], memory["heard"][rows[r]])
        again = moved | (changed & (shift != memory["shift"][rows]))  # else the aims keep their pace
        if again.any():
            chosen = rows[again]
            aims = self.aims(view.ids[chosen], {key: memory[key][chosen] for key in ("start", "goals", "decisions")})
            memory["start"][chosen] = aims
            goals = places[again, :LEADERS]
            goals[..., 0] += shift[again][:, None]
            memory["goals"][chosen] = goals
            memory["decisions"][chosen] = 0
            memory["shift"][chosen] = shift[again]

    @staticmethod
    def clearing(places: np.ndarray, silent: np.ndarray, heard: np.ndarray) -> float:
        """The shift (m) along x of the planned ``places`` ``(7, 2)`` clear of the robots taken for
        crashed (``silent`` ``(7,)``, heard last at ``heard`` ``(7, 2)``): :func:`clearing_shift`."""
        return clearing_shift(places[~silent], heard[silent], float(places.mean(axis=0)[0]))

    # -- followers -----------------------------------------------------------------------------
    def follow(self, view: View, rows: np.ndarray, alive: np.ndarray, spotted: np.ndarray) -> np.ndarray:
        """The stress law's velocities ``(f, 2)`` for the followers ``rows`` on where they take their
        formation to be, after checking what they hear against what they see."""
        memory, ids = view.memory, view.ids[rows]
        here = view.pose[rows, :2]
        bounds = np.take(self.tiles, ids // MEMBERS, axis=0)
        seen = view.seen
        owner = seen.owner
        # Robots beyond its tile belong to other formations: neither claimed nor liars.
        mine = np.full(len(view), -1)
        mine[rows] = np.arange(len(rows))
        keep = (mine[owner] >= 0) & in_tile(spotted, np.take(bounds, np.maximum(mine[owner], 0), axis=0))
        counts = np.bincount(mine[owner][keep], minlength=len(rows))
        hood = Neighbourhood(np.concatenate(([0], np.cumsum(counts))), {})
        state = take_all({key: memory[key] for key in ("heard", "plans", "strikes", "liar", "liar_at")}, rows)
        sensed = judge(here, ids % MEMBERS, alive, bounds, hood, spotted[keep], state)
        put_all(memory, rows, state)
        known = positions(state["heard"], alive, state["plans"], state["liar"], state["liar_at"], sensed)
        pull = rules.stress(here, known, np.take(WEIGHTS, ids % MEMBERS, axis=0))
        return rules.capped(-GAIN * pull, self.spec.v_max)


def wheels_stuck(view: View) -> np.ndarray:
    """Which robots deciding now take their wheels for stuck: their odometry's position has not
    changed by a bit over :data:`STILL` decisions in a row while their wheels were told to drive
    (a robot the safety layer stops is told to stand, and does), or before."""
    memory = view.memory
    still = (np.abs(view.command[:, 0]) > DRIVE) & ~rules.each_any(view.pose[:, :2] != memory["was"])
    memory["still"] = np.where(still | (memory["still"] >= STILL), memory["still"] + 1, 0)
    return memory["still"] >= STILL


def listen(view: View) -> None:
    """A radio round of the robots deciding now: keep each message's position, when it came (unless
    it says its wheels are stuck: the failure detector then takes it for crashed) and, a follower,
    a moving leader's word on the leaders' aims (which the leaders, who plan, never read)."""
    memory, heard = view.memory, view.heard
    memory["rounds"] = memory["rounds"] + 1
    owner, place = heard.owner, heard["sender"] % MEMBERS
    slot = owner * MEMBERS + place  # the message's row in its hearer's tables of the formation
    _scatter(memory["heard"], slot, heard["x"], heard["y"])
    moving = heard["stuck"] == 0
    rounds = heard.broadcast(memory["rounds"])  # each message's hearer's round
    _scatter(memory["news"], slot[moving], rounds[moving])
    # A follower heeds a moving leader's word on the aims (a stuck leader's is not heeded).
    lead = moving & (place < LEADERS) & (view.ids[owner] % MEMBERS >= LEADERS)
    aims = heard.pick(AIMS, np.flatnonzero(lead)).reshape(-1, LEADERS, 2)
    _scatter(aims, np.arange(len(aims)) * LEADERS + place[lead], np.nan, np.nan)  # its word on others only
    _scatter(memory["plans"], owner[lead] * LEADERS + place[lead], *aims.reshape(len(aims), 2 * LEADERS).T)


def _scatter(table: np.ndarray, slots: np.ndarray, *columns: Any) -> None:
    """Write ``table[r, m] = (columns[0][e], columns[1][e], ...)`` (or scalars) for each entry e of
    ``slots`` ``r * w + m`` (``table`` ``(k, w, ...)`` C-contiguous, as memory arrays are) one value
    at a time: NumPy copies a row of several values, indexed by two arrays, one call a row, 2-5
    times slower."""
    if not table.flags.c_contiguous:
        raise ValueError(f"a table of shape {table.shape} to write slots of must be C-contiguous")
    rows = table.reshape(table.shape[0] * table.shape[1], math.prod(table.shape[2:]))  # a view
    for c, values in enumerate(columns):
        rows[:, c][slots] = values


def in_tile(points: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """Which ``points`` ``(..., 2)`` lie in their tiles ``bounds`` ``(..., 4)``, give or take
    :data:`MATCH` (claims lag; a robot of the next formation that close to the edge passes too)."""
    x, y = points[..., 0], points[..., 1]
    xmin, xmax, ymin, ymax = np.moveaxis(bounds, -1, 0)
    return (x >= xmin - MATCH) & (x <= xmax + MATCH) & (y >= ymin - MATCH) & (y <= ymax + MATCH)


def _squared_gaps(spotted: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Squared distances ``(e, 7)`` from each robot seen ``(e, 2)`` to the points ``(e, 7, 2)`` of its row."""
    return rules.squared_length(spotted[:, None, :] - points)


def judge(
    here: np.ndarray,
    me: np.ndarray,
    alive: np.ndarray,
    bounds: np.ndarray,
    hood: Neighbourhood,
    spotted: np.ndarray,
    state: dict[str, np.ndarray],
) -> np.ndarray:
    """Check the claims of followers at ``here`` ``(f, 2)`` (places ``me``, tiles ``bounds``), who
    see the robots ``spotted`` ``(e, 2)`` in rows ``hood``: strike each robot whose claim, close
    enough to check, matches no robot seen, or lies where no correct robot can be
    (:func:`implausible`); else, when it sees close by a robot that no claim accounts for, the one
    robot whose claim lies out of its sight. :data:`STRIKES` in a row make a liar. Updates
    ``state`` (``heard``, ``plans``, ``strikes``, ``liar``, ``liar_at``) and returns which liars it
    sees now ``(f, 7)`` (at ``liar_at``)."""
    heard, liar, liar_at = state["heard"], state["liar"].astype(bool), state["liar_at"]
    members = np.arange(MEMBERS)
    trusted = np.isfinite(heard[..., 0]) & ~liar & (members != me[:, None])
    checkable = trusted & (rules.squared_length(heard - here[:, None]) < (VERIFY - MATCH) ** 2)
    matched = hood.min(_squared_gaps(spotted, hood.broadcast(heard))) <= MATCH**2
    missed = (checkable & ~matched) | (trusted & implausible(heard, alive, state["plans"], liar, bounds))
    located = ~rules.each_any(liar & np.isnan(liar_at[..., 0]))
    lone = ~rules.each_any(missed) & ((trusted & ~checkable).sum(axis=1) == 1) & located
    if lone.any():
        accounted = np.where((trusted | liar)[..., None], np.where(liar[..., None], liar_at, heard), np.nan)
        unaccounted = ~rules.each_any(_squared_gaps(spotted, hood.broadcast(accounted)) <= MATCH**2)
        close = np.hypot(*(spotted - hood.broadcast(here)).T) <= RANGE
        lone &= hood.any(close & unaccounted)
        missed = np.where(lone[:, None], trusted & ~checkable, missed)
    state["strikes"] = np.where(trusted, np.where(missed, state["strikes"] + 1, 0), state["strikes"])
    liar |= trusted & (state["strikes"] >= STRIKES)
    sensed = np.zeros(liar.shape, dtype=bool)
    if liar.any():
        claims = np.where((~liar & np.isfinite(heard[..., 0]))[..., None], heard, np.nan)
        unclaimed = ~rules.each_any(_squared_gaps(spotted, hood.broadcast(claims)) <= MATCH**2)
        count, rows = hood.where(unclaimed).count, np.arange(len(here))
        tracked = liar & np.isfinite(liar_at[..., 0])
        one = np.argmax(liar, axis=1)
        found = (liar.sum(axis=1) == 1) & (count == 1) & ~tracked[rows, one]
        entry = hood.nearest(np.where(unclaimed, 0.0, np.inf))
        liar_at[found, one[found]] = spotted[entry[found]]
        sensed[found, one[found]] = True
        for j in range(MEMBERS):  # a liar seen before: the same robot, moved on a little
            following = tracked[:, j] & (count > 0)
            if following.any():
                gap = np.where(unclaimed, np.hypot(*(spotted - hood.broadcast(liar_at[:, j])).T), np.inf)
                entry = hood.nearest(gap)
                near = following & (hood.pick(gap, entry) < 2 * MATCH)
                liar_at[near, j] = spotted[entry[near]]
                sensed[near, j] = True
    state["liar"] = liar
    return sensed


def implausible(
    heard: np.ndarray, alive: np.ndarray, plans: np.ndarray, liar: np.ndarray, bounds: np.ndarray
) -> np.ndarray:
    """Which claims ``heard`` ``(f, 7, 2)`` no correct robot makes: outside the formation's tile, or a
    living leader's place :data:`PLAN_SLACK` from every place the other living, trusted leaders
    plan for it (``plans`` ``(f, 3, 3, 2)``: leader i's word on leader m)."""
    out = ~in_tile(heard, bounds[:, None, :])
    living = alive[:, :LEADERS] & ~liar[:, :LEADERS]
    places = plans if living.all() else np.where(living[:, :, None, None], plans, np.nan)  # [row, i, m]
    gaps = rules.squared_length(heard[:, None, :LEADERS] - places)
    off = rules.each_any(np.isfinite(gaps)) & ~rules.each_any(gaps <= PLAN_SLACK**2)
    # A crashed leader stands where it stopped, off the plan that moves on.
    out[:, :LEADERS] |= off & alive[:, :LEADERS]
    return out


def positions(
    heard: np.ndarray, alive: np.ndarray, plans: np.ndarray, liar: np.ndarray, liar_at: np.ndarray, sensed: np.ndarray
) -> np.ndarray:
    """Where followers take the robots of their formation to be ``(f, 7, 2)`` (NaN: unknown), for
    the law: what they claim; liars where seen; crashed leaders, and lying ones out of sight,
    where the living leaders plan them; the others (crashed followers, lying ones out of sight)
    at their places in the affine image of the nominal shape that the rest span."""
    known = np.where(np.isfinite(heard[..., :1]), heard, np.nan)  # all a follower with no liar or crash needs
    troubled = rules.each_any(liar | ~alive)
    if troubled.any():
        rows = np.flatnonzero(troubled)
        parts = (heard, alive, plans, liar, liar_at, sensed)
        known[rows] = _troubled_positions(*(part[rows] for part in parts))
    return known


def _troubled_positions(
    heard: np.ndarray, alive: np.ndarray, plans: np.ndarray, liar: np.ndarray, liar_at: np.ndarray, sensed: np.ndarray
) -> np.ndarray:
    """:func:`positions` of followers that take some robot of their formation for a liar or for
    crashed."""
    have = np.isfinite(heard[..., 0])
    living = alive[:, :LEADERS] & ~liar[:, :LEADERS]
    planned = np.full((len(heard), LEADERS, 2), np.nan)
    for i in range(LEADERS):  # a later leader's word over an earlier one's
        word = living[:, i, None] & np.isfinite(plans[:, i, :, 0])
        planned = np.where(word[..., None], plans[:, i], planned)
    known = np.where((~liar & alive & have)[..., None], heard, np.nan)
    known = np.where((liar & sensed)[..., None], liar_at, known)
    lead = known[:, :LEADERS]
    from_plan = np.isfinite(planned[..., 0]) & liar[:, :LEADERS] & ~sensed[:, :LEADERS]
    lead = np.where(from_plan[..., None], planned, lead)
    crashed = ~liar[:, :LEADERS] & ~alive[:, :LEADERS] & have[:, :LEADERS]
    lead = np.where(crashed[..., None], np.where(np.isfinite(planned), planned, heard[:, :LEADERS]), lead)
    known[:, :LEADERS] = lead
    unknown = have & np.isnan(known[..., 0])
    for r in np.flatnonzero(rules.each_any(unknown)):
        found = np.flatnonzero(np.isfinite(known[r, :, 0]))
        missing = np.flatnonzero(unknown[r])
        image = affine_image({int(j): known[r, j] for j in found}, [int(j) for j in missing])
        for j in map(int, missing):
            if j in image:
                known[r, j] = image[j]
            elif not liar[r, j]:
                known[r, j] = heard[r, j]  # too few to span the image: where it last said
    return known


def nominal_place(ids: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """The places ``(k, 2)`` (m) of robots ``ids`` in the nominal shape of their tiles."""
    return formation("nominal")[ids % MEMBERS] + centres[ids // MEMBERS]


def leader_goals(memory: dict[str, np.ndarray], ids: np.ndarray, centres: np.ndarray) -> Any:
    """The planned places ``(k, 2)`` (m) of leaders ``ids`` (their memory rows ``memory``; nominal
    before their first plan)."""
    goals = memory["goals"][np.arange(len(ids)), ids % MEMBERS]
    return np.where(np.isnan(goals), nominal_place(ids, centres), goals)
