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
import csv
import fcntl
import io
import itertools
import logging
import os
import signal
import stat
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from dream._files import check_writable, replaced
from dream.backends import BACKENDS
from dream.backends.robotarium import MAX_ROBOTS
from dream.experiments import EXPERIMENTS, Experiment, find, run
from dream.experiments.files import source_digest, source_file
from dream.experiments.runner import _count
from dream.faults import Faults

#: Input columns of every row, before one ``params.NAME`` column per declared parameter.
INPUTS = ("experiment", "source_digest", "n", "seed", "backend", "swarm", "step_cap")
#: Metric columns of every row (``simulator``: the backend that ran, when ``backend`` is "auto").
METRICS = ("simulator", "steps", "completed_step", "collisions", "boundary", "actuator", "success")
#: Last columns: one ``measures.NAME`` column per measure comes before them.
TAIL = ("wall_time", "worker", "error")

Row = dict[str, Any]


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
        not parse (naming the file and line), or a CSV another sweep is writing; before any run.
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
    sweep_plan = plan(experiment, seeds, n, params, backend, steps, faults, swarm)
    with Table(out, sweep_plan) as table:
        todo = [task for task in sweep_plan.tasks if task.key() not in table.done]
        if todo:
            _execute(sweep_plan.source, todo, workers, scheduler, progress, dashboard, table.add)
        rows = [table.done[task.key()] for task in sweep_plan.tasks]
    # The same columns in every row (a run that raised has no metrics; the file may hold other sweeps' columns).
    found = (column for row in rows for column, value in row.items() if value is not None)
    columns = _ordered([*INPUTS, *sweep_plan.inputs, *METRICS, *found, *TAIL])
    rows = [{column: row.get(column) for column in columns} for row in rows]
    if plot is not None:
        from dream.sweep_plot import plot_sweep  # matplotlib only when drawing

        plot_sweep(rows, sweep_plan.swept, plot)
    return SweepRows(rows, len(todo), len(sweep_plan.tasks) - len(todo))


def run_task(source: str | type[Experiment], task: Task) -> Row:
    """Run one task (on a Dask worker): its row, with the error instead of metrics if it raised."""
    from distributed import get_worker

    start = time.perf_counter()
    row = task.inputs()
    try:
        with _ONE_RUN_AT_A_TIME:
            cls = find(source) if isinstance(source, str) else source
            result = run(
                cls, n=task.n, seed=task.seed, backend=task.backend, steps=task.step_cap,
                faults=task.fault_model(), swarm=task.swarm, **dict(task.params),
            )  # fmt: skip
        data = result.to_dict()
        row.update({"simulator": data["backend"], **{key: data[key] for key in METRICS[1:]}})
        row.update(_flatten(data["measures"], "measures."))
        row["error"] = None
    except Exception as err:  # noqa: BLE001 -- the experiment's code, whatever it raised: a row, not a lost sweep
        row["error"] = f"{type(err).__name__}: {err}"
    row["wall_time"] = time.perf_counter() - start
    row["worker"] = get_worker().address
    return row


