"""dream.rl's environments: PettingZoo's and Gymnasium's own checks, and what a robot observes and
does (its own knowledge, its own clock, faults, seeds)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

from dream import Experiment, Faults
from dream.rl import batch_env, parallel_env, team_env
from dream.rl.observation import Layout

ROOT = Path(__file__).parents[2]
RENDEZVOUS = str(ROOT / "examples" / "rendezvous.py")


@pytest.mark.parametrize("experiment", ["hrvo-circle", "line-consensus", RENDEZVOUS])
def test_parallel_env_passes_pettingzoos_api_test(experiment):
    parallel_api_test(parallel_env(experiment, n=10), num_cycles=200)


@pytest.mark.parametrize(("experiment", "n"), [("affine-formation", 7), ("voronoi-coverage", 10)])
def test_every_built_in_is_a_learning_world(experiment, n):
    # The learner takes the robots' place: the operator's orders to affine-formation's leaders
    # and voronoi-coverage's own sensors stay out of its way.
    parallel_api_test(parallel_env(experiment, n=n), num_cycles=60)


@pytest.mark.filterwarnings("ignore:.*Box observation space m..imum value is .*infinity")
def test_team_env_passes_gymnasiums_checker():
    check_env(team_env("hrvo-circle", n=5, max_steps=40), skip_render_check=True)


def test_observations_are_in_their_space_and_agents_are_robots():
    env = parallel_env(RENDEZVOUS, n=6, max_steps=60)
    obs, infos = env.reset(seed=2)
    assert env.agents == [f"robot_{i}" for i in range(6)]
    seen_any = heard_any = False
    while env.agents:
        obs, rewards, terminated, truncated, infos = env.step({a: env.action_space(a).sample() for a in env.agents})
        for agent, ob in obs.items():
            assert env.observation_space(agent).contains(ob)
            seen_any |= bool(ob["seen_mask"].any())
            heard_any |= bool(ob["heard_mask"].any())
    assert seen_any and heard_any  # the padding holds detections and messages, not only zeros


def run(env, seed, actions):
    """The observations of one episode, with ``actions(step, n)`` for every robot."""
    obs, info = env.reset(seed=seed)
    out = [obs]
    for t in range(env.team.cap):
        obs, _, terminated, truncated, info = env.step(actions(t, env.num_envs))
        out.append(obs)
        if (terminated | truncated).all():
            break
    return np.array(out)


def test_runs_are_seeded():
    env = batch_env(RENDEZVOUS, n=8, max_steps=40, faults=Faults(loss=0.3))
    rng = np.random.default_rng(5)
    actions = rng.uniform(-1, 1, (40, 8, 2))
    first = run(env, 7, lambda t, n: actions[t])
    assert np.array_equal(first, run(env, 7, lambda t, n: actions[t]))
    assert not np.array_equal(first, run(env, 8, lambda t, n: actions[t]))


def test_a_robot_acts_only_when_its_timer_fires():
    env = batch_env(RENDEZVOUS, n=8, max_steps=40)
    acting = []

    def actions(t, n, noise=None):
        acts = env.team.acting.copy()
        acting.append(acts)
        out = np.where(acts[:, None], 0.8, 0.0) * np.ones((n, 2))
        return out if noise is None else np.where(acts[:, None], out, noise[t])

    held = run(env, 3, actions)
    noise = np.random.default_rng(0).uniform(-1, 1, (40, 8, 2))
    assert np.array_equal(held, run(env, 3, lambda t, n: actions(t, n, noise)))  # idle robots' actions ignored
    counts = np.array(acting).sum(axis=0)
    assert 0 < counts.min() and counts.max() < len(acting)  # on their own clocks: not every step


def test_lost_messages_never_reach_an_observation():
    layout = Layout(4, goals=False)
    heard = layout.slices["heard_mask"]
    lossless = run(batch_env(RENDEZVOUS, n=8, max_steps=60), 0, lambda t, n: np.zeros((n, 2)))
    lossy = run(batch_env(RENDEZVOUS, n=8, max_steps=60, faults=Faults(loss=1.0)), 0, lambda t, n: np.zeros((n, 2)))
    assert lossless[..., heard].any() and not lossy[..., heard].any()


def test_a_crashed_robot_leaves_the_agents():
    env = parallel_env(RENDEZVOUS, n=10, max_steps=80, faults=Faults(crash=0.3, crash_at=20))
    env.reset(seed=0)
    left = set()
    while env.agents:
        before = set(env.agents)
        _, rewards, terminated, truncated, _ = env.step({a: np.zeros(2, np.float32) for a in env.agents})
        gone = before - set(env.agents)
        if env.team.t < env.team.cap:
            assert all(terminated[a] for a in gone)
            left |= gone
    crashed = {f"robot_{i}" for i in np.flatnonzero(env.team.crashed)}
    assert crashed and left == crashed


def test_goals_reward_progress_and_violations_cost():
    env = batch_env("hrvo-circle", n=4, max_steps=30)
    obs, _ = env.reset(seed=1)
    goal = env.team.layout.slices["goal"]
    towards = []
    for _ in range(30):  # every robot heads for its goal: each step's reward is its progress
        wish = obs[:, goal] / np.maximum(np.linalg.norm(obs[:, goal], axis=1, keepdims=True), 1e-9)
        obs, rewards, terminated, truncated, _ = env.step(wish)
        towards.append(rewards)
    assert np.sum(towards) > 0.1
    still = batch_env("hrvo-circle", n=4, max_steps=30)
    still.reset(seed=1)
    assert all(still.step(np.zeros((4, 2)))[1].sum() == 0 for _ in range(30))


def test_unicycle_actions_drive_the_wheels():
    env = batch_env("hrvo-circle", n=4, max_steps=10, action="unicycle")
    env.reset(seed=0)
    before = env.team.sim.poses
    for _ in range(10):
        env.step(np.tile([1.0, 0.0], (4, 1)))
    moved = np.hypot(*(env.team.sim.poses[:2] - before[:2]))
    assert np.all(moved > 0.5 * 9 * 0.033 * env.team.engine.limits.v_max)


def test_render_draws_through_dream_viz():
    env = parallel_env("hrvo-circle", n=4, render_mode="rgb_array")
    env.reset(seed=0)
    image = env.render()
    assert image.dtype == np.uint8 and image.shape[2] == 3 and image.std() > 0


class ObjectsOnly(Experiment):
    """Robot objects and timers (``build``), no swarm robot: nothing a learner can take over."""

    name = "objects-only"

    def build(self, n):
        pass


@pytest.mark.parametrize(
    ("experiment", "options", "message"),
    [
        (ObjectsOnly, {}, r"objects-only has no swarm robot .* \(hrvo-circle, line-consensus\)"),
        ("hrvo-circle", {"action": "unicycle", "avoid": True}, "avoid .HRVO. works on wished velocities"),
        ("hrvo-circle", {"action": "wheels"}, "action must be one of velocity, unicycle"),
        ("hrvo-circle", {"k": -1}, r"k \(detections and messages observed\)"),
        ("hrvo-circle", {"radio_gap": 0}, "parameter 'radio_gap' of hrvo-circle must be >= 1"),
    ],
)
def test_bad_options_are_refused_by_name(experiment, options, message):
    with pytest.raises(ValueError, match=message):
        parallel_env(experiment, n=4, **options)


def test_actions_of_the_wrong_shape_are_refused():
    env = batch_env("hrvo-circle", n=4, max_steps=10)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions must be finite, of shape \(n, 2\) = \(4, 2\)"):
        env.step(np.zeros((3, 2)))
