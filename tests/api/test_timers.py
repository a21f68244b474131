"""Timers: start-up delay, per-entry gaps, arguments by tag, world isolation and errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dream import Timer, World, create_timer, timers, update_timers
from dream.world import current_world


def _recorder(log, name=None):
    """A callback that appends (name, args) to ``log``."""

    def call(*args):
        log.append((name, args))

    return call


def _run(timer_delay, gap, times):
    """Times at which a single entry with ``gap`` fires, for the given update times."""
    fired = []
    timer = Timer(0, timer_delay, [{"delay": gap, "tag": "t", "call": lambda now: fired.append(now)}])
    for now in times:
        timer.update(now, {"t": (now,)})
    return fired


# Sequences worked out by hand from the rule: off while t <= start-up delay, then fire when
# t - last >= gap, last starting at 0 and set to t on each activation.
@pytest.mark.parametrize(
    ("timer_delay", "gap", "times", "expected"),
    [
        (0, 3, range(13), [3, 6, 9, 12]),  # t=0 is within the start-up delay
        (0, 1, range(5), [1, 2, 3, 4]),
        (5, 0, range(9), [6, 7, 8]),  # nothing up to and including t=5
        (5, 1, range(9), [6, 7, 8]),
        (5, 4, range(13), [6, 10]),  # 6 - 0 >= 4 already at the first live tick
        (2, 10, range(13), [10]),  # the gap counts from 0, not from the end of the delay
        (0, 3, range(0, 13, 2), [4, 8, 12]),  # last = the time it fired, not last + gap
        (0, 2.5, range(13), [3, 6, 9, 12]),  # fractional gaps compare as numbers
        (20, 4, range(30), [21, 25, 29]),  # the circle experiment's robot timer (start 20)
    ],
)
def test_timer_update_fires_at_expected_times(timer_delay, gap, times, expected):
    assert _run(timer_delay, gap, times) == expected


def test_timer_update_start_up_delay_boundary():
    # Exactly at current_time == delay nothing runs; one step later it does.
    assert _run(7, 0, [7]) == []
    assert _run(7, 0, [8]) == [8]


def test_timer_update_passes_params_of_its_tag():
    received = []
    timer = Timer(2, 0, [{"delay": 1, "tag": "radio", "call": lambda *args: received.append(args)}])
    x = np.arange(6.0).reshape(3, 2)
    timer.update(1, {"radio": (x, "second", 3), "other": ("wrong",)})
    assert len(received) == 1
    args = received[0]
    assert len(args) == 3
    assert args[0] is x  # passed as is, not copied
    assert args[1:] == ("second", 3)


def test_timer_update_accepts_list_of_arguments():
    received = []
    timer = Timer(0, 0, [{"delay": 0, "tag": "a", "call": lambda p, q: received.append((p, q))}])
    timer.update(1, {"a": [4, 5]})
    assert received == [(4, 5)]


def test_timer_update_several_entries_with_their_own_tags_and_gaps():
    log = []
    timer = Timer(
        0,
        0,
        [
            {"delay": 2, "tag": "a", "call": _recorder(log, "a")},
            {"delay": 3, "tag": "b", "call": _recorder(log, "b")},
        ],
    )
    for now in range(7):
        timer.update(now, {"a": (now, "A"), "b": (now, "B")})
    # a at 2, 4, 6; b at 3, 6; at t=6 in list order.
    assert log == [
        ("a", (2, "A")),
        ("b", (3, "B")),
        ("a", (4, "A")),
        ("a", (6, "A")),
        ("b", (6, "B")),
    ]


def test_timer_update_records_current_time():
    timer = Timer(0, 10, [])
    timer.update(4, {})
    assert timer.current_time == 4


def test_timer_accepts_numpy_integer_delays():
    fired = []
    timer = Timer(np.int64(1), np.int64(2), [{"delay": np.int32(3), "tag": "t", "call": lambda: fired.append(1)}])
    for now in range(8):
        timer.update(now, {"t": ()})
    # start at 3, then 3 - 0 >= 3 fires at 3, then 6.
    assert len(fired) == 2


def test_create_timer_registers_in_current_world(world):
    timer = create_timer(0, 0, [])
    assert isinstance(timer, Timer)
    assert world.timers == [timer]
    with World() as other:
        inner = create_timer(1, 0, [])
        assert other.timers == [inner]
    assert world.timers == [timer]  # the inner one did not leak out


def test_update_timers_updates_current_world_only(world):
    log = []
    with World() as first:
        create_timer(0, 0, [{"delay": 1, "tag": "t", "call": _recorder(log, "first")}])
    with World() as second:
        create_timer(0, 0, [{"delay": 1, "tag": "t", "call": _recorder(log, "second")}])
    create_timer(0, 0, [{"delay": 1, "tag": "t", "call": _recorder(log, "outer")}])

    with first:
        update_timers(5, {"t": ()})
    assert log == [("first", ())]
    assert (first.time, second.time, world.time) == (5, 0, 0)

    with second:
        update_timers(6, {"t": ()})
    assert log == [("first", ()), ("second", ())]

    update_timers(7, {"t": ()})  # the fixture's world is current again
    assert log[-1] == ("outer", ())
    assert current_world() is world


def test_update_timers_runs_every_timer_of_the_world(world):
    seen = []
    for robot in range(3):
        create_timer(robot, robot, [{"delay": 0, "tag": "t", "call": lambda r=robot: seen.append(r)}])
    update_timers(2, {"t": ()})
    # robot 2's start-up delay is 2: still off at t=2.
    assert seen == [0, 1]


@pytest.mark.parametrize("missing", ["delay", "tag", "call"])
def test_timer_rejects_entry_missing_key(missing):
    entry = {"delay": 1, "tag": "odom", "call": print}
    del entry[missing]
    with pytest.raises(KeyError, match=rf"robot 3.*'{missing}'"):
        Timer(3, 0, [entry])


def test_create_timer_rejects_missing_key_and_registers_nothing(world):
    with pytest.raises(KeyError, match=r"robot 4.*'call'"):
        create_timer(4, 0, [{"delay": 1, "tag": "odom"}])
    assert world.timers == []


@pytest.mark.parametrize("call", [None, 3, "update"])
def test_timer_rejects_non_callable_call(call):
    with pytest.raises(TypeError, match=r"robot 2.*'odom'.*callable"):
        Timer(2, 0, [{"delay": 1, "tag": "odom", "call": call}])


@pytest.mark.parametrize("delay", [-1, -0.5, math.nan, math.inf, "3", None])
def test_timer_rejects_bad_start_up_delay(delay):
    with pytest.raises(ValueError, match="robot 5"):
        Timer(5, delay, [])


@pytest.mark.parametrize("delay", [-1, math.nan])
def test_timer_rejects_bad_entry_delay(delay):
    with pytest.raises(ValueError, match=r"robot 5.*'radio'"):
        Timer(5, 0, [{"delay": delay, "tag": "radio", "call": print}])


def test_timer_update_rejects_tag_absent_from_params():
    timer = Timer(6, 0, [{"delay": 1, "tag": "odom", "call": print}])
    with pytest.raises(KeyError, match=r"robot 6.*'odom'"):
        timer.update(1, {"movement": ()})


def test_timer_update_absent_tag_is_fine_while_entry_not_due():
    # The tag is looked up only when its entry fires.
    timer = Timer(0, 0, [{"delay": 5, "tag": "odom", "call": print}])
    timer.update(1, {})
    with pytest.raises(KeyError, match="'odom'"):
        timer.update(5, {})


@pytest.mark.parametrize("args", [np.zeros((3, 2)), 1.5, "xyz", None])
def test_timer_update_rejects_params_that_are_not_a_tuple(args):
    timer = Timer(8, 0, [{"delay": 1, "tag": "odom", "call": lambda *a: None}])
    with pytest.raises(TypeError, match=r"robot 8.*'odom'"):
        timer.update(1, {"odom": args})


@pytest.mark.parametrize("gap", [0, 1, 2, 3, 4, 10, 30])
def test_due_matches_timer_update_step_by_step(gap):
    delays = np.array([0, 1, 5, 10, 11, 12, 29, 40])
    times = range(120)
    fired = [_run(int(delay), gap, times) for delay in delays]
    for step in times:
        expected = [step in steps for steps in fired]
        np.testing.assert_array_equal(timers.due(step, delays, gap), expected)
