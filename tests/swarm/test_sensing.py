"""What a swarm robot may declare besides its movement sensor and radio: an obstacle sensor
(``Obstacles``), a motion guard of its own (``Guard``), no command for no wish (``halts``), and
each robot's Voronoi cell from what it alone knows (``known_cells``)."""

from __future__ import annotations

import numpy as np
import pytest

import dream
from dream import Faults, Obstacle, kernels
from dream._csr import merged
from dream.obstacles import sensed
from dream.specs import ROBOTARIUM
from dream.swarm import Engine, Guard, Movement, Obstacles, SwarmRobot, View, known_cells


class Reader(SwarmRobot):
    """Wishes ``wish`` and keeps every view it was given."""

    period = 1

    def __init__(self, wish=(0.0, 0.0), **declared):
        self.wish = np.asarray(wish, dtype=np.float64)
        self.views = []
        for key, value in declared.items():
            setattr(self, key, value)

    def decide(self, view):
        self.views.append(view)
        return np.tile(self.wish, (len(view), 1))


def step(robot, x, t=1, faults=None, one_by_one=False):
    """Robot ``robot``'s commands ``(2, n)`` for poses ``x`` at step ``t`` (from still)."""
    n = x.shape[1]
    engine = Engine(robot, n, 0, ROBOTARIUM, one_by_one=one_by_one)
    state = None if faults is None else dream.World(0).inject(faults, n)
    if state is not None:
        state.advance(t)
    return engine.step(t, x, np.zeros((2, n)), state)


def test_an_obstacle_sensor_reads_the_closest_points_in_range_where_the_obstacles_are_now():
    boxes = [Obstacle((0.5, 0.0), (0.2, 0.2)), Obstacle((3.0, 0.0), (0.2, 0.2)), Obstacle((-2.0, 0.5), (0.4, 0.4))]
    robot = Reader(obstacles=Obstacles(boxes, range=1.0))
    x = np.array([[0.0, 2.5, -2.0], [0.0, 0.0, 0.5], [0.0, 0.0, 0.0]])  # robot 2 is inside the third box
    step(robot, x)
    view = robot.views[-1]
    want = sensed(boxes, x[:2].T, 1.0) - x[:2].T[:, None]  # (3 robots, 3 boxes, 2), NaN: not sensed
    for r in range(3):
        row = slice(view.obstacles.offsets[r], view.obstacles.offsets[r + 1])
        got = np.column_stack((view.obstacles["dx"][row], view.obstacles["dy"][row]))
        np.testing.assert_array_equal(got, want[r][~np.isnan(want[r, :, 0])])
    assert list(view.obstacles.count) == [1, 1, 0]
    np.testing.assert_allclose(view.obstacles["distance"], [0.4, 0.4], atol=1e-12)
    boxes[0].center[:] = (5.0, 5.0)  # moved away: the next reading has it no more
    step(robot, x)
    assert list(robot.views[-1].obstacles.count) == [0, 1, 0]
    with pytest.raises(ValueError, match="Obstacles range"):
        Obstacles(boxes, range=-1.0)
    with pytest.raises(ValueError, match="sequence of dream.Obstacle"):
        Obstacles([(0.0, 0.0)])


def test_obstacle_readings_are_noisy_and_dropped_alike_both_ways():
    boxes = [Obstacle((0.0, 0.0), (0.2, 0.2)), Obstacle((1.0, 0.0), (0.2, 0.2))]
    x = np.vstack((np.linspace(-0.8, 1.8, 12), np.full(12, 0.3), np.zeros(12)))
    faults = Faults(sensor_noise=0.01, sensor_dropout=0.3)
    readings = []
    for one_by_one in (False, True):
        robot = Reader(obstacles=Obstacles(boxes, range=0.8, noise=0.02))
        step(robot, x, t=3, faults=faults, one_by_one=one_by_one)
        ids = np.concatenate([view.ids for view in robot.views])
        dx = np.concatenate([view.obstacles["dx"] for view in robot.views])
        readings.append((ids, dx))
    assert np.array_equal(readings[0][0], readings[1][0]) and np.array_equal(readings[0][1], readings[1][1])
    assert len(readings[0][0]) < 12  # some readings were lost: those robots did not decide
    clean = Reader(obstacles=Obstacles(boxes, range=0.8))
    step(clean, x, t=3)
    kept = np.isin(clean.views[0].ids, readings[0][0])
    exact = clean.views[0].obstacles.where(np.repeat(kept, clean.views[0].obstacles.count))["dx"]
    assert exact.shape == readings[0][1].shape and 0 < np.abs(readings[0][1] - exact).max() < 0.2


