"""Rerun recordings of a run: robots, headings, velocities, goals, obstacles, faults and measures,
to look at in the Rerun viewer (native or web).

``dream.run(..., rerun=TARGET)`` (``dream run ... --rerun [FILE.rrd]`` or ``--rerun-serve``)
records the run as it steps, every ``log_every``-th step; :func:`from_log` (``dream view``) turns
a trajectory log (:mod:`dream.trajectory_log`) into one. ``TARGET`` is:

- a path ending in ``.rrd``: a file, written beside its path and renamed there when the run ends
  (a run that fails leaves none);
- ``"spawn"``: a native viewer, spawned, that shows the run live;
- ``"serve"``: a web viewer served on 127.0.0.1 only (reach a remote machine through an SSH
  tunnel): a ``rerun`` server process that outlives the run, until :func:`wait_served` returns
  or the process ends.

The entities: ``arena`` (its border), ``robots`` (points, with a class per fault status: ok,
byzantine, stuck, crashed, coloured as in :mod:`dream.viz`), ``robots/heading`` and
``robots/velocity`` (arrows: the heading, one robot radius long, and the velocity carried out
over one second), ``goals``, ``obstacles``, the links and cell of the focus robot (robot 0) when
the experiment's frame has them (``focus/links``, ``focus/cell``), for a
:class:`~dream.swarm.SwarmRobot` what the focus robot read and heard at its last decision
(``focus/seen``: where it saw the others; ``focus/heard``: lines to the senders of its inbox;
``focus/inbox``: its messages as a table), and ``measures/<name>``
(time series: the experiment's measures, and ``messages/sent``, ``heard`` and ``lost``: the
whole swarm's so far). Two timelines: ``step`` and ``time`` (s).

The robots' columns go out in batches of many steps (``send_columns``): one call per entity for
up to :data:`BATCH_POINTS` robot positions, so that 100,000 robots cost a few calls a step.
Rerun is an optional dependency: ``pip install "dream-robotics[rerun]"``.
"""

from __future__ import annotations

import atexit
import os
import re
import shutil
import socket
import subprocess
import sys
import time
from collections.abc import Iterator, Mapping
from contextlib import ExitStack
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np

from dream._files import check_writable, replaced_path
from dream.frames import STATUSES
from dream.specs import GRITSBOT, ArenaSpec
from dream.trajectory_log import MESSAGE_COLUMNS, step_columns, traffic_of

if TYPE_CHECKING:
    from dream.backends.base import Backend
    from dream.experiments.stepper import Stepper

#: Robot positions kept before the robots' columns are sent (also sent every :data:`BATCH_SECONDS`).
BATCH_POINTS = 1 << 20
BATCH_SECONDS = 0.5
#: The colour of each of :data:`dream.frames.STATUSES` (those of :mod:`dream.viz`; ok: its blue).
STATUS_COLOURS = ((31, 119, 180), (214, 39, 40), (255, 127, 14), (184, 184, 184))
#: The robot the focus entities follow.
FOCUS = 0
#: The ports a served viewer tries first (gRPC for the data, HTTP for the web viewer).
GRPC_PORT, WEB_PORT = 9876, 9090

_served: list[subprocess.Popen[bytes]] = []  # servers started by "serve", ended with the process


def rerun_module() -> Any:
    """The ``rerun`` module, or an ImportError that says how to install it."""
    try:
        import rerun
    except ImportError as err:
        raise ImportError(
            'Rerun recordings need the rerun-sdk package: pip install "dream-robotics[rerun]" (Python >= 3.11)'
        ) from err
    return rerun


def check_target(target: str | os.PathLike[str]) -> None:
    """Refuse, before a run, a recording target that is neither ``"spawn"``, ``"serve"`` nor a
    writable ``.rrd`` path (``ValueError``), or Rerun missing (``ImportError``)."""
    rerun_module()
    if target in ("spawn", "serve"):
        return
    if Path(target).suffix != ".rrd":
        raise ValueError(f'rerun {target}: give a file name ending in .rrd, "spawn" or "serve"')
    check_writable(target, "rerun")


