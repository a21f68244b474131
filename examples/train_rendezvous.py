"""Train a rendezvous policy with the cross-entropy method, in NumPy alone, in a few minutes (or,
with ``--torch``, a small network by a policy gradient in torch).

Every robot of ``examples/rendezvous.py`` runs the same linear policy (:class:`dream.rl.LinearPolicy`)
on what it knows: its odometry, the robots its movement sensor sees and the positions its radio
hears (:mod:`dream.rl.observation`). It acts on its own clock, and its reward is how much closer
it came to the team's centre, less collisions (the experiment's ``potential`` hook, see
:mod:`dream.rl.team`). The cross-entropy method samples policies around a mean, keeps the best
few and moves the mean to them: no gradient, no torch.

    python examples/train_rendezvous.py
    python examples/train_rendezvous.py --iterations 20 --out rendezvous_policy.npz
    dream export examples/rendezvous.py --policy rendezvous_policy.npz -o bundle
    python examples/train_rendezvous.py --torch  # dream.rl.MlpPolicy, needs torch (the rl extra)

``--torch`` trains a :class:`dream.rl.MlpPolicy` (two hidden layers of 64) by REINFORCE: every
robot samples its actions about the network's, and each action a robot chose (when its timer
fired) is made likelier by how much more reward that robot then earned than its teammates did
(discounted, from that step on). Its weights file is torch's (``.pt``): the lab bundle ships the
NumPy policy only.

It prints the mean return per robot of a random policy (uniform actions), of the untrained
policy (all weights zero: every robot stands still) and of the trained one, on seeds it did not
train on.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from dream.rl import BatchEnv, LinearPolicy, batch_env

EXPERIMENT = str(Path(__file__).with_name("rendezvous.py"))
Policy = Callable[[np.ndarray], np.ndarray]


def episode_return(env: BatchEnv, policy: Policy, seed: int) -> float:
    """The mean return per robot of one episode from ``seed``."""
    obs, _ = env.reset(seed=seed)
    total = 0.0
    while True:
        obs, rewards, terminated, truncated, _ = env.step(policy(obs))
        total += float(rewards.mean())
        if (terminated | truncated).all():
            return total


def mean_return(env: BatchEnv, policy: Policy, seeds: list[int]) -> float:
    return float(np.mean([episode_return(env, policy, seed) for seed in seeds]))


def train(
    env: BatchEnv, iterations: int, population: int, elite: int, seeds: list[int], rng: np.random.Generator
) -> LinearPolicy:
    """The cross-entropy method over the linear policy's parameters."""
    start = LinearPolicy.zeros(env.single_observation_space.shape[0], k=env.team.layout.k, avoid=True)
    mean, spread = start.flat, np.full(len(start.flat), 0.5)
    for iteration in range(iterations):
        candidates = mean + spread * rng.standard_normal((population, len(mean)))
        scores = np.array([mean_return(env, start.with_flat(c), seeds) for c in candidates])
        best = candidates[np.argsort(scores)[-elite:]]
        mean, spread = best.mean(axis=0), best.std(axis=0) + 0.02  # a floor keeps it searching
        print(f"iteration {iteration + 1}/{iterations}: best {scores.max():.3f}, mean {scores.mean():.3f}", flush=True)
    return start.with_flat(mean)


def train_torch(env: BatchEnv, iterations: int, seeds: list[int], discount: float = 0.95) -> Any:
    """REINFORCE on a :class:`dream.rl.MlpPolicy`, every robot's choices one batch (see the docs)."""
    import torch

    from dream.rl import MlpPolicy

    torch.manual_seed(0)
    # One thread: on tensors of a few robots, the thread pool's hand-offs cost more than they
    # save (ten times the time on a busy 2-core machine).
    torch.set_num_threads(1)
    policy = MlpPolicy(env.single_observation_space.shape[0], k=env.team.layout.k, avoid=True)
    optimiser = torch.optim.Adam(policy.parameters(), lr=3e-3)
    for iteration in range(iterations):
        loss, returns = torch.zeros(()), []
        for seed in seeds:
            obs, info = env.reset(seed=seed)
            chosen, rewards, acted = [], [], []
            while True:
                spread = policy.distribution(torch.as_tensor(obs))
                actions = spread.sample()
                acted.append(info["acts"])  # whose actions count: the others hold their commands
                obs, reward, terminated, truncated, info = env.step(actions.numpy())
                chosen.append(spread.log_prob(actions).sum(dim=1))
                rewards.append(reward)
                if (terminated | truncated).all():
                    break
            later = np.zeros_like(rewards[0])
            togo = np.zeros((len(rewards), len(later)))
            for t in range(len(rewards) - 1, -1, -1):
                togo[t] = later = rewards[t] + discount * later
            advantage = (togo - togo.mean(axis=1, keepdims=True)) * np.array(acted)
            advantage /= advantage.std() + 1e-8
            weight = torch.as_tensor(advantage, dtype=torch.float32)
            loss = loss - (torch.stack(chosen) * weight).sum() / max(1, int(np.sum(acted)))
            returns.append(float(np.sum(rewards, axis=0).mean()))
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        print(f"iteration {iteration + 1}/{iterations}: mean return {np.mean(returns):.3f}", flush=True)
    return policy


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=10, help="cross-entropy iterations (default 10)")
    parser.add_argument("--population", type=int, default=16, help="policies tried per iteration (default 16)")
    parser.add_argument("-n", type=int, default=10, help="robots (default 10)")
    parser.add_argument("--steps", type=int, default=200, help="steps per episode (default 200, 6.6 s)")
    parser.add_argument("--out", help="the trained weights file (default rendezvous_policy.npz, .pt with --torch)")
    parser.add_argument("--torch", action="store_true", help="train a dream.rl.MlpPolicy by REINFORCE (needs torch)")
    args = parser.parse_args(argv)
    env = batch_env(EXPERIMENT, n=args.n, max_steps=args.steps, avoid=True)  # HRVO keeps them apart
    rng = np.random.default_rng(0)
    start = time.perf_counter()
    out = args.out or f"rendezvous_policy.{'pt' if args.torch else 'npz'}"
    if args.torch:
        network = train_torch(env, args.iterations, [0, 1])
        network.save(out)
        trained: Policy = network.act
    else:
        linear = train(env, args.iterations, args.population, max(2, args.population // 4), [0, 1], rng)
        linear.save(out)
        trained = linear
    evaluation = [100, 101, 102]
    size = env.single_observation_space.shape[0]
    random = mean_return(env, lambda obs: rng.uniform(-1.0, 1.0, (len(obs), 2)), evaluation)
    untrained = mean_return(env, LinearPolicy.zeros(size), evaluation)
    ours = mean_return(env, trained, evaluation)
    print(f"mean return per robot on seeds {evaluation}, {args.n} robots, {args.steps} steps:")
    print(f"  random policy     {random:8.3f}")
    print(f"  untrained policy  {untrained:8.3f}")
    print(f"  trained policy    {ours:8.3f}  (+{ours - max(random, untrained):.3f} over the better of the two)")
    print(f"trained in {time.perf_counter() - start:.0f} s; weights in {out}")


if __name__ == "__main__":
    main()