def test_without_an_obstacle_sensor_the_rows_are_empty():
    robot = Reader()
    step(robot, np.array([[0.0, 1.0], [0.0, 0.0], [0.0, 0.0]]))
    assert list(robot.views[-1].obstacles.count) == [0, 0]


@pytest.mark.parametrize("heading", [-3.0, -2.5, -np.pi / 2 - 0.01, -np.pi / 2, -1.0, 0.5, 2.5, np.pi])
def test_a_robot_that_halts_gets_no_command_for_no_wish(heading):
    # The unicycle conversion of a zero velocity turns a robot heading between -pi and -pi/2 at
    # w_max (atan2(+0, -0) = pi): coverage robots on their centroids spun, and never came to rest.
    x = np.array([[0.0], [0.0], [heading]])
    np.testing.assert_array_equal(step(Reader(halts=True), x), 0.0)
    spins = -np.pi < heading < -np.pi / 2
    assert (step(Reader(), x)[1, 0] != 0.0) == spins
    assert step(Reader(wish=(0.1, 0.0), halts=True), x)[0, 0] == step(Reader(wish=(0.1, 0.0)), x)[0, 0]


def test_a_guard_of_its_own_stops_a_robot_driving_into_one_it_sees_without_hrvo():
    x = np.array([[0.0, 0.15], [0.0, 0.0], [0.0, np.pi]])  # face to face, 0.15 m apart
    driving = step(Reader(wish=(0.1, 0.0), movement=Movement(range=0.5)), x)
    assert driving[0, 0] > 0  # no avoidance at all: it drives on
    guarded = step(Reader(wish=(0.1, 0.0), movement=Movement(range=0.5), guard=Guard(near=0.14)), x)
    assert guarded[0, 0] == 0.0 and guarded[1, 0] == driving[1, 0]
    far = step(Reader(wish=(0.1, 0.0), movement=Movement(range=0.5), guard=Guard(near=0.01)), x)
    assert far[0, 0] > 0  # 0.08 m/s for the guard's 0.25 s leaves it 0.13 m off: beyond 1 cm, within 14 cm
    with pytest.raises(ValueError, match="Guard near"):
        Guard(near=-0.1)


@pytest.mark.parametrize("seed", range(5))
def test_known_cells_are_each_robots_own_voronoi_cell(seed):
    rng = np.random.default_rng(seed)
    k = 30
    here = rng.uniform(-1.4, 1.4, (k, 2))
    kinds = []
    for most in (12, 4, 3):  # heard, seen, virtual agents
        counts = rng.integers(0, most, k)
        kinds.append((np.concatenate(([0], np.cumsum(counts))), rng.uniform(-1.5, 1.5, (counts.sum(), 2))))
    cells = known_cells(here, *kinds, radius=0.6, bounds=ROBOTARIUM.bounds, polygons=True)
    for r in range(k):
        rows = [points[offsets[r] : offsets[r + 1]] for offsets, points in kinds]
        centroid, area, polygon = kernels.voronoi_cell(
            here[r], rows[0], radius=0.6, bounds=ROBOTARIUM.bounds, virtual=np.vstack(rows[1:])
        )
        np.testing.assert_array_equal(cells.centroids[r], centroid)
        assert cells.areas[r] == area
        np.testing.assert_array_equal(cells.vertices[cells.offsets[r] : cells.offsets[r + 1]], polygon)
        alone = known_cells(
            here[r : r + 1], *[(np.array([0, len(row)]), row) for row in rows], radius=0.6, bounds=ROBOTARIUM.bounds
        )
        np.testing.assert_array_equal(alone.centroids[0], centroid)  # a row alone: the same bits
    with pytest.raises(ValueError, match=r"`known\[1\]` offsets must be offsets of shape \(31,\)"):
        known_cells(here, kinds[0], (np.array([0, 1]), np.zeros((1, 2))), radius=0.6, bounds=ROBOTARIUM.bounds)


def test_merged_rows_keep_each_kind_in_order():
    a = (np.array([0, 2, 2, 3]), np.array([1.0, 2.0, 3.0]))
    b = (np.array([0, 0, 1, 3]), np.array([10.0, 20.0, 30.0]))
    offsets, values = merged(a, b)
    assert offsets.tolist() == [0, 2, 3, 6] and values.tolist() == [1.0, 2.0, 10.0, 3.0, 20.0, 30.0]


