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
from dream._checks import FloatArray, as_array, as_shaped


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


def core_checks() -> bool:
    """Whether the Rust kernels are in use, whose bindings check every value they read (finite,
    and within reach where a kernel says so): a wrapper then leaves those checks to them."""
    return _core is not None


def kernel_input(value: Any, name: str, shape: tuple[int | None, ...]) -> FloatArray:
    """``value`` as a kernel's float64 input of ``shape`` (``None`` = any length): for the Rust
    kernels, as it lies, since their bindings read any layout in place and check on every core
    that each value is finite (a ValueError naming ``name``); for the reference,
    :func:`~dream._checks.as_array`'s checked C-contiguous array. At a million robots the copy and
    the check of one NumPy pass cost about a tenth of a swarm step's serial part.

    Raises
    ------
    ValueError
        If it is no float array of ``shape``; for the reference, also if a value is NaN or infinite.
    """
    return as_shaped(value, name, shape) if core_checks() else as_array(value, name, shape)
