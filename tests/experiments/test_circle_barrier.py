"""hrvo-circle's arrival barrier (dream.rules.arc_merge): safe under stale, lost and arbitrary
messages, live on the ring, and the same rule robot by robot and in swarm mode."""

from __future__ import annotations

import numpy as np
import pytest

from dream import kernels, rules
from dream.experiments import hrvo_circle
from dream.swarm import Neighbourhood, View


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
    # One CircleRobot decides for 60 robots at once and for each robot alone: the same round.
    n = 60
    rng = np.random.default_rng(4)
    goals = hrvo_circle.circle_goals(n)
    robot = hrvo_circle.CircleRobot(hrvo_circle.circle_layout(n), hrvo_circle.PACKED_SAFETY, 30, hrvo_circle.SENSING)
    state = rng.integers(1, 3, size=n)
    memory = {key: np.full(n, value) for key, value in robot.memory.items()}
    memory.update(state=state, left=rng.integers(0, 4, size=n), right=rng.integers(0, 4, size=n), released=state - 1)
    memory.update(watch_left=rng.integers(-1, n, size=n), age_left=rng.integers(0, 30, size=n))
    positions = goals[:, 0] * (1 + 0.05 * rng.standard_normal((n, 1)))
    indptr, senders, _ = kernels.neighbours(positions, 1.0)
    fields = {key: memory[key][senders] for key in hrvo_circle.MESSAGE}

    def view(rows):
        cut = np.concatenate([np.arange(indptr[i], indptr[i + 1]) for i in rows])
        offsets = np.concatenate(([0], np.cumsum(np.diff(indptr)[rows])))
        heard = Neighbourhood(offsets, {"sender": senders[cut], **{key: fields[key][cut] for key in fields}})
        seen = Neighbourhood(np.zeros(len(rows) + 1, dtype=np.int64), {key: np.zeros(0) for key in SEEN})
        pose = np.column_stack((positions[rows], np.zeros(len(rows))))
        mine = {key: values[rows].copy() for key, values in memory.items()}
        return View(np.asarray(rows), np.full(len(rows), 50.0), pose, seen, heard, mine)

    swarm = view(np.arange(n))
    robot.decide(swarm)
    for i in range(n):
        alone = view([i])
        np.testing.assert_array_equal(robot.decide(alone), robot.decide(view([i])))
        for key, values in alone.memory.items():
            assert values[0] == swarm.memory[key][i], (i, key)
    assert (swarm.memory["left"] + swarm.memory["right"] > memory["left"] + memory["right"]).any()
    assert (swarm.memory["released"] == state).any()


SEEN = ("distance", "bearing", "dx", "dy", "vx", "vy")
