"""NumPy reference of every DREAM kernel.

Written for clarity, not speed: these functions are the test oracle of the Rust kernels in
:mod:`dream._core`, and the fallback that lets every experiment run where the compiled
extension is absent (the Robotarium lab runs scripts with numpy, scipy and matplotlib only).
They depend on NumPy alone. Every kernel that :mod:`dream._core` has is here under the same
name and takes the same arguments, so that :mod:`dream.kernels` calls either one alike.
"""

from dream._reference.bursts import bursts
from dream._reference.draws import draws
from dream._reference.dynamics import (
    actuator_limit,
    colliding,
    dxi_to_dxu,
    dxu_to_dxi,
    threshold_velocities,
    threshold_wheels,
    unicycle_step,
    validate,
    wheel_speeds,
)
from dream._reference.guard import motion_guard
from dream._reference.hrvo import (
    HrvoPlanner,
    candidate_grid,
    detection_directions,
    hrvo,
    hrvo_rows,
    hrvo_velocity,
    unit_directions,
)
from dream._reference.length import hypot
from dream._reference.neighbours import far_from, linked, neighbours, neighbours_of, perceive
from dream._reference.obstacles import agents_from_closest, mirrored, virtual_agents
from dream._reference.raycast import distance_rays
from dream._reference.reduce import segment_any, segment_nearest, segment_nearest_to, segment_reduce
from dream._reference.sidestep import sidestep_ask, sidestep_mark
from dream._reference.tables import put_rows, take_rows
from dream._reference.voronoi import heard_cells, voronoi_cell, voronoi_cells

__all__ = [
    "bursts",
    "draws",
    "sidestep_ask",
    "sidestep_mark",
    "take_rows",
    "put_rows",
    "perceive",
    "linked",
    "motion_guard",
    "segment_any",
    "segment_nearest",
    "segment_nearest_to",
    "segment_reduce",
    "hrvo_rows",
    "HrvoPlanner",
    "actuator_limit",
    "agents_from_closest",
    "mirrored",
    "candidate_grid",
    "detection_directions",
    "distance_rays",
    "dxi_to_dxu",
    "dxu_to_dxi",
    "far_from",
    "hrvo",
    "hrvo_velocity",
    "hypot",
    "neighbours",
    "neighbours_of",
    "threshold_velocities",
    "threshold_wheels",
    "unicycle_step",
    "unit_directions",
    "validate",
    "colliding",
    "virtual_agents",
    "voronoi_cell",
    "heard_cells",
    "voronoi_cells",
    "wheel_speeds",
]
