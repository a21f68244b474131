"""Every experiment hands one Frame per step to `record`, consistent with its trace."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

import dream
from dream.experiments import EXPERIMENTS


@pytest.mark.parametrize("name", sorted(EXPERIMENTS))
def test_record_receives_one_frame_per_step(name):
    frames = []
    result = dream.run(name, steps=40, backend="fast", record=frames.append, trace=True)
    assert [f.step for f in frames] == list(range(1, result.steps + 1))
    assert_array_equal(frames[-1].poses, result.trace[-1])
    assert frames[-1].poses is not frames[-2].poses  # frames own their arrays
    n = result.n
    if frames[-1].goals is not None:
        assert frames[-1].goals.shape == (n, 2)
    if frames[-1].links is not None:
        assert frames[-1].links.shape[1] == 2 and np.all(frames[-1].links < n)
    assert name in frames[-1].title


@pytest.mark.parametrize("name", sorted(EXPERIMENTS))
def test_same_seed_same_trajectories(name):
    first = dream.run(name, steps=150, backend="fast", seed=5, trace=True)
    second = dream.run(name, steps=150, backend="fast", seed=5, trace=True)
    assert_array_equal(first.trace, second.trace)
    other = dream.run(name, steps=150, backend="fast", seed=6, trace=True)
    assert not np.array_equal(first.trace, other.trace)
