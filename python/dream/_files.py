"""Output files written whole or not at all, and paths checked before a run writes to them."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any


@contextmanager
def replaced(path: str | os.PathLike[str], mode: str = "w", **options: Any) -> Iterator[IO[Any]]:
    """A temporary file beside ``path`` to write into, renamed over ``path`` when the block ends
    without an error (and removed when it raises): a reader or a run killed half-way never finds
    a half-written file. ``mode`` is ``"w"`` or ``"wb"``; ``options`` go to :func:`open`."""
    target = Path(path)
    handle, temporary = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".part")
    try:
        with os.fdopen(handle, mode, **options) as out:
            yield out
            out.flush()
            os.fsync(out.fileno())
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def check_writable(path: str | os.PathLike[str], what: str) -> None:
    """Refuse, before a run, an output ``path`` that cannot be written: a folder, or a file in a
    folder that does not exist or is not writable. ``what`` names it in the message.

    Raises
    ------
    ValueError
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if target.is_dir():
        raise ValueError(f"{what} {path}: is a folder; give a file name")
    if not folder.is_dir():
        raise ValueError(f"{what} {path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise ValueError(f"{what} {path}: the folder {folder} is not writable")
