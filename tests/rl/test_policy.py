"""A trained policy outside the environments: its weights file, the observation padding it reads,
and robots driven by it in `dream.run`, robot by robot and as one swarm."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dream
from dream.rl import LinearPolicy
from dream.rl.learner import driven
from dream.rl.observation import padded
from dream.swarm import Neighbourhood

ROOT = Path(__file__).parents[2]
RENDEZVOUS = str(ROOT / "examples" / "rendezvous.py")
TRAINED = ROOT / "tests" / "data" / "rendezvous_policy.npz"


@pytest.mark.parametrize("k", [0, 1, 3, 7])
@pytest.mark.parametrize("counts", [[], [0], [5], [0, 3, 1, 0, 9, 2]])
def test_padded_keeps_each_rows_k_nearest_in_order(k, counts):
    rng = np.random.default_rng(len(counts) + k)
    offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    key = rng.integers(0, 4, offsets[-1]).astype(float)  # ties, to check that the first entry wins
    values = rng.normal(size=(offsets[-1], 3))
    out, mask = padded(Neighbourhood(offsets, {}), values, key, k)
    assert out.shape == (len(counts), k, 3) and mask.shape == (len(counts), k)
    for row, (start, stop) in enumerate(zip(offsets[:-1], offsets[1:])):
        want = start + np.argsort(key[start:stop], kind="stable")[:k]
        assert np.array_equal(mask[row], np.arange(k) < len(want))
        assert np.array_equal(out[row, : len(want)], values[want])
        assert not out[row, len(want) :].any()


def test_weights_file_round_trips_and_bad_files_are_refused(tmp_path):
    policy = LinearPolicy(np.arange(8.0).reshape(4, 2), [0.5, -0.5], k=3, avoid=True)
    policy.save(tmp_path / "p.npz")
    back = LinearPolicy.load(tmp_path / "p.npz")
    assert np.array_equal(back.weights, policy.weights) and np.array_equal(back.bias, policy.bias)
    assert (back.k, back.avoid) == (3, True)
    np.savez(tmp_path / "other.npz", w=np.zeros(3))
    with pytest.raises(ValueError, match="other.npz: not a LinearPolicy weights file"):
        LinearPolicy.load(tmp_path / "other.npz")
    with pytest.raises(ValueError, match=r"weights must have shape \(size, 2\)"):
        LinearPolicy(np.zeros((4, 3)), np.zeros(2))


def test_a_policy_of_the_wrong_size_is_refused():
    with pytest.raises(ValueError, match="the policy takes observations of 5 values, but this experiment's robots"):
        dream.run(driven(RENDEZVOUS, LinearPolicy.zeros(5)), n=4, steps=5, backend="fast")


def test_driven_robots_move_alike_robot_by_robot_and_as_a_swarm():
    cls = driven(RENDEZVOUS, LinearPolicy.load(TRAINED))
    one = dream.run(cls, n=6, seed=1, steps=120, backend="fast", trace=True)
    swarm = dream.run(cls, n=6, seed=1, steps=120, backend="fast", trace=True, swarm=True)
    assert np.array_equal(one.trace, swarm.trace)
    start, end = one.trace[0, :2], one.trace[-1, :2]
    spread = [np.hypot(*(p - p.mean(axis=1, keepdims=True))).max() for p in (start, end)]
    assert spread[1] < spread[0]  # the trained policy brings the team together
