"""Sweeps: one experiment over seeds, robot counts and parameter values, run on Dask distributed.

    dream sweep hrvo-circle --seeds 0:8 -n 10 --workers 2 --out s.csv --plot s.png
    dream sweep my_experiment.py --seeds 0:100 -n 10,20 --param loss=0,0.3 --scheduler tcp://head:8786 --out r.csv

Every (n, parameter values, seed) of the cartesian product is one task; by default the tasks run on
a ``LocalCluster`` of worker processes on this machine, with ``scheduler`` on an existing Dask
cluster. The local cluster's scheduler, workers and HTTP endpoints listen on 127.0.0.1 only, and
its dashboard is off unless asked for (``--dashboard``: at http://127.0.0.1:8787/status, or
another port if that one is taken; the address is printed).

Rows reach the CSV as runs finish, so an interrupted sweep keeps what it has done, and running it
again with the same file only runs what is missing (or failed), or was run by other code: each row
holds the ``source_digest`` of the experiment's file (:func:`~dream.experiments.files.source_digest`),
and a row of this sweep's runs whose digest differs from the file's current one (or a row from a
table written before sweeps recorded it) is dropped with a warning and its run done again. While
a sweep runs it holds a lock on ``OUT.lock`` beside the CSV, and a second sweep on the same file
refuses to start. The rows read back are checked: a last row cut short (no line end: its sweep was
killed while writing it) is dropped with a warning and its run is done again; any other row that
does not parse (wrong number of fields, a value of the wrong kind, a row without result or error)
stops the sweep before any run with one line naming the file and line. Such a row is someone's
data, or the sign of a file mixed up with another: the sweep would drop it at its first rewrite,
so it leaves the file as it is and the researcher mends or deletes the line.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dream._files import check_writable
from dream.backends import BACKENDS
from dream.backends.robotarium import MAX_ROBOTS
from dream.experiments import EXPERIMENTS, Experiment, find, run
from dream.experiments.files import source_digest, source_file
from dream.experiments.runner import _count
from dream.faults import Faults
from dream.sweep.table import INPUTS, METRICS, TAIL, Row, Table, _cell, _ordered


class SweepRows(list[Row]):
    """The rows of a sweep, in task order: a list of dicts, with ``new`` (how many runs this sweep
    did) and ``kept`` (how many rows it took from ``out`` instead)."""

    def __init__(self, rows: Iterable[Row], new: int, kept: int) -> None:
        super().__init__(rows)
        self.new = new
        self.kept = kept


# The current world is one per process (``dream.world``): a worker with several threads (``dask
# worker`` defaults to one per core) must run its tasks one at a time. A run holds the GIL anyway.
_ONE_RUN_AT_A_TIME = threading.Lock()


@dataclass(frozen=True)
class Task:
    """The inputs of one run of a sweep (one Dask task)."""

    experiment: str
    source_digest: str  #: of the experiment's file: a row of other code is another run
    n: int
    seed: int
    backend: str
    swarm: bool
    step_cap: int | None
    params: tuple[tuple[str, Any], ...]
    faults: tuple[tuple[str, str], ...] = ()  #: ``--fault`` kinds and values, as on the command line

    def inputs(self) -> Row:
        values = (self.experiment, self.source_digest, self.n, self.seed, self.backend, self.swarm, self.step_cap)
        columns = dict(zip(INPUTS, values))
        return {
            **columns,
            **{f"params.{name}": value for name, value in self.params},
            **{f"faults.{kind}": value for kind, value in self.faults},
        }

    def fault_model(self) -> Faults | None:
        return Faults.parse(f"{kind}={value}" for kind, value in self.faults) if self.faults else None

    def key(self) -> tuple[str, ...]:
        return tuple(_cell(value) for value in self.inputs().values())


@dataclass(frozen=True)
class Plan:
    """A validated sweep: what the workers load, and the tasks in order (seeds innermost)."""

    source: str | type[Experiment]
    tasks: list[Task]
    swept: list[str]  # the input columns that take more than one value (not the seed)

    @property
    def inputs(self) -> list[str]:
        return list(self.tasks[0].inputs())


def plan(
    experiment: type[Experiment] | Experiment | str,
    seeds: Iterable[int],
    n: int | Iterable[int] | None = None,
    params: Mapping[str, Any] | None = None,
    backend: str = "auto",
    steps: int | None = None,
    faults: Mapping[str, Iterable[Any]] | None = None,
    swarm: bool = False,
) -> Plan:
    """Check a sweep and list its tasks, without running anything.

    Parameter values (Python values, or text as on the command line) are converted to the
    experiment's declared types; the experiment's ``check`` sees every size. ``faults`` maps a
    ``--fault`` kind to its values (``{"loss": [0, 0.3], "crash": ["0.1@300"]}``), swept like
    the parameters. ``swarm`` runs the experiment's swarm mode.

    Raises
    ------
    ValueError
        Naming the argument: an unknown experiment, parameter or backend, a value of the wrong
        type, an empty list, a seed below 0, a robot count below 1 or one the experiment refuses,
        ``swarm`` for an experiment without a swarm mode.
    """
    source, cls, base = _source(experiment)
    if swarm and not cls.has_swarm_mode:
        raise ValueError(f"swarm: {cls.label()} has no swarm mode (dream list shows which experiments have one)")
    seeds = _counts(seeds, "seeds", 0)
    sizes = _counts(cls.default_n if n is None else n, "n", 1)
    if backend not in BACKENDS:
        raise ValueError(f"backend: unknown backend {backend!r}, choose one of {', '.join(BACKENDS)}")
    if steps is not None:
        steps = _count(steps, "steps", 1)
    grid = {name: _values(values, f"params[{name!r}]") for name, values in (params or {}).items()}
    fault_grid = {
        kind: [str(v) for v in _values(values, f"faults[{kind!r}]")] for kind, values in (faults or {}).items()
    }
    digest = source_digest(cls)
    tasks: dict[tuple[str, ...], Task] = {}  # converted values can coincide ("0" and "0.0"): one task each
    for combination, broken in itertools.product(
        itertools.product(*grid.values()), itertools.product(*fault_grid.values())
    ):
        exp = cls(**{**base, **dict(zip(grid, combination))})  # converts and checks the values
        fault_options = tuple(zip(fault_grid, broken))
        Faults.parse(f"{kind}={value}" for kind, value in fault_options)  # checks them, naming the option
        for size in sizes:
            if backend == "robotarium" and size > MAX_ROBOTS:
                raise ValueError(f"n: the Robotarium backend runs at most {MAX_ROBOTS} robots, got {size}")
            exp.check(size, backend)
            for seed in seeds:
                task = Task(
                    cls.label(), digest, size, seed, backend, bool(swarm), steps, tuple(exp.params.items()),
                    fault_options,
                )  # fmt: skip
                tasks.setdefault(task.key(), task)
    ordered = list(tasks.values())
    columns = ordered[0].inputs()
    swept = [c for c in columns if c != "seed" and len({_cell(t.inputs()[c]) for t in ordered}) > 1]
    return Plan(source, ordered, swept)


def sweep(
    experiment: type[Experiment] | Experiment | str,
    seeds: Iterable[int] = range(8),
    n: int | Iterable[int] | None = None,
    params: Mapping[str, Any] | None = None,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    out: str | Path | None = None,
    plot: str | Path | None = None,
    backend: str = "auto",
    steps: int | None = None,
    faults: Mapping[str, Iterable[Any]] | None = None,
    swarm: bool = False,
    progress: bool = True,
    dashboard: bool = False,
    log: bool = False,
    log_every: int = 1,
) -> SweepRows:
    """Run ``experiment`` for every (n, parameter values, seed) on Dask, one task per run.

    Parameters
    ----------
    experiment : Experiment subclass, instance, built-in name or path of a ``.py`` file
        A file is loaded again on each worker (:func:`dream.experiments.load_file`), so workers
        on other machines need the file at the same absolute path.
    seeds : iterable of int
        The seeds of each combination (``range(A, B)`` or a list).
    n : int or iterable of int, optional
        Robot counts (default: the experiment's ``default_n``).
    params : mapping of str to a list of values, optional
        Each declared parameter to sweep and its values (a single value is a list of one).
    workers : int, optional
        Worker processes of the local cluster (default: the number of cores).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://HOST:8786``) to use instead.
    out : path, optional
        CSV that receives a row per run as it finishes. Runs it already holds without an error
        (same input columns, ``source_digest`` included: the same experiment code) are not run
        again; rows of other sweeps in it are kept. Locked while
        the sweep runs (``OUT.lock``); its rows are checked as the module docstring says.
    plot : path, optional
        PNG of the success rate and the measures against the swept values.
    backend, steps
        As in :func:`dream.run` (``steps`` is the ``step_cap`` column).
    faults : mapping of str to a list of values, optional
        ``--fault`` kinds to sweep and their values (:mod:`dream.faults`), e.g.
        ``{"loss": [0, 0.3, 0.6]}``: the ``faults.KIND`` columns.
    swarm : bool
        Run the experiment's swarm mode (as :func:`dream.run`), for sweeps of thousands of robots.
    progress : bool
        A progress bar on stderr (only when stderr is a terminal).
    dashboard : bool
        Serve the local cluster's Dask dashboard on 127.0.0.1 (its address goes to stderr).
    log : bool
        Write each run's trajectory log (:mod:`dream.trajectory_log`) into the folder
        ``OUT-logs`` beside ``out`` (:func:`logs_folder`, made if need be; a cluster's workers
        need it at the same absolute path), one file per run (:func:`log_name`), whose path is the
        row's ``log`` column.
    log_every : int
        The logs' ``log_every`` (see :func:`dream.run`).

    Returns
    -------
    SweepRows
        A list of dicts, one row per run of this sweep, in task order (``pandas.DataFrame(rows)``
        makes a table), whose ``new`` and ``kept`` say how many runs were done now and how many
        rows came from ``out``. A row holds the inputs (``experiment, source_digest, n, seed,
        backend, swarm, step_cap, params.NAME, faults.KIND``), the metrics
        (``simulator, steps, completed_step, collisions, boundary, actuator, success,
        measures.NAME``), ``wall_time`` (s, on the worker), ``worker`` (its address) and
        ``error`` (``"Type: message"`` of a run that raised, else ``None``). Rows read back from
        ``out`` hold numbers, booleans and ``None`` parsed from their text.

    Raises
    ------
    ValueError
        Bad arguments (see :func:`plan`), a CSV that is not a sweep table or holds a row that does
        not parse (naming the file and line), a CSV another sweep is writing, or ``log`` without
        ``out``; before any run.
    """
    if workers is not None and scheduler is not None:
        raise ValueError("workers: sizes the local cluster; with scheduler, the cluster's own workers run the tasks")
    if dashboard and scheduler is not None:
        raise ValueError("dashboard: serves the local cluster's; with scheduler, open the cluster's own dashboard")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if out is not None:
        check_writable(out, "out")
    if plot is not None:
        from dream.sweep_plot import check_plot_path  # matplotlib only when drawing

        check_plot_path(plot)
    every = _count(log_every, "log_every", 1)
    if log and out is None:
        raise ValueError("log: each run's log goes beside the CSV: give out too")
    sweep_plan = plan(experiment, seeds, n, params, backend, steps, faults, swarm)
    with Table(out, sweep_plan) as table:
        logs = None if not log or out is None else (str(_made(logs_folder(out)).resolve()), every)
        todo = [task for task in sweep_plan.tasks if task.key() not in table.done]
        if todo:
            _execute(sweep_plan.source, todo, workers, scheduler, progress, dashboard, table.add, logs)
        rows = [table.done[task.key()] for task in sweep_plan.tasks]
    # The same columns in every row (a run that raised has no metrics; the file may hold other sweeps' columns).
    found = (column for row in rows for column, value in row.items() if value is not None)
    columns = _ordered([*INPUTS, *sweep_plan.inputs, *METRICS, *found, *TAIL])
    rows = [{column: row.get(column) for column in columns} for row in rows]
    if plot is not None:
        from dream.sweep_plot import plot_sweep  # matplotlib only when drawing

        plot_sweep(rows, sweep_plan.swept, plot)
    return SweepRows(rows, len(todo), len(sweep_plan.tasks) - len(todo))


def logs_folder(out: str | Path) -> Path:
    """The folder of a sweep's trajectory logs: ``OUT-logs`` beside the CSV ``out`` (``r.csv``:
    ``r-logs``)."""
    path = Path(out)
    return path.with_name(f"{path.stem}-logs")


def log_name(task: Task) -> str:
    """The file name of a run's trajectory log: ``EXPERIMENT-nN-seedS-KEY.parquet``, ``KEY`` 8 hex
    digits of the run's inputs (parameters and faults included), so no two runs share one."""
    key = hashlib.sha256("\x1f".join(task.key()).encode()).hexdigest()[:8]
    return f"{task.experiment}-n{task.n}-seed{task.seed}-{key}.parquet"


