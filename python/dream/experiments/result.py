"""What an experiment run returns: its metrics, a printable summary and an optional trace."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from dream.backends import Backend


@dataclass
class ExperimentResult:
    """Metrics of one run.

    ``collisions``, ``boundary`` and ``actuator`` are the rps validation counts summed over the
    run (pair-iterations of robots within a diameter, robot-iterations outside the arena,
    iterations with a command beyond the wheel limit). ``completed_step`` is the step at which
    the experiment reached its goal (``None`` if it did not). ``measures`` holds the
    experiment's own figures; ``trace``, when recorded, the poses ``(steps + 1, 3, n)``.
    ``swarm`` says whether the run was in the experiment's swarm mode.
    """

    experiment: str
    n: int
    seed: int
    backend: str
    steps: int
    completed_step: int | None
    collisions: int
    boundary: int
    actuator: int
    wall_time: float
    measures: dict[str, Any] = field(default_factory=dict)
    trace: np.ndarray | None = field(default=None, repr=False)
    params: dict[str, Any] = field(default_factory=dict)
    interrupted: bool = False
    signal: int | None = field(default=None, repr=False)  #: the signal that interrupted the run
    faults: dict[str, Any] = field(default_factory=dict)
    rules: str = "rps0"  #: the rps generation whose rules counted the violations
    swarm: bool = False  #: run in swarm mode (the whole swarm decided each step in one call)

    @property
    def completed(self) -> bool:
        return self.completed_step is not None

    @property
    def success(self) -> bool:
        """Completed, with zero collisions, boundary and actuator violations (under faults, the
        experiment's ``done`` decides what completing means for the robots still correct)."""
        return self.completed and not (self.collisions or self.boundary or self.actuator)

    @property
    def steps_per_second(self) -> float:
        return self.steps / self.wall_time if self.wall_time > 0 else float("inf")

    @classmethod
    def from_backend(
        cls,
        experiment: str,
        seed: int,
        backend: Backend,
        completed_step: int | None,
        wall_time: float,
        measures: dict[str, Any],
        trace: np.ndarray | None = None,
        params: dict[str, Any] | None = None,
    ) -> ExperimentResult:
        b, c, a = backend.violations
        return cls(
            experiment,
            backend.number_of_robots,
            seed,
            backend.name,
            backend.iterations,
            completed_step,
            c,
            b,
            a,
            wall_time,
            measures,
            trace,
            dict(params or {}),
            rules=backend.spec.rules,
        )

    def to_dict(self) -> dict[str, Any]:
        """The metrics as plain JSON-ready values (without the trace)."""
        data = asdict(self)
        data.pop("trace")
        data.pop("signal")
        data["steps_per_second"] = self.steps_per_second
        data["completed"] = self.completed
        data["success"] = self.success
        return data

    def summary(self) -> str:
        """A two-column table of the metrics."""
        rows = [
            ("experiment", self.experiment),
            ("robots", self.n),
            ("seed", self.seed),
            ("backend", f"{self.backend} (rules {self.rules})"),
            *((("mode", "swarm (the robots deciding in a step decide in one call)"),) if self.swarm else ()),
            *((f"  {key}", value) for key, value in self.params.items()),
            ("steps run", self.steps),
            ("completed at step", "not completed" if self.completed_step is None else self.completed_step),
            ("collisions", self.collisions),
            ("boundary", self.boundary),
            ("actuator", self.actuator),
            ("success", "yes" if self.success else "no (interrupted)" if self.interrupted else "no"),
            *self.measures.items(),
            *_fault_rows(self.faults),
            ("wall time (s)", f"{self.wall_time:.2f}"),
            ("steps/s", f"{self.steps_per_second:.0f}"),
        ]
        width = max(len(name) for name, _ in rows)
        return "\n".join(
            f"{name:<{width}}  {value:.4g}" if isinstance(value, float) else f"{name:<{width}}  {value}"
            for name, value in rows
        )


def _fault_rows(faults: dict[str, Any]) -> list[tuple[str, Any]]:
    """Summary rows of a run's faults: settings, robot fault events by kind, lost messages."""
    if not faults:
        return []
    settings = ", ".join(f"{key}={value}" for key, value in faults["settings"].items())
    kinds: dict[str, int] = {}
    for event in faults["events"]:
        kinds[event["kind"]] = kinds.get(event["kind"], 0) + 1
    pending = ", ".join(f"{fault['kind']}@{fault['step']}" for fault in faults.get("pending", []))
    return [
        ("faults", settings),
        *((f"  {kind} robots", count) for kind, count in kinds.items()),
        *((("  never happened", pending),) if pending else ()),
        ("  messages lost", faults["messages_lost"]),
        ("  readings dropped", faults["readings_dropped"]),
    ]
