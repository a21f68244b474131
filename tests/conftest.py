"""Shared fixtures: a seeded generator, an isolated world for every test, and a config folder (the
checkpoint key) of the test session's own, never the user's."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from dream import World


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


@pytest.fixture(autouse=True)
def world() -> World:
    """Each test runs in a fresh, seeded world: no messages or timers leak between tests."""
    with World(seed=7) as w:
        yield w


@pytest.fixture(autouse=True, scope="session")
def config_home(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """``XDG_CONFIG_HOME`` for the session (and the processes it starts): a temporary folder."""
    folder = tmp_path_factory.mktemp("config")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("XDG_CONFIG_HOME", str(folder))
        yield folder
