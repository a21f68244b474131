"""Simulator backends: the real Robotarium simulator (``rps``) and DREAM's Fast simulator."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from dream._checks import FloatArray, as_poses
from dream.backends.base import Backend
from dream.backends.fast import Fast
from dream.backends.robotarium import MAX_ROBOTS, Robotarium, rps_available, rps_generation
from dream.backends.startup import reachable_starts
from dream.specs import ROBOTARIUM, RULES, ArenaSpec, SimulatorSpec
from dream.world import current_world

__all__ = [
    "Backend",
    "Fast",
    "Robotarium",
    "backend_for",
    "initial_poses",
    "make_robotarium",
    "make_simulator",
    "rps_available",
    "rules_named",
    "rps_generation",
    "runs_startup",
]

BACKENDS = ("auto", "robotarium", "fast")


def initial_poses(
    n: int,
    rng: np.random.Generator,
    arena: ArenaSpec = ROBOTARIUM,
    spacing: float = 0.2,
    where: Callable[[np.ndarray, np.ndarray], Any] | None = None,
    space_order: bool = False,
) -> FloatArray:
    """Random poses ``(3, n)`` on a grid of ``spacing`` in the central part of the arena.

    As rps's ``generate_initial_conditions`` (distinct grid points in a 2.5 x 1.5 m area of the
    3.2 x 2 m arena, random headings), scaled to ``arena``, drawn from ``rng``. ``where(x, y)``,
    if given, keeps the grid points ``(k,)`` it is true of (relative to the arena's centre).

    The robots are numbered in the order drawn, as rps numbers them; with ``space_order``,
    column by column across the grid instead: robots near each other get near ids, so a swarm's
    per-robot arrays, which the kernels read in the order of space, stay in cache (at a million
    robots the rendezvous example's perception took half the time, its step 1.2-1.3x less:
    ``docs/benchmarks.md``). The poses drawn are the same either way, only numbered otherwise: a
    rule that gives robots roles by id (a line ordered by id, places on a ring) sees the
    difference, and a rule that draws at random robot by robot may draw otherwise.

    Without ``where`` only the chosen grid points are placed: time and memory grow with ``n``,
    not with the arena (a ring of 100,000 robots has 1.8e9 grid points). ``where`` tests every
    grid point, for arenas of fixed size.
    """
    width, height = arena.width * 2.5 / 3.2, arena.height * 1.5 / 2.0
    columns, rows = int(width // spacing), int(height // spacing)
    cx, cy = (arena.xmin + arena.xmax) / 2, (arena.ymin + arena.ymax) / 2
    cells = None  # every grid point is a candidate
    if where is not None:
        cells = np.arange(columns * rows)
        x, y = _grid_point(cells, rows, columns, spacing, cx, cy)
        cells = cells[np.asarray(where(x - cx, y - cy), dtype=np.bool_)]
    count = columns * rows if cells is None else len(cells)
    if count < n:
        raise ValueError(
            f"{n} robots do not fit {spacing} m apart in the central {width:.2f} x {height:.2f} m of the arena"
            f"{'' if where is None else ' where they may start'}: use a larger arena"
        )
    # An int population: numpy draws n distinct integers without a table of all of them
    # (Floyd's algorithm) unless n is over a fiftieth of it.
    chosen = rng.choice(count, size=n, replace=False)
    poses = np.empty((3, n))
    poses[0], poses[1] = _grid_point(chosen if cells is None else cells[chosen], rows, columns, spacing, cx, cy)
    poses[2] = rng.uniform(-np.pi, np.pi, size=n)
    # The grid's points are numbered column by column: each pose keeps its heading.
    return poses[:, np.argsort(chosen)] if space_order else poses


def _grid_point(
    cells: np.ndarray, rows: int, columns: int, spacing: float, cx: float, cy: float
) -> tuple[FloatArray, FloatArray]:
    """Positions ``x, y`` ``(k,)`` of grid points ``cells`` (numbered column by column) of a
    ``columns x rows`` grid of ``spacing`` centred on ``(cx, cy)``."""
    x = cx - (columns - 1) * spacing / 2 + (cells // rows) * spacing
    return x, cy - (rows - 1) * spacing / 2 + (cells % rows) * spacing


def rules_named(rules: str | None = None) -> SimulatorSpec:
    """The rules of the rps generation ``rules`` ("rps0" or "rps2"); default: the installed
    rps's, else rps 0.0.0's."""
    rules = rules if rules is not None else (rps_generation() or "rps0")
    if rules not in RULES:
        raise ValueError(f"unknown rules {rules!r}: choose one of {', '.join(RULES)}")
    return RULES[rules]


def make_robotarium(
    n: int,
    backend: str = "auto",
    initial_conditions: Any = None,
    *,
    arena: ArenaSpec | None = None,
    seed: int | None = None,
    rng: np.random.Generator | None = None,
    rules: str | None = None,
    startup: bool = True,
) -> Backend:
    """A simulator for ``n`` robots, for a script: the robots of the script's world keep to it.

    The current world (the script's) is given the simulator's arena and limits
    (:meth:`dream.World.keep_to`), so that its robots keep to them, made before or after it.
    :func:`dream.run` makes its simulator with :func:`make_simulator`, which reads and writes no
    world, and gives its own world the same.

    Parameters
    ----------
    backend : {"auto", "robotarium", "fast"}
        ``"auto"`` is the real Robotarium simulator when ``rps`` is installed, ``n <= 50`` and
        the arena is the Robotarium's, else the Fast backend.
    initial_conditions : (3, n) array_like, optional
        Initial poses; default: :func:`initial_poses` drawn from ``rng``, else from a generator
        seeded with ``seed`` (neither: a fresh, unseeded generator, as rps draws its own).
    seed : int, optional
        Seed of the initial poses' generator.
    rng : numpy.random.Generator, optional
        The initial poses' generator (not with ``seed``).
    arena : ArenaSpec, optional
        Default: the Robotarium arena.
    rules : {"rps0", "rps2"}, optional
        Which rps generation's dynamics and validation to follow (:data:`dream.specs.RULES`);
        default: the installed rps's, else "rps0". The Robotarium backend only has its own.
    startup : bool
        On the Robotarium backend with rps 2.x: drive the robots from the chargers to the initial
        conditions with rps's start-up phase first, as the lab's verifier does (rps 2.x's own
        default). The initial conditions are then moved apart where that phase could not reach
        them (:func:`dream.backends.startup.reachable_starts`), and the run begins where it
        ended. ``False`` starts at the initial conditions (``skip_initialization=True``).
    """
    _check_request(n, backend, rules)
    if initial_conditions is None:
        if seed is not None and rng is not None:
            raise ValueError("give the initial poses' generator (rng) or its seed, not both")
        arena_for_poses = ROBOTARIUM if arena is None else arena
        if rng is None:
            rng = np.random.default_rng(seed)
        initial_conditions = initial_poses(n, rng, arena_for_poses)
    sim = make_simulator(n, backend, initial_conditions, arena=arena, rules=rules, startup=startup)
    current_world().keep_to(sim.arena, sim.spec)
    return sim


def make_simulator(
    n: int,
    backend: str,
    initial_conditions: Any,
    *,
    arena: ArenaSpec | None = None,
    rules: str | None = None,
    startup: bool = True,
) -> Backend:
    """A simulator for ``n`` robots starting at ``initial_conditions`` ``(3, n)``; the parameters
    are :func:`make_robotarium`'s. It touches no world: the caller gives the simulator's arena and
    limits to the world its robots live in (:meth:`dream.World.keep_to`)."""
    _check_request(n, backend, rules)
    arena = ROBOTARIUM if arena is None else arena
    kind = backend_for(n, backend, arena, rules)
    poses = as_poses(initial_conditions, "initial_conditions", n)
    if kind == "robotarium":
        if runs_startup(n, kind, arena, rules, startup):
            return Robotarium(reachable_starts(poses, arena), skip_initialization=False)
        return Robotarium(poses)
    return Fast(poses, arena, rules_named(rules))


def backend_for(n: int, backend: str = "auto", arena: ArenaSpec | None = None, rules: str | None = None) -> str:
    """The backend, ``"robotarium"`` or ``"fast"``, that :func:`make_simulator` builds with these
    arguments (``"auto"`` resolved); a ``ValueError`` for a Robotarium backend that cannot be."""
    _check_request(n, backend, rules)
    rules = rules_named(rules).rules
    arena = ROBOTARIUM if arena is None else arena
    if backend == "auto":
        real = rps_available() and n <= MAX_ROBOTS and arena == ROBOTARIUM and rules == rps_generation()
        return "robotarium" if real else "fast"
    if backend == "robotarium":
        if n > MAX_ROBOTS:
            raise ValueError(f"the Robotarium runs at most {MAX_ROBOTS} robots, got {n}: use backend='fast'")
        if arena != ROBOTARIUM:
            raise ValueError("the Robotarium backend only has the Robotarium arena: use backend='fast'")
        if rules != rps_generation():
            raise ValueError(f"the installed rps follows {rps_generation()!r}, not rules={rules!r}: use backend='fast'")
    return backend


def runs_startup(
    n: int, backend: str = "auto", arena: ArenaSpec | None = None, rules: str | None = None, startup: bool = True
) -> bool:
    """Whether :func:`make_simulator` with these arguments runs rps 2.x's start-up phase (then
    :meth:`dream.Experiment.reachable_poses` gives a run's initial poses)."""
    return startup and backend_for(n, backend, arena, rules) == "robotarium" and rps_generation() == "rps2"


def _check_request(n: int, backend: str, rules: str | None) -> None:
    """Refuse an unknown backend or rules, or a bad number of robots, before drawing poses."""
    rules_named(rules)
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"the number of robots must be an integer >= 0, got {n!r}")
