"""The per-row choices of a swarm robot's decision: which robots send (``view.send(where=...)``),
which drive their wish without HRVO (``view.direct``), and W-MSR on a neighbourhood's rows."""

from __future__ import annotations

import numpy as np
import pytest

import dream
from dream import rules
from dream.swarm import Avoid, Movement, Neighbourhood, Radio, SwarmRobot


def ragged(rng, rows, most=9):
    counts = rng.integers(0, most, rows)
    offsets = np.concatenate(([0], np.cumsum(counts)))
    values = np.round(rng.normal(size=offsets[-1]), 1)  # rounded: ties with each other and with own
    return offsets, values, np.round(rng.normal(size=rows), 1)


@pytest.mark.parametrize("trimmed", [0, 1, 2, 4])
def test_wmsr_mean_is_the_per_robot_filter_on_random_ragged_rows(trimmed):
    rng = np.random.default_rng(trimmed)
    offsets, values, own = ragged(rng, 300)
    rows = Neighbourhood(offsets, {"v": values})
    got = rows.wmsr_mean("v", own, trimmed)
    for r in range(300):
        row = values[offsets[r] : offsets[r + 1]]
        kept = rules.wmsr_keep(row, own[r], trimmed)
        assert got[r] == pytest.approx(np.mean([*kept, own[r]]), rel=1e-12, abs=1e-12)
        # A row alone gives the same bits as among the others: robot by robot equals the swarm.
        alone = Neighbourhood(np.array([0, len(row)]), {"v": row}).wmsr_mean("v", own[r : r + 1], trimmed)
        assert alone[0] == got[r]
    assert trimmed == 0 or (rules.wmsr_kept(values, offsets, own, trimmed).sum() < len(values))


def test_wmsr_drops_a_liars_extreme_value():
    rows = Neighbourhood(np.array([0, 4]), {"v": np.array([0.1, 99.0, -0.2, 0.3])})
    assert rows.wmsr_mean("v", np.array([0.0]), 1)[0] == pytest.approx((0.1 + 0.3 + 0.0) / 3)  # 99 and -0.2 dropped
    with pytest.raises(ValueError, match=r"wmsr_mean takes values \(4,\) and own \(1,\)"):
        rows.wmsr_mean("v", np.zeros(2), 1)


class Pusher(SwarmRobot):
    """Two robots face each other; robot 0 drives its wish straight when ``direct``; robot 1 sends
    only at even clocks."""

    period = 1
    movement = Movement(range=1.0)
    radio = Radio(range=2.0, fields=("clock",))

    def __init__(self, direct):
        self.avoid = Avoid(safety=0.3, sidestep=3)
        self.direct = direct
        self.heard = []

    def decide(self, view):
        wish = np.where((view.ids == 0)[:, None], [[0.05, 0.0]], [[-0.05, 0.0]])
        if self.direct:
            view.direct(view.ids == 0)
        heard = {int(i): view.heard["clock"][view.heard.owner == r].tolist() for r, i in enumerate(view.ids)}
        self.heard.append((int(view.clock[0]), heard))
        view.send(where=(view.ids == 0) | (view.clock % 2 == 0), clock=view.clock)
        return wish


def run_pusher(direct, one_by_one=False):
    robot = Pusher(direct)
    engine = dream.swarm.Engine(robot, 2, 0, dream.specs.ROBOTARIUM, one_by_one=one_by_one)
    x = np.array([[-0.15, 0.15], [0.0, 0.0], [0.0, np.pi]])
    for t in range(8):
        engine.step(t, x, np.zeros((2, 2)))
    return robot, engine


@pytest.mark.parametrize("one_by_one", [False, True])
def test_direct_rows_skip_hrvo_and_stepping_aside(one_by_one):
    _, steered = run_pusher(direct=False, one_by_one=one_by_one)
    robot, direct = run_pusher(direct=True, one_by_one=one_by_one)
    # HRVO turns robot 0 away from robot 1, 0.3 m ahead; driven direct, it keeps its wish.
    assert not np.allclose(steered.dxi[0], [0.05, 0.0])
    assert np.array_equal(direct.dxi[0], [0.05, 0.0]) and direct.sidestep[0] == 0
    assert not np.allclose(direct.dxi[1], [-0.05, 0.0])  # robot 1 still avoids


def test_only_the_robots_picked_send():
    robot, _ = run_pusher(direct=False)
    # Robot 0 hears robot 1's message of the last even clock: it said nothing at odd clocks.
    assert len(robot.heard) == 7
    for clock, heard in robot.heard[2:]:  # from clock 3 on (the first decision is at clock 1)
        assert heard[0] == [float(clock - 1 - (clock - 1) % 2)] and heard[1] == [float(clock - 1)]


