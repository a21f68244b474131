"""The built-in experiments by name, and :func:`find`: a name or a ``.py`` file to its experiment."""

from __future__ import annotations

from dream.experiments.affine_formation import AffineFormation
from dream.experiments.files import load_file
from dream.experiments.hrvo_circle import HrvoCircle
from dream.experiments.line_consensus import LineConsensus
from dream.experiments.spec import Experiment
from dream.experiments.voronoi_coverage import VoronoiCoverage

#: Built-in experiments by name.
EXPERIMENTS: dict[str, type[Experiment]] = {
    cls.name: cls for cls in (HrvoCircle, LineConsensus, VoronoiCoverage, AffineFormation)
}


def find(source: str) -> type[Experiment]:
    """A built-in experiment by name, or the experiment a ``.py`` file defines."""
    if source in EXPERIMENTS:
        return EXPERIMENTS[source]
    if source.endswith(".py"):
        return load_file(source)
    raise ValueError(
        f"unknown experiment {source!r}: choose one of {', '.join(sorted(EXPERIMENTS))}, or give a .py file"
    )