class Table:
    """The rows of a sweep: those already in the CSV ``path`` (if any) and those added as runs finish.

    Entering the table locks the CSV for this sweep (:func:`_locked`) and reads it
    (:meth:`_read`, which refuses a row that does not parse). The first row added rewrites the file
    (header for this sweep's columns, failed runs of this sweep dropped since they run again), so
    a sweep that runs nothing leaves it as it was; then each row is appended and flushed, and the
    file is rewritten only when a row brings a new column.
    """

    def __init__(self, path: str | Path | None, sweep_plan: Plan) -> None:
        self.path = None if path is None else Path(path)
        self.plan = sweep_plan
        self.inputs = sweep_plan.inputs
        self.rows: list[Row] = []  # what the file holds: rows read (as text) and rows added
        self.done: dict[tuple[str, ...], Row] = {}  # finished runs by their inputs, as Python values
        self.columns = _ordered([*INPUTS, *self.inputs, *METRICS, *TAIL])
        self._file: Any = None
        self._lock: Any = None

    def __enter__(self) -> Table:
        if self.path is not None:
            self._lock = _locked(self.path)
            try:
                self._read(self.path)
            except BaseException:
                self._lock.close()
                raise
        return self

    def __exit__(self, *exc: object) -> None:
        if self._file is not None:
            self._file.close()
        if self._lock is not None:
            self._lock.close()  # releases the lock

    def _read(self, path: Path) -> None:
        """Take in the rows of the CSV at ``path``, if it holds any.

        A last row without its line end was cut short (a sweep stopped while writing it): it is
        dropped with a warning naming the file and line, and its run is done again. Any other row
        that does not parse (:func:`_row_problem`) stops the sweep before any run, naming the file
        and line: dropping it would lose it from the file at the first rewrite.
        """
        if not (path.is_file() and path.stat().st_size):
            return
        data = path.read_bytes()
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as err:
            line = data[: err.start].count(b"\n") + 1
            raise ValueError(
                f"out: {path}:{line}: not UTF-8 text (byte {err.start}); mend or delete the line"
            ) from None
        records = _records(text)
        last_line = len(io.StringIO(text, newline="").readlines())
        if len(records) > 1 and not text.endswith(("\n", "\r")) and records[-1][0] == last_line:
            line = records.pop()[0]
            warnings.warn(
                f"out: {path}:{line}: the last row is cut short (a sweep stopped while writing it): "
                "dropped, and its run is done again",
                RuntimeWarning,
                stacklevel=4,  # sweep()'s caller
            )
        (_, header), *rows = records
        if isinstance(header, csv.Error):
            raise ValueError(f"out: {path}:1: not a CSV header ({header})")
        repeated = [column for column in set(header) if header.count(column) > 1]
        if repeated:
            raise ValueError(f"out: {path}:1: the column {repeated[0]!r} comes twice; mend or delete the line")
        missing = [column for column in INPUTS if column not in header and column not in ("swarm", "source_digest")]
        if missing:
            raise ValueError(f"out: {path} is not a sweep table (no column {missing[0]!r})")
        ours = {task.key() for task in self.plan.tasks}
        digest = self.plan.tasks[0].source_digest
        at = self.inputs.index("source_digest")
        stale = 0  # rows of this sweep's runs from other code (or unknown code): they run again
        for line, fields in rows:
            if fields == []:
                continue  # a blank line
            problem = _row_problem(fields, header)
            if problem:
                raise ValueError(f"out: {path}:{line}: {problem}; mend or delete the line (a sweep would lose it)")
            row = dict(zip(header, fields))  # type: ignore[arg-type]  # a list once _row_problem passes it
            row.setdefault("swarm", "False")  # a table from before sweeps had --swarm: robot by robot
            row.setdefault("source_digest", "")  # from before sweeps recorded it: unknown code
            key = self._key(row)
            if (*key[:at], digest, *key[at + 1 :]) in ours and not (digest and row["source_digest"] == digest):
                stale += not row.get("error")
                continue  # its run is done again with the current code: the new row replaces it
            if not row.get("error"):
                # A digest of decimal digits only would read back as a number.
                self.done[key] = {
                    column: cell if column == "source_digest" else _value(cell) for column, cell in row.items()
                }
            elif key in ours:
                continue  # a failed run of this sweep runs again: its old row goes
            self.rows.append(row)
        self.columns = _ordered([*header, *self.columns])
        if stale:
            why = (
                "come from a table written before sweeps recorded the experiment's code (no source_digest column)"
                if "source_digest" not in header
                else f"come from other code of {self.plan.tasks[0].experiment} (another source_digest)"
            )
            warnings.warn(f"out: {path}: {stale} rows of this sweep {why}: run again", RuntimeWarning, stacklevel=4)

    def add(self, row: Row) -> None:
        self.rows.append(row)
        self.done[self._key(row)] = row  # an error row too: it is this sweep's answer for that task
        if self.path is None:
            return
        if self._file is None or set(row) - set(self.columns):
            self.columns = _ordered([*self.columns, *row])
            self._rewrite()
        else:
            csv.DictWriter(self._file, self.columns).writerow({k: _cell(v) for k, v in row.items()})
            self._file.flush()

    def _key(self, row: Row) -> tuple[str, ...]:
        return tuple(_cell(row.get(column)) for column in self.inputs)

    def _rewrite(self) -> None:
        """Write every row, whole or not at all: a temporary file renamed over the CSV."""
        if self.path is None:
            return
        if self._file is not None:
            self._file.close()
        with replaced(self.path, newline="", encoding="utf-8") as tmp:
            writer = csv.DictWriter(tmp, self.columns)
            writer.writeheader()
            writer.writerows({k: _cell(v) for k, v in row.items()} for row in self.rows)
        self._file = self.path.open("a", newline="", encoding="utf-8")


