"""The public vectorised kernels of DREAM: whole-swarm calls that other projects use directly.

Each function checks its input (shapes, NaN/inf, radii) and raises ``ValueError`` naming the
argument, then runs the Rust kernel of :mod:`dream._core` when it is available, or the NumPy
reference of :mod:`dream._reference` when the extension is missing or the environment
variable ``DREAM_PURE_PYTHON=1`` is set. Both give the same results (the test suite checks).

Shapes: poses ``(3, n)``, unicycle commands and single-integrator velocities ``(2, n)`` in the
Robotarium's layout; positions for geometry kernels ``(n, 2)``. Units: m, s, rad.
"""

from __future__ import annotations

# The kernels are written in submodules named like those of dream._reference, private so that
# no module shadows the function of its name (which also hides the function from the API page);
# each kernel calls its implementation through _dispatch. The public names are this package's.
from dream import _checks
from dream._reference.draws import Loss
from dream.errors import GeometryError
from dream.kernels._dispatch import IMPLEMENTATION
from dream.kernels._dynamics import (
    Violations,
    actuator_limit,
    colliding,
    dxi_to_dxu,
    dxu_to_dxi,
    threshold_velocities,
    unicycle_step,
    validate,
    validate_each,
    wheel_speeds,
)
from dream.kernels._guard import motion_guard
from dream.kernels._hrvo import HrvoPlanner, hrvo, hrvo_rows
from dream.kernels._length import hypot
from dream.kernels._neighbours import far_from, linked, neighbours, neighbours_of, perceive
from dream.kernels._obstacles import obstacle_agents, virtual_agents
from dream.kernels._raycast import distance_rays
from dream.kernels._reduce import segment_any, segment_nearest, segment_nearest_to, segment_reduce
from dream.kernels._sidestep import sidestep_ask, sidestep_mark
from dream.kernels._tables import put_rows, take_rows
from dream.kernels._voronoi import VoronoiCells, heard_cells, voronoi_cell, voronoi_cells

Bounds = _checks.Bounds
"""``tuple[float, float, float, float]``: ``(xmin, xmax, ymin, ymax)`` (m), the type of ``bounds`` arguments."""

# In the API page's order (docs/api/kernels.md sorts by it): by family, as the table of docs/kernels.md.
__all__ = [
    "IMPLEMENTATION",
    "GeometryError",
    "Violations",
    "unicycle_step",
    "threshold_velocities",
    "wheel_speeds",
    "validate",
    "validate_each",
    "colliding",
    "dxi_to_dxu",
    "dxu_to_dxi",
    "actuator_limit",
    "hypot",
    "neighbours",
    "neighbours_of",
    "far_from",
    "perceive",
    "Loss",
    "linked",
    "HrvoPlanner",
    "hrvo",
    "hrvo_rows",
    "VoronoiCells",
    "voronoi_cells",
    "voronoi_cell",
    "heard_cells",
    "obstacle_agents",
    "virtual_agents",
    "distance_rays",
    "segment_reduce",
    "segment_any",
    "segment_nearest",
    "segment_nearest_to",
    "motion_guard",
    "sidestep_ask",
    "sidestep_mark",
    "take_rows",
    "put_rows",
]
