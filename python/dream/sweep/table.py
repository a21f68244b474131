"""The table of a sweep's rows: the CSV read back, checked, locked, and written row by row.

Its columns are the inputs of a run, its parameters and faults, the metrics of its result, its
measures, then its wall time, worker and error (:func:`_ordered`); the rules for a row read back
are in :meth:`Table._read` and :func:`_row_problem`.
"""

from __future__ import annotations

import csv
import fcntl
import io
import os
import stat
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from dream._files import replaced

if TYPE_CHECKING:
    from dream.sweep import Plan

#: Input columns of every row, before one ``params.NAME`` column per declared parameter.
INPUTS = ("experiment", "source_digest", "n", "seed", "backend", "swarm", "step_cap")
#: Metric columns of every row (``simulator``: the backend that ran, when ``backend`` is "auto").
METRICS = ("simulator", "steps", "completed_step", "collisions", "boundary", "actuator", "success")
#: Last columns: one ``measures.NAME`` column per measure comes before them.
TAIL = ("wall_time", "worker", "error")

Row = dict[str, Any]


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
