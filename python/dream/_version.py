"""DREAM's version, written once in the workspace's Cargo.toml and read from what was built from it."""

from __future__ import annotations

from importlib import metadata

#: The PyPI distribution that installs the import package ``dream``.
DISTRIBUTION = "dream-robotics"


def version() -> str:
    """The version of this copy of DREAM, e.g. ``"0.1.0"``.

    The compiled extension sitting beside this file is asked first: it carries Cargo's version
    and always belongs to this source tree, even when run from a checkout on ``PYTHONPATH``
    next to another installed copy. Without the extension (a pure-Python copy), the installed
    distribution's metadata (which maturin also takes from Cargo) answers; a bare copy of the
    sources that is neither built nor installed reports ``"unknown"``.
    """
    try:
        from dream import _core
    except ImportError:
        pass
    else:
        return str(_core.__version__)
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return "unknown"
