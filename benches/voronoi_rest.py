"""How voronoi-coverage comes to rest without its moving obstacles: whether its last robots converge or chatter.

    python benches/voronoi_rest.py -n 1000 --seeds 0-2
    python benches/voronoi_rest.py -n 3000 --momentum 0 --lead 0     # Lloyd's step alone

Each run is swarm mode on Fast to the experiment's own step cap. Per run: success, the steps to
rest and the cap, violations, the cost at rest over the ideal spread's, wall time, and how the
robots moved: *starts* per robot (a robot with a command after a step without one; stop-and-go
creep restarts a robot hundreds of times), *reversals* (consecutive moving decisions of a robot
whose way to its centroid points backwards: oscillation about the centroid) and the robots still
moving at each tenth of the run. The table is printed with the machine, its load and the date.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

import dream
from dream.experiments import voronoi_coverage as vc
from dream.swarm import View
from harness import machine, table


class TracedRobot(vc.CoverageRobot):
    """A coverage robot that counts its reversals: consecutive moving decisions whose ways to the
    centroid point apart (nothing else changes)."""

    def __init__(self, n: int, *args: Any) -> None:
        super().__init__(*args)
        self.reversals = 0
        self.moves = 0
        self.way = np.zeros((n, 2))  # each robot's way to its centroid at its last moving decision
        self.moved = np.zeros(n, dtype=bool)  # whether its last decision moved it

    def decide(self, view: View) -> np.ndarray:
        wished = super().decide(view)
        who = view.ids
        way = np.column_stack((view.memory["goal_x"], view.memory["goal_y"])) - view.pose[:, :2]
        moving = wished.any(axis=1)
        both = moving & self.moved[who]
        self.reversals += int(np.count_nonzero(np.sum(way[both] * self.way[who[both]], axis=1) < 0))
        self.moves += int(np.count_nonzero(both))
        self.way[who[moving]] = way[moving]
        self.moved[who] = moving
        return wished


class Traced(vc.VoronoiCoverage):
    """voronoi-coverage that counts, per robot, its starts and reversals (nothing else changes)."""

    name = "voronoi-coverage-traced"

    def swarm_robot(self, n: int) -> vc.CoverageRobot:
        team = super().swarm_robot(n)
        assert team.guard is not None
        self.team = TracedRobot(n, self.obstacles, self.arena, team.arrival, team.guard.near)
        self.starts = np.zeros(n, dtype=np.int64)
        self.was_moving = np.zeros(n, dtype=bool)
        self.movers: list[int] = []
        return self.team

    def after_step(self, step: int, poses: np.ndarray) -> None:
        super().after_step(step, poses)
        moving = np.any(self.dxu != 0, axis=0)
        self.starts += moving & ~self.was_moving
        self.was_moving = moving
        self.movers.append(int(np.count_nonzero(moving)))


def run(n: int, seed: int) -> list[Any]:
    """One run's row of the table."""
    seen: list[Traced] = []

    class Kept(Traced):
        def swarm_robot(self, n: int) -> vc.CoverageRobot:
            seen.append(self)
            return super().swarm_robot(n)

    began = time.perf_counter()
    result = dream.run(Kept, n=n, seed=seed, backend="fast", swarm=True, moving_obstacles=False)
    wall = time.perf_counter() - began
    team = seen[0]
    cap = team.steps(n)
    tenths = " ".join(str(team.movers[min(len(team.movers) - 1, k * cap // 10)]) for k in range(1, 10))
    m = result.measures
    return [
        n,
        seed,
        result.success,
        f"{result.completed_step} / {cap}" if result.completed_step is not None else f"- / {cap}",
        f"{result.collisions} / {result.boundary} / {result.actuator} / {m['static_contacts']}",
        f"{m['cost_end'] / m['cost_ideal']:.2f}",
        f"{team.starts.mean():.0f} / {team.starts.max()}",
        f"{team.team.reversals} of {team.team.moves}",
        tenths,
        f"{wall:.0f}",
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, nargs="+", default=[300], help="team sizes")
    parser.add_argument("--seeds", default="0", help="a seed or a range a-b (inclusive)")
    parser.add_argument("--momentum", type=float, default=None, help=f"override MOMENTUM ({vc.MOMENTUM})")
    parser.add_argument("--lead", type=float, default=None, help=f"override LEAD ({vc.LEAD})")
    args = parser.parse_args()
    if args.momentum is not None:
        vc.MOMENTUM = args.momentum
    if args.lead is not None:
        vc.LEAD = args.lead
    first, _, last = args.seeds.partition("-")
    seeds = range(int(first), int(last or first) + 1)
    print(machine())
    print(f"MOMENTUM = {vc.MOMENTUM}, LEAD = {vc.LEAD}")
    header = [
        "N",
        "seed",
        "success",
        "steps to rest / cap",
        "collisions / boundary / actuator / static contacts",
        "cost / ideal",
        "starts per robot (mean / max)",
        "reversals",
        "moving at each tenth of the cap",
        "wall (s)",
    ]
    print(table(header, [run(n, seed) for n in args.n for seed in seeds]))


if __name__ == "__main__":
    main()
