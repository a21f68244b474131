"""The one experiment loop: every experiment, built-in or a researcher's own, runs through :func:`run`."""

from __future__ import annotations

import numbers
import signal
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from dream.backends import BACKENDS, make_robotarium
from dream.experiments.result import ExperimentResult
from dream.experiments.spec import Experiment
from dream.faults import Faults
from dream.frames import Frame, fault_status
from dream.world import World

Progress = Callable[[int, int], None]


def run(
    experiment: type[Experiment] | Experiment | str,
    n: int | None = None,
    seed: int = 0,
    backend: str = "auto",
    steps: int | None = None,
    *,
    record: Callable[[Frame], None] | None = None,
    progress: Progress | None = None,
    trace: bool = False,
    faults: Faults | None = None,
    **params: Any,
) -> ExperimentResult:
    """Run ``experiment`` until it is done or ``steps`` have run.

    Parameters
    ----------
    experiment : Experiment subclass, instance, or the name of a built-in experiment
        An instance contributes its parameter values; the run uses a fresh copy.
    n : int, optional
        Number of robots (default: the experiment's ``default_n``).
    seed : int
        Seeds the run's one random generator (``world.rng``): initial poses, noise, losses and
        whatever the experiment draws. The same seed gives the same run.
    backend : {"auto", "robotarium", "fast"}
        See :func:`dream.make_robotarium`.
    steps : int, optional
        Step cap (default: the experiment's :meth:`~Experiment.steps`).
    record : callable, optional
        Called with the experiment's :class:`~dream.frames.Frame` after every step.
    progress : callable, optional
        Called as ``progress(step, cap)`` after every step.
    trace : bool
        Keep the poses of every step in ``result.trace`` ``(steps + 1, 3, n)``.
    faults : Faults, optional
        What goes wrong (:mod:`dream.faults`), injected by the world; the result lists the
        settings, the robot fault events and the counts of lost messages and readings.
    **params
        Values of the experiment's declared parameters.

    Returns
    -------
    ExperimentResult
        A run stopped by Ctrl-C (SIGINT) or SIGTERM finishes its step and returns what it has
        measured so far, with ``interrupted`` set (a second Ctrl-C raises ``KeyboardInterrupt``).
    """
    exp = _instance(experiment, params)
    n = exp.default_n if n is None else _count(n, "n", 1)
    seed = _count(seed, "seed", 0)
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    exp.check(n, backend)
    with World(seed) as world:
        exp.n, exp.world, exp.arena = n, world, exp.arena_for(n)
        exp.build(n)
        sim = make_robotarium(n, backend, exp.initial_poses(n, world.rng), arena=exp.arena)
        exp.sim, exp.dxu = sim, np.zeros((2, n))
        state = world.inject(faults, n)
        w_per_v = sim.sim.max_angular / sim.sim.max_linear
        cap = exp.steps(n) if steps is None else _count(steps, "steps", 1)
        everyone = np.arange(n)
        poses = [sim.poses] if trace else []
        done_at = None
        start = time.perf_counter()
        with _StopOnSignal() as stop:
            for t in range(cap):
                exp.before_step(t)
                x = sim.get_poses()
                world.update_timers(t, exp.timer_params(x, exp.dxu))
                sim.set_velocities(everyone, exp.dxu if state is None else state.actuate(exp.dxu, w_per_v))
                sim.step()
                now = sim.poses
                exp.after_step(t + 1, now)
                if trace:
                    poses.append(now)
                if progress is not None:
                    progress(t + 1, cap)
                if record is not None:
                    frame = exp.frame(t + 1, now)
                    frame.time = (t + 1) * sim.time_step if frame.time is None else frame.time
                    if state is not None and frame.status is None:  # who has crashed, is stuck or lies
                        frame.status = fault_status(state.crashed, state.stuck, state.byzantine)
                    record(frame)
                if exp.done(t + 1, now):
                    done_at = t + 1
                    break
                if stop.signal is not None:
                    break
        wall = time.perf_counter() - start
    result = ExperimentResult.from_backend(
        exp.label(), seed, sim, done_at, wall, exp.measures(), np.array(poses) if trace else None, exp.params
    )
    result.interrupted, result.signal = stop.signal is not None, stop.signal
    result.faults = {} if state is None else state.summary()
    return result


def _instance(experiment: type[Experiment] | Experiment | str, params: dict[str, Any]) -> Experiment:
    if isinstance(experiment, str):
        from dream.experiments import find

        experiment = find(experiment)
    if isinstance(experiment, Experiment):
        return type(experiment)(**{**experiment.params, **params})
    if isinstance(experiment, type) and issubclass(experiment, Experiment):
        return experiment(**params)
    raise TypeError(f"run() takes an Experiment subclass, instance or name, got {experiment!r}")


def _count(value: Any, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
        raise ValueError(f"{name} must be an integer >= {least}, got {value!r}")
    return int(value)


class _StopOnSignal:
    """While a run steps, SIGINT and SIGTERM ask it to stop after the current step, so that
    nothing (a video being written, the metrics) is cut half-way; a second Ctrl-C interrupts at
    once. Only the main thread can take signals: elsewhere (a sweep's worker) this does nothing."""

    def __init__(self) -> None:
        self.signal: int | None = None
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: object) -> None:
        if self.signal == signal.SIGINT and signum == signal.SIGINT:
            raise KeyboardInterrupt
        self.signal = signum

    def __enter__(self) -> _StopOnSignal:
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
