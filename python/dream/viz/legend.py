"""The legend: one entry for each kind of thing on screen, with a handle that looks like it."""

from __future__ import annotations

from typing import Any

from dream.viz.style import (
    BYZANTINE_COLOUR,
    CRASHED_COLOUR,
    LEGEND_ANCHOR,
    LINK_COLOUR,
    MOVING_OBSTACLE_COLOUR,
    OBSTACLE_COLOUR,
    RANGE_COLOURS,
    STUCK_COLOUR,
)
from dream.viz.view import Framing


class Legend(Framing):
    """The legend of a :class:`~dream.viz.Renderer`, remade only when its entries change."""

    _legend: Any
    _legend_key: tuple[Any, ...]
    legend_labels: list[str]

    def _set_legend(self, entries: list[tuple[str, Any]]) -> None:
        key = tuple(entries)
        if key == self._legend_key:
            return
        self._legend_key = key
        if self._legend is not None:
            self._legend.remove()
        handles = [self._proxy(style) for _, style in entries]
        self.legend_labels = [label for label, _ in entries]
        self._legend = self.figure.legend(
            handles,
            self.legend_labels,
            loc="upper left",
            bbox_to_anchor=LEGEND_ANCHOR,
            fontsize=9.5 * self._text,
            frameon=False,
            handlelength=2.2,
            borderaxespad=0.0,
        )

    def _proxy(self, style: tuple[Any, ...]) -> Any:
        """A legend handle that looks like what ``style`` (a legend key) draws."""
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch

        first = tuple(self._colours[0]) if len(self._colours) else "C0"
        kind = style[0]

        def marker(symbol: str, **kw: Any) -> Line2D:
            return Line2D([], [], linestyle="none", marker=symbol, **{"markersize": 11 * self._text, **kw})

        if kind == "robot":
            return marker("o", markerfacecolor=first, markeredgecolor="black")
        if kind == "goal":
            return marker("x", color=first, markeredgewidth=1.5)
        if kind == "velocity":
            return marker(r"$\rightarrow$", color=first, markersize=16 * self._text)
        if kind == "link":
            return Line2D([], [], color=LINK_COLOUR, linewidth=1.0)
        if kind == "obstacle":
            return Patch(facecolor=OBSTACLE_COLOUR, edgecolor=OBSTACLE_COLOUR)
        if kind == "moving":
            return Patch(facecolor=MOVING_OBSTACLE_COLOUR, edgecolor="0.15", hatch="//")
        if kind == "cell":
            return Patch(facecolor="none", edgecolor="0.5")
        if kind == "crashed":
            return marker("X", markerfacecolor=CRASHED_COLOUR, markeredgecolor="black")
        if kind == "stuck":
            return marker("s", markerfacecolor="none", markeredgecolor=STUCK_COLOUR, markeredgewidth=2.0)
        if kind == "byzantine":
            return marker("o", markerfacecolor="none", markeredgecolor=BYZANTINE_COLOUR, markeredgewidth=2.0)
        if kind == "role":
            return marker(style[1], markerfacecolor="white", markeredgecolor="black")
        if kind == "view":
            return Line2D([], [], linestyle="none")
        if kind == "focus":
            return marker("o", markerfacecolor="none", markeredgecolor="black", markeredgewidth=2.2)
        if kind == "range":
            return Line2D([], [], color=RANGE_COLOURS[style[1] % len(RANGE_COLOURS)], linestyle="--", linewidth=1.4)
        return Line2D([], [], color=RANGE_COLOURS[0], linewidth=1.2)  # "heard"
