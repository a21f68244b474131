"""The torch path of dream.rl (the rl extra's torch; skipped where torch is not installed, as in
CI's test extra): dream.rl.MlpPolicy and examples/train_rendezvous.py --torch."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from dream.rl import MlpPolicy, batch_env  # noqa: E402  (after the skip: it imports torch)

ROOT = Path(__file__).parents[2]
SCRIPT = ROOT / "examples" / "train_rendezvous.py"
RENDEZVOUS = str(ROOT / "examples" / "rendezvous.py")


def test_mlp_policy_acts_within_bounds_and_its_weights_file_round_trips(tmp_path):
    torch.manual_seed(1)
    policy = MlpPolicy(7, (5, 3), k=2, avoid=True)
    obs = np.random.default_rng(0).normal(0, 10, (9, 7)).astype(np.float32)
    actions = policy.act(obs)
    assert actions.shape == (9, 2) and np.all(np.abs(actions) <= 1) and actions.std() > 0
    sample = policy.distribution(torch.as_tensor(obs)).sample()
    assert sample.shape == (9, 2) and not torch.equal(sample, torch.as_tensor(actions, dtype=torch.float32))
    policy.save(tmp_path / "p.pt")
    back = MlpPolicy.load(tmp_path / "p.pt")
    assert (back.size, back.hidden, back.k, back.avoid) == (7, (5, 3), 2, True)
    assert np.array_equal(back.act(obs), actions)
    (tmp_path / "other.pt").write_bytes(b"not torch")
    with pytest.raises(ValueError, match="other.pt: not an MlpPolicy weights file"):
        MlpPolicy.load(tmp_path / "other.pt")
    with pytest.raises(ValueError, match="size and hidden widths must be whole numbers >= 1"):
        MlpPolicy(7, (0,))


def test_the_exploration_is_about_the_mean_action_and_trains_every_parameter():
    env = batch_env(RENDEZVOUS, n=6, max_steps=40)
    obs, _ = env.reset(seed=0)
    for _ in range(20):  # past the start-up delays: rows with detections and messages
        obs = env.step(np.zeros((6, 2)))[0]
    torch.manual_seed(0)
    policy = MlpPolicy(obs.shape[1], spread=0.3)
    spread = policy.distribution(torch.as_tensor(obs))
    assert np.allclose(spread.mean.detach().numpy(), policy.act(obs)) and torch.allclose(
        spread.stddev, torch.tensor(0.3)
    )
    spread.log_prob(spread.sample()).sum().backward()
    assert all(p.grad is not None and p.grad.abs().sum() > 0 for p in policy.parameters())


def test_train_rendezvous_with_torch_prints_the_returns_and_writes_the_weights(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("train_rendezvous", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = tmp_path / "policy.pt"
    module.main(["--torch", "--iterations", "2", "-n", "4", "--steps", "15", "--out", str(out)])
    printed = capsys.readouterr().out
    assert re.search(r"iteration 2/2: mean return -?\d+\.\d+", printed)
    for name in ("random policy", "untrained policy", "trained policy"):
        assert re.search(rf"{name} +-?\d+\.\d+", printed)
    policy = MlpPolicy.load(out)
    assert policy.avoid and policy.k == 4 and policy.size == 36