class Recording:
    """One recording being made: its sink (see the module docs) and the robots' columns of the
    steps not sent yet. A context manager: the sink closes when the block ends, and a file is
    kept only if the block ends without an error."""

    def __init__(
        self, target: str | os.PathLike[str], name: str, arena: ArenaSpec, radius: float, inbox: bool = False
    ) -> None:
        check_target(target)
        self.target, self.name, self.arena, self.radius, self.inbox = target, name, arena, radius, inbox
        self._kept: list[dict[str, np.ndarray]] = []
        self._points = 0
        self._sent_at = time.monotonic()
        self._scalars: dict[str, tuple[list[int], list[float], list[float]]] = {}
        self._outputs = ExitStack()

    def __enter__(self) -> Recording:
        rr = rerun_module()
        self.rr = rr
        self.stream = rr.RecordingStream("dream-" + re.sub(r"[^A-Za-z0-9_-]", "-", self.name))
        layout = self._layout()
        if self.target == "spawn":
            self.stream.spawn(default_blueprint=layout)
        elif self.target == "serve":
            self.stream.connect_grpc(_serve(), default_blueprint=layout)
        else:
            self.stream.save(self._outputs.enter_context(replaced_path(self.target)), default_blueprint=layout)
        self._static()
        return self

    def _layout(self) -> Any:
        """The viewer's default layout: the arena large, the measures (and the focus robot's inbox,
        ``inbox``) beside it."""
        import rerun.blueprint as rrb

        side: list[Any] = [rrb.TimeSeriesView(origin="/measures", name="measures")]
        if self.inbox:
            side.append(rrb.TextDocumentView(origin="/focus/inbox", name=f"robot {FOCUS}'s inbox"))
        arena = rrb.Spatial2DView(origin="/", contents=["+ /**", "- /measures/**"], name=self.name)
        return rrb.Blueprint(rrb.Horizontal(arena, rrb.Vertical(*side), column_shares=[3, 1]))

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        try:
            if kind is None:
                self.flush()
            self.stream.flush()
            self.stream.disconnect()  # the file is whole before it is renamed
        except BaseException as failed:
            self._outputs.__exit__(type(failed), failed, failed.__traceback__)
            raise
        self._outputs.__exit__(kind, error, trace)

    def _static(self) -> None:
        """What never changes: the fault classes, the robots' size, the arena's border."""
        rr, a = self.rr, self.arena
        classes = [(k, status, colour) for k, (status, colour) in enumerate(zip(STATUSES, STATUS_COLOURS))]
        self.stream.log("/", rr.AnnotationContext(classes), static=True)
        self.stream.log("robots", rr.Points2D.from_fields(radii=self.radius), static=True)
        border = [[a.xmin, a.ymin], [a.xmax, a.ymin], [a.xmax, a.ymax], [a.xmin, a.ymax], [a.xmin, a.ymin]]
        self.stream.log("arena", rr.LineStrips2D([border], colors=[(90, 90, 90)]), static=True)

    def add(
        self, step: int, seconds: float, columns: Mapping[str, np.ndarray], goals: np.ndarray | None = None
    ) -> None:
        """Keep one step's robots (``columns``: x, y, theta, v, w and the fault flags, as a
        trajectory log's, each ``(n,)``; ``goals`` ``(n, 2)``, NaN rows for none), sent in a batch."""
        x, y, theta, v = columns["x"], columns["y"], columns["theta"], columns["v"]
        status = np.zeros(len(x), dtype=np.uint16)
        for k, name in enumerate(STATUSES[1:], start=1):  # the worst fault shows, as in frames.fault_status
            status[np.asarray(columns[name], dtype=bool)] = k
        kept = {
            "step": np.array([step]),
            "time": np.array([seconds]),
            "positions": np.column_stack((x, y)),
            "classes": status,
            "heading": self.radius * np.column_stack((np.cos(theta), np.sin(theta))),
            "velocity": np.column_stack((v * np.cos(theta), v * np.sin(theta))),
        }
        if goals is not None:
            kept["goals"] = goals[np.isfinite(goals).all(axis=1)]
        self._kept.append(kept)
        self._points += len(x)
        if self._points >= BATCH_POINTS or time.monotonic() - self._sent_at >= BATCH_SECONDS:
            self.flush()

    def scalars(self, step: int, seconds: float, values: Mapping[str, float]) -> None:
        """Keep one step's measures, sent as time series ``measures/<name>`` with the robots."""
        for name, value in values.items():
            steps, times, kept = self._scalars.setdefault(name, ([], [], []))
            steps.append(step)
            times.append(seconds)
            kept.append(float(value))

    def log(self, step: int, seconds: float, path: str, thing: Any) -> None:
        """Log one archetype at a step, now (the few things that are not per robot)."""
        self.stream.set_time("step", sequence=step)
        self.stream.set_time("time", duration=seconds)
        self.stream.log(path, thing)

    def flush(self) -> None:
        """Send the steps kept: each entity's columns in one call."""
        rr, kept = self.rr, self._kept
        self._sent_at = time.monotonic()
        if kept:
            steps, times = np.concatenate([k["step"] for k in kept]), np.concatenate([k["time"] for k in kept])
            indexes = [rr.TimeColumn("step", sequence=steps), rr.TimeColumn("time", duration=times)]
            lengths = [len(k["positions"]) for k in kept]
            whole = {
                key: np.concatenate([k[key] for k in kept]) for key in ("positions", "classes", "heading", "velocity")
            }
            send = self.stream.send_columns
            send(
                "robots",
                indexes,
                rr.Points2D.columns(positions=whole["positions"], class_ids=whole["classes"]).partition(lengths),
            )
            for arrow in ("heading", "velocity"):
                columns = rr.Arrows2D.columns(
                    origins=whole["positions"], vectors=whole[arrow], class_ids=whole["classes"]
                )
                send(f"robots/{arrow}", indexes, columns.partition(lengths))
            if "goals" in kept[0]:
                goals = [k["goals"] for k in kept]
                columns = rr.Points2D.columns(positions=np.concatenate(goals).reshape(-1, 2))
                send("goals", indexes, columns.partition([len(g) for g in goals]))
        for name, (steps_of, times_of, values) in self._scalars.items():
            indexes = [rr.TimeColumn("step", sequence=steps_of), rr.TimeColumn("time", duration=times_of)]
            path = "measures/" + "/".join(self.rr.escape_entity_path_part(part) for part in name.split("/"))
            self.stream.send_columns(path, indexes, rr.Scalars.columns(scalars=values))
        self._kept, self._points, self._scalars = [], 0, {}


