"""Faults injected by the world: settings, what each fault does, seeded events, CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

import dream
from dream import Experiment, Faults, GraphRadio, OdometrySensor, Robot, World, create_timer
from dream.cli import main
from dream.faults import FaultState


def _state(n=4, seed=0, **settings):
    return FaultState(Faults(**settings), n, np.random.default_rng(seed))


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"loss": 1.5}, r"loss is a probability in \[0, 1\], got 1.5"),
        ({"burst": (0.1, 2.0)}, "burst p_leave is a probability"),
        ({"latency": -1}, "latency must be a whole number >= 0"),
        ({"drift": 1.0}, r"drift is a clock-rate error in \[0, 1\)"),
        ({"lie": "loud"}, "lie must be one of constant, random, drift"),
        ({"actuator_noise": -0.1}, "actuator_noise must be a number >= 0"),
    ],
)
def test_faults_refuse_bad_settings(settings, message):
    with pytest.raises(ValueError, match=message):
        Faults(**settings)


def test_faults_parse_the_cli_forms():
    parsed = Faults.parse(["loss=0.3", "crash=0.1@300", "burst=0.05:0.3", "byzantine=2:random", "latency=5"])
    assert parsed == Faults(loss=0.3, crash=0.1, crash_at=300, burst=(0.05, 0.3), byzantine=2, lie="random", latency=5)
    assert parsed.to_dict()["burst"] == [0.05, 0.3] and "stuck" not in parsed.to_dict()
    assert not Faults().any and parsed.any


@pytest.mark.parametrize(
    ("option", "message"),
    [("teleport=1", "unknown fault 'teleport'"), ("loss", "expected KIND=VALUE"), ("burst=0.1", "P_ENTER:P_LEAVE")],
)
def test_faults_parse_errors_name_the_option_and_the_kinds(option, message):
    with pytest.raises(ValueError, match=rf"--fault '{option}': .*{message}.*\(kinds: loss, burst"):
        Faults.parse([option])


def test_independent_loss_drops_its_share():
    state = _state(loss=0.3)
    through = [state.delivered(0, 1, 0.0, 0.0) for _ in range(20000)]
    assert abs(1 - np.mean(through) - 0.3) < 0.015 and state.messages_lost == through.count(False)


def test_bursty_loss_comes_in_bursts_at_the_stationary_rate():
    enter, leave = 0.05, 0.25
    state = _state(burst=(enter, leave))
    lost = np.array([not state.delivered(0, 1, 0.0, 0.0) for _ in range(40000)])
    assert abs(lost.mean() - enter / (enter + leave)) < 0.02
    starts = np.count_nonzero(lost[1:] & ~lost[:-1])
    assert abs(lost.sum() / starts - 1 / leave) < 0.5  # mean burst length 1 / p_leave, not ~1


def test_loss_grows_with_distance():
    state = _state(distance_loss=0.5)
    near = np.mean([state.delivered(0, 1, 0.0, 0.2) for _ in range(5000)])
    far = np.mean([state.delivered(0, 1, 0.0, 1.6) for _ in range(5000)])
    assert abs(near - 0.9) < 0.03 and abs(far - 0.2) < 0.03


def test_latency_jitter_stays_within_its_bounds():
    state = _state(latency=5, jitter=2)
    delays = {state.delay(1) for _ in range(500)}
    assert delays == {4, 5, 6, 7, 8}


def test_liars_replace_floats_and_keep_ids():
    constant, drifting = _state(byzantine=1), _state(byzantine=1, lie="drift")
    assert constant.lie(0, (3, 1.5, -0.2), 10) == (3, 0.0, 0.0)
    assert drifting.lie(0, [3, 1.0], 100) == [3, pytest.approx(1.2)]
    lied = _state(byzantine=1, lie="random").lie(0, {"p": np.array([9.0, 9.0])}, 5)
    assert np.all(np.abs(lied["p"]) <= 1.6)


def test_sensor_dropout_drops_its_share():
    state = _state(sensor_dropout=0.1)
    dropped = [state.dropped() for _ in range(20000)]
    assert abs(np.mean(dropped) - 0.1) < 0.01 and state.readings_dropped == sum(dropped)


class Chatter(Experiment):
    """Still robots on a complete graph that publish (id, x) and count what they hear."""

    name = "chatter"
    default_n = 6

    def build(self, n):
        self.heard = np.zeros(n, dtype=int)
        self.ticks = np.zeros(n, dtype=int)
        for i in range(n):
            robot = Robot(i)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            radio = GraphRadio(i, f"radio_{i}", self._listener(i, robot), np.ones((n, n)))
            create_timer(
                i,
                0,
                [
                    {"delay": 1, "tag": "odom", "call": odometry.update},
                    {"delay": 1, "tag": "radio", "call": radio.update},
                ],
            )

    def _listener(self, i, robot):
        def listen(messages):
            self.ticks[i] += 1
            self.heard[i] += len(messages)
            self.last = messages
            return (i, robot.pos_x)

        return listen

    def timer_params(self, x, dxu):
        return {"odom": (x,), "radio": (x,)}

    def measures(self):
        return {"heard": self.heard.tolist(), "ticks": self.ticks.tolist()}


def test_crashed_robots_stop_talking_and_moving_and_events_are_seeded():
    faults = Faults(crash=0.5, crash_at=50)
    first = dream.run(Chatter, backend="fast", steps=100, faults=faults, seed=2, trace=True)
    again = dream.run(Chatter, backend="fast", steps=100, faults=faults, seed=2)
    other = dream.run(Chatter, backend="fast", steps=100, faults=faults, seed=4)
    crashed = sorted(event["robot"] for event in first.faults["events"])
    assert len(crashed) == 3 and {e["step"] for e in first.faults["events"]} == {50}
    assert first.faults["events"] == again.faults["events"] != other.faults["events"]
    ticks = np.array(first.measures["ticks"])
    alive = np.setdiff1d(np.arange(6), crashed)
    assert np.all(ticks[crashed] < ticks[alive])  # crashed robots' timers stopped
    # After the crash the survivors hear only each other: 2 robots each instead of 5.
    plain = dream.run(Chatter, backend="fast", steps=100, seed=2)
    heard, heard_plain = np.array(first.measures["heard"]), np.array(plain.measures["heard"])
    assert np.all(heard_plain[alive] - heard[alive] == 3 * 50)  # exchanges at steps 50-99
    assert np.all(first.trace[51:][:, :, crashed] == first.trace[50][:, crashed])


def test_stuck_robots_keep_talking():
    result = dream.run(Chatter, backend="fast", steps=60, faults=Faults(stuck=1.0, stuck_at=0), seed=1)
    assert len(result.faults["events"]) == 6 and all(e["kind"] == "stuck" for e in result.faults["events"])
    assert min(result.measures["heard"]) > 0


def test_clock_drift_changes_how_often_timers_fire():
    result = dream.run(Chatter, backend="fast", steps=400, faults=Faults(drift=0.2), seed=4)
    ticks = np.array(result.measures["ticks"])
    assert ticks.max() - ticks.min() > 40  # rates 0.8-1.2 of 400 steps, instead of equal counts


def test_no_faults_draws_nothing_and_changes_nothing():
    plain = dream.run("hrvo-circle", backend="fast", steps=150, seed=5, trace=True)
    empty = dream.run("hrvo-circle", backend="fast", steps=150, seed=5, trace=True, faults=Faults())
    np.testing.assert_array_equal(plain.trace, empty.trace)
    assert empty.faults == {}


def test_actuator_noise_stays_within_the_wheels_limits():
    result = dream.run("hrvo-circle", backend="fast", steps=300, seed=1, faults=Faults(actuator_noise=0.05))
    assert result.actuator == 0 and result.collisions == 0


def test_cli_fault_settings_reach_the_json(tmp_path, capsys):
    out = tmp_path / "out.json"
    argv = ["run", "line-consensus", "-n", "10", "--backend", "fast", "--steps", "50", "--json", str(out)]
    assert main([*argv, "--fault", "loss=0.3", "--fault", "latency=5"]) == 0
    faults = json.loads(out.read_text())["faults"]
    assert faults["settings"] == {"loss": 0.3, "latency": 5} and faults["messages_lost"] > 0
    assert main([*argv, "--fault", "loss=2"]) == 2
    assert "--fault 'loss=2': loss is a probability" in capsys.readouterr().err


def test_world_without_injection_keeps_the_radio_loss_on_its_generator():
    with World(3) as world:
        assert world.fault_state is None and world.inject(Faults(), 4) is None


# -- faults that never happen, and success that must hold (issue 30, item 11) ---------------------
class Parked(Experiment):
    """Robots that never move; done from step 189 on, or while every robot is correct with ``fragile``."""

    name = "parked"
    default_n = 10
    fragile = False

    def build(self, n):
        pass

    def done(self, step, poses):
        return step >= 189 and (not self.fragile or bool(self.correct.all()))


class ParkedHeld(Parked):
    hold_steps = 150


class FragileHeld(ParkedHeld):
    fragile = True


def test_a_fault_scheduled_after_the_run_ends_warns_and_is_recorded():
    with pytest.warns(RuntimeWarning, match="fault crash@300 never happened: the run ended at step 189"):
        result = dream.run(Parked, backend="fast", faults=Faults(crash=0.1, crash_at=300))
    assert result.success and result.completed_step == 189
    assert result.faults["events"] == [] and result.faults["pending"] == [{"kind": "crash", "step": 300}]
    assert "never happened    crash@300" in result.summary()


def test_the_json_lists_the_faults_that_never_happened(tmp_path, capsys):
    source, out = tmp_path / "parked.py", tmp_path / "out.json"
    source.write_text(
        "from dream import Experiment\n\n\nclass Parked(Experiment):\n    name = 'parked'\n\n"
        "    def build(self, n):\n        pass\n\n    def done(self, step, poses):\n        return step >= 189\n"
    )
    argv = ["run", str(source), "--backend", "fast", "--no-progress", "--json", str(out)]
    assert main([*argv, "--fault", "crash=0.1@300", "--fault", "stuck=0.1@100"]) == 0
    assert capsys.readouterr().err == (
        "dream: warning: fault crash@300 never happened: the run ended at step 189 "
        "(an experiment's hold_steps keeps a run going after done)\n"
    )
    faults = json.loads(out.read_text())["faults"]
    assert faults["pending"] == [{"kind": "crash", "step": 300}]
    assert [event["kind"] for event in faults["events"]] == ["stuck"]


def test_success_must_hold_for_the_experiments_hold_steps():
    result = dream.run(ParkedHeld, backend="fast", faults=Faults(crash=0.1, crash_at=300))
    assert result.completed_step == 339 and result.faults["pending"] == []  # held from 189 to 339
    assert [event["step"] for event in result.faults["events"]] == [300]
    # a crash at 300 breaks a success that needs every robot: the count starts again, never to end
    fragile = dream.run(FragileHeld, backend="fast", steps=600, faults=Faults(crash=0.1, crash_at=300))
    assert not fragile.completed and fragile.steps == 600
    assert dream.run(FragileHeld, backend="fast").completed_step == 339  # without the crash


def test_hold_steps_must_be_a_whole_number():
    with pytest.raises(TypeError, match=r"Bad.hold_steps must be an integer >= 0, got -1"):
        type("Bad", (Parked,), {"hold_steps": -1})


def test_every_kind_turns_on_every_fault_kind_and_takes_changes_by_name():
    from dream.faults import KINDS

    every = Faults.every_kind()
    assert set(every.to_dict()) >= set(KINDS)  # each kind the CLI knows differs from no fault
    assert Faults.every_kind(loss=0.5).loss == 0.5 and Faults.every_kind(loss=0.5).latency == every.latency
