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
from dream.swarm import draws, engine, threads

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


def test_normal_draws_worked_out_on_threads_are_the_same_bits(monkeypatch):
    # A noisy sensor's normal draws are worked out in pieces, one a thread: the same numbers as
    # on one thread, at every shape (a row a message, the full broadcast, one number).
    cases = [
        (np.arange(10_001)[:, None] // 3, np.arange(10_001)[:, None], np.arange(4)),
        (np.arange(2_000), np.arange(3)[:, None]),
        (7,),
    ]
    monkeypatch.setattr(threads, "threads", lambda: 1)
    one = [draws.normal(5, draws.DETECTION_NOISE, 3, *keys) for keys in cases]
    pieces = []
    spread = threads.spread
    monkeypatch.setattr(draws, "spread", lambda work, size: pieces.append(size) or spread(work, size))
    monkeypatch.setattr(threads, "threads", lambda: 3)
    monkeypatch.setattr(threads, "LEAST_PIECE", 100)
    many = [draws.normal(5, draws.DETECTION_NOISE, 3, *keys) for keys in cases]
    for a, b in zip(one, many, strict=True):
        assert type(a) is type(b) and np.shape(a) == np.shape(b) and np.array_equal(a, b)
    assert pieces == [40_004, 6_000, 1]


@pytest.mark.parametrize(("size", "least", "expected"), [(1000, 100, 3), (250, 100, 2), (99, 100, 1), (0, 100, 1)])
def test_spread_cuts_the_items_into_one_piece_a_thread(monkeypatch, size, least, expected):
    monkeypatch.setattr(threads, "threads", lambda: 3)
    worked = []
    threads.spread(lambda piece: worked.append((piece.start, piece.stop)), size, least)
    assert len(worked) == expected
    covered = sorted(worked)
    assert covered[0][0] == 0 and covered[-1][1] == size
    assert all(a[1] == b[0] for a, b in zip(covered, covered[1:]))  # every item once
    assert all(stop - start >= min(least, size) for start, stop in worked)


def test_a_noisy_sensors_offsets_worked_out_on_threads_are_the_same_bits(monkeypatch):
    monkeypatch.setattr(threads, "threads", lambda: 3)
    monkeypatch.setattr(threads, "LEAST_PIECE", 100)
    rng = np.random.default_rng(0)
    distance, bearing = np.abs(rng.normal(size=1_001)), rng.uniform(-4.0, 4.0, 1_001)
    dx, dy = engine._offsets(distance, bearing)
    assert np.array_equal(dx, distance * np.cos(bearing)) and np.array_equal(dy, distance * np.sin(bearing))
