"""Robot by robot, the engine perceives and drives the deciding robots at once and calls decide
once per robot (:mod:`dream.swarm.byrobot`): each robot's view is its row of the swarm's, and
choices that only some robots make come out as the swarm's."""

from __future__ import annotations

import numpy as np
import pytest

import dream
from dream.swarm import Avoid, Movement, Radio, SwarmRobot, byrobot


def scene(n=12, seed=3):
    rng = np.random.default_rng(seed)
    return np.vstack((rng.uniform(-0.4, 0.4, (2, n)), rng.uniform(-np.pi, np.pi, n)))


class Choosy(SwarmRobot):
    """Each robot makes its own choices, or none: a robot alone calls a view's method only for
    itself, the swarm calls it for all, with what the others would have had anyway."""

    period = 1
    movement = Movement(range=0.5)
    radio = Radio(range=0.6, fields={"x": float, "id": int})
    avoid = Avoid(safety=0.24, sidestep=3)
    memory = {"count": 0, "last": np.nan, "heard": 0.0}

    def decide(self, view):
        ids, alone = view.ids, len(view) == 1
        tight, straight, aside, quiet = ids % 3 == 0, ids % 4 == 1, ids % 5 == 2, ids % 2 == 0
        if not alone or tight.all():
            view.keep_apart(np.where(tight, 0.15, 0.24))
        if not alone or straight.all():
            view.direct(straight)
        if not alone or aside.all():
            view.aside(np.where(aside, -1.0, 0.0), stop=aside & (view.clock > 4))
        heeds = ids % 2 == 1  # heeds only the robots within 0.3 m
        if not alone or heeds.all():
            view.heed(~heeds[view.seen.owner] | (view.seen["distance"] < 0.3))
        if not alone or not quiet.all():
            view.send(where=~quiet, x=view.pose[:, 0], id=ids)
        view.memory["count"] += 1  # in place, on the robot's own row
        view.memory["last"] = view.clock
        forgets = ids % 6 == 5  # keeps what it heard before
        if alone and forgets.all():
            view.memory["heard"] += 100.0  # on its own row, then forgotten: the memory keeps the old value
            del view.memory["heard"]
        else:
            view.memory["heard"] = np.where(forgets, view.memory["heard"], view.heard.sum("x"))
        return 0.1 * np.column_stack((np.cos(ids + view.clock), np.sin(ids - view.clock)))


def run(robot, one_by_one, steps=12, count_traffic=True):
    n = 12
    engine = dream.swarm.Engine(robot, n, 0, dream.specs.ROBOTARIUM, one_by_one=one_by_one is True)
    engine.count_traffic = count_traffic
    x, commands, out = scene(n), np.zeros((2, n)), []
    for t in range(steps):
        commands = engine.step(t, x, commands)
        x = x + 0.033 * np.vstack((commands[0] * np.cos(x[2]), commands[0] * np.sin(x[2]), commands[1]))
        out.append(commands)
    return engine, np.array(out)


def assert_same_state(engine, other):
    """The two engines' robots ended with the same state, memory and message counts."""
    for name in ("dxi", "sidestep", "side", "sent_at", "belief"):
        assert np.array_equal(getattr(engine, name), getattr(other, name), equal_nan=True), name
    for key in other.memory:
        assert np.array_equal(engine.memory[key], other.memory[key], equal_nan=True), key
    for name in ("sent", "heard", "lost"):
        assert np.array_equal(getattr(engine.traffic, name), getattr(other.traffic, name)), name


@pytest.mark.parametrize("count_traffic", [True, False], ids=["inbox found at once", "inbox found when read"])
def test_choices_some_robots_make_come_out_as_the_swarms(count_traffic):
    one, alone = run(Choosy(), True, count_traffic=count_traffic)
    swarm, together = run(Choosy(), False, count_traffic=count_traffic)
    assert np.array_equal(alone, together)  # bit for bit, every step
    assert_same_state(one, swarm)
    assert one.memory["count"].tolist() == [11] * 12 and (one.memory["heard"][:5] != 0).all()
    assert one.memory["heard"][[5, 11]].tolist() == [0.0, 0.0]  # forgotten each time
    assert (one.traffic.heard > 0).any() == count_traffic  # counted only when asked to
    assert (one.traffic.sent > 0).tolist() == [count_traffic and i % 2 == 1 for i in range(12)]  # odd ids send
    assert (one.sidestep > 0).any() or (one.side < 0).any()  # someone was blocked and stepped aside


class Threaded(Choosy):
    """Choosy, decided in blocks on several threads: notes the rows of each call (a test's record)."""

    threaded = True

    def __init__(self):
        self.calls = []

    def decide(self, view):
        self.calls.append(view.ids.tolist())
        return super().decide(view)


@pytest.mark.parametrize("count_traffic", [True, False], ids=["inbox found at once", "inbox found when read"])
def test_blocks_decided_on_threads_come_out_as_the_swarms(monkeypatch, count_traffic):
    monkeypatch.setattr(dream.swarm.engine, "LEAST_BLOCK", 3)
    monkeypatch.setattr(dream.swarm.engine, "threads", lambda: 4)
    threaded = Threaded()
    blocks, apart = run(threaded, False, count_traffic=count_traffic)
    swarm, together = run(Choosy(), False, count_traffic=count_traffic)
    assert np.array_equal(apart, together)  # bit for bit, every step
    assert_same_state(blocks, swarm)
    decided = [call for call in threaded.calls if len(call) > 0]
    assert sorted(map(len, decided[:4])) == [3, 3, 3, 3]  # every step: four blocks of three rows
    assert sorted(sum(decided[:4], [])) == list(range(12))