def _made(folder: Path) -> Path:
    try:
        folder.mkdir(exist_ok=True)
    except OSError as err:
        raise ValueError(f"log: cannot make the folder {folder} for the logs: {err.strerror or err}") from None
    return folder


def run_task(source: str | type[Experiment], task: Task, logs: tuple[str, int] | None = None) -> Row:
    """Run one task (on a Dask worker): its row, with the error instead of metrics if it raised;
    with ``logs`` (folder, log_every), its trajectory log in that folder."""
    from distributed import get_worker

    start = time.perf_counter()
    row = task.inputs()
    log = None if logs is None else Path(logs[0]) / log_name(task)
    try:
        with _ONE_RUN_AT_A_TIME:
            cls = find(source) if isinstance(source, str) else source
            result = run(
                cls, n=task.n, seed=task.seed, backend=task.backend, steps=task.step_cap,
                faults=task.fault_model(), swarm=task.swarm, log=log, log_every=1 if logs is None else logs[1],
                **dict(task.params),
            )  # fmt: skip
        if log is not None:
            row["log"] = str(log)
        data = result.to_dict()
        row.update({"simulator": data["backend"], **{key: data[key] for key in METRICS[1:]}})
        row.update(_flatten(data["measures"], "measures."))
        row["error"] = None
    except Exception as err:  # noqa: BLE001 -- the experiment's code, whatever it raised: a row, not a lost sweep
        row["error"] = f"{type(err).__name__}: {err}"
    row["wall_time"] = time.perf_counter() - start
    row["worker"] = get_worker().address
    return row


