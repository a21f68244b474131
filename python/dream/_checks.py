"""Input checks shared by the public API: every error names the argument and what is wrong."""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
Bounds = tuple[float, float, float, float]


def as_array(value: Any, name: str, shape: tuple[int | None, ...]) -> FloatArray:
    """``value`` as a C-contiguous float64 array of ``shape`` (``None`` = any length), all finite.

    Raises
    ------
    ValueError
        If the shape differs (the message shows expected and actual shapes) or a value is NaN/inf.
    """
    array = as_shaped(value, name, shape, np.ascontiguousarray)
    if not all_finite(array):
        bad = np.argwhere(~np.isfinite(array))[0]
        raise ValueError(f"`{name}` contains a non-finite value (NaN or inf) at index {tuple(int(i) for i in bad)}")
    return array


def as_shaped(
    value: Any, name: str, shape: tuple[int | None, ...], convert: Callable[..., Any] = np.asarray
) -> FloatArray:
    """``value`` as a float64 array of ``shape`` (``None`` = any length) by ``convert``
    (:func:`numpy.asarray`: in the layout it has, no copy of a float64 array), its values unchecked.

    Raises
    ------
    ValueError
        If it is no float array, or its shape differs (the message shows expected and actual shapes).
    """
    try:
        array: FloatArray = convert(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ValueError(f"`{name}` must be a float array of shape {_show(shape)}: {err}") from None
    fits = array.shape == shape or (
        array.ndim == len(shape) and all(want is None or got == want for got, want in zip(array.shape, shape))
    )
    if not fits:
        raise ValueError(f"`{name}` must have shape {_show(shape)}, got {array.shape}")
    return array


def as_flags(value: Any, name: str, n: int) -> NDArray[np.bool_]:
    """``value`` as a C-contiguous ``(n,)`` bool array (which robots a kernel answers for)."""
    array = np.ascontiguousarray(value)
    if array.dtype != np.bool_:
        raise ValueError(f"`{name}` must be a bool array of shape ({n},), got dtype {array.dtype}")
    if array.shape != (n,):
        raise ValueError(f"`{name}` must have shape ({n},), got {array.shape}")
    return array


def as_offsets(value: Any, name: str, length: int, rows: int | None = None, part: str = "") -> NDArray[np.int64]:
    """``value`` as int64 CSR offsets ``(rows + 1,)`` rising from 0 to ``length``, the number of
    entries they cut into rows (any number of rows when ``rows`` is ``None``); errors name
    ``name`` and the ``part`` of it that the offsets are (``"indptr"``, say)."""
    what = f"`{name}`" + (f" {part}" if part else "")
    array = np.asarray(value)
    if array.size and array.dtype.kind not in "iu":
        raise ValueError(f"{what} must hold integer offsets, got dtype {array.dtype}")
    cuts = np.ascontiguousarray(array, dtype=np.int64)
    fits = cuts.ndim == 1 and len(cuts) >= 1 and (rows is None or len(cuts) == rows + 1)
    if not fits or not _rising(cuts, length):
        shape = "(rows + 1,)" if rows is None else f"({rows + 1},)"
        raise ValueError(f"{what} must be offsets of shape {shape} rising from 0 to {length}, got {cuts.tolist()[:8]}")
    return cuts


def _rising(cuts: NDArray[np.int64], length: int) -> bool:
    """Whether ``cuts`` ``(m,)`` rise from 0 to ``length``; a robot's few offsets in Python (NumPy's
    per-call cost is most of the check there)."""
    if len(cuts) <= 64:
        values = cuts.tolist()
        return values[0] == 0 and values[-1] == length and all(map(operator.le, values, values[1:]))
    return bool(cuts[0] == 0 and cuts[-1] == length and not np.any(np.diff(cuts) < 0))


def as_index(value: Any, name: str) -> NDArray[np.int64]:
    """``value`` as int64 rows ``(e,)`` of some array (the kernel checks that they are its rows)."""
    array = np.asarray(value)
    if array.ndim != 1 or (array.size and array.dtype.kind not in "iu"):
        raise ValueError(f"`{name}` must be integer rows of shape (e,), got dtype {array.dtype} shape {array.shape}")
    return np.ascontiguousarray(array, dtype=np.int64)


def check_rows(index: np.ndarray, name: str, length: int) -> None:
    """Every entry of ``index`` must be a row of an array of ``length`` rows."""
    if len(index) and (index.min() < 0 or index.max() >= length):
        bad = index[(index < 0) | (index >= length)][0]
        raise ValueError(f"`{name}` holds {bad}, which is not a row of the {length} it indexes")


def all_finite(array: np.ndarray) -> bool:
    """Whether every value of the float ``array`` is finite; a robot's small arrays through
    :func:`math.isfinite` (several times faster there than NumPy's per-call cost). A large
    array's sum is finite only if every value is, and summing needs no mask of the array's size:
    the values are tested one by one only when the sum is not finite (a NaN, an infinity or an
    overflow)."""
    if array.size <= 64:
        return all(map(math.isfinite, array.ravel().tolist()))
    with np.errstate(over="ignore", invalid="ignore"):
        total = np.sum(array)
    return bool(np.isfinite(total) or np.isfinite(array).all())


def as_poses(value: Any, name: str = "poses", n: int | None = None) -> FloatArray:
    """A ``(3, n)`` pose array (x, y, theta rows)."""
    return as_array(value, name, (3, n))


def check_robot_id(robot_id: int, n: int, what: str = "poses") -> int:
    """``robot_id`` as an int, or an IndexError naming it, the number of robots and the way out."""
    if not 0 <= robot_id < n:
        ids = "no robots" if n == 0 else f"ids 0 to {n - 1}"
        raise IndexError(
            f"robot id {robot_id} is out of range for {what} of {n} robots ({ids}): a robot, its sensors "
            "and its radio take the index of its column in the simulator's poses"
        )
    return int(robot_id)


def check_finite(value: float, name: str) -> float:
    """``value`` as a float, or a ValueError naming ``name`` if it is NaN or infinite."""
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"`{name}` must be finite, got {value}")
    return value


