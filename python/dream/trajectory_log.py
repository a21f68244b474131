"""The trajectory log: a run as a tidy Parquet table, one row per robot and logged step.

``dream.run(..., log="run.parquet", log_every=K)`` (``dream run ... --log run.parquet
--log-every K``) logs step 0 and every K-th step after it, and the step the run ends at. The
columns, in this order:

- ``step`` (int64), ``time`` (float64, s), ``robot`` (int64, the robot's id);
- ``x``, ``y``, ``theta`` (m, m, rad): the pose after that step;
- ``v``, ``w`` (m/s, rad/s): the velocities the simulator carried out in the step that brought the
  robot there (0 at step 0);
- ``crashed``, ``stuck``, ``byzantine`` (bool): the robot's faults so far;
- ``sent``, ``heard``, ``lost`` (int64): its radio messages so far (:mod:`dream.traffic`), where
  the run knows them (robot objects, or a :class:`~dream.swarm.SwarmRobot`; a hand-written
  swarm mode has no radios and no such columns);
- then the experiment's per-robot measures (:meth:`~dream.Experiment.robot_measures`), one
  column each.

The rows go out in row groups of at least :data:`ROW_GROUP_ROWS` rows (a step's rows never
split), so memory stays flat however long the run. The run's metadata (experiment, n, seed,
params, faults, version, backend, swarm, log_every, time_step, arena) is in the schema's
metadata, each value JSON (:func:`read_metadata`). The file is written beside its path and
renamed there when the run ends (:func:`dream._files.replaced`): a run that fails leaves no
file, one stopped by a signal leaves the steps it ran.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np

from dream._files import check_writable, replaced

if TYPE_CHECKING:
    import pyarrow as pa

    from dream.backends.base import Backend
    from dream.experiments.stepper import Stepper
    from dream.traffic import Traffic

#: Rows gathered before a row group is written (a step with more robots makes a group alone).
ROW_GROUP_ROWS = 1 << 17

#: The columns every log has, before the message counts and the experiment's measures.
BASE_COLUMNS = ("step", "time", "robot", "x", "y", "theta", "v", "w", "crashed", "stuck", "byzantine")
MESSAGE_COLUMNS = ("sent", "heard", "lost")


def traffic_of(stepper: Stepper) -> Traffic | None:
    """The message counts of the run ``stepper`` drives: its engine's, else its world's (``None``
    for a hand-written swarm mode, whose robots have no radios)."""
    engine = stepper.exp.engine
    return engine.traffic if engine is not None else stepper.world.traffic


def step_columns(stepper: Stepper, sim: Backend, step: int, poses: np.ndarray) -> dict[str, np.ndarray]:
    """One logged step's columns (see the module docs), each ``(n,)``, owned by the caller.

    Raises
    ------
    ValueError
        The experiment's :meth:`~dream.Experiment.robot_measures` gave a value that is not one
        number per robot, or named a column the log has already.
    """
    exp, state = stepper.exp, stepper.state
    n = exp.n
    nobody = np.zeros(n, dtype=bool)
    columns: dict[str, np.ndarray] = {
        "step": np.full(n, step, dtype=np.int64),
        "time": np.full(n, step * sim.time_step),
        "robot": np.arange(n, dtype=np.int64),
        "x": poses[0].copy(),
        "y": poses[1].copy(),
        "theta": poses[2].copy(),
        "v": sim.velocities[0].copy(),
        "w": sim.velocities[1].copy(),
        "crashed": nobody if state is None else state.crashed.copy(),
        "stuck": nobody if state is None else state.stuck.copy(),
        "byzantine": nobody if state is None else state.byzantine.copy(),
    }
    traffic = traffic_of(stepper)
    if traffic is not None:
        columns.update(sent=traffic.sent.copy(), heard=traffic.heard.copy(), lost=traffic.lost.copy())
    for name, values in exp.robot_measures().items():
        array = np.array(values)
        if name in columns:
            raise ValueError(f"{exp.label()}.robot_measures() names {name!r}, a column the trajectory log has already")
        if array.shape != (n,) or array.dtype.kind not in "biuf":
            raise ValueError(
                f"{exp.label()}.robot_measures()[{name!r}] must be one number per robot, shape ({n},), "
                f"got {array.dtype} of shape {array.shape}"
            )
        columns[name] = array
    return columns


def run_metadata(stepper: Stepper, sim: Backend, every: int) -> dict[str, Any]:
    """What the log's schema metadata says of the run (JSON-ready values)."""
    from dream._version import version

    exp = stepper.exp
    return {
        "experiment": exp.label(),
        "n": exp.n,
        "seed": stepper.world.seed or 0,
        "params": exp.params,
        "faults": {} if stepper.state is None else stepper.state.faults.to_dict(),
        "version": version(),
        "backend": sim.name,
        "swarm": stepper.swarm,
        "log_every": every,
        "time_step": sim.time_step,
        "arena": asdict(exp.arena),
    }