def _locked(path: Path) -> IO[bytes]:
    """An exclusive lock on ``NAME.lock`` beside the CSV ``path``, held until the returned file is
    closed: a second sweep on the same file would otherwise rewrite it without the first one's
    rows. The lock file is left in place (empty); removing it could let two sweeps lock two files.

    Raises
    ------
    ValueError
        Another sweep holds the lock, or the lock's path is not a regular file.
    """
    lock = path.with_name(f"{path.name}.lock")
    try:
        handle = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK, 0o666)
    except OSError as err:
        raise ValueError(f"out: cannot open the lock {lock}: {err.strerror}") from None
    file = os.fdopen(handle, "rb")
    try:
        if not stat.S_ISREG(os.fstat(handle).st_mode):
            raise ValueError(f"out: the lock {lock} is not a regular file")
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        file.close()
        raise ValueError(f"out: {path} is in use by another sweep (it holds {lock.name}); let it finish") from None
    except BaseException:
        file.close()
        raise
    return file


def _records(text: str) -> list[tuple[int, list[str] | csv.Error]]:
    """The records of CSV ``text``, each with the line it starts on; parsing stops at the first
    malformed one, which is a :class:`csv.Error` in the list."""
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    records: list[tuple[int, list[str] | csv.Error]] = []
    line = 1
    try:
        for fields in reader:
            records.append((line, fields))
            line = reader.line_num + 1
    except csv.Error as err:
        records.append((line, err))
    return records


#: Columns whose cells hold a whole number, a boolean or a number (an empty cell: no value).
_KINDS = {
    **dict.fromkeys(("n", "seed", "step_cap", "steps", "completed_step", "collisions", "boundary", "actuator"), int),
    **dict.fromkeys(("swarm", "success"), bool),
    "wall_time": float,
}
_KIND_NAMES = {int: "a whole number", bool: "True or False", float: "a number"}


def _row_problem(fields: list[str] | csv.Error, header: list[str]) -> str | None:
    """What keeps a CSV record from being a row of a sweep table with ``header``, or ``None``: not
    CSV, a wrong number of fields, a missing input, a cell that does not parse as its column's
    kind, or neither a result (``success``) nor an ``error``."""
    if isinstance(fields, csv.Error):
        return f"not a CSV row ({fields})"
    if len(fields) != len(header):
        return f"{len(fields)} fields, the header has {len(header)}"
    row = dict(zip(header, fields))
    for column in ("experiment", "n", "seed", "backend"):
        if not row.get(column):
            return f"no {column}"
    for column, kind in _KINDS.items():
        text = row.get(column)
        found = type(_value(text))
        if text and not (found is kind or (kind is float and found is int)):
            return f"{column} {text!r} is not {_KIND_NAMES[kind]}"
    if not row.get("error") and row.get("success") not in ("True", "False"):
        return "neither a result (success) nor an error"
    return None


def _execute(
    source: str | type[Experiment],
    tasks: Sequence[Task],
    workers: int | None,
    scheduler: str | None,
    progress: bool,
    dashboard: bool,
    record: Callable[[Row], None],
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
        futures = {client.submit(run_task, source, task, pure=False): task for task in tasks}
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


def _ordered(columns: Iterable[str]) -> list[str]:
    """Inputs, parameters and faults, metrics, measures, then wall time, worker and error (first seen
    first in a group)."""
    fixed = {column: rank for rank, group in enumerate((INPUTS, (), METRICS, (), TAIL)) for column in group}

    def group(column: str) -> int:
        if column in fixed:
            return fixed[column]
        return 1 if column.startswith(("params.", "faults.")) else 3

    unique = list(dict.fromkeys(columns))
    return sorted(unique, key=lambda column: (group(column), unique.index(column)))


def _cell(value: Any) -> str:
    """A value as the CSV holds it (``None``: empty)."""
    return "" if value is None else str(value)


def _value(text: str | None) -> Any:
    """A CSV cell back as a Python value: empty is ``None``, then bool, int, float, else the text."""
    if text is None or text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text
