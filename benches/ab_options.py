"""Two ways of one step's work, in one build and one process, in turns: what a change of method
(not of build) is worth. The scenes, captured from swarm runs of ``--robots`` robots as
``ab_kernels.py`` captures them:

- ``perceive`` with the bearings of the robots seen and without (voronoi-coverage and the
  rendezvous example: the engine asks for them only for a noisy sensor);
- ``hrvo_rows`` on the rendezvous example's robots seen as angles (an ``atan2`` in ``perceive``
  and a sine and a cosine in HRVO) and as offsets (``relative=True``);
- the affine formation's memory rows of the robots deciding at one step, copied out and back
  field by field with NumPy and every field at once (``dream.kernels.take_rows``/``put_rows``).

Run: ``python benches/ab_options.py [--robots N]``. Each row: the medians of the first way and
the second, their ratio, and whether the answers agree (to the bit, or as said).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from dream import _core, kernels
from dream.experiments.affine_formation.robot import FormationRobot

sys.path.insert(0, str(Path(__file__).parent))
from ab_kernels import captured, compare  # noqa: E402
from harness import machine, table  # noqa: E402


def ways(first: Callable[[], Any], second: Callable[[], Any]) -> Callable[[str], Any]:
    """A call that :func:`ab_kernels.compare` gives a label ("before" or "after") as its build."""
    return lambda which: first() if which == "before" else second()


def unturned(perceived: tuple[Any, Any]) -> tuple[Any, Any]:
    """What ``perceive`` found but the bearings: the same either way."""
    seen, heard = perceived
    return (*seen[:3], *seen[4:]), heard


def angles(positional: tuple[Any, ...], keywords: dict[str, Any]) -> tuple[Any, ...]:
    """The rendezvous example's ``hrvo_rows`` detections ``(distance, dx, dy, vx, vy)`` as the
    movement sensor's angles ``(distance, angle, vx, vy)`` (from the robot seen, as before)."""
    distance, dx, dy, vx, vy = positional[4]
    bearing = np.arctan2(dy, dx)
    return (*positional[:4], (distance, np.where(bearing > 0, bearing - np.pi, bearing + np.pi), vx, vy))


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", type=int, default=100_000)
    args = parser.parse_args(argv)
    print(machine())
    calls = captured(args.robots)
    rows: list[list[str]] = []
    for scene in ("voronoi-coverage", "the rendezvous example"):
        positional, keywords = calls["perceive", scene]
        with_bearings = {**keywords, "bearings": True}
        call = ways(
            lambda p=positional, k=with_bearings: unturned(_core.perceive(*p, **k)),
            lambda p=positional, k=keywords: unturned(_core.perceive(*p, **k)),
        )
        rows.append([f"`perceive`, {scene}: with bearings / without", *compare("before", "after", call, RNG)])
    positional, keywords = calls["hrvo_rows", "the rendezvous example"]
    polar, options = angles(positional, keywords), {k: v for k, v in keywords.items() if k != "relative"}
    call = ways(lambda: _core.hrvo_rows(*polar, **options), lambda: _core.hrvo_rows(*positional, **keywords))
    rows.append(["`hrvo_rows`, the rendezvous example: angles / offsets", *compare("before", "after", call, RNG)])
    rows[-1][-1] += " (to an ulp: see below)"
    n = args.robots
    memory = [np.full((n, *np.shape(value)), value) for value in FormationRobot.memory.values()]
    deciding = np.flatnonzero(np.isin(np.arange(n) % 7, (1, 5)))  # the robots of two of the 7 start delays

    def numpy_way() -> tuple[np.ndarray, ...]:
        taken = [np.take(field, deciding, axis=0) for field in memory]
        for field, values in zip(memory, taken, strict=True):
            field[deciding] = values
        return tuple(taken)

    def kernel_way() -> tuple[np.ndarray, ...]:
        taken = kernels.take_rows(memory, deciding)
        kernels.put_rows(memory, deciding, taken)
        return tuple(taken)

    call = ways(numpy_way, kernel_way)
    rows.append(
        [f"memory rows out and back, affine-formation's {len(memory)} fields", *compare("before", "after", call, RNG)]
    )
    print(table(["scene: first way / second", "first (ms)", "second (ms)", "speed-up", "same answer"], rows))
    moved = _core.hrvo_rows(*polar, **options), _core.hrvo_rows(*positional, **keywords)
    print(
        f"`hrvo_rows`: rows whose velocity differs by more than 1e-12 between the two ways: "
        f"{int((np.abs(moved[0] - moved[1]) > 1e-12).any(axis=1).sum())} of {len(moved[0])}"
    )


RNG = np.random.default_rng(1)  #: who goes first in each round

if __name__ == "__main__":
    main(sys.argv[1:])
