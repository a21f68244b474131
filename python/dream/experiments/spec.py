"""What an experiment declares: its parameters, how its robots are built, and when it succeeded.

An experiment is a subclass of :class:`Experiment`. It declares its name, its default size, its
parameters (with :func:`param`) and a few hooks; :func:`dream.run` owns the loop, so every
experiment, the thesis's four and a researcher's own, gets the same runner, metrics, video,
progress bar, CLI (``dream run my_experiment.py --param gain=2``) and sweeps::

    class GoRight(Experiment):
        name = "go-right"
        default_n = 5
        speed: float = param(0.1, "how fast the robots drive right (m/s)", gt=0)

        def build(self, n):
            for i in range(n):
                robot = MyRobot(i, speed=self.speed, arena=self.arena)
                odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
                create_timer(i, 10, [{"delay": 2, "tag": "odom", "call": odometry.update},
                                     {"delay": 4, "tag": "robot", "call": robot.update}])
                self.robots.append(robot)

        def done(self, step, poses):
            return bool((poses[0] > 1.0).all())

A run creates a fresh instance, so an experiment keeps its run's state on ``self``.

An experiment may also have a swarm mode (``has_swarm_mode = True``, and the hooks
:meth:`~Experiment.build_swarm` and :meth:`~Experiment.swarm_step`): the whole swarm decides every
step through one call, for swarms too large for robot objects and timers. The same runner runs it
(``dream.run(GoRight, swarm=True)``, ``dream run go-right --swarm``); GoRight would add::

        has_swarm_mode = True

        def build_swarm(self, n):
            pass  # nothing to keep: every robot drives at the same speed

        def swarm_step(self, step, x):
            return np.vstack((np.full(self.n, self.speed), np.zeros(self.n)))  # (2, n): v and w
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from dream.backends import Backend, initial_poses
from dream.backends.startup import reachable_starts
from dream.frames import Frame
from dream.specs import ROBOTARIUM, ArenaSpec, SimulatorSpec
from dream.swarm import Engine, SwarmRobot
from dream.world import World

_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


@dataclass(frozen=True)
class Param:
    """A declared parameter: its default (whose type is the parameter's type), its help and, for a
    number, its range (see :func:`param`)."""

    default: Any
    help: str
    name: str = ""
    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    finite: bool = True

    @property
    def kind(self) -> type:
        return type(self.default)

    @property
    def range(self) -> str:
        """The values the parameter takes, in words (``"finite and > 0"``, ``"in [0, 1]"``); ``""``
        for any value of its type."""
        if (self.gt, self.ge) != (None, None) and (self.lt, self.le) != (None, None):  # finite whatever `finite`
            left = f"({self.gt:g}" if self.gt is not None else f"[{self.ge:g}"
            right = f"{self.lt:g})" if self.lt is not None else f"{self.le:g}]"
            return f"in {left}, {right}"
        said = ["finite"] if self.kind is float and self.finite else []
        signs = ((">", self.gt), (">=", self.ge), ("<", self.lt), ("<=", self.le))
        return " and ".join(said + [f"{sign} {bound:g}" for sign, bound in signs if bound is not None])

    def __set_name__(self, owner: type, name: str) -> None:
        object.__setattr__(self, "name", name)

    def __get__(self, instance: Any, owner: type) -> Any:
        # On the class: the declaration itself. An instance holds its value in its own dict,
        # which Python looks up before this (non-data) descriptor.
        return self if instance is None else self.default

    def convert(self, value: Any, experiment: str) -> Any:
        """``value`` (a Python value, or the text given on the command line) as this parameter's
        type, checked against its range.

        Raises
        ------
        ValueError
            Naming the parameter and the experiment: a value of another type, or out of range
            (the message gives the range).
        """
        where = f"parameter {self.name!r} of {experiment}"
        value = self._typed(value, where)
        if not self.admits(value):
            raise ValueError(f"{where} must be {self.range}, got {value!r}")
        return value

    def admits(self, value: Any) -> bool:
        """Whether ``value`` (of the parameter's type) is in its range."""
        if self.kind not in (int, float):
            return True
        if math.isnan(value) or (self.finite and math.isinf(value)):
            return False
        bounds = ((operator.gt, self.gt), (operator.ge, self.ge), (operator.lt, self.lt), (operator.le, self.le))
        return all(bound is None or holds(value, bound) for holds, bound in bounds)

    def _typed(self, value: Any, where: str) -> Any:
        kind = self.kind
        if isinstance(value, str) and kind is not str:
            text = value.strip().lower()
            try:
                if kind is bool:
                    if text not in _TRUE | _FALSE:
                        raise ValueError
                    return text in _TRUE
                return kind(value)
            except ValueError:
                raise ValueError(f"{where} expects {_kind_name(kind)}, got {value!r}") from None
        if kind is float and isinstance(value, (int, np.integer)) and not isinstance(value, bool):
            return float(value)
        if isinstance(value, bool) != (kind is bool) or not isinstance(value, kind):
            raise ValueError(f"{where} expects {_kind_name(kind)}, got {value!r}")
        return value


def _kind_name(kind: type) -> str:
    return {bool: "true or false", int: "an integer", float: "a number", str: "text"}.get(kind, kind.__name__)


def param(
    default: Any,
    help: str,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    finite: bool = True,
) -> Any:
    """Declare a parameter of an :class:`Experiment` (type: that of ``default``).

    A number may say its range: ``gt`` (>), ``ge`` (>=), ``lt`` (<) and ``le`` (<=) bound it, and a
    float is finite unless ``finite=False`` (NaN never is). A value out of range is refused
    before the run builds anything, in one line that names the parameter and its range::

        spacing: float = param(0.3, "distance between neighbours (m)", gt=0)
        loss: float = param(0.0, "share of messages lost", ge=0, le=1)
        radio_gap: int = param(10, "steps between radio exchanges", ge=1)

    Raises
    ------
    TypeError
        A default that is not a bool, int, float or str, or a range on a bool or a str.
    ValueError
        A default outside its own range.
    """
    if not isinstance(default, (bool, int, float, str)):
        raise TypeError(f"a parameter's default must be a bool, int, float or str, got {default!r}")
    bounds = (gt, ge, lt, le)
    if (any(bound is not None for bound in bounds) or not finite) and isinstance(default, (bool, str)):
        raise TypeError(f"only a number has a range; this parameter's default is {default!r}")
    if (gt is not None and ge is not None) or (lt is not None and le is not None):
        raise TypeError("a range has one lower bound (gt or ge) and one upper bound (lt or le)")
    declared = Param(default, help, gt=gt, ge=ge, lt=lt, le=le, finite=finite)
    if not declared.admits(default):
        raise ValueError(f"a parameter's default must be in its range ({declared.range}), got {default!r}")
    return declared


class Experiment:
    """Base class of an experiment run by :func:`dream.run` (see the module docs).

    Class attributes
    ----------------
    name : str
        The name the CLI and the results use (``hrvo-circle``).
    default_n : int
        Number of robots when the run does not say.
    success : str
        One sentence: what counts as success (``dream list NAME`` prints it).
    has_swarm_mode : bool
        Whether the experiment also runs in swarm mode (default False): it defines
        :meth:`build_swarm` and :meth:`swarm_step`.
    hold_steps : int
        How many steps :meth:`done` must go on holding once it holds before the run ends, done
        (default 0: at the first step it holds); a step where it does not hold starts the count
        again, and the result's ``completed_step`` is the step the run ended at. A fault test
        needs it: a crash scheduled at step 300 means nothing in a run done at step 189.

    Hooks, in the order the runner calls them (all but :meth:`build` optional)
    --------------------------------------------------------------------------
    :meth:`check` (refuse sizes that cannot succeed), :meth:`arena_for`, :meth:`build`,
    :meth:`initial_poses` (then :meth:`reachable_poses` before rps 2.x's start-up phase),
    :meth:`steps`; then every step :meth:`before_step`, the timers with :meth:`timer_params`, the
    simulator's step, :meth:`after_step`, :meth:`frame` (when recording) and :meth:`done`,
    :meth:`robot_measures` (when logging); at the end :meth:`measures`.

    Swarm mode (``dream.run(..., swarm=True)``) calls :meth:`build_swarm` instead of :meth:`build`
    (the swarm's arrays instead of robot objects and timers) and, every step,
    :meth:`swarm_step` (every robot's command at once, from the poses) instead of the timers;
    every other hook is called as in the per-robot mode, so :meth:`done`, :meth:`measures` and
    :meth:`frame` look at :attr:`swarm` to know where the robots' state is. Faults reach a
    hand-written swarm mode through its wheels only (crashed and stuck robots, actuator noise):
    it has no radios or sensors to lose messages or readings. An experiment whose robots are a
    :class:`~dream.swarm.SwarmRobot` (:meth:`swarm_robot`) needs no swarm mode of its own, and
    gets every fault both ways.

    Attributes the runner sets
    --------------------------
    steps_cap (the step cap the run was given, ``steps=`` or ``--steps``; ``None`` when
    :meth:`steps` decides) before :meth:`check`, so that :meth:`arena_for` and :meth:`build` can
    size the run by it; n, world, rules (the :class:`~dream.specs.SimulatorSpec` the run
    follows), arena, swarm (whether the run is in swarm mode) before :meth:`build` or
    :meth:`build_swarm`; sim, dxu (the
    swarm's command array, ``(2, n)``, that controllers write into; in swarm mode the last
    :meth:`swarm_step`'s) once the simulator exists. ``robots`` is a list for :meth:`build` to
    fill (used by the default :meth:`frame`).
    """

    name: ClassVar[str] = ""
    default_n: ClassVar[int] = 10
    success: ClassVar[str] = "the run reaches done() with zero collisions, boundary and actuator violations"
    has_swarm_mode: ClassVar[bool] = False
    hold_steps: ClassVar[int] = 0

    steps_cap: int | None = None
    n: int
    swarm: bool = False
    world: World
    rules: SimulatorSpec
    arena: ArenaSpec
    sim: Backend
    dxu: np.ndarray
    engine: Engine | None = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.swarm_robot is not Experiment.swarm_robot:  # a swarm robot runs both ways
            cls.has_swarm_mode = True
        hold = cls.hold_steps
        if isinstance(hold, bool) or not isinstance(hold, int) or hold < 0:
            raise TypeError(f"{cls.__name__}.hold_steps must be an integer >= 0, got {hold!r}")

    def __init__(self, **params: Any) -> None:
        declared = self.parameters()
        for key, value in params.items():
            if key not in declared:
                have = ", ".join(declared) or "none"
                raise ValueError(f"{self.label()} has no parameter {key!r} (its parameters: {have})")
            setattr(self, key, declared[key].convert(value, self.label()))
        self.robots: list[Any] = []

    @classmethod
    def label(cls) -> str:
        return cls.name or cls.__name__

    @classmethod
    def parameters(cls) -> dict[str, Param]:
        """The declared parameters, by name, in declaration order (base classes first)."""
        found: dict[str, Param] = {}
        for klass in reversed(cls.__mro__):
            found.update({key: value for key, value in vars(klass).items() if isinstance(value, Param)})
        return found

    @property
    def correct(self) -> np.ndarray:
        """``(n,)`` bool: robots that have neither crashed, got stuck, nor lie (all of them in a
        run without faults). Success under faults is the job done by these."""
        state = self.world.fault_state
        return np.ones(self.n, dtype=bool) if state is None else state.correct

    @property
    def params(self) -> dict[str, Any]:
        """This instance's parameter values."""
        return {key: getattr(self, key) for key in self.parameters()}

    # -- hooks -------------------------------------------------------------------------------
    def check(self, n: int, backend: str) -> None:
        """Raise ``ValueError`` (saying why and what the limit is) for a size that cannot succeed."""

    def arena_for(self, n: int) -> ArenaSpec:
        """The arena for ``n`` robots, a :class:`dream.ArenaSpec` (default: the Robotarium's,
        :data:`dream.specs.ROBOTARIUM`); :attr:`steps_cap` is set."""
        return ROBOTARIUM

    def swarm_robot(self, n: int) -> SwarmRobot | None:
        """The robots as one :class:`~dream.swarm.SwarmRobot` (its decision written once, on arrays),
        or ``None`` for robot objects and timers (:meth:`build`). An experiment with a swarm robot
        needs neither :meth:`build` nor a swarm mode of its own: the runner runs it robot by
        robot, or as one swarm with ``swarm=True``, with the same poses at every step."""
        return None

    def build(self, n: int) -> None:
        """Create the robots, sensors, radios and timers (in :attr:`world`, the current world).

        Draw anything random from ``self.world.rng`` (the run's only generator).
        """
        raise NotImplementedError(f"{self.label()} must define build(self, n)")

    def build_swarm(self, n: int) -> None:
        """Swarm mode's :meth:`build`: set up the swarm's arrays (one row or column per robot)
        instead of robot objects and timers. Draw anything random from ``self.world.rng``."""
        raise NotImplementedError(f"{self.label()} has has_swarm_mode set but no build_swarm(self, n)")

    def swarm_step(self, step: int, x: np.ndarray) -> np.ndarray:
        """Swarm mode's decision at step ``step`` (0-based): every robot's command ``(2, n)``
        ``[v; w]`` (m/s, rad/s) from the poses ``x`` ``(3, n)`` that this step's ``get_poses()``
        returned; called after :meth:`before_step`, where the per-robot mode runs the timers."""
        raise NotImplementedError(f"{self.label()} has has_swarm_mode set but no swarm_step(self, step, x)")

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """Initial poses ``(3, n)`` (default: random grid points in the arena's centre, as rps)."""
        return initial_poses(n, rng, self.arena)

    def reachable_poses(self, poses: np.ndarray) -> np.ndarray:
        """The initial poses ``(3, n)`` of a run that goes through rps 2.x's start-up phase (a lab
        bundle on 2.x, the Robotarium backend on 2.x), from those of :meth:`initial_poses`: that
        phase never reaches poses closer than 0.35 m apart (default:
        :func:`dream.backends.startup.reachable_starts`, which moves the robots too close to
        nearby free points; override it to keep clear of obstacles, say)."""
        return reachable_starts(poses, self.arena)

    def steps(self, n: int) -> int:
        """The step cap when the run does not give one."""
        return 3000

    def timer_params(self, x: np.ndarray, dxu: np.ndarray) -> dict[str, tuple[Any, ...]]:
        """The arguments of each timer tag at this step (``x``: poses ``(3, n)``)."""
        return {"odom": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)}

    def before_step(self, step: int) -> None:
        """Called before the robots decide at step ``step`` (0-based): scheduled events."""

    def after_step(self, step: int, poses: np.ndarray) -> None:
        """Called after the simulator's step; ``step`` steps have run, ``poses`` ``(3, n)``."""

    def done(self, step: int, poses: np.ndarray) -> bool:
        """Whether the experiment has reached its goal (the run stops there)."""
        return False

    def measures(self) -> dict[str, Any]:
        """The experiment's own figures for the result (plain numbers)."""
        return {}

    def robot_measures(self) -> dict[str, np.ndarray]:
        """Per-robot figures of the step just run, by name, each ``(n,)`` numbers: the trajectory
        log's last columns (:mod:`dream.trajectory_log`), asked at every logged step (default
        none); the same names at every step."""
        return {}

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        """What a renderer draws of this step (default: poses, and ``dxi`` of robots that have one;
        the runner titles a frame left without a title with the name and :meth:`measures`)."""
        velocities = [getattr(robot, "dxi", None) for robot in self.robots]
        drawn = None if self.engine is None else self.engine.dxi.copy()
        if self.robots and all(v is not None for v in velocities):
            drawn = np.array(velocities, dtype=np.float64).reshape(-1, 2)
        return Frame(step, self.arena, poses, velocities=drawn)
