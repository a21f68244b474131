"""Checkpoints: a long run written to a file as it goes, so that it can go on where it stopped.

A run of hours (hrvo-circle with 10,000 robots takes about a million steps) outlives a batch
job's time limit or a laptop's lid. With ``dream.run(..., checkpoint=PATH)`` the run's whole
state (the experiment and its robots, the world's clock, messages and random generator, the
simulator, the faults) is written to ``PATH`` every ``checkpoint_every`` steps and when a signal
stops it; :func:`dream.resume` (``dream resume PATH``) loads it and runs on. Since the random
generator is saved with the rest, the resumed run takes exactly the steps the uninterrupted run
would have.

A checkpoint is code: a pickle, which runs whatever it names when loaded, and for an experiment
from a researcher's file, that file's path, which is imported (it must still hold the experiment
when the run resumes: the run's state is saved, not its code). So every checkpoint is signed
with an HMAC-SHA256 over the whole file, keyed by the user's own key (:func:`key_path`, made
with mode 0600 on first use), and :func:`load` checks the signature before it imports or
unpickles anything: a file changed since it was saved, or written with another key, is refused
unless the caller trusts it (``trust=True``, ``dream resume --trust``).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import pickle
import secrets
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
    from dream.experiments.stepper import Stepper

#: The first line of a checkpoint; the signature (hex HMAC-SHA256 of the whole file but this line),
#: a JSON line (version, experiment file) and the pickle follow.
MAGIC = b"DREAM-CHECKPOINT 2\n"
#: What the first line of every checkpoint format starts with.
FAMILY = b"DREAM-CHECKPOINT "
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
    """Write ``checkpoint`` to ``path``, signed with the user's key (:func:`key_path`), whole or
    not at all (a run killed while saving keeps its previous checkpoint).

    Raises
    ------
    CheckpointError
        If part of the run cannot be saved (an object pickle cannot write, such as a lock or an
        open window; the message names it), or the key cannot be read or made.
    OSError
        The file cannot be written.
    """
    try:
        data = pickle.dumps(checkpoint, protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, TypeError, AttributeError) as err:
        raise CheckpointError(f"cannot checkpoint this run to {path}: {err}") from err
    source = source_file(type(checkpoint.stepper.exp))
    header = {"version": version(), "source": source, "digest": None if source is None else _digest(source)}
    line = json.dumps(header).encode() + b"\n"
    signature = _signature(_key(), line, data)
    with replaced(path, "wb") as out:
        out.write(MAGIC + signature + b"\n" + line)
        out.write(data)


def load(path: str | os.PathLike[str], *, trust: bool = False) -> Checkpoint:
    """The checkpoint in ``path``.

    Its signature is checked first, over the whole file: nothing is imported or unpickled from a
    file that this user's key did not sign, unless ``trust`` (a colleague's file: it is loaded
    with a warning, since loading it runs its code). An experiment from a researcher's file is
    taken from the module already loaded from that file, else the file is loaded; if the file has
    changed since the save, a warning says so (the run's state is saved, its code is not, nor the
    file's module-level variables).

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        No such file.
    CheckpointError
        Not a DREAM checkpoint, not signed with this user's key (and not ``trust``), written by
        another DREAM version, or its experiment's file is gone or no longer loads.
    """
    target = Path(path)
    content = target.read_bytes()  # read once: what is checked is what is loaded
    if not content.startswith(MAGIC):
        if content.startswith(FAMILY):
            raise CheckpointError(f"{target}: an unsigned checkpoint of an older DREAM; resume it with that version")
        raise CheckpointError(f"{target} is not a DREAM checkpoint")
    signed_at = content.find(b"\n", len(MAGIC)) + 1
    header_at = content.find(b"\n", signed_at) + 1
    if not 0 < signed_at < header_at:
        raise CheckpointError(f"{target}: damaged checkpoint header")
    view = memoryview(content)  # slices of it copy nothing: a checkpoint can be large
    line, data = view[signed_at:header_at], view[header_at:]
    if not hmac.compare_digest(content[len(MAGIC) : signed_at - 1], _signature(_key(), line, data)):
        why = f"{target}: its signature does not match your checkpoint key {key_path()} (changed, or signed elsewhere)"
        if not trust:
            raise CheckpointError(f"{why}; loading it would run its code: resume only a file you trust, with --trust")
        warnings.warn(f"{why}; resumed as trusted, running its code", RuntimeWarning, stacklevel=3)
    try:
        header = json.loads(bytes(line))
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
        checkpoint = pickle.loads(data)
    except Exception as err:  # a damaged pickle can raise nearly anything
        raise CheckpointError(f"{target}: cannot read the checkpoint ({type(err).__name__}: {err})") from err
    if not isinstance(checkpoint, Checkpoint):
        raise CheckpointError(f"{target} is not a DREAM checkpoint")
    return checkpoint


def key_path() -> Path:
    """The user's checkpoint key: ``$XDG_CONFIG_HOME/dream/checkpoint.key``, by default
    ``~/.config/dream/checkpoint.key``. Whoever holds it can write checkpoints this user resumes."""
    config = os.environ.get("XDG_CONFIG_HOME", "")
    folder = Path(config) if os.path.isabs(config) else Path.home() / ".config"  # the XDG rule: absolute only
    return folder / "dream" / "checkpoint.key"


def _key() -> bytes:
    """The user's checkpoint key (32 bytes, as hex in :func:`key_path`), made on first use."""
    path = key_path()
    try:
        if not path.exists():
            _make_key(path)
        text = path.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError) as err:
        raise CheckpointError(f"cannot read or make the checkpoint key {path}: {err}") from err
    try:
        key = bytes.fromhex(text)
    except ValueError:
        key = b""
    if len(key) != 32:
        raise CheckpointError(f"{path} is not a checkpoint key (64 hex digits): remove it and DREAM makes a new one")
    return key


def _make_key(path: Path) -> None:
    """Write a new key to ``path`` (mode 0600), unless another process makes one first.

    The key is written whole to a file of its own (created with ``O_EXCL``), then hard-linked to
    ``path``: the link appears atomically and fails if ``path`` exists, so two processes never
    both make a key, and none reads a key half-written.
    """
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{secrets.token_hex(4)}")
    handle = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        os.fchmod(handle, 0o600)  # whatever the umask
        with os.fdopen(handle, "w", encoding="ascii") as out:
            out.write(secrets.token_hex(32) + "\n")
            out.flush()
            os.fsync(out.fileno())
        try:
            os.link(temporary, path)
        except FileExistsError:
            pass  # another process made the key first: use theirs
    finally:
        temporary.unlink()


def _signature(key: bytes, line: bytes | memoryview, data: bytes | memoryview) -> bytes:
    """The hex HMAC-SHA256 of a checkpoint's content but its signature line."""
    mac = hmac.new(key, MAGIC, hashlib.sha256)
    mac.update(line)
    mac.update(data)
    return mac.hexdigest().encode()


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
