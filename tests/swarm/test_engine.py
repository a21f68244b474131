"""The swarm engine: one robot class, written on arrays, runs robot by robot and as one swarm
with the same poses at every step (with and without faults), and the world's rules (clocks,
sensors, radio, faults) hold on the arrays."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import dream
from dream import Faults, timers
from dream.experiments.files import load_file
from dream.swarm import Avoid, Movement, Radio, SwarmRobot, View, draws
from dream.swarm.engine import Engine

ROOT = Path(__file__).resolve().parents[2]
EVERY_FAULT = Faults.every_kind()


def rendezvous():
    spec = importlib.util.spec_from_file_location("rendezvous_example", ROOT / "examples" / "rendezvous.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.Rendezvous


def both_ways(experiment, n, faults=None, steps=300, seed=1, **options):
    """The traces of a run robot by robot and of the same run as one swarm."""
    runs = [
        dream.run(
            experiment, n=n, seed=seed, steps=steps, backend="fast", trace=True, swarm=swarm, faults=faults, **options
        )
        for swarm in (False, True)
    ]
    return runs


@pytest.mark.parametrize("faults", [None, EVERY_FAULT], ids=["no faults", "every fault"])
def test_rendezvous_is_the_same_robot_by_robot_and_as_a_swarm(faults):
    one, swarm = both_ways(rendezvous(), 20, faults)
    assert one.trace.shape == swarm.trace.shape and len(one.trace) > 100
    assert np.array_equal(one.trace, swarm.trace)  # bit for bit, every step
    assert one.faults == swarm.faults
    assert np.ptp(one.trace[:, :2], axis=0).max() > 0.1  # the robots did move
    if faults is not None:
        assert one.faults["messages_lost"] > 0 and one.faults["readings_dropped"] > 0


FLOCK = '''
import numpy as np
from dream import Experiment, param
from dream.swarm import Avoid, Movement, Radio, SwarmRobot


class Flocker(SwarmRobot):
    """Aligns its heading with the headings it hears, keeps away from the robots it sees."""

    period = 3
    memory = {"decisions": 0}

    def __init__(self, speed):
        self.speed = speed
        self.movement = Movement(range=0.4, fov=4.0, noise=0.002)
        self.radio = Radio(range=0.8, fields={"id": int, "heading": float}, latency=1)
        self.avoid = Avoid(safety=0.18)

    def start(self, ids):
        return ids % 7

    def decide(self, view):
        heading = view.pose[:, 2]
        heard = view.heard
        mean = np.arctan2(heard.sum(np.sin(heard["heading"])), heard.sum(np.cos(heard["heading"])))
        aim = np.where(heard.count > 0, mean, heading)
        close = view.seen.nearest()
        away = -view.seen.pick(["dx", "dy"], close, fill=0.0)
        view.memory["decisions"] += 1
        view.send(id=view.ids, heading=aim)
        return self.speed * np.column_stack((np.cos(aim), np.sin(aim))) + 0.2 * away


class Flock(Experiment):
    name = "flock"
    speed: float = param(0.05, "cruise speed (m/s)")

    def swarm_robot(self, n):
        return Flocker(self.speed)
'''


@pytest.mark.parametrize("faults", [None, EVERY_FAULT], ids=["no faults", "every fault"])
def test_an_experiment_file_is_the_same_both_ways(tmp_path, faults):
    path = tmp_path / "flock.py"
    path.write_text(FLOCK)
    flock = load_file(path)
    one, swarm = both_ways(flock, 16, faults, steps=200)
    assert np.array_equal(one.trace, swarm.trace)
    assert one.collisions == swarm.collisions == 0


def test_rendezvous_succeeds_as_a_swarm_of_300_under_faults():
    faults = Faults(loss=0.3, latency=5, crash=0.1, crash_at=50, byzantine=3)
    result = dream.run(rendezvous(), n=300, seed=0, backend="fast", swarm=True, faults=faults)
    assert result.success and result.completed_step is not None
    assert (result.collisions, result.boundary, result.actuator) == (0, 0, 0)
    assert len([e for e in result.faults["events"] if e["kind"] == "crash"]) == 30


# -- the world's rules on the arrays --------------------------------------------------------------
class Recorder(SwarmRobot):
    """Stands still and keeps what it was given, for the tests to look at."""

    def __init__(self, period=4, radio=None, movement=None, starts=None):
        self.period, self.radio, self.movement, self.starts = period, radio, movement, starts
        self.views: list[tuple[int, np.ndarray, dict]] = []

    def start(self, ids):
        return np.zeros(len(ids), dtype=np.int64) if self.starts is None else self.starts[ids]

    def decide(self, view: View) -> np.ndarray:
        self.views.append((int(view.clock[0]), view.ids.copy(), {k: view.heard[k].copy() for k in view.heard.names}))
        if self.radio is not None:
            fields = {key: view.ids * 1.0 + view.clock / 1000 for key in self.radio.kinds}
            view.send(**{key: view.ids if kind is int else fields[key] for key, kind in self.radio.kinds.items()})
        return np.zeros((len(view), 2))


def drive(robot, n, steps, faults=None, seed=0, one_by_one=False, poses=None):
    engine = dream.swarm.Engine(robot, n, seed, dream.specs.ROBOTARIUM, one_by_one=one_by_one)
    state = None
    if faults is not None:
        state = dream.World(seed).inject(faults, n)
    x = np.zeros((3, n)) if poses is None else poses
    x[0] = np.linspace(-0.5, 0.5, n) if poses is None else x[0]
    commands = np.zeros((2, n))
    for t in range(steps):
        if state is not None:
            state.advance(t)
        engine.step(t, x, commands, state)
    return engine, state


def test_decisions_follow_the_timer_rule():
    starts = np.array([0, 3, 7, 12, 2])
    robot = Recorder(period=4, starts=starts)
    drive(robot, 5, 40)
    for i in range(5):
        decided = [t for t, ids, _ in robot.views if i in ids]
        expected = [t for t in range(40) if timers.due(t, starts[i : i + 1], 4)[0]]
        assert decided == expected


@pytest.mark.parametrize("latency", [0, 1, 2, 5])
def test_a_message_is_heard_latency_steps_after_it_was_sent(latency):
    robot = Recorder(period=1, radio=Radio(range=5.0, fields=("value",), latency=latency))
    drive(robot, 2, 12)
    delay = max(latency, 1)  # never in the step it was sent
    for t, _ids, heard in robot.views:  # every robot sends at every step from step 1 on
        if t - delay >= 1:
            assert sorted(heard["sender"]) == [0, 1]
            assert np.allclose(heard["value"] % 1, (t - delay) / 1000)
        else:
            assert len(heard["sender"]) == 0


def test_lost_crashed_and_lying_senders():
    n = 12
    radio = Radio(range=5.0, fields={"value": float, "id": int})
    robot = Recorder(period=1, radio=radio)
    _, state = drive(robot, n, 30, Faults(crash=0.25, crash_at=10, byzantine=2, lie="constant"))
    crashed, liars = np.flatnonzero(state.crashed), np.flatnonzero(state.byzantine)
    late = [heard for t, _, heard in robot.views if t >= 12]
    assert late and all(not np.isin(heard["sender"], crashed).any() for heard in late)  # silenced
    for heard in late:
        lying = np.isin(heard["sender"], liars)
        assert (heard["value"][lying] == 0.0).all() and (heard["value"][~lying] != 0.0).all()
        assert np.array_equal(heard["id"], heard["sender"])  # ints are never falsified
    robot = Recorder(period=1, radio=Radio(range=5.0, fields=("value",), loss=1.0))
    drive(robot, 4, 10)
    assert all(len(heard["sender"]) == 0 for _, _, heard in robot.views)


def test_a_sensor_sees_only_within_its_range_and_field_of_view():
    seen = []

    class Looker(SwarmRobot):
        period = 1
        movement = Movement(range=0.3, fov=np.pi / 2)

        def decide(self, view):
            seen.append(
                {int(i): sorted(view.seen["dx"][view.seen.owner == r].round(3)) for r, i in enumerate(view.ids)}
            )
            return np.zeros((len(view), 2))

    poses = np.array([[0.0, 0.2, -0.2, 0.5], [0.0, 0.0, 0.0, 0.0], [0.0, np.pi, 0.0, 0.0]])
    drive(Looker(), 4, 2, poses=poses)  # the first decision is at step 1 (the timer rule)
    # robot 0 faces +x: sees robot 1 (0.2 ahead), not robot 2 (behind) nor robot 3 (0.5 away)
    assert seen[0][0] == [0.2] and seen[0][1] == [-0.2] and seen[0][3] == []


def test_the_decision_gets_rows_never_the_swarm():
    robot = Recorder(period=2, radio=Radio(range=1.0, fields=("value",)))
    drive(robot, 6, 3)
    assert set(View.__dataclass_fields__) == {
        "ids",
        "clock",
        "pose",
        "seen",
        "heard",
        "memory",
        "obstacles",
        "command",
        "said",
        "saying",
        "straight",
        "heeded",
        "safety",
        "turn",
        "board_cells",
    }
    assert all(len(ids) == 6 for _, ids, _ in robot.views)


def test_a_view_holds_each_robots_own_last_command():
    # A robot knows what it told its wheels (after the safety layer): its odometry against it
    # tells whether they obey (affine-formation's stuck-wheel detector).
    robot = Recorder(period=1)
    engine = dream.swarm.Engine(robot, 4, 0, dream.specs.ROBOTARIUM)
    x = np.zeros((3, 4))
    x[0] = np.linspace(-0.5, 0.5, 4)
    commands = np.arange(8.0).reshape(2, 4) / 100
    seen = []
    robot.decide = lambda view: seen.append((view.ids.copy(), view.command.copy())) or np.zeros((len(view), 2))
    engine.step(1, x, commands)
    ids, command = seen[0]
    assert len(ids) == 4 and np.array_equal(command, commands[:, ids].T)


@pytest.mark.parametrize(
    "meddle",
    [
        lambda view: view.ids.__setitem__(0, 5),
        lambda view: view.seen["dx"].__setitem__(slice(None), 0.0),
        lambda view: view.heard["value"].__setitem__(slice(None), 0.0),
        lambda view: view.heard.offsets.__setitem__(slice(None), 0),
        lambda view: view.command.__setitem__((0, 0), 1.0),
    ],
    ids=["ids", "detections", "messages", "rows", "command"],
)
def test_a_decision_cannot_change_what_the_others_perceive(meddle):
    class Meddler(SwarmRobot):
        period = 1
        movement = Movement(range=2.0)
        radio = Radio(range=2.0, fields=("value",))

        def decide(self, view):
            view.send(value=view.pose[:, 0])
            if view.clock[0] > 3:
                meddle(view)
            return np.zeros((len(view), 2))

    with pytest.raises(ValueError, match="read-only"):
        drive(Meddler(), 4, 6)


@pytest.mark.parametrize(
    ("said", "message"),
    [
        (lambda view: {"value": view.pose[:1, 0]}, r"message field 'value' must have one value per deciding robot"),
        (lambda view: {"value": view.pose[:, 0], "count": view.pose[:, 0]}, "'count' holds int64 values, got float64"),
    ],
)
def test_a_message_that_would_mix_robots_is_refused(said, message):
    class Sender(SwarmRobot):
        period = 1
        radio = Radio(range=1.0, fields={"value": float, "count": int})

        def decide(self, view):
            view.send(**{"count": view.ids, **said(view)})
            return np.zeros((len(view), 2))

    with pytest.raises(ValueError, match=message):
        drive(Sender(), 4, 3)


def test_memory_keeps_its_kind_and_one_value_per_robot():
    class Counter(SwarmRobot):
        period = 1
        memory = {"decisions": 0, "last": np.nan}

        def decide(self, view):
            view.memory["decisions"] += 1
            view.memory["last"] = view.clock
            return np.zeros((len(view), 2))

    engine, _ = drive(Counter(), 3, 6)
    assert engine.memory["decisions"].tolist() == [5, 5, 5] and engine.memory["last"].tolist() == [5.0] * 3

    class Bad(Counter):
        def decide(self, view):
            view.memory["decisions"] = view.clock + 0.5  # a float into an int memory
            return np.zeros((len(view), 2))

    with pytest.raises(ValueError, match="memory 'decisions' holds int64 values, got float64"):
        drive(Bad(), 3, 3)


def test_an_array_memory_field_keeps_one_array_per_robot():
    class Tally(SwarmRobot):
        period = 1
        memory = {"count": np.zeros(3, dtype=np.int64), "heard": np.full((2, 2), np.nan)}

        def decide(self, view):
            assert view.memory["count"].shape == (len(view), 3) and view.memory["heard"].shape == (len(view), 2, 2)
            view.memory["count"][:, view.clock.astype(int) % 3] += 1  # each row its own counts
            view.memory["heard"][:, 1] = view.pose[:, :2]
            return np.zeros((len(view), 2))

    for one_by_one in (False, True):
        engine, _ = drive(Tally(), 3, 7, one_by_one=one_by_one)
        assert engine.memory["count"].tolist() == [[2, 2, 2]] * 3  # decided at steps 1-6
        assert np.isnan(engine.memory["heard"][:, 0]).all()
        assert np.array_equal(engine.memory["heard"][:, 1], np.column_stack((np.linspace(-0.5, 0.5, 3), np.zeros(3))))

    class Bad(Tally):
        def decide(self, view):
            view.memory["count"] = np.zeros((len(view), 2), dtype=np.int64)
            return np.zeros((len(view), 2))

    with pytest.raises(ValueError, match=r"memory 'count' must have one value per deciding robot, shape \(3, 3\)"):
        drive(Bad(), 3, 3)


@pytest.mark.parametrize("heed", [None, True, False])
def test_the_safety_layer_heeds_only_the_detections_flagged(heed):
    class HeadOn(SwarmRobot):
        period = 1
        movement = Movement(range=1.0)
        avoid = Avoid(safety=0.2)

        def decide(self, view):
            if heed is not None:
                view.heed(np.full(view.seen.offsets[-1], heed))
            return np.where(view.ids[:, None] == 0, [[0.1, 0.0]], [[-0.1, 0.0]])

    poses = np.array([[-0.15, 0.15], [0.0, 0.0], [0.0, np.pi]])
    engine, _ = drive(HeadOn(), 2, 2, poses=poses)
    wished = np.array([[0.1, 0.0], [-0.1, 0.0]])
    # Heeding nobody, the robots drive into each other as wished; else HRVO turns them away.
    assert np.allclose(engine.dxi, wished) == (heed is False)


def test_draws_depend_on_keys_not_on_order():
    keys = np.arange(1000)
    together = draws.uniform(5, draws.LOSS, 7, keys, keys[::-1])
    apart = np.array([draws.uniform(5, draws.LOSS, 7, k, 999 - k) for k in keys])
    assert np.array_equal(together, apart.ravel())
    assert 0.0 <= together.min() and together.max() < 1.0 and abs(together.mean() - 0.5) < 0.05
    normal = draws.normal(5, draws.DETECTION_NOISE, 7, keys)
    assert abs(normal.mean()) < 0.1 and abs(normal.std() - 1) < 0.1
    assert not np.array_equal(together, draws.uniform(6, draws.LOSS, 7, keys, keys[::-1]))  # the seed counts


def test_loss_bursts_follow_each_link_as_a_set_of_links_does(rng):
    """The engine's links in a burst (a sorted array, kept by the ``bursts`` kernel) against a Python
    set of links, step by step: messages heard in any order, a link heard twice in a step."""
    n, (enter, leave) = 50, (0.3, 0.4)
    engine = SimpleNamespace(n=n, seed=3, lossy=np.zeros(0, dtype=np.int64))
    bursts: set[int] = set()
    for t in range(60):
        me, others = rng.integers(0, n, 400), rng.integers(0, n, 400)
        links = me * n + others
        now = Engine._burst(engine, t, me, others, links, (enter, leave))  # type: ignore[arg-type]
        was = np.array([link in bursts for link in links.tolist()], dtype=bool)
        flip = draws.uniform(3, draws.BURST, t, me, others) < np.where(was, leave, enter)
        assert np.array_equal(now, was ^ flip)
        bursts = (bursts - set(links[was & ~now].tolist())) | set(links[now & ~was].tolist())
        assert engine.lossy.tolist() == sorted(bursts)
    assert 0 < len(bursts) < n * n


@pytest.mark.parametrize(
    ("decide", "message"),
    [
        (lambda view: np.zeros((len(view), 3)), r"decide must return finite velocities of shape \(k, 2\)"),
        (lambda view: np.full((len(view), 2), np.nan), "with NaN or inf"),
    ],
)
def test_a_bad_decision_is_named(decide, message):
    class Bad(SwarmRobot):
        period = 1

    Bad.decide = lambda self, view: decide(view)
    with pytest.raises(ValueError, match=message):
        drive(Bad(), 3, 2)


def test_a_message_must_have_every_declared_field():
    class Partial(SwarmRobot):
        period = 1
        radio = Radio(range=1.0, fields=("x", "y"))

        def decide(self, view):
            view.send(x=view.pose[:, 0])
            return np.zeros((len(view), 2))

    with pytest.raises(ValueError, match=r"sent fields \['x'\], but its radio declares \['x', 'y'\]"):
        drive(Partial(), 3, 2)


def test_a_graph_radio_hears_its_links_whatever_the_distance():
    # A ring of 5: robot i hears i - 1 and i + 1 (mod 5), 10 m apart or not.
    n = 5
    indices = np.array([[(i - 1) % n, (i + 1) % n] for i in range(n)]).ravel()
    radio = Radio(range=0.0, fields=("value",), graph=(np.arange(0, 2 * n + 1, 2), indices))
    robot = Recorder(period=1, radio=radio)
    poses = np.zeros((3, n))
    poses[0] = np.arange(n) * 10.0
    drive(robot, n, 5, poses=poses)
    _, ids, heard = robot.views[-1]
    offsets = np.concatenate(([0], np.cumsum([2] * n)))
    for r, i in enumerate(ids):
        assert sorted(heard["sender"][offsets[r] : offsets[r + 1]]) == sorted({(i - 1) % n, (i + 1) % n})
    with pytest.raises(ValueError, match="graph links 5 robots, but the run has 6"):
        drive(Recorder(period=1, radio=radio), 6, 3)


@pytest.mark.parametrize("faults", [None, EVERY_FAULT], ids=["no faults", "every fault"])
def test_a_graph_radio_is_the_same_both_ways(faults):
    n = 12
    rng = np.random.default_rng(3)
    links = [sorted(set(rng.choice(n, 3, replace=False)) - {i}) for i in range(n)]
    graph = (np.concatenate(([0], np.cumsum([len(row) for row in links]))), np.concatenate(links))

    class Consensus(SwarmRobot):
        period = 2
        movement = Movement(range=0.4)
        avoid = Avoid(safety=0.2)
        radio = Radio(fields=("x", "y"), graph=graph)

        def decide(self, view):
            here = view.pose[:, :2]
            view.send(x=here[:, 0], y=here[:, 1])
            centre = (view.heard.sum(["x", "y"]) + here) / (view.heard.count + 1)[:, None]
            return np.clip(0.5 * (centre - here), -0.1, 0.1)

    class Meet(dream.Experiment):
        name = "graph-meet"

        def swarm_robot(self, n):
            return Consensus()

    one, swarm = both_ways(Meet, n, faults, steps=150)
    assert np.array_equal(one.trace, swarm.trace) and one.collisions == 0


class Apart(SwarmRobot):
    """Robots that all wish the same velocity, each row with its own safety radius (``radii``, by
    id) or the Avoid's, stepping aside to ``side``."""

    period = 1
    movement = Movement(range=1.0)

    def __init__(self, safety, radii=None, side=None):
        self.avoid, self.radii, self.side = Avoid(safety=safety), radii, side

    def decide(self, view):
        if self.radii is not None:
            view.keep_apart(self.radii[view.ids])
        if self.side is not None:
            view.aside(self.side, stop=True)
        return np.tile([0.1, 0.05], (len(view), 1))


