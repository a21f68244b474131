"""DREAM's batch HRVO against navground's C++ HRVO and ORCA, on the same scenes, in one process.

    pip install navground       # optional: without it this script says so and exits
    python benches/peers.py [--sizes 100 1000 10000]

navground runs a whole world step in C++ (``World.update_dry``: each agent's neighbour search
within the sensing range, then its behaviour's command; no motion), so both sides include the
neighbour search. Agents are omnidirectional discs of radius safety / 2 with DREAM's top speed,
heading along each robot's preferred velocity at its speed; DREAM is timed through the public
``dream.kernels.hrvo``. The two libraries solve the same problem with different algorithms
(navground's HRVO and ORCA are exact geometric solvers, DREAM samples candidates), so the
ratio is a cost comparison, not a claim that the answers agree.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from dream import kernels
from harness import machine, median_seconds, show, table
from scenes import RANGE, SCENES, V_MAX, Scene

SAFETY = 0.24  #: DREAM's combined safety radius (m): two agents of radius SAFETY / 2
STEP = 0.033  #: time step given to navground (s); update_dry does not move the agents


def navground_world(scene: Scene, behaviour: str):
    """A navground world with one agent per robot of ``scene`` running ``behaviour``."""
    from navground import core, sim

    world = sim.World()
    for p, v, pref in zip(*scene):
        agent = sim.Agent(radius=SAFETY / 2)
        agent.kinematics = core.Kinematics.make_type("Omni")
        agent.kinematics.max_speed = V_MAX
        agent.behavior = core.Behavior.make_type(behaviour)
        agent.behavior.safety_margin = 0.0
        agent.behavior.horizon = RANGE
        estimation = sim.StateEstimation.make_type("Bounded")
        estimation.range = RANGE
        agent.state_estimation = estimation
        agent.position = p
        agent.velocity = v
        speed = float(np.hypot(*pref))
        if speed > 0:
            agent.behavior.target = core.Target.Direction(pref / speed)
            agent.behavior.optimal_speed = speed
        world.add_agent(agent)
    world.update_dry(STEP, advance_time=False)  # navground prepares agents lazily on the first step
    return world


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1_000, 10_000])
    sizes = parser.parse_args().sizes
    try:
        import navground.sim  # noqa: F401
    except ImportError:
        print("navground is not installed (pip install navground): nothing to compare, skipped.")
        sys.exit(0)
    from importlib.metadata import version

    print(machine())
    print(f"DREAM kernels: {kernels.IMPLEMENTATION}; navground {version('navground')}; medians of >= 7 samples\n")
    rows = []
    for name, make in SCENES.items():
        for n in sizes:
            scene = make(n)
            p, v, pref = scene
            dream = median_seconds(
                lambda p=p, v=v, pref=pref: kernels.hrvo(p, v, pref, radius=RANGE, safety=SAFETY, v_max=V_MAX)
            )
            cells: list[object] = [f"{name}/n={n}", show(dream)]
            for behaviour in ("HRVO", "ORCA"):
                world = navground_world(scene, behaviour)
                peer = median_seconds(lambda world=world: world.update_dry(STEP, advance_time=False))
                cells += [show(peer), f"{peer / dream:.1f}x"]
            rows.append(cells)
            print(table(["scene", "DREAM hrvo", "navground HRVO", "ratio", "navground ORCA", "ratio"], rows[-1:]))
    print()
    header = ["scene", "DREAM hrvo (median)", "navground HRVO", "HRVO / DREAM", "navground ORCA", "ORCA / DREAM"]
    print(table(header, rows))


if __name__ == "__main__":
    main()