def read_metadata(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The run's metadata from the schema of the log at ``path`` (see the module docs)."""
    import pyarrow.parquet as pq

    raw = pq.read_schema(path).metadata or {}
    return {key.decode(): json.loads(value) for key, value in raw.items() if not key.startswith(b"ARROW:")}


class TrajectoryLog:
    """The writer of one run's log (see the module docs), driven by :func:`dream.run`: used as a
    context manager around the run; :meth:`see` before the first step and after every step.

    Parameters
    ----------
    path : path
        The ``.parquet`` file to write (checked writable now, before the run).
    every : int
        Log every ``every``-th step (and step 0, and the last).

    Raises
    ------
    ValueError
        ``path`` cannot be written (see :func:`dream._files.check_writable`).
    """

    def __init__(self, path: str | os.PathLike[str], every: int) -> None:
        check_writable(path, "log")
        self.path, self.every = path, every
        self.rows = 0  #: rows written so far
        self._last = -1  # the step logged last
        self._kept: list[dict[str, np.ndarray]] = []
        self._kept_rows = 0
        self._writer: Any = None
        self._schema: pa.Schema | None = None

    def __enter__(self) -> TrajectoryLog:
        self._file = replaced(self.path, "wb")
        self._out = self._file.__enter__()
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        try:
            if kind is None:
                self._flush()
                self._writer.close()
        except BaseException as failed:
            self._file.__exit__(type(failed), failed, failed.__traceback__)
            raise
        self._file.__exit__(kind, error, trace)

    def see(self, step: int, stepper: Stepper, sim: Backend, poses: np.ndarray, last: bool = False) -> None:
        """Log step ``step`` (poses ``(3, n)``) if it is due, or ``last`` (the run's end) and not
        logged yet. The first step seen is always logged."""
        if step == self._last or not (step % self.every == 0 or last or self._schema is None):
            return
        self._last = step
        columns = step_columns(stepper, sim, step, poses)
        if self._schema is None:
            self._schema = self._schema_of(columns, run_metadata(stepper, sim, self.every))
        elif list(columns) != self._schema.names:
            raise ValueError(
                f"{stepper.exp.label()}: the trajectory log's columns changed at step {step}: "
                f"{', '.join(columns)} instead of {', '.join(self._schema.names)} (robot_measures() must name "
                "the same measures at every step)"
            )
        self._kept.append(columns)
        self._kept_rows += stepper.exp.n
        if self._kept_rows >= ROW_GROUP_ROWS:
            self._flush()

    @staticmethod
    def _schema_of(columns: dict[str, np.ndarray], metadata: dict[str, Any]) -> pa.Schema:
        import pyarrow as pa

        fields = [pa.field(name, pa.from_numpy_dtype(values.dtype)) for name, values in columns.items()]
        encoded = {key: json.dumps(value, default=str) for key, value in metadata.items()}
        return pa.schema(fields, metadata=encoded)

    def _flush(self) -> None:
        """Write the kept steps as one row group."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        if not self._kept or self._schema is None:
            return
        if self._writer is None:
            # A dictionary only where values repeat: tried on every float column, it cost 5x the write.
            self._writer = pq.ParquetWriter(self._out, self._schema, use_dictionary=["step", "time"])
        arrays = [np.concatenate([step[name] for step in self._kept]) for name in self._schema.names]
        self._writer.write_table(pa.Table.from_arrays(arrays, schema=self._schema), row_group_size=self._kept_rows)
        self.rows += self._kept_rows
        self._kept, self._kept_rows = [], 0