class Recorder:
    """The recording of a run, driven by :func:`dream.run` (``rerun=TARGET``): a context manager
    around the run; :meth:`see` before the first step and after every step.

    Parameters
    ----------
    target : path, "spawn" or "serve"
        See the module docs (checked now, before the run).
    every : int
        Record every ``every``-th step (and step 0, and the last).
    """

    def __init__(self, target: str | os.PathLike[str], every: int) -> None:
        check_target(target)
        self.target, self.every = target, every
        self._recording: Recording | None = None
        self._last = -1

    def __enter__(self) -> Recorder:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        if self._recording is not None:
            self._recording.__exit__(kind, error, trace)

    def see(self, step: int, stepper: Stepper, sim: Backend, poses: np.ndarray, last: bool = False) -> None:
        """Record step ``step`` (poses ``(3, n)``) if it is due (see :class:`~dream.experiments.runner.Watcher`)."""
        first = self._recording is None
        if step == self._last or not (step % self.every == 0 or last or first):
            return
        self._last = step
        exp = stepper.exp
        if self._recording is None:
            recording = Recording(self.target, exp.label(), exp.arena, GRITSBOT.radius, exp.engine is not None)
            self._recording = recording.__enter__()
            if exp.engine is not None:  # keep the focus robot's readings and inbox as it decides
                exp.engine.focus = FOCUS
        recording = self._recording
        frame = stepper.frame(step, poses)
        seconds = float(frame.time if frame.time is not None else step * sim.time_step)
        recording.add(step, seconds, step_columns(stepper, sim, step, poses), frame.goals)
        traffic = traffic_of(stepper)
        totals = {} if traffic is None else {f"messages/{k}": getattr(traffic, k).sum() for k in MESSAGE_COLUMNS}
        recording.scalars(step, seconds, {**_numbers(exp.measures()), **totals})
        rr = recording.rr
        if frame.obstacles:
            strips = [np.vstack((p, p[:1])) for p in frame.obstacles]
            recording.log(step, seconds, "obstacles", rr.LineStrips2D(strips, colors=[(64, 64, 64)]))
        if frame.links is not None and len(frame.links):
            links = frame.links[(frame.links == FOCUS).any(axis=1)]
            strips = [poses[:2, pair].T for pair in links]
            recording.log(step, seconds, "focus/links", rr.LineStrips2D(strips, colors=[(150, 150, 150)]))
        if len(frame.cells) > FOCUS:
            cell = frame.cells[FOCUS]
            recording.log(step, seconds, "focus/cell", rr.LineStrips2D([np.vstack((cell, cell[:1]))]))
        if exp.engine is not None and exp.engine.focus_view:
            _log_focus(recording, step, seconds, exp.engine.focus_view, poses)