def test_each_row_keeps_its_own_safety_radius():
    rng = np.random.default_rng(2)
    n = 12
    poses = np.vstack((rng.uniform(-0.4, 0.4, (2, n)), rng.uniform(-np.pi, np.pi, n)))
    radii = np.where(np.arange(n) % 2, 0.12, 0.3)

    def commands(robot, one_by_one=False):
        engine = dream.swarm.Engine(robot, n, 0, dream.specs.ROBOTARIUM, one_by_one=one_by_one)
        return engine.step(1, poses.copy(), np.zeros((2, n)))

    mixed = commands(Apart(0.24, radii))
    np.testing.assert_array_equal(mixed, commands(Apart(0.24, radii), one_by_one=True))
    for radius in (0.12, 0.3):
        rows = radii == radius
        np.testing.assert_array_equal(mixed[:, rows], commands(Apart(radius))[:, rows])
    assert not np.array_equal(commands(Apart(0.12)), commands(Apart(0.3)))  # the radius matters here
    with pytest.raises(ValueError, match="safety radii must be finite and >= 0"):
        commands(Apart(0.24, -radii))


def test_a_row_chooses_its_side_and_stops_stepping_aside():
    engine = dream.swarm.Engine(Apart(0.24, side=-1.0), 3, 0, dream.specs.ROBOTARIUM)
    engine.sidestep[:] = 5
    engine.step(1, np.array([[-1.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), np.zeros((2, 3)))
    np.testing.assert_array_equal(engine.sidestep, 0)
    np.testing.assert_array_equal(engine.side, -1.0)
    with pytest.raises(ValueError, match="Avoid horizon"):
        Avoid(horizon=-1.0)


def test_an_inbox_only_summed_is_summed_in_the_perception_pass(monkeypatch):
    # The rendezvous robot reads its inbox only through heard.sum and heard.count: after its first
    # decision the engine sums it in the perception's pass, without its rows. A run whose inbox is
    # listed at every step instead (as a decision that reads more of it gets it) is the same, bit
    # for bit.
    summed = []
    perceive = dream.kernels.perceive

    def spy(*args, **kwargs):
        summed.append(len(kwargs.get("summed") or ()))
        return perceive(*args, **kwargs)

    monkeypatch.setattr(dream.kernels, "perceive", spy)
    runs = []
    for learns in (True, False):
        if not learns:  # every load taken for more than a sum: the inbox is listed from then on
            monkeypatch.setattr(dream.swarm.engine, "summing", lambda: False)
        summed.clear()
        runs.append(dream.run(rendezvous(), n=60, seed=3, steps=250, backend="fast", swarm=True, trace=True))
        # Both fields, x and y, at every step after the first decisions (which load the inbox).
        assert len(summed) > 50 and all(s == (2 if learns else 0) for s in summed[2:])
    in_pass, listed = runs
    assert np.array_equal(in_pass.trace, listed.trace)
    assert np.ptp(in_pass.trace[:, :2], axis=0).max() > 0.1  # the robots did move
