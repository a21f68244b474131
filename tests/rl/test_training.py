"""examples/train_rendezvous.py runs briefly: it prints the three returns and writes its weights."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

from dream.rl import LinearPolicy

SCRIPT = Path(__file__).parents[2] / "examples" / "train_rendezvous.py"


def test_train_rendezvous_prints_the_returns_and_writes_the_weights(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("train_rendezvous", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = tmp_path / "policy.npz"
    module.main(["--iterations", "1", "--population", "2", "-n", "4", "--steps", "15", "--out", str(out)])
    printed = capsys.readouterr().out
    for name in ("random policy", "untrained policy", "trained policy"):
        assert re.search(rf"{name} +-?\d+\.\d+", printed)
    policy = LinearPolicy.load(out)
    assert policy.avoid and policy.k == 4 and policy.weights.any()