#: The most inbox messages :func:`_log_focus` lists in its text.
LISTED = 20


def _log_focus(recording: Recording, step: int, seconds: float, view: Mapping[str, Any], poses: np.ndarray) -> None:
    """The focus robot's last decision (a swarm robot's): lines to the senders it heard, points
    where it saw the others, and its inbox as a text."""
    rr, me = recording.rr, poses[:2, FOCUS]
    heard, seen = view["heard"], view["seen"]
    senders = heard["sender"]
    lines = [np.vstack((me, poses[:2, sender])) for sender in senders]
    recording.log(step, seconds, "focus/heard", rr.LineStrips2D(lines, colors=[(44, 160, 44)]))
    if "dx" in seen:
        recording.log(step, seconds, "focus/seen", rr.Points2D(me + np.column_stack((seen["dx"], seen["dy"]))))
    fields = [name for name in heard if name != "sender"]
    rows = [
        f"| {sender} | " + " | ".join(f"{heard[name][k]:.4g}" for name in fields) + " |"
        for k, sender in enumerate(senders[:LISTED])
    ]
    text = "\n".join(
        [
            f"Robot {FOCUS} at its decision of step {view['step']}: saw {len(seen.get('distance', []))} robots, "
            f"heard {len(senders)} messages" + (f" (the first {LISTED}):" if len(senders) > LISTED else ":"),
            "",
            "| sender | " + " | ".join(fields) + " |",
            "|---" * (len(fields) + 1) + "|",
            *rows,
        ]
    )
    recording.log(step, seconds, "focus/inbox", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN))


def from_log(path: str | os.PathLike[str], target: str | os.PathLike[str]) -> int:
    """Turn the trajectory log at ``path`` into a recording at ``target`` (see the module docs);
    returns the number of steps recorded. Besides the robots, the time series are the swarm's
    messages so far (``messages/sent``, ...), its faulty robots (``faults/crashed``, ...) and
    the mean of each per-robot measure (``mean/<name>``) at each logged step.

    Raises
    ------
    ValueError
        ``path`` is not a DREAM trajectory log, or ``target`` is not a recording target.
    """
    import pyarrow.parquet as pq

    from dream.trajectory_log import BASE_COLUMNS, read_metadata

    meta = read_metadata(path)
    names = pq.read_schema(path).names
    missing = [c for c in BASE_COLUMNS if c not in names]
    if missing or "experiment" not in meta:
        raise ValueError(f"{path}: not a DREAM trajectory log (no {', '.join(missing) or 'run metadata'})")
    arena = ArenaSpec(**meta["arena"])
    steps = 0
    with Recording(target, meta["experiment"], arena, GRITSBOT.radius) as recording:
        for step, columns in _steps(pq.ParquetFile(path)):
            seconds = float(columns["time"][0])
            recording.add(step, seconds, columns)
            summary = {f"faults/{name}": columns[name].sum() for name in STATUSES[1:]}
            summary.update({f"messages/{c}": columns[c].sum() for c in MESSAGE_COLUMNS if c in columns})
            summary.update(
                {f"mean/{c}": columns[c].mean() for c in names if c not in (*BASE_COLUMNS, *MESSAGE_COLUMNS)}
            )
            recording.scalars(step, seconds, summary)
            steps += 1
    return steps


