"""Experiments from a researcher's own file: ``dream run my_experiment.py``."""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import sys
from pathlib import Path

from dream.experiments.spec import Experiment


class ExperimentFileError(ValueError):
    """A file that does not define exactly one experiment, or that fails to load."""


#: Modules made from researchers' files are named this and the file's stem and path digest.
MODULE_PREFIX = "dream_user_"


def load_file(path: str | Path) -> type[Experiment]:
    """The one :class:`~dream.Experiment` subclass that the Python file ``path`` defines.

    Raises
    ------
    ExperimentFileError
        The file is missing, fails to import (the error and its line), or defines no
        Experiment or more than one.
    """
    path = Path(path)
    if not path.is_file():
        raise ExperimentFileError(f"{path}: no such file")
    name = module_name(path)
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ExperimentFileError(f"{path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look the module up by name
    try:
        spec.loader.exec_module(module)
    except SyntaxError as err:
        del sys.modules[name]
        raise ExperimentFileError(f"{path}, line {err.lineno}: syntax error: {err.msg}") from None
    except Exception as err:  # the user's code: report it, whatever it raised
        del sys.modules[name]
        raise ExperimentFileError(f"{path}: loading it raised {type(err).__name__}: {err}") from err
    found = [
        value
        for value in vars(module).values()
        if isinstance(value, type) and issubclass(value, Experiment) and value.__module__ == name
    ]
    if len(found) != 1:
        names = ", ".join(cls.__name__ for cls in found)
        what = "no Experiment subclass" if not found else f"{len(found)} Experiment subclasses ({names})"
        raise ExperimentFileError(f"{path}: defines {what}; a file for `dream run` defines exactly one")
    return found[0]


def module_name(path: str | Path) -> str:
    """The module :func:`load_file` makes of ``path``: the same name in every process, so that
    pickles of its objects (checkpoints, Dask workers) find it."""
    path = Path(path)
    return f"{MODULE_PREFIX}{path.stem}_{hashlib.sha1(str(path.resolve()).encode()).hexdigest()[:12]}"


def source_file(cls: type) -> str | None:
    """The file that defines ``cls`` if it comes from :func:`load_file`, else None."""
    if not cls.__module__.startswith(MODULE_PREFIX):
        return None
    file = getattr(sys.modules.get(cls.__module__), "__file__", None)
    return None if file is None else str(Path(file).resolve())


def source_digest(cls: type) -> str:
    """A short SHA-256 (16 hex digits) of the file that defines ``cls``: a built-in's module, a
    file from :func:`load_file`, or a script; of the class's own source where there is no file (a
    notebook's cell), and ``""`` where neither can be read (code that cannot be told apart)."""
    try:
        path = inspect.getsourcefile(cls)
        data = Path(path).read_bytes() if path and Path(path).is_file() else inspect.getsource(cls).encode()
    except (OSError, TypeError):
        return ""
    return hashlib.sha256(data).hexdigest()[:16]
