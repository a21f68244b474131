"""The bindings read a C-ordered array in place and copy any other: the Rust kernels give the same
answers, to the bit, for C-ordered, Fortran-ordered and strided inputs, and leave them as they were."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import _core


@pytest.fixture
def swarm():
    rng = np.random.default_rng(3)
    n = 400
    poses = np.vstack((rng.uniform(-3, 3, (2, n)), rng.uniform(-np.pi, np.pi, n)))
    commands = np.vstack((rng.uniform(-0.2, 0.2, n), rng.uniform(-2, 2, n)))
    return poses, commands


def layouts(array):
    """``array`` C-ordered, Fortran-ordered and as a strided view of a larger array."""
    wide = np.zeros((array.shape[0], 2 * array.shape[1])) if array.ndim == 2 else np.zeros(2 * len(array))
    strided = wide[:, ::2] if array.ndim == 2 else wide[::2]
    strided[...] = array
    return [np.ascontiguousarray(array), np.asfortranarray(array), strided]


def same(a, b):
    if isinstance(a, tuple):
        return all(same(x, y) for x, y in zip(a, b, strict=True))
    return np.array_equal(np.asarray(a), np.asarray(b))


def test_dynamics_kernels_read_any_layout_alike(swarm):
    poses, commands = swarm
    checks = dict(diameter=0.11, wheel_radius=0.016, base_length=0.105, max_wheel=12.5)
    calls = [
        lambda p, u: _core.unicycle_step(p, u, 0.033),
        lambda p, u: _core.validate(p, u, (-2.0, 2.0, -2.0, 2.0), **checks),
        lambda p, u: _core.dxu_to_dxi(u, p[2], 0.05),
    ]
    for call in calls:
        want = call(*(layouts(a)[0] for a in (poses, commands)))
        for p, u in zip(layouts(poses), layouts(commands)):
            kept = p.copy(), u.copy()
            assert same(call(p, u), want)
            assert_array_equal(p, kept[0])  # read, never written
            assert_array_equal(u, kept[1])


def test_perceive_reads_any_layout_alike(swarm):
    poses, commands = swarm
    rows = np.arange(0, poses.shape[1], 3)
    talking = np.ones(poses.shape[1], dtype=bool)

    def call(positions, headings, vx):
        return _core.perceive(
            positions, headings, rows, sight=(0.8, 4.0, 0.0), radio_range=1.2, talking=talking, carried=[vx]
        )

    want = call(np.ascontiguousarray(poses[:2].T), *layouts(poses[2])[:1], *layouts(commands[0])[:1])
    for positions, headings, vx in zip(layouts(poses[:2].T), layouts(poses[2]), layouts(commands[0])):
        assert same(call(positions, headings, vx), want)
