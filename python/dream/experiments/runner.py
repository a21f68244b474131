"""The one experiment loop: every experiment, built-in or a researcher's own, runs through :func:`run`."""

from __future__ import annotations

import contextlib
import numbers
import os
import signal
import threading
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from types import TracebackType
from typing import Any, Protocol, TypeVar

import numpy as np

from dream._files import check_writable
from dream.backends import BACKENDS, make_simulator, rules_named, runs_startup
from dream.backends.base import Backend
from dream.experiments.checkpoint import CHECKPOINT_EVERY, Checkpoint, CheckpointError, load, save
from dream.experiments.registry import find
from dream.experiments.result import ExperimentResult
from dream.experiments.spec import Experiment
from dream.experiments.stepper import Stepper
from dream.faults import Faults
from dream.frames import Frame
from dream.memory import check_fits
from dream.world import World

Progress = Callable[[int, int], None]
_Call = TypeVar("_Call", bound=Callable[..., None])


class Watcher(Protocol):
    """An output that looks at the run as it steps (the trajectory log, a Rerun recording): opened
    and closed around the steps (closed with the error when the run fails), it sees the state
    before the first step, after every step, and at the end (``last``)."""

    def __enter__(self) -> Any: ...

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> Any: ...

    def see(self, step: int, stepper: Stepper, sim: Backend, poses: np.ndarray, last: bool = False) -> None: ...