@pytest.mark.parametrize(
    "faults",
    [None, Faults(loss=0.3, distance_loss=0.2), Faults(burst=(0.1, 0.3), loss=0.1)],
    ids=["lossless", "lossy", "bursty"],
)
def test_cells_from_the_board_are_the_cells_from_the_rows(monkeypatch, faults):
    # A range radio's cells come from the messages near each cell on the board (heard_cells),
    # losses drawn there as the perception draws them (a burst's: the links lost as the inbox was
    # listed). Forced through every message delivered, a whole coverage run (packed start: many
    # ties between equidistant neighbours) is the same, and so are the messages lost, counted in
    # the perception's pass or as the inbox is listed.

    class RowsOnly(View):
        """A view that never gets the engine's board (its cells go through its rows)."""

        board_cells = property(lambda self: None, lambda self, value: None)

    def run():
        return dream.run(
            "voronoi-coverage", n=40, seed=2, backend="fast", steps=200, swarm=True, trace=True, faults=faults
        )

    board = run()
    monkeypatch.setattr(dream.swarm.engine, "View", RowsOnly)
    rows = run()
    assert np.array_equal(board.trace, rows.trace)
    assert np.ptp(board.trace[:, :2], axis=0).max() > 0.3  # the team did spread
    if faults is not None:
        assert board.faults == rows.faults and board.faults["messages_lost"] > 0


def test_a_deferred_neighbourhood_is_found_once_and_only_when_read():
    calls = []

    def load():
        calls.append(1)
        return dream.swarm.Neighbourhood(np.array([0, 2, 3]), {"v": np.array([1.0, 2.0, 4.0])})

    hood = dream.swarm.neighbourhood.Deferred(load)
    assert calls == []
    assert len(hood) == 2 and hood.sum("v").tolist() == [3.0, 4.0] and hood.count.tolist() == [2, 1]
    assert calls == [1]


def test_a_summed_inbox_answers_its_counts_sums_and_means_without_its_rows():
    # The sums the perception's pass found (Summed) give each row's count, sums and means, to the
    # bit, an empty row's mean NaN, in blocks of rows too; anything else loads the rows, once.
    rng = np.random.default_rng(5)
    board = {"x": rng.normal(size=20), "y": rng.normal(size=20)}
    offsets = np.array([0, 3, 3, 7, 12])
    senders = np.sort(rng.choice(20, 12))
    rows = dream.swarm.Neighbourhood(offsets, {"sender": senders}, (senders, board)).frozen()
    calls = []

    def load():
        calls.append(1)
        return rows

    sums = {name: kernels.segment_reduce(values, offsets, "sum", senders) for name, values in board.items()}
    summed = dream.swarm.neighbourhood.Summed(np.diff(offsets), sums)
    hood = dream.swarm.neighbourhood.Deferred(load, summed)
    for op in ("sum", "mean"):
        for what in ("x", ["x", "y"], ("y",)):
            got, want = getattr(hood, op)(what), getattr(rows, op)(what)
            assert got.shape == want.shape and np.array_equal(got, want, equal_nan=True), (op, what)
    assert np.isnan(hood.mean("x")[1]) and hood.count.tolist() == [3, 0, 4, 5]
    blocks = dream.swarm.byrobot._rows(hood, [0, 1, 4])
    assert np.array_equal(blocks[1].sum(["x", "y"]), rows.sum(["x", "y"])[1:]) and blocks[1].count.tolist() == [0, 4, 5]
    assert calls == []
    assert hood.sum(np.ones(12)).tolist() == [3.0, 0.0, 4.0, 5.0] and calls == [1]  # not a column summed: loaded
    assert hood.nearest_to(["x", "y"], np.zeros((4, 2)), 1).shape == (4, 1) and calls == [1]


def test_a_derived_column_is_worked_out_when_read_and_kept_through_where_and_rows():
    calls = []

    def doubled(hood):
        calls.append(len(hood["v"]))
        return 2 * hood["v"]

    hood = dream.swarm.Neighbourhood(np.array([0, 2, 3]), {"v": np.array([1.0, 2.0, 4.0])}, derived={"w": doubled})
    assert hood.names == ["v", "w"] and calls == []
    kept = hood.where(np.array([True, False, True]))
    assert kept["w"].tolist() == [2.0, 8.0] and calls == [2]  # worked out from the entries kept
    frozen = hood.frozen()
    assert frozen.sum("w").tolist() == [6.0, 8.0] and not frozen["w"].flags.writeable and calls == [2, 3]


def test_points_are_the_origins_plus_the_offsets_to_the_bit():
    rng = np.random.default_rng(4)
    offsets = np.concatenate(([0], np.cumsum(rng.integers(0, 6, 50))))
    dx, dy = rng.normal(size=(2, offsets[-1]))
    hood = dream.swarm.Neighbourhood(offsets, {"dx": dx, "dy": dy}).frozen()
    here = rng.normal(size=(50, 2))
    got = hood.points(here)
    assert np.array_equal(got, hood.broadcast(here) + np.column_stack((dx, dy)))
    assert got.flags.writeable and np.array_equal(hood["dx"], dx)  # its own array; the columns untouched
    with pytest.raises(ValueError, match=r"origins of shape \(49, 2\)"):
        hood.points(here[1:])


