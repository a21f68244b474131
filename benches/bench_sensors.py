"""The swarm's infrared distance sensors: Rust ray casting against its NumPy reference, side by side.

    python benches/bench_sensors.py              # N = 100, 1,000 and 10,000 (reference up to 1,000)
    python benches/bench_sensors.py --quick      # N = 1,000 only

N robots, 7 rays each (range 1.2 m), on a jittered lattice with ~10 robots within 1 m of each
(as bench_kernels), among 20 random line-segment walls of 0.5-2 m crossing the swarm's area.
One call casts every robot's rays (``dream.kernels.distance_rays``): what one step of a swarm
of DistanceSensors needs. Target: <= 2 ms per step at N = 1,000.

Wall time depends on what else the machine runs; the "CPU" column (process CPU time per call,
summed over threads) does not, and bounds the wall time on an idle machine from above.
"""

from __future__ import annotations

import argparse
import datetime
import functools
import math
import os
import statistics
import time
from collections.abc import Callable

import numpy as np

from dream import _core, _reference, kernels
from dream.specs import ONBOARD
from harness import cpu_model, median_seconds, show, table

WALLS = 20
SPACING = 1.0 * math.sqrt(math.pi / 10)  #: lattice spacing for ~10 robots within 1 m


def median_cpu_seconds(call: Callable[[], object], repeat: int, loops: int = 20) -> float:
    """Median process CPU time of one ``call()`` (all threads), over ``repeat`` samples of ``loops`` calls."""
    samples = []
    for _ in range(repeat):
        start = time.process_time()
        for _ in range(loops):
            call()
        samples.append((time.process_time() - start) / loops)
    return statistics.median(samples)


def scene(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Poses ``(3, n)`` and walls ``(WALLS, 2, 2)``."""
    rng = np.random.default_rng(seed)
    columns = math.ceil(math.sqrt(n))
    lattice = np.column_stack(np.divmod(np.arange(n), columns)).astype(np.float64) * SPACING
    xy = lattice + rng.uniform(-SPACING / 4, SPACING / 4, (n, 2))
    poses = np.vstack((xy.T, rng.uniform(-np.pi, np.pi, n)))
    side = columns * SPACING
    starts = rng.uniform(0.0, side, (WALLS, 2))
    angles, lengths = rng.uniform(0, np.pi, WALLS), rng.uniform(0.5, 2.0, WALLS)
    ends = starts + lengths[:, None] * np.column_stack((np.cos(angles), np.sin(angles)))
    return poses, np.stack((starts, ends), axis=1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="N = 1,000 only")
    parser.add_argument("--repeat", type=int, default=7, help="timed samples per cell (median reported)")
    args = parser.parse_args()
    if _core is None:
        raise SystemExit("the compiled extension dream._core is not available: nothing to compare")

    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    print(f"# Distance sensors ({datetime.datetime.now().isoformat(timespec='seconds')})")
    print(f"machine: {cpu_model()}, {os.cpu_count()} logical cores; load average {load}")
    print(f"medians of {args.repeat} runs; {WALLS} walls; 7 rays of {ONBOARD.range} m per robot\n")

    rays = np.array(ONBOARD.rays)
    options = {"centre_offset": ONBOARD.centre_offset, "robot_diameter": ONBOARD.robot_diameter, "range": ONBOARD.range}
    rows = []
    for n in [1_000] if args.quick else [100, 1_000, 10_000]:
        poses, walls = scene(n)
        segments = walls.reshape(-1, 4)
        cast = functools.partial(kernels.distance_rays, poses, walls)
        reference = functools.partial(_reference.distance_rays, poses, segments, rays, **options)
        exact = cast()
        rust = median_seconds(cast, repeat=args.repeat)
        cpu = median_cpu_seconds(cast, repeat=args.repeat)
        if n <= 1_000:
            assert np.allclose(exact, reference(), rtol=0, atol=1e-12), "Rust and NumPy disagree"
            numpy = median_seconds(reference, repeat=args.repeat)
            cells = [show(numpy), f"{numpy / rust:.0f}x"]
        else:
            cells = ["not run (minutes)", "-"]
        seen = f"{np.mean(exact >= 0):.0%}"
        rows.append([f"distance_rays/n={n:,}", show(rust), show(cpu), *cells, seen])
    print(table(["kernel", "Rust", "Rust CPU", "NumPy reference", "ratio", "rays that see something"], rows))
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    print(f"\nload average after: {load}")


if __name__ == "__main__":
    main()
