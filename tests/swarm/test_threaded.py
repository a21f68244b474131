"""Every robot of DREAM's own that decides in blocks on several threads
(:attr:`~dream.swarm.robot.SwarmRobot.threaded`) drives its swarm to the same poses, bit for bit, as
one call for all its rows: its decision reads its own rows alone. The blocks here are small, so
that a run of a hundred-odd robots cuts into several."""

from __future__ import annotations

import multiprocessing
import os
import time
from pathlib import Path

import numpy as np
import pytest

import dream
from dream.experiments.voronoi_coverage import CoverageRobot
from dream.faults import Faults
from dream.swarm import engine

EXAMPLE = str(Path(__file__).resolve().parents[2] / "examples" / "rendezvous.py")
FAULTS = Faults(loss=0.1, crash=0.05, crash_at=40, sensor_noise=0.002, latency=1, byzantine=2)


def trace(name, n, faults, monkeypatch, threads, **params):
    monkeypatch.setattr(engine, "LEAST_BLOCK", 2)
    monkeypatch.setattr(engine, "threads", lambda: threads)
    blocks, cut = [], engine.Engine._pieces

    def pieces(self, whole, bounds):
        blocks.append(len(bounds) - 1)
        return cut(self, whole, bounds)

    monkeypatch.setattr(engine.Engine, "_pieces", pieces)
    if name == "voronoi-coverage":  # not declared (see CoverageRobot), yet row by row all the same
        monkeypatch.setattr(CoverageRobot, "threaded", True)
    result = dream.run(name, n=n, steps=90, seed=4, backend="fast", swarm=True, trace=True, faults=faults, **params)
    assert max(blocks, default=1) == threads  # one block a thread, where the rows allow: the robot is threaded
    return result.trace


@pytest.mark.parametrize(
    "name, n, params",
    [
        ("hrvo-circle", 60, {}),
        ("line-consensus", 60, {}),
        ("affine-formation", 70, {}),
        ("voronoi-coverage", 60, {}),
        (EXAMPLE, 60, {"radius": 0.2}),  # not met within the run
    ],
    ids=["hrvo-circle", "line-consensus", "affine-formation", "voronoi-coverage", "rendezvous example"],
)
@pytest.mark.parametrize("faults", [None, FAULTS], ids=["no faults", "faults"])
def test_blocks_on_threads_give_the_poses_of_one_call(name, n, params, faults, monkeypatch):
    one = trace(name, n, faults, monkeypatch, 1, **params)
    blocks = trace(name, n, faults, monkeypatch, 4, **params)
    assert np.array_equal(one, blocks)
    assert not np.array_equal(one[0], one[-1])  # they moved


def test_a_forked_child_decides_in_blocks_on_threads_of_its_own(monkeypatch):
    monkeypatch.setattr(engine, "LEAST_BLOCK", 2)
    monkeypatch.setattr(engine, "threads", lambda: 3)
    list(engine._pool().map(time.sleep, [0.05] * 3))  # the parent's pool, every thread started
    context = multiprocessing.get_context("fork")
    ours, theirs = context.Pipe()
    child = context.Process(target=_run, args=(theirs, "hrvo-circle", 40))
    child.start()
    done = ours.poll(120)  # on the parent's dead threads, the child would wait forever
    child.kill()
    child.join()
    assert done and ours.recv() == "moved"


def _run(pipe, name, n):
    result = dream.run(name, n=n, steps=60, seed=1, backend="fast", swarm=True, trace=True)
    pipe.send("moved" if not np.array_equal(result.trace[0], result.trace[-1]) else "stood")


@pytest.mark.parametrize(("asked", "expected"), [("3", 3), ("0", None), ("", None), ("many", None)])
def test_the_decision_threads_follow_the_kernels_pool(monkeypatch, asked, expected):
    monkeypatch.setenv("RAYON_NUM_THREADS", asked)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert engine.threads() == (cores if expected is None else expected)  # rayon's default for 0 or none
