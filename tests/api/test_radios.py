"""Radios: who hears whom, copies on the board, worlds, loss, latency and input errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dream import GraphRadio, Radio, RangeRadio, World


def _poses(*points):
    """A (3, n) pose array from (x, y) points, headings 0."""
    xy = np.array(points, dtype=float).T
    return np.vstack((xy, np.zeros(xy.shape[1])))


class _Inbox:
    """A radio callback that records what it received and returns a fixed reply."""

    def __init__(self, reply=None):
        self.reply = reply
        self.received = []

    def __call__(self, messages):
        self.received.append(messages)
        return self.reply


def test_range_radio_excludes_itself_but_hears_co_located_robot():
    # Robots 0 and 1 share a spot: self is excluded by id, not by distance > 0.
    x = _poses((0.2, 0.3), (0.2, 0.3))
    inbox = _Inbox()
    radio = RangeRadio(0, "radio", inbox)
    Radio(1).send_data("from 1")
    radio.send_data("from 0")
    radio.update(x)
    assert inbox.received == [["from 1"]]


@pytest.mark.parametrize(
    ("distance", "heard"),
    [(0.25, True), (0.5, True), (0.5000001, False), (0.75, False)],
)
def test_range_radio_range_is_inclusive(distance, heard):
    x = _poses((0.0, 0.0), (0.0, -distance))
    inbox = _Inbox()
    radio = RangeRadio(0, "radio", inbox, range=0.5)
    Radio(1).send_data("hello")
    radio.update(x)
    assert inbox.received == [["hello"] if heard else []]


def test_range_radio_orders_messages_by_sender_id_and_skips_silent_robots():
    x = _poses((0, 0), (0.1, 0), (0.2, 0), (0.3, 0), (0.4, 0), (0.5, 0))
    for sender in (5, 3, 1, 2):  # published out of order; robot 4 never publishes
        Radio(sender).send_data(f"m{sender}")
    inbox = _Inbox()
    RangeRadio(0, "radio", inbox, range=1.0).update(x)
    assert inbox.received == [["m1", "m2", "m3", "m5"]]


def test_range_radio_publishes_callback_return_value(world):
    x = _poses((0, 0), (0.1, 0))
    RangeRadio(0, "radio", _Inbox(reply={"state": [1, 2]})).update(x)
    assert world.messages == {0: {"state": [1, 2]}}
    listener = _Inbox()
    RangeRadio(1, "radio", listener).update(x)
    assert listener.received == [[{"state": [1, 2]}]]


def test_range_radio_publishes_nothing_when_callback_returns_none(world):
    x = _poses((0, 0), (0.1, 0))
    radio = RangeRadio(0, "radio", _Inbox(reply=None))
    radio.update(x)
    assert 0 not in world.messages
    # An earlier message stays; None does not overwrite it.
    radio.send_data("kept")
    radio.update(x)
    assert world.messages[0] == "kept"


def test_radio_send_data_later_send_overwrites(world):
    radio = Radio(3)
    radio.send_data("first")
    radio.send_data("second")
    assert world.messages == {3: "second"}


def test_radio_send_data_board_keeps_a_copy():
    # SPEC §9: the original stored messages by reference.
    data = [1, 2, {"k": 3}]
    Radio(1).send_data(data)
    data.append(4)
    data[2]["k"] = 99
    inbox = _Inbox()
    RangeRadio(0, "radio", inbox).update(_poses((0, 0), (0.1, 0)))
    assert inbox.received == [[[1, 2, {"k": 3}]]]


def test_range_radio_receivers_get_copies(world):
    x = _poses((0, 0), (0.1, 0), (0.2, 0))
    Radio(2).send_data([1, 2])

    def vandal(messages):
        messages[0].append("mutated")

    RangeRadio(0, "radio", vandal).update(x)
    inbox = _Inbox()
    RangeRadio(1, "radio", inbox).update(x)
    assert inbox.received == [[[1, 2]]]
    assert world.messages[2] == [1, 2]


def test_range_radio_shares_only_what_no_reader_can_change(world):
    # A tuple of numbers needs no copy; a tuple holding a list still gets one.
    x = _poses((0, 0), (0.1, 0), (0.2, 0))
    Radio(2).send_data((2, 0.5, [1.0]))

    def vandal(messages):
        messages[0][2].append("mutated")

    RangeRadio(0, "radio", vandal).update(x)
    inbox = _Inbox()
    RangeRadio(1, "radio", inbox).update(x)
    assert inbox.received == [[(2, 0.5, [1.0])]]
    Radio(2).send_data((2, 0.5, np.float64(1.0)))
    RangeRadio(1, "radio", inbox).update(x)
    assert inbox.received[-1] == [(2, 0.5, 1.0)]


def test_board_notes_per_message_whether_readers_must_copy_it(world):
    # The board decides once per message, also for one that arrives late: a list sent after a
    # tuple (and a tuple after a list) is read as what it is.
    world.publish(2, (2, 0.5))
    shared = world.receive([2])[0]
    assert shared is world.messages[2]
    world.publish(2, [1.0], latency=2)
    assert world.receive([2]) == [(2, 0.5)]  # the list is still in the air
    world.time = 2
    first, second = world.receive([2])[0], world.receive([2])[0]
    first.append("mutated")
    assert second == [1.0] and world.messages[2] == [1.0]
    world.publish(2, (3, 0.25))
    assert world.receive([2])[0] is world.messages[2]


def test_range_radio_copies_messages_of_arrays_deeply(world):
    # Arrays, alone or in a tuple, skip pickle: they must still be copies, dtype and values kept.
    x = _poses((0, 0), (0.1, 0), (0.2, 0))
    states, beats = np.array([1, 2]), np.array([0.5, 1.5])
    Radio(2).send_data((states, beats))
    states[0], beats[0] = 7, 7.0

    def vandal(messages):
        messages[0][0][1] = -1

    RangeRadio(0, "radio", vandal).update(x)
    inbox = _Inbox()
    RangeRadio(1, "radio", inbox).update(x)
    (got,) = inbox.received[0]
    assert type(got) is tuple and got[0].dtype == np.int64 and got[1].dtype == np.float64
    assert got[0].tolist() == [1, 2] and got[1].tolist() == [0.5, 1.5]
    assert world.messages[2][0].tolist() == [1, 2]


def test_graph_radio_hears_positive_links_only():
    # Row 0: self-loop (ignored), 0.5 link, 0 no link, negative no link, 2 link.
    adjacency = np.array(
        [
            [1.0, 0.5, 0.0, -1.0, 2.0],
            [1.0, 0.0, 1.0, 1.0, 1.0],
            [0.0, 1.0, 0.0, 1.0, 1.0],
            [1.0, 1.0, 1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0, 1.0, 0.0],
        ]
    )
    for sender in range(5):
        Radio(sender).send_data(sender * 10)
    inbox = _Inbox()
    radio = GraphRadio(0, "graph", inbox, adjacency)
    radio.update()
    assert inbox.received == [[10, 40]]


def test_graph_radio_ignores_distance_and_publishes_reply(world):
    # Far apart but linked: the graph decides, not the range.
    adjacency = [[0, 1], [1, 0]]
    Radio(1).send_data("far")
    inbox = _Inbox(reply="back")
    radio = GraphRadio(0, "graph", inbox, adjacency)
    radio.update(_poses((-1.5, -0.9), (1.5, 0.9)))
    assert inbox.received == [["far"]]
    assert world.messages[0] == "back"
    assert (radio.pos_x, radio.pos_y) == (-1.5, -0.9)


@pytest.mark.parametrize("adjacency", [np.ones((2, 3)), np.ones(4), np.ones((2, 2, 2))])
def test_graph_radio_rejects_non_square_adjacency(adjacency):
    with pytest.raises(ValueError, match="adjacency"):
        GraphRadio(0, "graph", _Inbox(), adjacency)


def test_graph_radio_rejects_nan_adjacency():
    with pytest.raises(ValueError, match="adjacency"):
        GraphRadio(0, "graph", _Inbox(), [[0, math.nan], [1, 0]])


@pytest.mark.parametrize("robot_id", [3, 10, -1])
def test_graph_radio_rejects_robot_outside_adjacency(robot_id):
    with pytest.raises(IndexError, match=f"robot id {robot_id}"):
        GraphRadio(robot_id, "graph", _Inbox(), np.ones((3, 3)))


def test_radios_in_two_worlds_are_isolated(world):
    x = _poses((0, 0), (0.1, 0))
    with World() as first:
        sender_a, inbox_a = Radio(0), _Inbox()
        listener_a = RangeRadio(1, "radio", inbox_a)
    with World() as second:
        sender_b, inbox_b = Radio(0), _Inbox()
        listener_b = RangeRadio(1, "radio", inbox_b)
    # Radios keep the world they were created in, whichever world is current later.
    sender_a.send_data("A")
    sender_b.send_data("B")
    listener_a.update(x)
    listener_b.update(x)
    assert inbox_a.received == [["A"]]
    assert inbox_b.received == [["B"]]
    assert first.messages == {0: "A"}
    assert second.messages == {0: "B"}
    assert world.messages == {}


def test_range_radio_loss_one_drops_everything():
    x = _poses((0, 0), (0.1, 0), (0.2, 0))
    Radio(1).send_data("a")
    Radio(2).send_data("b")
    inbox = _Inbox()
    radio = RangeRadio(0, "radio", inbox, loss=1.0)
    for _ in range(20):
        radio.update(x)
    assert inbox.received == [[]] * 20


def _lossy_run(seed, rounds=200):
    """What robot 0 receives over ``rounds`` updates with loss 0.5 from four senders."""
    x = _poses((0, 0), (0.1, 0), (0.2, 0), (0.3, 0), (0.4, 0))
    with World(seed=seed):
        for sender in range(1, 5):
            Radio(sender).send_data(sender)
        inbox = _Inbox()
        radio = RangeRadio(0, "radio", inbox, loss=0.5)
        for _ in range(rounds):
            radio.update(x)
    return inbox.received


def test_range_radio_loss_is_seeded_and_drops_about_half():
    first = _lossy_run(seed=3)
    assert first == _lossy_run(seed=3)
    assert first != _lossy_run(seed=4)
    delivered = sum(len(messages) for messages in first)
    # 800 messages, p = 0.5: the mean is 400, the standard deviation ~14.
    assert 320 < delivered < 480
    # Whatever survives still comes in sender order.
    assert all(messages == sorted(messages) for messages in first)


def test_graph_radio_loss_one_drops_everything():
    Radio(1).send_data("a")
    inbox = _Inbox()
    GraphRadio(0, "graph", inbox, np.ones((2, 2)), loss=1.0).update()
    assert inbox.received == [[]]


@pytest.mark.parametrize("latency", [1, 3])
def test_radio_latency_delays_visibility(world, latency):
    x = _poses((0, 0), (0.1, 0))
    world.update_timers(10, {})
    RangeRadio(0, "radio", _Inbox(), latency=latency).send_data("late")
    inbox = _Inbox()
    listener = RangeRadio(1, "radio", inbox)
    for now in range(10, 10 + latency):
        world.update_timers(now, {})
        listener.update(x)
        assert 0 not in world.messages
    world.update_timers(10 + latency, {})
    listener.update(x)
    assert inbox.received == [[]] * latency + [["late"]]
    assert world.messages[0] == "late"


def test_radio_latency_zero_is_immediate(world):
    Radio(0, latency=0).send_data("now")
    assert world.messages == {0: "now"}


def test_radio_latency_copies_the_message_at_send_time(world):
    data = [1]
    Radio(0, latency=2).send_data(data)
    data.append(2)
    world.update_timers(2, {})
    assert world.messages[0] == [1]


@pytest.mark.parametrize("loss", [-0.1, 1.5, math.nan])
def test_radio_rejects_invalid_loss(loss):
    with pytest.raises(ValueError, match="loss"):
        RangeRadio(0, "radio", _Inbox(), loss=loss)


@pytest.mark.parametrize("latency", [-1, 1.5, True, "2"])
def test_radio_rejects_invalid_latency(latency):
    with pytest.raises(ValueError, match="latency"):
        RangeRadio(0, "radio", _Inbox(), latency=latency)


@pytest.mark.parametrize("range_", [-0.1, math.nan])
def test_range_radio_rejects_invalid_range(range_):
    with pytest.raises(ValueError, match="range"):
        RangeRadio(0, "radio", _Inbox(), range=range_)


@pytest.mark.parametrize("robot_id", [3, 7, -1])  # -1 would silently be the last robot
def test_range_radio_update_rejects_robot_outside_poses(robot_id):
    radio = RangeRadio(robot_id, "radio", _Inbox())
    with pytest.raises(IndexError, match=f"robot id {robot_id}"):
        radio.update(np.zeros((3, 3)))


def test_range_radio_update_rejects_nan_poses():
    x = _poses((0, 0), (0.1, 0))
    x[1, 1] = math.nan
    with pytest.raises(ValueError, match="`x`"):
        RangeRadio(0, "radio", _Inbox()).update(x)


@pytest.mark.parametrize("shape", [(2, 3), (3,), (4, 3)])
def test_range_radio_update_rejects_bad_pose_shape(shape):
    with pytest.raises(ValueError, match="`x`"):
        RangeRadio(0, "radio", _Inbox()).update(np.zeros(shape))


def test_radio_update_takes_own_pose():
    radio = Radio(1)
    radio.update(np.array([[0.0, 0.5], [0.0, -0.25], [0.0, 1.0]]))
    assert (radio.pos_x, radio.pos_y, radio.rot_w) == (0.5, -0.25, 1.0)
