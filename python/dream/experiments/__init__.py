"""Experiments: the :class:`Experiment` spec, the runner, and the thesis's four experiments."""

from __future__ import annotations

from dream.experiments.affine_formation import AffineFormation
from dream.experiments.files import ExperimentFileError, load_file
from dream.experiments.hrvo_circle import HrvoCircle
from dream.experiments.line_consensus import LineConsensus
from dream.experiments.registry import EXPERIMENTS, find
from dream.experiments.result import ExperimentResult
from dream.experiments.runner import resume, run
from dream.experiments.spec import Experiment, Param, param
from dream.experiments.voronoi_coverage import VoronoiCoverage

__all__ = [
    "EXPERIMENTS",
    "AffineFormation",
    "Experiment",
    "ExperimentFileError",
    "ExperimentResult",
    "HrvoCircle",
    "LineConsensus",
    "Param",
    "VoronoiCoverage",
    "find",
    "load_file",
    "param",
    "resume",
    "run",
]
