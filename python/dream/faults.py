"""Faults: what goes wrong in a run, injected by the world so that every experiment gets them.

A :class:`Faults` says what can fail; the world draws who fails and when from its own seeded
generator (a child stream, so a run without faults draws exactly what it drew before), applies
the faults where they happen (radios, sensors, timers, wheels) and records them:

- radio: independent ``loss``; bursty loss on each link (``burst``: a two-state Gilbert-Elliott
  channel that enters its lossy state with probability ``p_enter`` per message and leaves it with
  ``p_leave``; every message in the lossy state is lost); loss growing with the distance between
  the robots (``distance_loss`` per metre); ``latency`` plus a uniform ``jitter`` (steps);
- robots: ``crash`` (fail-stop: a fraction of the robots, drawn by the seed, stops moving,
  sensing and talking at step ``crash_at``); ``stuck`` (wheels stop at ``stuck_at``; sensors,
  radio and decisions go on); ``byzantine`` robots send values chosen by an adversary rule
  (``lie``) instead of their own: every float in their messages becomes a constant, a random
  value, or drifts away from the truth (integers, such as ids, are kept);
- sensors: ``sensor_dropout`` (a reading is lost) and ``sensor_noise`` (Gaussian, added to every
  value, on top of the sensor's own noise);
- clocks: each robot's clock runs at a rate drawn in ``[1 - drift, 1 + drift]`` and each step's
  reading is off by up to ``clock_jitter`` steps, so its timers fire early or late;
- actuators: Gaussian ``actuator_noise`` on the commanded linear (m/s) and angular (rad/s,
  scaled by w_max / v_max) velocities.

On the command line each fault is ``--fault KIND=VALUE`` (:meth:`Faults.parse`)::

    --fault loss=0.3 --fault burst=0.05:0.3 --fault distance_loss=0.2
    --fault latency=5 --fault jitter=2 --fault crash=0.1@300 --fault stuck=0.1@300
    --fault byzantine=1:random --fault sensor_dropout=0.05 --fault sensor_noise=0.01
    --fault drift=0.05 --fault clock_jitter=1 --fault actuator_noise=0.01
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field, fields
from typing import Any

import numpy as np

from dream import kernels
from dream.specs import RobotSpec

LIES = ("constant", "random", "drift")
#: What a constant liar sends in place of every float, and how fast a drifting one drifts (per step).
CONSTANT_LIE = 0.0
DRIFT_PER_STEP = 0.002
#: The range a random liar draws its floats from (the Robotarium's half width, m).
RANDOM_LIE = 1.6


@dataclass(frozen=True)
class Faults:
    """What can fail in a run (see the module docs for each field). All default to nothing."""

    loss: float = 0.0
    burst: tuple[float, float] | None = None
    distance_loss: float = 0.0
    latency: int = 0
    jitter: int = 0
    crash: float = 0.0
    crash_at: int = 0
    stuck: float = 0.0
    stuck_at: int = 0
    byzantine: int = 0
    lie: str = "constant"
    sensor_dropout: float = 0.0
    sensor_noise: float = 0.0
    drift: float = 0.0
    clock_jitter: int = 0
    actuator_noise: float = 0.0

    def __post_init__(self) -> None:
        for name in ("loss", "crash", "stuck", "sensor_dropout"):
            _probability(getattr(self, name), name)
        if self.burst is not None:
            if len(self.burst) != 2:
                raise ValueError(f"burst is (p_enter, p_leave), got {self.burst!r}")
            for value, name in zip(self.burst, ("burst p_enter", "burst p_leave")):
                _probability(value, name)
        for name in ("distance_loss", "sensor_noise", "actuator_noise"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a number >= 0, got {value!r}")
        for name in ("latency", "jitter", "crash_at", "stuck_at", "byzantine", "clock_jitter"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise ValueError(f"{name} must be a whole number >= 0, got {value!r}")
        if not (isinstance(self.drift, (int, float)) and 0 <= self.drift < 1):
            raise ValueError(f"drift is a clock-rate error in [0, 1), got {self.drift!r}")
        if self.lie not in LIES:
            raise ValueError(f"lie must be one of {', '.join(LIES)}, got {self.lie!r}")

    @property
    def any(self) -> bool:
        """Whether anything can fail."""
        return self != Faults()

    def to_dict(self) -> dict[str, Any]:
        """The settings that differ from no fault, JSON-ready."""
        none = Faults()
        return {
            key: list(value) if isinstance(value, tuple) else value
            for key, value in asdict(self).items()
            if value != getattr(none, key)
        }

    @classmethod
    def parse(cls, options: Iterable[str]) -> Faults:
        """Faults from ``KIND=VALUE`` texts (the CLI's ``--fault``); see the module docs.

        Raises
        ------
        ValueError
            Naming the option: an unknown kind, a value it cannot take, or a kind given twice.
        """
        settings: dict[str, Any] = {}
        given: dict[str, str] = {}
        for option in options:
            kind, equals, value = option.partition("=")
            kind = kind.strip()
            if kind in given:
                raise ValueError(f"--fault {kind} given twice ({given[kind]!r}, {option!r}): give each kind once")
            given[kind] = option
            try:
                if not equals:
                    raise ValueError("expected KIND=VALUE")
                parsed = _parse_one(kind, value.strip())
                cls(**parsed)  # checks this option's values on their own, so the error can name it
                settings.update(parsed)
            except ValueError as err:
                kinds = ", ".join(KINDS)
                raise ValueError(f"--fault {option!r}: {err} (kinds: {kinds})") from None
        return cls(**settings)

    @classmethod
    def every_kind(cls, **changes: Any) -> Faults:
        """Every kind of fault at once, at rates a team can live through (any changed by name):
        the stress under which a robot must still run the same robot by robot and as a swarm."""
        return cls(**{**_EVERY_KIND, **changes})


#: The rates of :meth:`Faults.every_kind`.
_EVERY_KIND: dict[str, Any] = {
    "loss": 0.2,
    "burst": (0.05, 0.3),
    "distance_loss": 0.2,
    "latency": 3,
    "jitter": 2,
    "crash": 0.1,
    "crash_at": 40,
    "stuck": 0.1,
    "stuck_at": 60,
    "byzantine": 2,
    "lie": "random",
    "sensor_dropout": 0.05,
    "sensor_noise": 0.01,
    "drift": 0.05,
    "clock_jitter": 1,
    "actuator_noise": 0.01,
}


def _parse_one(kind: str, value: str) -> dict[str, Any]:
    if kind in ("crash", "stuck"):
        fraction, at, step = value.partition("@")
        return {kind: float(fraction), f"{kind}_at": int(step) if at else 0}
    if kind == "burst":
        enter, colon, leave = value.partition(":")
        if not colon:
            raise ValueError("burst takes P_ENTER:P_LEAVE")
        return {"burst": (float(enter), float(leave))}
    if kind == "byzantine":
        count, colon, rule = value.partition(":")
        return {"byzantine": int(count), **({"lie": rule} if colon else {})}
    if kind not in KINDS:
        raise ValueError(f"unknown fault {kind!r}")
    kind_type = {f.name: f.type for f in fields(Faults)}[kind]
    return {kind: int(value) if kind_type == "int" else float(value)}


#: The ``--fault`` kinds, with the form of their values.
KINDS = {
    "loss": "P",
    "burst": "P_ENTER:P_LEAVE",
    "distance_loss": "P_PER_METRE",
    "latency": "STEPS",
    "jitter": "STEPS",
    "crash": "FRACTION@STEP",
    "stuck": "FRACTION@STEP",
    "byzantine": "COUNT[:constant|random|drift]",
    "sensor_dropout": "P",
    "sensor_noise": "STD",
    "drift": "FRACTION",
    "clock_jitter": "STEPS",
    "actuator_noise": "STD",
}


def _probability(value: Any, name: str) -> None:
    if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
        raise ValueError(f"{name} is a probability in [0, 1], got {value!r}")


@dataclass
class FaultState:
    """The faults of one run as drawn: who fails, when, and what happened so far.

    Attributes
    ----------
    crashed, stuck, byzantine : (n,) bool ndarray
        Robots crashed / stuck so far, and the liars (from the start).
    rates : (n,) ndarray
        Each robot's clock rate.
    events : list of dict
        ``{"kind", "robot", "step"}`` of every robot fault, as it happens.
    messages_lost, readings_dropped : int
        Counts of lost radio messages and dropped sensor readings.
    step : int
        The last step the faults were advanced to (-1 before the first).
    """

    faults: Faults
    n: int
    rng: np.random.Generator
    crashed: np.ndarray = field(init=False)
    stuck: np.ndarray = field(init=False)
    byzantine: np.ndarray = field(init=False)
    rates: np.ndarray = field(init=False)
    events: list[dict[str, Any]] = field(default_factory=list)
    messages_lost: int = 0
    readings_dropped: int = 0
    step: int = -1

    def __post_init__(self) -> None:
        f, n, rng = self.faults, self.n, self.rng
        self._will_crash = self._pick(f.crash)
        self._will_stick = self._pick(f.stuck)
        self.crashed = np.zeros(n, dtype=bool)
        self.stuck = np.zeros(n, dtype=bool)
        self.byzantine = np.zeros(n, dtype=bool)
        if f.byzantine > n:
            raise ValueError(f"byzantine={f.byzantine} robots, but the run has only {n}")
        self.byzantine[rng.choice(n, size=f.byzantine, replace=False)] = True
        self.events += [{"kind": "byzantine", "robot": int(i), "step": 0} for i in np.flatnonzero(self.byzantine)]
        self.rates = rng.uniform(1 - f.drift, 1 + f.drift, n) if f.drift else np.ones(n)
        self._lossy_links: set[tuple[int, int]] = set()
        self._lie_values: dict[int, np.ndarray] = {}

    def _pick(self, fraction: float) -> np.ndarray:
        chosen = np.zeros(self.n, dtype=bool)
        chosen[self.rng.choice(self.n, size=round(fraction * self.n), replace=False)] = True
        return chosen

    @property
    def correct(self) -> np.ndarray:
        """``(n,)`` bool: robots neither crashed, stuck nor lying (so far)."""
        return ~(self.crashed | self.stuck | self.byzantine)

    def advance(self, step: int) -> np.ndarray:
        """Apply the robot faults due at ``step``; returns the robots that crash now."""
        self.step = step
        crashing = np.zeros(self.n, dtype=bool)
        if step == self.faults.crash_at:
            crashing = self._will_crash & ~self.crashed
            self.crashed |= crashing
            self.events += [{"kind": "crash", "robot": int(i), "step": step} for i in np.flatnonzero(crashing)]
        if step == self.faults.stuck_at:
            sticking = self._will_stick & ~self.stuck
            self.stuck |= sticking
            self.events += [{"kind": "stuck", "robot": int(i), "step": step} for i in np.flatnonzero(sticking)]
        return crashing

    def clock(self, robot: int, step: float) -> float:
        """What robot ``robot``'s clock reads at the world's ``step``."""
        reading = self.rates[robot] * step
        if self.faults.clock_jitter:
            reading += self.rng.integers(-self.faults.clock_jitter, self.faults.clock_jitter + 1)
        return max(reading, 0.0)

    def delay(self, latency: int) -> int:
        """A message's latency: the radio's own plus the fault's, with jitter."""
        f = self.faults
        spread = int(self.rng.integers(-f.jitter, f.jitter + 1)) if f.jitter else 0
        return max(latency + f.latency + spread, 0)

    def delivered(self, receiver: int | None, sender: int, loss: float, distance: float) -> bool:
        """Whether one message gets through (draws the loss of every kind, counts the lost)."""
        f = self.faults
        keep = (1.0 - loss) * (1.0 - f.loss) * max(1.0 - f.distance_loss * distance, 0.0)
        through = keep >= 1.0 or self.rng.random() < keep
        if f.burst is not None:
            link = (-1 if receiver is None else receiver, sender)
            lossy = link in self._lossy_links
            if self.rng.random() < (f.burst[1] if lossy else f.burst[0]):
                lossy = not lossy
                (self._lossy_links.add if lossy else self._lossy_links.discard)(link)
            through = through and not lossy
        self.messages_lost += not through
        return through

    def lie(self, robot: int, data: Any, step: int) -> Any:
        """``data`` as a Byzantine robot sends it: every float replaced by the adversary rule."""

        def replace(value: Any) -> Any:
            if isinstance(value, (float, np.floating)):
                if self.faults.lie == "constant":
                    return CONSTANT_LIE
                if self.faults.lie == "random":
                    return float(self.rng.uniform(-RANDOM_LIE, RANDOM_LIE))
                return float(value) + DRIFT_PER_STEP * step
            if isinstance(value, np.ndarray) and value.dtype.kind == "f":
                return np.array([replace(float(v)) for v in value.ravel()]).reshape(value.shape)
            if isinstance(value, (list, tuple)):
                return type(value)(replace(v) for v in value)
            if isinstance(value, dict):
                return {key: replace(v) for key, v in value.items()}
            return value

        return replace(data)

    def dropped(self) -> bool:
        """Whether a sensor reading is lost (counts it)."""
        lost = self.faults.sensor_dropout > 0 and self.rng.random() < self.faults.sensor_dropout
        self.readings_dropped += lost
        return bool(lost)

    def actuate(self, dxu: np.ndarray, limits: RobotSpec) -> np.ndarray:
        """The commands ``(2, n)`` the wheels carry out: none for crashed or stuck robots; noisy ones
        for the others, within what the wheels can do (a motor does not exceed its top speed).
        The noise on ``w`` is scaled like the robots' speed range (``w_max / v_max``)."""
        out = np.array(dxu, dtype=np.float64)
        if self.faults.actuator_noise:
            noise = self.rng.normal(0.0, self.faults.actuator_noise, out.shape)
            out = kernels.actuator_limit(out + noise * np.array([[1.0], [limits.w_max / limits.v_max]]), limits)
        out[:, self.crashed | self.stuck] = 0.0
        return out

    @property
    def pending(self) -> list[dict[str, Any]]:
        """``{"kind", "step"}`` of every robot fault scheduled at a step the run has not reached
        (a crash at step 300 in a run done at step 189): it never happened."""
        f = self.faults
        scheduled = (("crash", f.crash, f.crash_at), ("stuck", f.stuck, f.stuck_at))
        return [{"kind": kind, "step": at} for kind, share, at in scheduled if share and at > self.step]

    def summary(self) -> dict[str, Any]:
        """Settings, events, the faults still pending and counts, JSON-ready."""
        return {
            "settings": self.faults.to_dict(),
            "events": list(self.events),
            "pending": self.pending,
            "messages_lost": self.messages_lost,
            "readings_dropped": self.readings_dropped,
        }