@pytest.mark.parametrize("noise", [0.0, 0.01])
@pytest.mark.parametrize("one_by_one", [False, True])
def test_bearings_are_read_whether_or_not_the_step_needs_them(noise, one_by_one):
    # Without HRVO or noise the engine leaves the bearings to the decision that reads them.
    rng = np.random.default_rng(3)
    x = np.vstack((rng.uniform(-1.0, 1.0, (2, 30)), rng.uniform(-np.pi, np.pi, 30)))
    robot = Reader(movement=dream.swarm.Movement(range=0.8, noise=noise))
    step(robot, x, one_by_one=one_by_one)
    for view in robot.views:
        seen = view.seen
        assert "bearing" in seen.names and not seen["bearing"].flags.writeable
        if noise == 0.0:
            assert np.array_equal(seen["bearing"], np.arctan2(seen["dy"], seen["dx"]))
        else:  # the noisy offsets come from the noisy bearings
            assert np.allclose(seen["dx"], seen["distance"] * np.cos(seen["bearing"]))
    if noise == 0.0 and not one_by_one:  # the kernel's own bearings, to an ulp
        (view,) = robot.views
        seen, _ = kernels.perceive(x[:2].T, x[2], view.ids, sight=(0.8, 2 * np.pi, 0.0))
        assert len(seen[3]) > 30 and np.allclose(view.seen["bearing"], seen[3], rtol=0, atol=1e-15)


class VelocityReader(Reader):
    """A :class:`Reader` whose decision reads the velocities of the robots it sees."""

    def decide(self, view):
        self.read = (view.seen["vx"].copy(), view.seen["vy"].copy())
        return super().decide(view)


@pytest.mark.parametrize("one_by_one", [False, True])
def test_the_velocities_seen_are_worked_out_only_once_read(monkeypatch, one_by_one):
    # Without HRVO or noise the engine leaves the velocities of the robots seen to the decision
    # that reads them (every robot's command converted); read once, they are carried from then on.
    from dream.swarm import engine as engine_module

    calls = []

    def counted(commands, headings):
        calls.append(len(headings))
        return dream.sensors.seen_velocity(commands, headings)

    monkeypatch.setattr(engine_module, "seen_velocity", counted)
    rng = np.random.default_rng(5)
    x = np.vstack((rng.uniform(-1.0, 1.0, (2, 30)), rng.uniform(-np.pi, np.pi, 30)))
    commands = np.vstack((rng.uniform(-0.1, 0.1, 30), rng.uniform(-1.0, 1.0, 30)))
    sight = Movement(range=0.8)
    blind = Engine(Reader(movement=sight), 30, 0, ROBOTARIUM, one_by_one=one_by_one)
    blind.step(1, x, commands, None)
    assert calls == [] and not blind.velocities_read
    robot = VelocityReader(movement=sight)
    engine = Engine(robot, 30, 0, ROBOTARIUM, one_by_one=one_by_one)
    carried = dream.sensors.seen_velocity(commands, x[2])
    for t, want_calls in ((1, [30]), (2, [30, 30])):
        robot.views.clear()
        engine.step(t, x, commands, None)
        assert calls == want_calls and engine.velocities_read  # read lazily once, then carried
        ids = np.concatenate([view.ids for view in robot.views])
        (*_, vx, vy), _ = kernels.perceive(x[:2].T, x[2], ids, sight=(0.8, 2 * np.pi, 0.0), carried=carried)
        assert len(vx) > 30 and np.array_equal(robot.read[0], vx[-len(robot.read[0]) :])
        assert np.array_equal(robot.read[1], vy[-len(robot.read[1]) :])


@pytest.mark.parametrize("faults", [None, Faults(loss=0.2, latency=2)], ids=["lossless", "lossy"])
def test_runs_are_the_same_whether_or_not_the_messages_are_counted(tmp_path, faults):
    # Without an output that shows the message counts (a trajectory log, a recording) the runner
    # does not count them, and a range radio's inbox is found only when the decision reads it (a
    # coverage robot's never is; its losses are drawn where the messages are found): the run is
    # the same.

    runs = [
        dream.run(
            "voronoi-coverage", n=30, seed=1, steps=150, backend="fast", swarm=True, trace=True, faults=faults, log=log
        )
        for log in (None, tmp_path / "run.parquet")
    ]
    assert np.array_equal(runs[0].trace, runs[1].trace)
    assert np.ptp(runs[0].trace[:, :2], axis=0).max() > 0.3