def _steps(log: Any) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
    """Each step of a trajectory log with its columns, one row group read at a time."""
    for group in range(log.num_row_groups):
        table = log.read_row_group(group)
        columns = {name: table.column(name).to_numpy() for name in table.column_names}
        step = columns["step"]
        bounds = np.flatnonzero(np.diff(step)) + 1
        for rows in np.split(np.arange(len(step)), bounds):
            if len(rows):
                yield int(step[rows[0]]), {name: values[rows] for name, values in columns.items()}


def _numbers(measures: Mapping[str, Any], prefix: str = "") -> dict[str, float]:
    """The measures that are numbers (nested ones as ``outer.inner``; booleans as 0 and 1)."""
    found: dict[str, float] = {}
    for key, value in measures.items():
        if isinstance(value, Mapping):
            found.update(_numbers(value, f"{prefix}{key}."))
        elif isinstance(value, (bool, int, float, np.bool_, np.integer, np.floating)):
            found[f"{prefix}{key}"] = float(value)
    return found


def _serve() -> str:
    """Start a ``rerun`` server on 127.0.0.1 with a web viewer; returns the gRPC address to send
    to. The web viewer's address is printed (stderr)."""
    grpc, web = _free_port(GRPC_PORT), _free_port(WEB_PORT)
    command = [_viewer(), "--serve-web", "--bind", "127.0.0.1", "--port", str(grpc), "--web-viewer-port", str(web)]
    server = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
    _served.append(server)
    if len(_served) == 1:
        atexit.register(_stop_served)
    address = f"rerun+http://127.0.0.1:{grpc}/proxy"
    _wait_listening(grpc, server)
    print(f"Rerun web viewer: http://127.0.0.1:{web}/?url={address}", file=sys.stderr)
    return address


def _viewer() -> str:
    """The ``rerun`` binary of the installed SDK (not a wrapper script: stopping the server must
    stop the process that listens)."""
    import rerun_cli

    binary = Path(rerun_cli.__file__).parent / ("rerun.exe" if sys.platform == "win32" else "rerun")
    return str(binary) if binary.exists() else shutil.which("rerun") or "rerun"


def wait_served() -> None:
    """Keep the web viewers this process serves until Ctrl-C (for a command that ends after its
    run: the viewers die with the process)."""
    if not _served:
        return
    print("Serving the recording; Ctrl-C to stop.", file=sys.stderr)
    try:
        for server in _served:
            server.wait()
    except KeyboardInterrupt:
        pass
    finally:
        _stop_served()


def _stop_served() -> None:
    while _served:
        server = _served.pop()
        server.terminate()
        server.wait(timeout=10)


def _free_port(preferred: int) -> int:
    """``preferred`` if nothing listens there on 127.0.0.1, else a port the system picks."""
    for port in (preferred, 0):
        with socket.socket() as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return int(probe.getsockname()[1])
    raise OSError("no free port on 127.0.0.1 for the Rerun server")


def _wait_listening(port: int, server: subprocess.Popen[bytes], seconds: float = 30.0) -> None:
    """Wait until the server accepts connections on ``port`` (it takes a moment to start)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if server.poll() is not None:
            raise OSError(f"the Rerun server stopped as it started (exit status {server.returncode})")
        with socket.socket() as probe:
            if probe.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise OSError(f"the Rerun server did not listen on 127.0.0.1:{port} within {seconds:.0f} s")