def check_nonnegative(value: float, name: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value >= 0):
        raise ValueError(f"`{name}` must be finite and >= 0, got {value}")
    return value


def checked_bounds(bounds: Any) -> Bounds | None:
    """``bounds`` as finite floats ``(xmin, xmax, ymin, ymax)`` with xmin < xmax and ymin < ymax; ``None`` kept."""
    if bounds is None:
        return None
    values = tuple(float(b) for b in bounds)
    if len(values) != 4 or not all(np.isfinite(values)) or values[0] >= values[1] or values[2] >= values[3]:
        raise ValueError(
            f"`bounds` must be finite (xmin, xmax, ymin, ymax) with xmin < xmax and ymin < ymax, got {bounds}"
        )
    return values  # type: ignore[return-value]


def _show(shape: tuple[int | None, ...]) -> str:
    names = iter("nmk")
    parts = [str(s) if s is not None else next(names) for s in shape]
    return "(" + ", ".join(parts) + ("," if len(parts) == 1 else "") + ")"


class RobotCallback:
    """The ``callback`` attribute of a sensor or radio (an object with ``robot_id`` and ``tag``).

    Refuses, when it is set, a robot's bound method (say ``robot.update_odom``) whose robot has
    another id than the sensor or radio: that sensor would read, or the radio speak for, another
    robot than the one it reports to, and nothing would fail.
    """

    def __set_name__(self, owner: type, name: str) -> None:
        self.slot = "_" + name

    def __get__(self, obj: Any, objtype: type | None = None) -> Any:
        return self if obj is None else getattr(obj, self.slot)

    def __set__(self, obj: Any, callback: Any) -> None:
        theirs = getattr(getattr(callback, "__self__", None), "robot_id", None)
        if isinstance(theirs, int) and theirs != obj.robot_id:
            raise ValueError(
                f"{type(obj).__name__} {obj.tag!r} has robot id {obj.robot_id} but reports to robot {theirs}'s "
                f"{getattr(callback, '__name__', 'callback')}: give a robot's sensors and radio its own id"
            )
        setattr(obj, self.slot, callback)


def per_robot(values: Any, k: int, kind: np.dtype, what: str, shape: tuple[int, ...] = ()) -> np.ndarray:
    """``values`` as ``(k, *shape)`` of ``kind``: one value (of ``shape``) per deciding robot, or one
    for all of them; anything else (a shape that would spread one robot's value over the others,
    a float for an int field) is refused, naming ``what``."""
    if type(values) is np.ndarray and values.shape == (k, *shape) and values.dtype == kind:
        return values  # already one value of its kind per robot (most memory): no copy to make
    array = np.asarray(values)
    if array.shape not in (shape, (k, *shape)):
        want = ", ".join(map(str, (k, *shape))) + ("," if not shape else "")
        raise ValueError(f"{what} must have one value per deciding robot, shape ({want}), got shape {array.shape}")
    if not np.can_cast(array.dtype, kind, casting="same_kind"):
        raise ValueError(f"{what} holds {kind} values, got {array.dtype}")
    return np.broadcast_to(array, (k, *shape)).astype(kind)