def test_blocks_of_a_swarm_are_at_least_the_least_block():
    assert byrobot.blocks(100, 16, 40) == [0, 50, 100]
    assert byrobot.blocks(79, 16, 40) is None  # one block: decided as it is
    assert byrobot.blocks(10, 4, 1) == [0, 2, 5, 7, 10]


def test_each_robot_gets_its_own_row_of_the_swarms_view():
    n, x = 12, scene()
    engine = dream.swarm.Engine(Choosy(), n, 0, dream.specs.ROBOTARIUM, one_by_one=True)
    whole = dream.swarm.Engine(Choosy(), n, 0, dream.specs.ROBOTARIUM)
    for t in (0, 1):  # a round of messages on the air (the robots decide first at step 1)
        engine.step(t, x, np.zeros((2, n)))
        whole.step(t, x, np.zeros((2, n)))
    last = np.vstack((np.linspace(0.0, 0.1, n), np.linspace(-1.0, 1.0, n)))  # the commands they gave
    views = engine.perceive(2, x, last)
    (view,) = whole.perceive(2, x, last)
    assert view.heard.offsets[-1] > 0 and view.seen.offsets[-1] > 0
    assert [len(v) for v in views] == [1] * n and [int(v.ids[0]) for v in views] == view.ids.tolist()
    for r, mine in enumerate(views):
        assert np.array_equal(mine.pose, view.pose[r : r + 1]) and np.array_equal(mine.clock, view.clock[r : r + 1])
        assert np.array_equal(mine.command, last[:, mine.ids].T)
        assert np.array_equal(mine.command, view.command[r : r + 1])
        for hood, rows in ((mine.seen, view.seen), (mine.heard, view.heard), (mine.obstacles, view.obstacles)):
            cut = slice(rows.offsets[r], rows.offsets[r + 1])
            assert hood.offsets.tolist() == [0, cut.stop - cut.start] and hood.names == rows.names
            for name in rows.names:
                assert np.array_equal(hood[name], rows[name][cut])
        assert mine.memory.keys() == view.memory.keys()
        for key, values in view.memory.items():
            assert np.array_equal(mine.memory[key], values[r : r + 1], equal_nan=True)
    for array in (views[0].ids, views[0].command, views[0].seen.offsets, views[0].seen["dx"], views[0].heard["x"]):
        with pytest.raises(ValueError, match="read-only"):
            array[...] = 0
    views[0].memory["count"] += 5  # a robot's memory is its own
    assert views[0].memory["count"][0] == 6 and views[1].memory["count"][0] == 1


def test_views_not_cut_by_the_engine_are_carried_out_one_by_one():
    n, x = 12, scene()
    engine = dream.swarm.Engine(Choosy(), n, 0, dream.specs.ROBOTARIUM, one_by_one=True)
    views = engine.perceive(1, x, np.zeros((2, n)))
    wishes = [engine.robot.decide(view) for view in views]
    apart = engine.act(1, views[:5], wishes[:5], np.zeros((2, n)))  # some of them: each on its own
    assert (apart[:, 5:] == 0).all() and (apart[:, :5] != 0).any()
    again = dream.swarm.Engine(Choosy(), n, 0, dream.specs.ROBOTARIUM, one_by_one=True)
    pieces = again.perceive(1, x, np.zeros((2, n)))
    together = again.act(1, pieces, [again.robot.decide(view) for view in pieces], np.zeros((2, n)))
    assert np.array_equal(apart[:, :5], together[:, :5])


def test_an_empty_neighbourhood_cuts_into_empty_rows():
    hood = dream.swarm.Neighbourhood(np.zeros(4, dtype=np.int64), {"dx": np.zeros(0)}).frozen()
    rows = byrobot._rows(hood, range(4))
    assert [row.offsets.tolist() for row in rows] == [[0, 0]] * 3 and all(row.read_only for row in rows)


class Failing(Threaded):
    """Fails in the block that holds robot 7, as a user's rule may."""

    def decide(self, view):
        if 7 in view.ids:
            raise ArithmeticError("robot 7 divided by zero")
        return super().decide(view)


def test_an_error_in_a_block_reaches_the_caller_and_keeps_the_memory(monkeypatch):
    monkeypatch.setattr(dream.swarm.engine, "LEAST_BLOCK", 3)
    monkeypatch.setattr(dream.swarm.engine, "threads", lambda: 4)
    n, x = 12, scene()
    engine = dream.swarm.Engine(Failing(), n, 0, dream.specs.ROBOTARIUM)
    before = {key: values.copy() for key, values in engine.memory.items()}
    with pytest.raises(ArithmeticError, match="robot 7"):
        engine.step(1, x, np.zeros((2, n)))
    for key, values in before.items():  # no block's memory was written back
        assert np.array_equal(engine.memory[key], values, equal_nan=True), key
