"""A trained policy outside the environments: its weights file, the observation rows it reads (each
robot's k nearest detections and messages), and robots driven by it in `dream.run`, robot by
robot and as one swarm."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dream
from dream import Faults
from dream.rl import LinearPolicy, batch_env
from dream.rl.learner import driven

ROOT = Path(__file__).parents[2]
RENDEZVOUS = str(ROOT / "examples" / "rendezvous.py")
TRAINED = ROOT / "tests" / "data" / "rendezvous_policy.npz"


@pytest.mark.parametrize("k", [0, 1, 3, 7])
def test_observation_rows_hold_each_robots_k_nearest_detections_and_messages_in_order(k):
    env = batch_env(RENDEZVOUS, n=30, k=k, max_steps=60, faults=Faults(loss=0.3))
    env.reset(seed=4)
    for _ in range(25):  # past the start-up delays: detections and messages to pick from
        env.step(np.zeros((30, 2)))
    view, layout = env.team.views[0], env.team.layout
    rows = layout.rows(view, None)
    seen, heard = view.seen, view.heard
    assert seen.count.max() > k and heard.count.max() > k  # some robots have more than k to choose from
    for r in range(len(view)):
        part = layout.as_dict(rows[r])
        assert np.array_equal(
            part["pose"], np.float32([*view.pose[r, :2], np.cos(view.pose[r, 2]), np.sin(view.pose[r, 2])])
        )
        cut = slice(seen.offsets[r], seen.offsets[r + 1])
        order = np.argsort(seen["distance"][cut], kind="stable")[:k]
        want = np.column_stack([seen[c][cut] for c in ("dx", "dy", "vx", "vy")])[order]
        assert np.array_equal(part["seen"][: len(order)], want.astype(np.float32))
        assert np.array_equal(part["seen_mask"], np.arange(k) < len(order)) and not part["seen"][len(order) :].any()
        cut = slice(heard.offsets[r], heard.offsets[r + 1])
        offsets = np.column_stack((heard["x"][cut], heard["y"][cut])) - view.pose[r, :2]
        order = np.argsort((offsets**2).sum(axis=1), kind="stable")[:k]
        assert np.array_equal(part["heard"][: len(order)], offsets[order].astype(np.float32))
        assert np.array_equal(part["heard_mask"], np.arange(k) < len(order)) and not part["heard"][len(order) :].any()


def test_a_robots_action_does_not_depend_on_the_other_rows():
    policy = LinearPolicy.load(TRAINED)
    obs = np.random.default_rng(3).normal(0, 2, (500, policy.size)).astype(np.float32)
    together = policy(obs)
    assert np.array_equal(np.concatenate([policy(obs[i : i + 1]) for i in range(500)]), together)
    assert np.array_equal(policy(obs[123:130]), together[123:130])


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
