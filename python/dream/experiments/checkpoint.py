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

import json
import os
import pickle
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dream._version import version
from dream.experiments.files import ExperimentFileError, load_file, source_file

if TYPE_CHECKING:
    from dream.backends.base import Backend
    from dream.experiments.runner import Stepper

#: The first line of a checkpoint; a JSON line (version, experiment file) and the pickle follow.
MAGIC = b"DREAM-CHECKPOINT 1\n"


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
    wall_time : float
        Seconds spent stepping so far, over every part of the run.
    poses : list of (3, n) ndarray, or None
        The trace so far, when the run keeps one.
    """

    stepper: Stepper
    sim: Backend
    step: int
    cap: int
    wall_time: float = 0.0
    poses: list[Any] | None = None


def save(path: str | os.PathLike[str], checkpoint: Checkpoint) -> None:
    """Write ``checkpoint`` to ``path`` whole or not at all: into a temporary file beside it, then
    renamed over it, so that a run killed while saving keeps its previous checkpoint.

    Raises
    ------
    CheckpointError
        If part of the run cannot be saved (an object pickle cannot write, such as an open
        window or a simulator outside Python); the message names it.
    """
    target = Path(path)
    try:
        data = pickle.dumps(checkpoint, protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, TypeError, AttributeError) as err:
        raise CheckpointError(f"cannot checkpoint this run to {target}: {err}") from err
    header = {"version": version(), "source": source_file(type(checkpoint.stepper.exp))}
    handle, temporary = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".part")
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(MAGIC + json.dumps(header).encode() + b"\n")
            out.write(data)
            out.flush()
            os.fsync(out.fileno())
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def load(path: str | os.PathLike[str]) -> Checkpoint:
    """The checkpoint in ``path``.

    Raises
    ------
    FileNotFoundError
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
            written_by, source = header["version"], header["source"]
        except (ValueError, KeyError, TypeError):
            raise CheckpointError(f"{target}: damaged checkpoint header") from None
        if written_by != version():
            raise CheckpointError(
                f"{target} was written by DREAM {written_by}; this is DREAM {version()}: resume it with that version"
            )
        if source is not None:  # its classes live in the module that loading the file makes
            try:
                load_file(source)
            except ExperimentFileError as err:
                raise CheckpointError(f"{target}: the run's experiment file does not load: {err}") from err
        try:
            checkpoint = pickle.load(stream)
        except Exception as err:  # a damaged pickle can raise nearly anything
            raise CheckpointError(f"{target}: cannot read the checkpoint ({type(err).__name__}: {err})") from err
    if not isinstance(checkpoint, Checkpoint):
        raise CheckpointError(f"{target} is not a DREAM checkpoint")
    return checkpoint
