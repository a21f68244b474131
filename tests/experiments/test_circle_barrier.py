"""hrvo-circle's arrival barrier (dream.rules.arc_merge): safe under stale, lost and arbitrary
messages, live on the ring, and the same rule robot by robot and in swarm mode."""

from __future__ import annotations

import numpy as np
import pytest

from dream import rules
from dream.experiments import hrvo_circle


def _round(n, mine, heard, rows, senders):
    """One round of the rule for every robot: ``mine`` and ``heard`` ``(4, n)`` [state, left,
    right, released] (what each robot holds, and what each sent, possibly long ago)."""
    state, left, right, released = mine
    merged = rules.arc_merge(n, state, left, right, released, rows, (senders - rows) % n, heard[:, senders].T)
    return merged[0], merged[1], rules.arc_release(n, state, *merged)


@pytest.mark.parametrize("seed", range(4))
def test_barrier_never_releases_a_level_some_robot_has_not_reached(seed):
    # Robots reach their goals at random times; each round every robot hears a random handful
    # of others (any ids, anywhere), 30 % of messages are lost and each is up to 6 rounds old.
    rng = np.random.default_rng(seed)
    n, goals = 23, 3
    state = np.zeros(n, dtype=np.int64)
    left, right, released = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
    moving = np.ones(n, dtype=bool)  # heading for its next goal
    history = []
    for _ in range(3000):
        arrive = moving & (rng.random(n) < 0.05)
        state[arrive] += 1
        left[arrive] = right[arrive] = 0
        moving &= ~arrive
        history = [np.stack((state, left, right, released))] + history[:6]
        rows = np.repeat(np.arange(n), 4)
        senders = rng.integers(0, n, size=len(rows))
        kept = (rng.random(len(rows)) > 0.3) & (senders != rows)
        rows, senders = rows[kept], senders[kept]
        heard = history[int(rng.integers(len(history)))]  # one stale snapshot a round
        left, right, released = _round(n, (state, left, right, released), heard, rows, senders)
        for i in range(n):  # every arc claims only robots at or beyond the robot's level
            arc = (i + np.arange(-left[i], right[i] + 1)) % n
            assert np.all(state[arc] >= state[i])
        assert np.all(released <= state.min())  # released: every robot has got there
        go = rules.moves_on(state, released >= state, moving, goals)
        moving |= go
        if state.min() == goals:
            break
    assert state.min() == goals  # and it is live: everyone finished


def test_barrier_releases_a_ring_within_a_pass_around_it():
    # Robots on the ring's goals, each hearing its ring neighbours at most 2 ids away: after the
    # last arrival, the arcs close within about n / 4 rounds and the release follows.
    n = 40
    state = np.ones(n, dtype=np.int64)
    zeros = np.zeros(n, dtype=np.int64)
    mine = (state, zeros, zeros, zeros)
    rows = np.repeat(np.arange(n), 4)
    senders = (rows + np.tile([-2, -1, 1, 2], n)) % n
    rounds, released = 0, zeros
    while not np.all(released == 1) and rounds < n:
        left, right, released = _round(n, mine, np.stack(mine), rows, senders)
        mine, rounds = (state, left, right, released), rounds + 1
    assert np.all(released == 1) and rounds <= n // 4 + 2


def test_robot_and_swarm_take_the_same_barrier_step():
    n = 60
    rng = np.random.default_rng(4)
    goals = hrvo_circle.circle_goals(n)
    team = hrvo_circle.CircleSwarm.start(goals)
    team.state = rng.integers(1, 3, size=n)
    team.left, team.right = rng.integers(0, 4, size=n), rng.integers(0, 4, size=n)
    team.released = team.state - 1
    positions = goals[:, 0] * (1 + 0.05 * rng.standard_normal((n, 1)))
    robots = []
    for i in range(n):
        robot = hrvo_circle.CircleRobot(i, f"robot_{i}", goals[i], n)
        robot.state, robot.left, robot.right, robot.released = (
            int(team.state[i]),
            int(team.left[i]),
            int(team.right[i]),
            int(team.released[i]),
        )
        robot.change_state = True  # travelling: it only learns
        robots.append(robot)
    sent = [(i, r.state, r.left, r.right, r.released, np.zeros(n, dtype=np.int64)) for i, r in enumerate(robots)]
    hrvo_circle._radio_round(team, positions)
    for i, robot in enumerate(robots):
        near = np.hypot(*(positions - positions[i]).T) <= 1.0
        robot.update_radio([sent[j] for j in np.flatnonzero(near) if j != i])
        assert (robot.left, robot.right, robot.released) == (team.left[i], team.right[i], team.released[i])
    assert team.left.sum() + team.right.sum() > 0 and (team.released == team.state).any()