def run(
    experiment: type[Experiment] | Experiment | str,
    n: int | None = None,
    seed: int = 0,
    backend: str = "auto",
    steps: int | None = None,
    *,
    record: Callable[[Frame], None] | None = None,
    progress: Progress | bool | None = None,
    trace: bool = False,
    faults: Faults | None = None,
    rules: str | None = None,
    swarm: bool = False,
    checkpoint: str | os.PathLike[str] | None = None,
    checkpoint_every: int = CHECKPOINT_EVERY,
    log: str | os.PathLike[str] | None = None,
    log_every: int = 1,
    rerun: str | os.PathLike[str] | None = None,
    startup: bool = True,
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
        Step cap (default: the experiment's :meth:`~Experiment.steps`); the experiment sees it as
        :attr:`~Experiment.steps_cap` from :meth:`~Experiment.check` on.
    record : callable, optional
        Called with the experiment's :class:`~dream.frames.Frame` after every step.
    progress : callable, optional
        Called as ``progress(step, cap)`` after every step (``None`` or ``False``: nothing is).
    trace : bool
        Keep the poses of every step in ``result.trace`` ``(steps + 1, 3, n)``.
    faults : Faults, optional
        What goes wrong (:mod:`dream.faults`), injected by the world; the result lists the
        settings, the robot fault events and the counts of lost messages and readings.
    rules : {"rps0", "rps2"}, optional
        The rps generation whose dynamics and validation the run follows, i.e. the lab it
        targets (default: the installed rps's, else "rps0"); see :func:`dream.make_robotarium`.
    swarm : bool
        Run the experiment's swarm mode (:meth:`~Experiment.build_swarm`,
        :meth:`~Experiment.swarm_step`: the whole swarm decides every step in one call) instead
        of robot objects and timers.
    checkpoint : path, optional
        Save the whole run to this file before the first step, every ``checkpoint_every``
        steps, and when it stops short of done (a signal, the cap), so that :func:`resume`
        can go on with it (:mod:`dream.experiments.checkpoint`); a run that cannot be saved
        (one holding a live window, say) fails before its first step.
    checkpoint_every : int
        Steps between two saves (default 20,000).
    log : path, optional
        Write the run's trajectory log, a Parquet table with one row per robot and logged step
        (:mod:`dream.trajectory_log`).
    log_every : int
        Log (and record, with ``rerun``) every ``log_every``-th step, and step 0 and the last.
    rerun : path, "spawn" or "serve", optional
        Record the run for the Rerun viewer (:mod:`dream.recording`; needs the ``rerun`` extra):
        into a ``.rrd`` file, live into a viewer it spawns, or served to a web viewer.
    startup : bool
        On the Robotarium backend with rps 2.x: first run rps's start-up phase from the chargers,
        as the lab's verifier does, to the experiment's initial poses moved apart where that
        phase could not reach them (see :func:`dream.make_robotarium`); ``False`` skips it.
    **params
        Values of the experiment's declared parameters.

    Returns
    -------
    ExperimentResult
        A run stopped by Ctrl-C (SIGINT) or SIGTERM finishes its step and returns what it has
        measured so far, with ``interrupted`` set; a second Ctrl-C cuts short the step the
        experiment is computing (the run then ends at the step before, and saves no checkpoint
        of the half step) but never a frame or a checkpoint being written (see
        :func:`outputs_kept`).

    Raises
    ------
    ValueError
        Bad arguments, a size the experiment refuses, or ``swarm=True`` for an experiment
        without a swarm mode.
    """
    exp = _instance(experiment, params)
    n = exp.default_n if n is None else _count(n, "n", 1)
    seed = _count(seed, "seed", 0)
    exp.steps_cap = None if steps is None else _count(steps, "steps", 1)
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    if faults is not None and not isinstance(faults, Faults):
        raise ValueError(f"faults must be a dream.Faults, such as Faults(loss=0.3), got {faults!r}")
    record = _callback(record, "record", "record(frame)")
    progress = _callback(progress, "progress", "progress(step, cap)")
    check_fits(n)  # before the experiment sizes anything by n
    exp.check(n, backend)
    every = _count(checkpoint_every, "checkpoint_every", 1)
    if checkpoint is not None:
        check_writable(checkpoint, "checkpoint")
    watch = _watchers(log, _count(log_every, "log_every", 1), rerun)
    startup = runs_startup(n, backend, exp.arena_for(n), rules, startup)  # then the starts must be reachable
    world = World(seed)
    with world:
        try:
            stepper = Stepper(exp, n, world, rules_named(rules), swarm=swarm, startup=startup)
        except ValueError as err:  # from the layers below, in their terms: say which parameters the run set
            raise _naming_params(exp, err) from err
        if exp.engine is not None:  # messages are counted for the outputs that show them
            exp.engine.count_traffic = bool(watch)
        sim = make_simulator(
            n, backend, stepper.initial_conditions, arena=exp.arena, rules=exp.rules.rules, startup=startup
        )
        stepper.attach(sim, faults)
    cap = exp.steps(n) if exp.steps_cap is None else exp.steps_cap
    state = Checkpoint(stepper, sim, 0, cap, every, poses=[sim.poses] if trace else None)
    if checkpoint is not None:
        save(checkpoint, state)  # a run that cannot be saved fails here, before its first step
    with contextlib.ExitStack() as outputs:  # each output closed whole, or removed if the run fails
        for watcher in watch:
            outputs.enter_context(watcher)
        return _go_on(state, record, progress, checkpoint, watch)


def _watchers(log: str | os.PathLike[str] | None, every: int, rerun: str | os.PathLike[str] | None) -> list[Watcher]:
    """The outputs that look at the run as it steps, their paths checked before it starts."""
    watch: list[Watcher] = []
    if log is not None:
        from dream.trajectory_log import TrajectoryLog

        watch.append(TrajectoryLog(log, every))
    if rerun is not None:
        from dream.recording import Recorder

        watch.append(Recorder(rerun, every))
    return watch


def resume(
    checkpoint: str | os.PathLike[str],
    steps: int | None = None,
    *,
    record: Callable[[Frame], None] | None = None,
    progress: Progress | bool | None = None,
    checkpoint_every: int | None = None,
    trust: bool = False,
) -> ExperimentResult:
    """Go on with the run saved in ``checkpoint`` (see :func:`run`), saving to the same file.

    The result is the one the run would have given uninterrupted (its wall time summed over
    every part). ``steps`` sets a new step cap (default: the run's own), ``checkpoint_every``
    a new interval between saves (default: the run's own); ``record`` and ``progress`` are as
    in :func:`run` (a video of the resumed part starts at its first step).

    A checkpoint is code (loading it runs it): only a file signed with the user's key is
    resumed, unless ``trust`` (a colleague's file, resumed with a warning); see
    :mod:`dream.experiments.checkpoint`.

    Raises
    ------
    FileNotFoundError, dream.experiments.checkpoint.CheckpointError
        No such file, or not a checkpoint this DREAM can resume (not signed with the user's key
        and not ``trust``, another version's, ...).
    ValueError
        ``steps`` fewer than the run has taken already.
    """
    record = _callback(record, "record", "record(frame)")
    progress = _callback(progress, "progress", "progress(step, cap)")
    state = load(checkpoint, trust=trust)
    if checkpoint_every is not None:
        state.every = _count(checkpoint_every, "checkpoint_every", 1)
    if steps is not None:
        cap = _count(steps, "steps", 1)
        if cap < state.step:
            raise ValueError(f"steps={cap}: the run in {checkpoint} has taken {state.step} steps already")
        state.cap = state.stepper.exp.steps_cap = cap
    return _go_on(state, record, progress, checkpoint)


def _go_on(
    state: Checkpoint,
    record: Callable[[Frame], None] | None,
    progress: Progress | None,
    checkpoint: str | os.PathLike[str] | None,
    watch: Sequence[Watcher] = (),
) -> ExperimentResult:
    """Step the run from ``state.step`` until it is done, reaches its cap or a signal stops it;
    with ``checkpoint``, save it there every ``state.every`` steps and when it stops short of
    done; ``watch`` sees the run before its steps, after each and at the end."""
    stepper, sim = state.stepper, state.sim
    everyone = np.arange(stepper.exp.n)
    done_at, cut = None, False
    start, before = time.perf_counter(), state.wall_time
    stop = _kept[-1] if _kept else _Signals()  # the CLI's, whose outputs are written after the run
    stop.install()
    try:
        with stepper.world:
            for watcher in watch:
                watcher.see(state.step, stepper, sim, sim.poses)
            try:
                while state.step < state.cap:
                    t = state.step
                    stop.cuttable = True  # the experiment computes: a second Ctrl-C may cut it short
                    x = sim.get_poses()
                    sim.set_velocities(everyone, stepper.decide(t, x))
                    sim.step()
                    now = sim.poses
                    done = stepper.after(t + 1, now)
                    stop.cuttable = False  # what the step writes is written whole
                    state.step = t + 1
                    if state.poses is not None:
                        state.poses.append(now)
                    if progress is not None:
                        progress(t + 1, state.cap)
                    if record is not None:
                        record(stepper.frame(t + 1, now))
                    for watcher in watch:
                        watcher.see(t + 1, stepper, sim, now)
                    if done:
                        done_at = t + 1
                        break
                    if stop.signal is not None:
                        break
                    if checkpoint is not None and state.step % state.every == 0 and state.step < state.cap:
                        state.wall_time = before + time.perf_counter() - start
                        _save_on(checkpoint, state)
            except KeyboardInterrupt:
                if not stop.cuttable:
                    raise
                stop.cuttable, cut = False, True  # the half step is no state to resume from
            stopped = stop.signal  # a signal from here on comes once the steps are over: it stops nothing
            state.wall_time = before + time.perf_counter() - start
            for watcher in watch:
                watcher.see(state.step, stepper, sim, sim.poses, last=True)
            if checkpoint is not None and done_at is None and not cut:  # a signal or the cap: resume() goes on
                _save_on(checkpoint, state)
    finally:
        stop.cuttable = False
        if not _kept or stop is not _kept[-1]:
            stop.restore()
    trace = None if state.poses is None else np.array(state.poses)
    result = stepper.result(done_at, state.wall_time, trace)
    result.interrupted, result.signal = stopped is not None, stopped
    for fault in [] if result.interrupted else result.faults.get("pending", []):
        message = f"fault {fault['kind']}@{fault['step']} never happened: the run ended at step {state.step}"
        warnings.warn(f"{message} (an experiment's hold_steps keeps a run going after done)", RuntimeWarning, 3)
    return result


def _save_on(path: str | os.PathLike[str], state: Checkpoint) -> None:
    """Save a run under way; a save that fails (a full disk, the folder gone) is reported and the
    run goes on: hours of stepping are worth more than one checkpoint."""
    try:
        save(path, state)
    except (OSError, CheckpointError) as err:
        message = f"checkpoint not saved at step {state.step}: {err}; the run goes on"
        warnings.warn(message, RuntimeWarning, stacklevel=3)


def _instance(experiment: type[Experiment] | Experiment | str, params: dict[str, Any]) -> Experiment:
    if isinstance(experiment, str):
        experiment = find(experiment)
    if isinstance(experiment, Experiment):
        return type(experiment)(**{**experiment.params, **params})
    if isinstance(experiment, type) and issubclass(experiment, Experiment):
        return experiment(**params)
    raise TypeError(f"run() takes an Experiment subclass, instance or name, got {experiment!r}")


def _naming_params(exp: Experiment, err: ValueError) -> ValueError:
    """``err``, raised while ``exp`` was built, prefixed with the parameters set away from their
    defaults: a value refused by a layer below (a radio's ``range``) is the user's parameter."""
    declared = exp.parameters()
    changed = [f"{key}={value!r}" for key, value in exp.params.items() if value != declared[key].default]
    return ValueError(f"{exp.label()} with {', '.join(changed)}: {err}") if changed else err


def _callback(value: _Call | bool | None, name: str, call: str) -> _Call | None:
    """A callback argument: callable, or ``None`` or ``False`` for none (``progress=False`` reads as
    "no progress")."""
    if value is None or value is False:
        return None
    if not callable(value):
        raise ValueError(f"{name} must be a function called as {call}, or None or False for none, got {value!r}")
    return value


def _count(value: Any, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
        raise ValueError(f"{name} must be an integer >= {least}, got {value!r}")
    return int(value)


class _Signals:
    """SIGINT and SIGTERM while a run steps, so that nothing it writes (a video, a checkpoint, the
    metrics) is cut half-way. Only the main thread can take signals: elsewhere (a sweep's worker)
    this catches nothing.

    The first signal asks the run to stop after the current step (:attr:`signal`). A second Ctrl-C
    raises ``KeyboardInterrupt`` while the experiment computes (:attr:`cuttable`: a step that
    hangs can be cut short), and waits for the end of the step while a frame or a checkpoint is
    written. Once the steps are over, signals are only noted: the run's last checkpoint is saved
    whole, and within :func:`outputs_kept`, its video and JSON too.
    """

    def __init__(self) -> None:
        self.signal: int | None = None  #: the first signal received
        self.cuttable = False
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: object) -> None:
        if self.signal is None:
            self.signal = signum
        elif self.cuttable and signum == signal.SIGINT:
            raise KeyboardInterrupt

    def install(self) -> None:
        """Take SIGINT and SIGTERM (once; from the main thread only)."""
        if not self._previous and threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self._previous[signum] = signal.signal(signum, self._handle)

    def restore(self) -> None:
        """Give SIGINT and SIGTERM back to the handlers :meth:`install` found."""
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous.clear()

    def ignore_from_now(self) -> None:
        """Ignore SIGINT and SIGTERM from now on, instead of giving them back: for a process that
        ends once its outputs are written, where a late Ctrl-C has nothing left to stop (Python's
        own handler would print a traceback, or kill it as it exits)."""
        for signum in self._previous:
            signal.signal(signum, signal.SIG_IGN)
        self._previous.clear()


#: The guards of :func:`outputs_kept` blocks, innermost last: the run within takes the last.
_kept: list[_Signals] = []


@contextlib.contextmanager
def outputs_kept() -> Iterator[_Signals]:
    """A block that runs (or resumes) a run and then writes what it recorded: the signals that come
    once the run has begun to step are handled as the run handles them (see :func:`run`) until the
    block ends, so that a second Ctrl-C lets the video close and the metrics be written. The
    guard's ``signal`` is the first signal received (``None`` if none came); before the run
    steps, signals act as they did before the block (Ctrl-C raises ``KeyboardInterrupt``).

    Examples
    --------
    >>> with outputs_kept() as guard:
    ...     result = run("hrvo-circle", n=4, steps=3, backend="fast")
    ...     # close the video, write the JSON: a Ctrl-C now waits until the block ends
    >>> guard.signal is None
    True
    """
    guard = _Signals()
    _kept.append(guard)
    try:
        yield guard
    finally:
        _kept.remove(guard)
        guard.restore()
