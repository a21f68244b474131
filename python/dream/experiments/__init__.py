"""The reference experiments of the thesis, as library modules with ``run(...)``."""

from __future__ import annotations

from types import ModuleType

from dream.experiments import affine_formation, hrvo_circle, line_consensus, voronoi_coverage
from dream.experiments.result import ExperimentResult

#: CLI name -> module with a ``run(n, seed, backend, steps, ...)`` function.
EXPERIMENTS: dict[str, ModuleType] = {
    module.NAME: module for module in (hrvo_circle, line_consensus, voronoi_coverage, affine_formation)
}

__all__ = ["EXPERIMENTS", "ExperimentResult", "affine_formation", "hrvo_circle", "line_consensus", "voronoi_coverage"]