def _execute(
    source: str | type[Experiment],
    tasks: Sequence[Task],
    workers: int | None,
    scheduler: str | None,
    progress: bool,
    dashboard: bool,
    record: Callable[[Row], None],
    logs: tuple[str, int] | None = None,
) -> None:
    """Submit every task and record each row as its run finishes; the cluster closes on any exit.

    A local cluster listens on 127.0.0.1 only (scheduler, workers, nannies and their HTTP
    endpoints: Dask's default for the dashboard is every interface), with the dashboard off
    unless ``dashboard``.
    """
    from distributed import Client, LocalCluster, as_completed
    from tqdm import tqdm

    with contextlib.ExitStack() as stack:
        if scheduler is None:
            count = min(workers or os.cpu_count() or 1, len(tasks))  # no idle processes for a small sweep
            with _ignoring_ctrl_c():
                cluster = LocalCluster(
                    n_workers=count,
                    threads_per_worker=1,  # a run holds the GIL: parallel runs need processes
                    processes=True,
                    host="127.0.0.1",
                    # Every failure reaches its run's row (the exception, or the worker's death): the logs
                    # would only add the noise of a close that stops running tasks (Ctrl-C).
                    silence_logs=logging.CRITICAL,
                    dashboard_address="127.0.0.1:8787" if dashboard else None,  # taken: Dask picks another port
                    # K single-threaded processes fill the cores already; a rayon pool in each would oversubscribe them.
                    env={"RAYON_NUM_THREADS": os.environ.get("RAYON_NUM_THREADS", "1")},
                )
            stack.enter_context(cluster)
            client = stack.enter_context(Client(cluster))
            if dashboard:
                print(f"dashboard: {cluster.dashboard_link}", file=sys.stderr)
        else:
            try:
                client = stack.enter_context(Client(scheduler, timeout="10s"))
            except OSError as err:
                raise ValueError(f"scheduler: cannot reach {scheduler}: {err}") from None
        futures = {client.submit(run_task, source, task, logs, pure=False): task for task in tasks}
        bar = stack.enter_context(
            tqdm(total=len(tasks), unit="run", file=sys.stderr, disable=None if progress else True, dynamic_ncols=True)
        )
        for future in as_completed(futures):
            if future.status == "finished":
                row = future.result()
            else:  # the worker died (or the task was lost): the run's row says so
                error = future.exception()
                row = {**futures[future].inputs(), "error": f"{type(error).__name__}: {error}"}
            record(row)
            future.release()
            bar.update()


