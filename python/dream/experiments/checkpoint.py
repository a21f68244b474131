"""Checkpoints: a long run written to a file as it goes, so that it can go on where it stopped.

A run of hours (hrvo-circle with 10,000 robots takes about a million steps) outlives a batch
job's time limit or a laptop's lid. With ``dream.run(..., checkpoint=PATH)`` the run's whole
state (the experiment and its robots, the world's clock, messages and random generator, the
simulator, the faults) is written to ``PATH`` every ``checkpoint_every`` steps and when a signal
stops it; :func:`dream.resume` (``dream resume PATH``) loads it and runs on. Since the random
generator is saved with the rest, the resumed run takes exactly the steps the uninterrupted run
would have.

A checkpoint is a pickle: load only checkpoints you wrote. Its header records the DREAM version
that wrote it and, for an experiment from a researcher's file, that file's path, which must still
hold the experiment when the run resumes (the run's state is saved, not its code).
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dream._files import replaced
from dream._version import version
from dream.experiments.files import ExperimentFileError, load_file, module_name, source_file

if TYPE_CHECKING:
    from dream.backends.base import Backend
    from dream.experiments.runner import Stepper

#: The first line of a checkpoint; a JSON line (version, experiment file) and the pickle follow.
MAGIC = b"DREAM-CHECKPOINT 1\n"
#: Steps between two saves of a run: 20,000 steps of 10,000 robots take minutes; of 10 robots,
#: seconds (and their saves milliseconds).
CHECKPOINT_EVERY = 20_000


class CheckpointError(ValueError):
    """A file that is not a DREAM checkpoint, or one this DREAM cannot resume."""


@dataclass
class Checkpoint:
    """A run between two steps.

    Attributes
    ----------
    stepper : Stepper
        The experiment, its world and its faults.
    sim : Backend
        The simulator, with its poses and violation counts.
    step : int
        Steps run so far.
    cap : int
        The run's step cap.
    every : int
        Steps between two saves.
    wall_time : float
        Seconds the run has taken so far (stepping and saving), over every part of it.
    poses : list of (3, n) ndarray, or None
        The trace so far, when the run keeps one (each save writes it whole).
    """

    stepper: Stepper
    sim: Backend
    step: int
    cap: int
    every: int = CHECKPOINT_EVERY
    wall_time: float = 0.0
    poses: list[Any] | None = None


def save(path: str | os.PathLike[str], checkpoint: Checkpoint) -> None:
    """Write ``checkpoint`` to ``path`` whole or not at all (a run killed while saving keeps its
    previous checkpoint).

    Raises
    ------
    CheckpointError
        If part of the run cannot be saved (an object pickle cannot write, such as a lock or an
        open window); the message names it.
    OSError
        The file cannot be written.
    """
    try:
        data = pickle.dumps(checkpoint, protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, TypeError, AttributeError) as err:
        raise CheckpointError(f"cannot checkpoint this run to {path}: {err}") from err
    source = source_file(type(checkpoint.stepper.exp))
    header = {"version": version(), "source": source, "digest": None if source is None else _digest(source)}
    with replaced(path, "wb") as out:
        out.write(MAGIC + json.dumps(header).encode() + b"\n")
        out.write(data)


def load(path: str | os.PathLike[str]) -> Checkpoint:
    """The checkpoint in ``path``.

    An experiment from a researcher's file is taken from the module already loaded from that
    file, else the file is loaded; if the file has changed since the save, a warning says so (the
    run's state is saved, its code is not, nor the file's module-level variables).

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        No such file.
    CheckpointError
        Not a DREAM checkpoint, written by another DREAM version, or its experiment's file is
        gone or no longer loads.
    """
    target = Path(path)
    with target.open("rb") as stream:
        if stream.readline() != MAGIC:
            raise CheckpointError(f"{target} is not a DREAM checkpoint")
        try:
            header = json.loads(stream.readline())
            written_by, source, digest = header["version"], header["source"], header.get("digest")
            if not isinstance(written_by, str) or not all(isinstance(v, (str, type(None))) for v in (source, digest)):
                raise TypeError
        except (ValueError, KeyError, TypeError):
            raise CheckpointError(f"{target}: damaged checkpoint header") from None
        if written_by != version():
            raise CheckpointError(
                f"{target} was written by DREAM {written_by}; this is DREAM {version()}: resume it with that version"
            )
        if source is not None:
            _experiment_from(source, digest, target)
        try:
            checkpoint = pickle.load(stream)
        except Exception as err:  # a damaged pickle can raise nearly anything
            raise CheckpointError(f"{target}: cannot read the checkpoint ({type(err).__name__}: {err})") from err
    if not isinstance(checkpoint, Checkpoint):
        raise CheckpointError(f"{target} is not a DREAM checkpoint")
    return checkpoint


def _experiment_from(source: str, digest: str | None, target: Path) -> None:
    """Make the module of the experiment file ``source`` importable for the pickle."""
    if module_name(source) in sys.modules:
        return
    try:
        load_file(source)
    except ExperimentFileError as err:
        raise CheckpointError(f"{target}: the run's experiment file does not load: {err}") from err
    if digest != _digest(source):
        warnings.warn(
            f"{source} has changed since {target} was saved: the run goes on with the file's new code",
            RuntimeWarning,
            stacklevel=4,
        )


def _digest(source: str) -> str | None:
    try:
        return hashlib.sha256(Path(source).read_bytes()).hexdigest()
    except OSError:
        return None
