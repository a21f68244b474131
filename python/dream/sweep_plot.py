"""The picture of a sweep: success rate and the experiment's measures against the swept values."""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from dream._files import check_writable

#: At most this many measures get a row of panels (the first ones the experiment reports).
MAX_MEASURES = 4


def check_plot_path(path: str | Path) -> None:
    """Refuse, before a sweep runs, a plot path that :func:`plot_sweep` could not write: one
    :func:`~dream._files.check_writable` refuses, or a suffix that names no image format.

    Raises
    ------
    ValueError
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    check_writable(path, "plot")
    formats = FigureCanvasAgg.get_supported_filetypes()
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in formats:
        shown = f"suffix {Path(path).suffix!r}" if suffix else "no suffix"
        raise ValueError(f"plot {path}: {shown}; give an image file, such as .png ({', '.join(sorted(formats))})")


def plot_sweep(rows: Sequence[dict[str, Any]], swept: Sequence[str], path: str | Path) -> None:
    """Write a PNG: one row of panels per metric, one column per swept input.

    The metrics: the success rate, the step at which the runs were done, and the measures that
    vary (at most :data:`MAX_MEASURES`). Each panel puts one swept input on the x axis and draws
    one line per combination of the other swept inputs: the success rate (a run that raised
    counts as a failure), or the mean of a metric over the seeds with its standard deviation as
    error bars. A sweep over seeds alone
    plots each seed's values.

    Parameters
    ----------
    rows : sequence of dict
        The rows :func:`dream.sweep` returns.
    swept : sequence of str
        The input columns that take more than one value (``"n"``, ``"params.gain"``, ...).
    path : path
        The PNG to write.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    # A measure with one value in every run (a constant of the setup) would only draw a flat line.
    measures = [column for column in _columns(rows) if column.startswith("measures.") and _varies(rows, column)]
    metrics = ["success", "completed_step", *measures[:MAX_MEASURES]]
    axes_of = list(swept) or ["seed"]
    figure = Figure(figsize=(4.2 * len(axes_of), 2.6 * len(metrics)), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    grid = figure.subplots(len(metrics), len(axes_of), squeeze=False, sharex="col")
    for col, x_name in enumerate(axes_of):
        others = [name for name in swept if name != x_name]
        xs = sorted({row[x_name] for row in rows}, key=_order)
        numeric = all(_is_number(x) for x in xs)  # else one evenly spaced tick per value (bool, text)
        positions = xs if numeric else list(range(len(xs)))
        lines = sorted({tuple(row[name] for name in others) for row in rows}, key=lambda k: tuple(map(_order, k)))
        for line in lines:
            label = ", ".join(f"{_short(name)}={value}" for name, value in zip(others, line)) or None
            group = [row for row in rows if tuple(row[name] for name in others) == line]
            for axes, metric in zip(grid[:, col], metrics):
                means, spreads = zip(*(_summary([r for r in group if r[x_name] == x], metric) for x in xs))
                spread = None if metric == "success" else spreads  # a rate: no spread over the seeds
                axes.errorbar(positions, means, yerr=spread, marker="o", capsize=3, label=label)
        for row_index, (axes, metric) in enumerate(zip(grid[:, col], metrics)):
            axes.set_ylabel({"success": "success rate", "completed_step": "steps to done"}.get(metric, _short(metric)))
            axes.grid(alpha=0.3)
            if metric == "success":
                axes.set_ylim(-0.05, 1.05)
            if row_index == len(metrics) - 1:
                axes.set_xlabel(_short(x_name))
                if not numeric:
                    axes.set_xticks(positions, [str(x) for x in xs])
        if len(lines) > 1:
            grid[0, col].legend(fontsize="small")
    seeds = len({row["seed"] for row in rows})
    per_point = f"{seeds} seeds per point" if swept else "one point per seed"
    figure.suptitle(f"{rows[0]['experiment']}: {len(rows)} runs, {per_point}")
    figure.savefig(path)


def _summary(rows: Sequence[dict[str, Any]], metric: str) -> tuple[float, float]:
    """Mean and standard deviation of ``metric`` over ``rows`` (nan when no row has it)."""
    if metric == "success":
        values = [1.0 if row.get("success") is True else 0.0 for row in rows]
    else:
        values = [float(row[metric]) for row in rows if _is_number(row.get(metric))]
    if not values:
        return float("nan"), 0.0
    return float(np.mean(values)), float(np.std(values))


def _columns(rows: Sequence[dict[str, Any]]) -> list[str]:
    return list(dict.fromkeys(column for row in rows for column in row))


def _varies(rows: Sequence[dict[str, Any]], column: str) -> bool:
    """Whether ``column`` holds numbers, and more than one value."""
    values = [row.get(column) for row in rows if row.get(column) is not None]
    return all(_is_number(value) for value in values) and len(set(values)) > 1


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _order(value: Any) -> tuple[int, Any]:
    """Numbers by value, then everything else by its text (a bool or a string axis)."""
    return (0, value) if _is_number(value) else (1, str(value))


def _short(column: str) -> str:
    return column.split(".", 1)[-1]