@pytest.mark.parametrize(
    ("choice", "message"),
    [
        (lambda view: view.direct(np.ones(len(view) + 1, dtype=bool)), "rows driven direct must have one value"),
        (lambda view: view.direct(np.ones(len(view))), "rows driven direct holds bool values, got float64"),
        (lambda view: view.send(where=[True], value=view.clock), r"senders \(`where`\) must have one value"),
    ],
)
def test_a_bad_row_choice_is_named(choice, message):
    class Bad(SwarmRobot):
        period = 1
        avoid = Avoid()
        radio = Radio(range=1.0, fields=("value",))

        def decide(self, view):
            choice(view)
            return np.zeros((len(view), 2))

    engine = dream.swarm.Engine(Bad(), 3, 0, dream.specs.ROBOTARIUM)
    with pytest.raises(ValueError, match=message):
        for t in range(3):
            engine.step(t, np.array([[-0.5, 0.0, 0.5], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), np.zeros((2, 3)))


def test_a_field_named_where_is_refused():
    with pytest.raises(ValueError, match="other than 'sender' and 'where'"):
        Radio(fields=("where",))


def messages_on_a_board(rng, n, e, rows):
    """A board of ``n`` robots' messages (fields ``x``, ``y``, ``k``), ``e`` of them heard in
    ``rows`` rows: the board, the senders, the offsets, the rows reading the board in place and
    the same rows with the fields copied out."""
    board = {"x": rng.normal(size=n), "y": rng.normal(size=n), "k": rng.integers(-5, 5, n)}
    senders = rng.integers(0, n, e)
    offsets = np.concatenate(([0], np.sort(rng.integers(0, e, rows - 1)), [e]))
    on_board = Neighbourhood(offsets, {"sender": senders}, (senders, board))
    copied = Neighbourhood(offsets, {name: board[name][senders] for name in board})
    return board, senders, offsets, on_board, copied


@pytest.mark.parametrize("op", ["sum", "mean", "min", "max"])
def test_board_fields_reduced_together_equal_field_by_field(op):
    """Several message fields read from the board in one pass give, to the bit, what each field
    gives alone and what the fields copied out give."""
    _, _, _, rows, copied = messages_on_a_board(np.random.default_rng(7), 50, 400, 30)
    together = getattr(rows, op)(["x", "y", "k"])
    apart = np.column_stack([getattr(rows, op)(name) for name in ("x", "y", "k")])
    assert together.shape == (30, 3)
    np.testing.assert_array_equal(together, apart)
    np.testing.assert_array_equal(together, getattr(copied, op)(["x", "y", "k"]))


def test_nearest_messages_read_on_the_board_equal_those_copied_out():
    """The k messages nearest each robot, ranked with their positions read on the board in place,
    and their fields picked there, are those the fields copied out give."""
    rng = np.random.default_rng(11)
    board, _, offsets, on_board, copied = messages_on_a_board(rng, 60, 500, 40)
    origins = rng.normal(size=(40, 2))
    entries = on_board.nearest_to(["x", "y"], origins, 3)
    np.testing.assert_array_equal(entries, copied.nearest_to(["x", "y"], origins, 3))
    assert entries.shape == (40, 3) and (entries[np.diff(offsets) == 0] == -1).all()
    for name in board:
        picked = on_board.pick(name, entries)
        np.testing.assert_array_equal(picked, copied.pick(name, entries))
        assert np.isnan(picked[entries < 0]).all()
    assert "x" not in on_board.columns  # read in place, never copied out whole


def test_several_fields_picked_on_the_board_equal_those_copied_out():
    """Several message fields picked at any entries, read on the board at those entries only,
    side by side: what each field gives alone, and what the fields copied out give."""
    rng = np.random.default_rng(13)
    board, senders, _, on_board, copied = messages_on_a_board(rng, 60, 500, 40)
    entries = np.flatnonzero(rng.random(500) < 0.4)
    picked = on_board.pick(["x", "y", "k"], entries)
    assert picked.shape == (len(entries), 3)
    np.testing.assert_array_equal(picked, copied.pick(["x", "y", "k"], entries))
    np.testing.assert_array_equal(picked, np.column_stack([on_board.pick(name, entries) for name in "xyk"]))
    np.testing.assert_array_equal(picked[:, 2], board["k"][senders[entries]])
    with_gaps = on_board.pick(["x", "k"], np.array([entries[0], -1]))
    assert np.isnan(with_gaps[1]).all() and with_gaps[0, 1] == board["k"][senders[entries[0]]]
    assert "x" not in on_board.columns  # read in place, never copied out whole


def test_squared_length_orders_vectors_as_their_length_does():
    vectors = np.random.default_rng(5).normal(size=(40, 7, 2))
    squared = rules.squared_length(vectors)
    assert squared.shape == (40, 7)
    np.testing.assert_allclose(np.sqrt(squared), np.hypot(vectors[..., 0], vectors[..., 1]), rtol=1e-15)
    assert rules.squared_length([3.0, 4.0]) == 25.0


@pytest.mark.parametrize("shape", [(50, 7), (50, 3, 3), (50, 1), (50, 0), (0, 7)])
def test_each_any_is_numpys_any_along_the_rows(shape):
    flags = np.random.default_rng(3).random(shape) < 0.2
    np.testing.assert_array_equal(rules.each_any(flags), flags.any(axis=1))
    with pytest.raises(ValueError, match=r"each_any takes flags of shape \(k, m, ...\), got \(7,\)"):
        rules.each_any(np.zeros(7, dtype=bool))


def test_broadcast_gives_each_entry_its_rows_values():
    """A row's values at each of its entries, empty rows included, as indexing by ``owner`` gives
    them; values of the wrong length are refused, naming both sizes."""
    rng = np.random.default_rng(5)
    offsets, _, _ = ragged(rng, 40)
    rows = Neighbourhood(offsets, {})
    here, flags = rng.normal(size=(40, 2)), rng.random(40) < 0.5
    np.testing.assert_array_equal(rows.broadcast(here), here[rows.owner])
    np.testing.assert_array_equal(rows.broadcast(flags), flags[rows.owner])
    assert rows.broadcast(rng.normal(size=(40, 7, 2))).shape == (offsets[-1], 7, 2)
    with pytest.raises(ValueError, match=r"values of shape \(39, 2\) for a neighbourhood of 40 rows"):
        rows.broadcast(here[1:])