@contextlib.contextmanager
def _ignoring_ctrl_c() -> Iterator[None]:
    """Start processes that ignore Ctrl-C (they inherit it), so that only this process handles it.

    A terminal's Ctrl-C reaches every process of its group: the workers would die on their own,
    with tracebacks, while the client closes them in order.
    """
    if threading.current_thread() is not threading.main_thread():  # only the main thread sets handlers
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _source(experiment: type[Experiment] | Experiment | str) -> tuple[str | type[Experiment], type[Experiment], Row]:
    """What the workers resolve, the class, and the base parameter values (an instance's)."""
    base: Row = {}
    if isinstance(experiment, Experiment):
        base, experiment = experiment.params, type(experiment)
    if isinstance(experiment, str):
        cls = find(experiment)  # an unknown name or a broken file fails here, not on every worker
        return (str(Path(experiment).resolve()) if experiment.endswith(".py") else experiment), cls, base
    if not (isinstance(experiment, type) and issubclass(experiment, Experiment)):
        raise TypeError(f"sweep() takes an Experiment subclass, instance, name or .py path, got {experiment!r}")
    if EXPERIMENTS.get(experiment.name) is experiment:
        return experiment.name, experiment, base
    path = source_file(experiment)
    if path is not None:  # load_file's modules: not importable by name
        return path, experiment, base
    return experiment, experiment, base  # importable, or from __main__ (cloudpickle sends it by value)


def _counts(values: int | Iterable[int], name: str, least: int) -> list[int]:
    return [_count(value, name, least) for value in _values(values, name)]


def _values(values: Any, name: str) -> list[Any]:
    listed = [values] if isinstance(values, (str, bytes)) or not isinstance(values, Iterable) else list(values)
    if not listed:
        raise ValueError(f"{name} has no values")
    return listed


def _flatten(data: Mapping[str, Any], prefix: str) -> Row:
    flat: Row = {}
    for key, value in data.items():
        if isinstance(value, Mapping):
            flat.update(_flatten(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value.item() if isinstance(value, np.generic) else value
    return flat
