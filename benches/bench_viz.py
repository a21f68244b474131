"""Drawing speed: recording a video, and the live window (run it under a display).

    python benches/bench_viz.py                       # recording only (headless)
    xvfb-run -a -s "-screen 0 1920x1080x24" python benches/bench_viz.py   # and the live window

Frames come from real runs (hrvo-circle, Fast backend), collected first, so that only drawing
is timed. Each figure is the median over 7 runs; the machine, its load and the date are
printed with them (on a shared machine, the CPU time of this process is the steadier figure).
"""

from __future__ import annotations

import datetime
import os
import statistics
import tempfile
import time
from pathlib import Path

from dream.experiments import run
from dream.frames import Frame
from dream.viz import Recorder
from harness import table

RUNS = 7
STEPS = 90


def machine() -> str:
    model = "unknown CPU"
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    return f"{model}, {os.cpu_count()} cores, load average {load}, {datetime.datetime.now():%Y-%m-%d %H:%M}"


def frames(n: int) -> list[Frame]:
    out: list[Frame] = []
    run("hrvo-circle", n=n, backend="fast", steps=STEPS, record=out.append)
    return out


def per_frame(make: callable, shots: list[Frame]) -> tuple[float, float]:
    """Median over RUNS of (wall, CPU) milliseconds per frame drawn by a fresh ``make()`` recorder."""
    walls, cpus = [], []
    for _ in range(RUNS):
        recorder = make()
        recorder(shots[0])  # the first frame draws everything (and starts ffmpeg): not timed
        wall, cpu = time.perf_counter(), time.process_time()
        for frame in shots[1:]:
            recorder(frame)
        walls.append((time.perf_counter() - wall) / (len(shots) - 1) * 1e3)
        cpus.append((time.process_time() - cpu) / (len(shots) - 1) * 1e3)
        recorder.close()
    return statistics.median(walls), statistics.median(cpus)


def main() -> None:
    print(machine())
    rows = []
    ten = frames(10)
    with tempfile.TemporaryDirectory() as folder:
        for suffix in (".mp4", ".gif"):
            wall, cpu = per_frame(lambda s=suffix: Recorder(video=Path(folder) / f"run{s}"), ten)
            rows.append([f"record {suffix} n=10, 1280x800", f"{wall:.1f}", f"{cpu:.1f}", f"{1e3 / wall:.0f}"])
    if os.environ.get("DISPLAY"):
        import matplotlib

        matplotlib.use("TkAgg")
        fifty = frames(50)
        wall, cpu = per_frame(lambda: Recorder(show=True), fifty)
        rows.append(["live window n=50, 1280x800 (TkAgg)", f"{wall:.1f}", f"{cpu:.1f}", f"{1e3 / wall:.0f}"])
        rates = []
        for _ in range(RUNS):
            with Recorder(show=True) as recorder:
                rates.append(run("hrvo-circle", n=50, backend="fast", steps=STEPS, record=recorder).steps_per_second)
        rows.append(["run hrvo-circle n=50 --show, steps/s", "", "", f"{statistics.median(rates):.0f}"])
        plain = statistics.median(
            run("hrvo-circle", n=50, backend="fast", steps=STEPS).steps_per_second for _ in range(RUNS)
        )
        rows.append(["run hrvo-circle n=50 without drawing, steps/s", "", "", f"{plain:.0f}"])
    else:
        print("(no DISPLAY: live window not measured; run under xvfb-run)")
    print(table(["drawing", "ms/frame (wall)", "ms/frame (CPU)", "frames/s"], rows))
    print(machine())


if __name__ == "__main__":
    main()
