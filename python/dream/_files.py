"""Output files written whole or not at all, and paths checked before a run writes to them.

DREAM writes only to regular files and new paths: renaming a finished file over a symlink, a
device (``/dev/null``), a FIFO or a folder would replace that entry with a plain file, so such a
path is refused, naming what stands there.
"""

from __future__ import annotations

import os
import secrets
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

#: What stands at a path that is not a regular file, by its ``stat`` type test.
_KINDS = (
    (stat.S_ISLNK, "a symlink"),
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
)


def _not_a_file(path: str | os.PathLike[str]) -> str | None:
    """What stands at ``path`` if it is neither a regular file nor nothing ("a symlink", "a
    folder", "a character device", ...); ``None`` for a regular file or a new path. A symlink is
    named as such, whatever it points to."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return None
    return next((kind for test, kind in _KINDS if test(mode)), None if stat.S_ISREG(mode) else "a special file")


@contextmanager
def replaced(path: str | os.PathLike[str], mode: str = "w", **options: Any) -> Iterator[IO[Any]]:
    """A temporary file beside ``path`` to write into, renamed over ``path`` when the block ends
    without an error (and removed when it raises): a reader or a run killed half-way never finds
    a half-written file. ``mode`` is ``"w"`` or ``"wb"``; ``options`` go to :func:`open`.

    The file gets the mode :func:`open` would give it: a new file the umask's, a replaced file
    its own.

    Raises
    ------
    OSError
        ``path`` is not a regular file or a new path (a symlink, a device, a FIFO, a folder), or
        cannot be written.
    """
    target = Path(path)
    kind = _not_a_file(target)
    if kind is not None:
        raise OSError(f"{path}: is {kind}; DREAM writes only to regular files or new paths")
    handle, temporary = _create_beside(target)
    try:
        if target.exists():
            os.fchmod(handle, stat.S_IMODE(target.stat().st_mode))
        with os.fdopen(handle, mode, **options) as out:
            yield out
            out.flush()
            os.fsync(out.fileno())
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


@contextmanager
def replaced_path(path: str | os.PathLike[str]) -> Iterator[str]:
    """As :func:`replaced`, for a writer that takes a path rather than a file (a library that
    opens the file itself): the path of an empty temporary file beside ``path``, renamed over
    ``path`` when the block ends without an error and removed when it raises.

    Raises
    ------
    OSError
        As :func:`replaced`.
    """
    target = Path(path)
    kind = _not_a_file(target)
    if kind is not None:
        raise OSError(f"{path}: is {kind}; DREAM writes only to regular files or new paths")
    handle, temporary = _create_beside(target)
    os.close(handle)
    try:
        yield temporary
        written = os.open(temporary, os.O_RDONLY)
        try:
            os.fsync(written)
        finally:
            os.close(written)
        if target.exists():
            os.chmod(temporary, stat.S_IMODE(target.stat().st_mode))
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _create_beside(target: Path) -> tuple[int, str]:
    """A new, empty file beside ``target``, created as :func:`open` creates one (mode 0o666 less
    the umask; :func:`tempfile.mkstemp` would make it 0o600), exclusively, never over another.

    Its name is short whatever ``target``'s (``.dream-`` and 8 hex digits): a name of the longest
    length the file system allows must not fail once the work is done."""
    while True:
        temporary = str(target.parent / f".dream-{secrets.token_hex(4)}.part")
        try:
            return os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), temporary
        except FileExistsError:
            continue


def check_writable(path: str | os.PathLike[str], what: str) -> None:
    """Refuse, before a run, an output ``path`` that cannot be written: anything but a regular
    file or a new path (a folder, a symlink, a device, a FIFO), a name longer than the file system
    allows, or a folder that does not exist or where no file can be made (a temporary file like
    the one :func:`replaced` writes is made there and removed). ``what`` names it in the message.

    Raises
    ------
    ValueError
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise ValueError(f"{what} {path}: the folder {folder} does not exist")
    longest = _longest_name(folder)
    if len(os.fsencode(target.name)) > longest:
        raise ValueError(f"{what} {path}: the file name is longer than the {longest} bytes the file system allows")
    kind = _not_a_file(target)
    if kind == "a folder":
        raise ValueError(f"{what} {path}: is a folder; give a file name")
    if kind is not None:
        raise ValueError(f"{what} {path}: is {kind}, not a regular file; give a file's path or a new one")
    try:
        handle, temporary = _create_beside(target)
    except OSError as err:
        raise ValueError(f"{what} {path}: cannot write in the folder {folder}: {err.strerror or err}") from None
    os.close(handle)
    os.unlink(temporary)


def _longest_name(folder: Path) -> int:
    """The longest file name (bytes) the file system of ``folder`` takes (255 where it cannot say)."""
    try:
        return os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):  # no pathconf (Windows), or no such limit
        return 255
