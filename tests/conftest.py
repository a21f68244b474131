"""Shared fixtures: a seeded generator and an isolated world for every test."""

from __future__ import annotations

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
