"""Which implementation the kernels run: the Rust of :mod:`dream._core` or the NumPy of :mod:`dream._reference`.

The choice is made once, at import: the reference when ``DREAM_PURE_PYTHON=1`` is set or the
extension is missing. Tests and benchmarks that want another implementation patch ``_core``
here (``None`` for the reference); :func:`implementation` reads it on every call.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from types import ModuleType
from typing import Any

import dream._reference as _reference


def _load_core() -> ModuleType | None:
    if os.environ.get("DREAM_PURE_PYTHON", "") not in ("", "0"):
        return None
    try:
        from dream import _core
    except ImportError:
        return None
    return _core


_core = _load_core()

#: ``"rust"`` when the compiled kernels are in use, ``"numpy"`` for the reference fallback.
IMPLEMENTATION = "numpy" if _core is None else "rust"


def implementation(name: str) -> Callable[..., Any]:
    """The kernel ``name`` of :mod:`dream._core`, or of :mod:`dream._reference` without the extension.

    Both modules give each kernel the same name and arguments, so a caller writes one call.
    """
    return getattr(_reference if _core is None else _core, name)
