"""The Experiment spec and the one runner: parameters, refusals, files, and the ported experiments."""

from __future__ import annotations

import numpy as np
import pytest

import dream
from dream.experiments import EXPERIMENTS, Experiment, ExperimentFileError, load_file, param


class Still(Experiment):
    """Robots that never move; done after `wait` steps."""

    name = "still"
    default_n = 3
    wait: int = param(5, "steps before done")
    gain: float = param(1.0, "unused")
    loud: bool = param(False, "unused")

    def build(self, n):
        self.built = n

    def done(self, step, poses):
        return step >= self.wait

    def measures(self):
        return {"built": self.built}


def test_params_are_declared_in_order_with_defaults_and_help():
    declared = Still.parameters()
    assert list(declared) == ["wait", "gain", "loud"]
    assert declared["wait"].default == 5 and declared["wait"].help == "steps before done"
    assert Still().params == {"wait": 5, "gain": 1.0, "loud": False}


@pytest.mark.parametrize(
    ("given", "expected"),
    [({"wait": "7"}, 7), ({"gain": 2}, 2.0), ({"gain": "0.5"}, 0.5), ({"loud": "yes"}, True), ({"loud": "0"}, False)],
)
def test_params_convert_text_and_numbers(given, expected):
    assert next(iter(Still(**given).params[name] for name in given)) == expected


@pytest.mark.parametrize(
    ("given", "message"),
    [
        ({"speed": 1}, r"still has no parameter 'speed' \(its parameters: wait, gain, loud\)"),
        ({"wait": "x"}, r"parameter 'wait' of still expects an integer, got 'x'"),
        ({"wait": 2.5}, r"parameter 'wait' of still expects an integer, got 2.5"),
        ({"loud": "maybe"}, r"parameter 'loud' of still expects true or false"),
        ({"gain": True}, r"parameter 'gain' of still expects a number"),
    ],
)
def test_params_reject_unknown_names_and_wrong_types(given, message):
    with pytest.raises(ValueError, match=message):
        Still(**given)


class Ranged(Experiment):
    name = "ranged"
    spacing: float = param(0.3, "> 0 and finite", gt=0)
    share: float = param(0.5, "a fraction", ge=0, le=1)
    gap: int = param(10, "at least one step", ge=1)
    reach: float = param(1.0, "inf: unlimited", ge=0, finite=False)
    gain: float = param(1.0, "any finite number")


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("spacing", "inf", "must be finite and > 0, got inf"),
        ("spacing", "0", "must be finite and > 0, got 0.0"),
        ("spacing", "-1", "must be finite and > 0, got -1.0"),
        ("spacing", "nan", "must be finite and > 0, got nan"),
        ("share", 1.5, r"must be in \[0, 1\], got 1.5"),
        ("gap", "0", "must be >= 1, got 0"),
        ("reach", "nan", "must be >= 0, got nan"),
        ("gain", "-inf", "must be finite, got -inf"),
    ],
)
def test_params_refuse_values_out_of_their_range_naming_it(name, value, message):
    with pytest.raises(ValueError, match=rf"^parameter '{name}' of ranged {message}$"):
        Ranged(**{name: value})


def test_params_take_any_value_in_their_range():
    given = Ranged(spacing="1e-9", share=1, gap=1, reach="inf", gain=-5).params
    assert given == {"spacing": 1e-9, "share": 1.0, "gap": 1, "reach": float("inf"), "gain": -5.0}
    assert [p.range for p in Ranged.parameters().values()] == ["finite and > 0", "in [0, 1]", ">= 1", ">= 0", "finite"]
    assert Still.parameters()["wait"].range == "" and Still.parameters()["loud"].range == ""


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda: param(0.0, "x", gt=0), ValueError, r"default must be in its range \(finite and > 0\), got 0.0"),
        (lambda: param(True, "x", ge=0), TypeError, "only a number has a range"),
        (lambda: param("a", "x", finite=False), TypeError, "only a number has a range"),
        (lambda: param(1.0, "x", gt=0, ge=0), TypeError, "one lower bound"),
    ],
)
def test_param_refuses_a_range_that_cannot_hold(call, error, message):
    with pytest.raises(error, match=message):
        call()


@pytest.mark.parametrize("name", sorted(EXPERIMENTS))
def test_every_number_parameter_of_a_built_in_experiment_declares_its_range(name):
    for declared in EXPERIMENTS[name].parameters().values():
        if declared.kind in (int, float):
            assert declared.range not in ("", "finite"), f"{name}: {declared.name}"


def test_a_value_a_layer_below_refuses_is_named_by_the_users_parameter():
    class Hear(Experiment):
        name = "hear"
        radio: float = param(1.0, "how far a robot hears (m); no range declared")

        def build(self, n):
            for i in range(n):
                dream.RangeRadio(i, f"radio_{i}", lambda messages: None, range=self.radio)

    with pytest.raises(ValueError, match=r"^hear with radio=-1.0: `range` must be finite and >= 0, got -1.0$"):
        dream.run(Hear, n=2, radio=-1, progress=lambda step, cap: pytest.fail("stepped"))


def test_run_takes_a_class_an_instance_or_a_name():
    by_class = dream.run(Still, backend="fast", wait=3)
    assert (by_class.completed_step, by_class.steps, by_class.n, by_class.params["wait"]) == (3, 3, 3, 3)
    by_instance = dream.run(Still(wait=4), n=2, backend="fast")
    assert by_instance.completed_step == 4 and by_instance.measures == {"built": 2}
    assert by_instance.success
    by_name = dream.run("line-consensus", backend="fast", steps=2)
    assert by_name.experiment == "line-consensus" and by_name.steps == 2 and not by_name.completed


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"n": 0}, "n must be an integer >= 1, got 0"),
        ({"seed": -1}, "seed must be an integer >= 0, got -1"),
        ({"steps": 0}, "steps must be an integer >= 1, got 0"),
        ({"backend": "gazebo"}, "unknown backend 'gazebo'"),
    ],
)
def test_run_refuses_bad_options_before_any_step(options, message):
    with pytest.raises(ValueError, match=message):
        dream.run(Still, **options)


def test_run_takes_false_for_no_progress_and_refuses_what_it_cannot_call():
    assert dream.run(Still, backend="fast", progress=False, record=None).steps == 5
    for options, message in [
        ({"progress": True}, r"progress must be a function called as progress\(step, cap\), or None or False"),
        ({"record": "x.gif"}, r"record must be a function called as record\(frame\)"),
        ({"faults": {"loss": 0.3}}, r"faults must be a dream.Faults"),
    ]:
        with pytest.raises(ValueError, match=message):
            dream.run(Still, backend="fast", **options)


class Capped(Experiment):
    """Sizes its arena by the step cap: room for the robots to drive at 0.1 m/s for the whole run."""

    name = "capped"
    default_n = 2

    def check(self, n, backend):
        self.seen = {"check": self.steps_cap}

    def arena_for(self, n):  # the hook's signature of before the cap: still called as it is
        self.seen["arena_for"] = self.steps_cap
        side = 3.0 if self.steps_cap is None else max(3.0, 0.1 * 0.033 * self.steps_cap * 2)
        return dream.ArenaSpec.centred(side, side)

    def build(self, n):
        self.seen["build"] = self.steps_cap

    def steps(self, n):
        return 7

    def measures(self):
        return {**self.seen, "width": self.arena.width}


def test_the_experiment_sees_the_step_cap_before_it_sizes_its_arena_and_builds(tmp_path):
    given = dream.run(Capped, backend="fast", steps=5000)
    assert given.measures == {"check": 5000, "arena_for": 5000, "build": 5000, "width": pytest.approx(33.0)}
    assert given.steps == 5000
    own = dream.run(Capped, backend="fast")
    assert own.measures == {"check": None, "arena_for": None, "build": None, "width": 3.0} and own.steps == 7
    path = tmp_path / "run.ckpt"
    dream.run(Capped, backend="fast", checkpoint=path)
    resumed = dream.resume(path, steps=9)
    assert resumed.steps == 9 and resumed.measures["check"] is None  # measured when it was built...
    assert dream.experiments.checkpoint.load(path).stepper.exp.steps_cap == 9  # ...and sees the new cap


def test_arena_spec_is_a_public_name():
    assert dream.ArenaSpec is dream.specs.ArenaSpec and "ArenaSpec" in dream.__all__
    assert dream.ArenaSpec() == dream.specs.ROBOTARIUM


def test_run_refuses_unknown_experiment_names():
    with pytest.raises(ValueError, match="unknown experiment 'nope': choose one of affine-formation"):
        dream.run("nope")


def _write(tmp_path, text):
    path = tmp_path / "mine.py"
    path.write_text(text)
    return path


def test_load_file_finds_the_one_experiment(tmp_path):
    path = _write(tmp_path, "from dream import Experiment\nclass Mine(Experiment):\n    name = 'mine'\n")
    assert load_file(path).name == "mine"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("x = 1\n", "defines no Experiment subclass"),
        (
            "from dream import Experiment\nclass A(Experiment): pass\nclass B(Experiment): pass\n",
            r"defines 2 Experiment subclasses \(A, B\)",
        ),
        ("def broken(:\n", "line 1: syntax error"),
        ("import not_a_module_anywhere\n", "loading it raised ModuleNotFoundError"),
    ],
)
def test_load_file_refuses_files_without_exactly_one_experiment(tmp_path, text, message):
    with pytest.raises(ExperimentFileError, match=message):
        load_file(_write(tmp_path, text))


def test_load_file_refuses_a_missing_file(tmp_path):
    with pytest.raises(ExperimentFileError, match="no such file"):
        load_file(tmp_path / "absent.py")


@pytest.mark.parametrize("name", sorted(EXPERIMENTS))
def test_every_experiment_succeeds_at_its_default_size_under_each_labs_rules(name):
    """What the lab's verifier checks: rps 2.1's colliders (0.135 m, 0.025 m ahead), its wheel
    base and its actuator test on the commands as given; and rps 0.0.0's."""
    for rules in ("rps0", "rps2"):
        result = dream.run(name, seed=0, backend="fast", rules=rules)
        assert result.rules == rules
        assert result.success, (rules, result.summary())
        assert (result.collisions, result.boundary, result.actuator) == (0, 0, 0)


class Drive(Experiment):
    """Robots that all drive forward; in swarm mode one call decides for all of them."""

    name = "drive"
    default_n = 4
    has_swarm_mode = True
    speed: float = param(0.05, "forward speed (m/s)")

    def build(self, n):
        self.calls = []

    def build_swarm(self, n):
        self.calls = ["build_swarm"]

    def before_step(self, step):
        self.calls.append(("before_step", step))

    def swarm_step(self, step, x):
        assert x.shape == (3, self.n)
        self.calls.append(("swarm_step", step))
        return np.vstack((np.full(self.n, self.speed), np.zeros(self.n)))

    def measures(self):
        return {"swarm": self.swarm, "calls": len(self.calls)}


def test_swarm_mode_calls_build_swarm_and_swarm_step_in_the_one_runner():
    result = dream.run(Drive, backend="fast", steps=3, swarm=True, trace=True)
    assert result.swarm and result.experiment == "drive" and result.steps == 3
    assert result.measures == {"swarm": True, "calls": 7}
    travelled = np.hypot(*(result.trace[-1, :2] - result.trace[0, :2]))
    assert np.all(travelled > 0.0)
    per_robot = dream.run(Drive, backend="fast", steps=3)
    assert not per_robot.swarm and per_robot.measures == {"swarm": False, "calls": 3}  # no timers: nobody moves


def test_swarm_mode_commands_go_through_the_faulty_wheels():
    # Half the robots crash at step 2: from then on their commands are not carried out.
    result = dream.run(
        Drive, n=4, backend="fast", steps=10, swarm=True, trace=True, faults=dream.Faults(crash=0.5, crash_at=2)
    )
    crashed = [event["robot"] for event in result.faults["events"] if event["kind"] == "crash"]
    assert len(crashed) == 2
    still = np.zeros(4, dtype=bool)
    still[crashed] = True
    moved = np.hypot(*(result.trace[-1, :2] - result.trace[3, :2]))
    assert np.all(moved[still] == 0.0) and np.all(moved[~still] > 0.0)


def test_swarm_mode_is_refused_by_an_experiment_without_one():
    with pytest.raises(ValueError, match=r"still has no swarm mode"):
        dream.run(Still, backend="fast", steps=2, swarm=True)


def test_swarm_step_must_return_one_command_column_per_robot():
    class Short(Drive):
        def swarm_step(self, step, x):
            return np.zeros((2, self.n - 1))

    with pytest.raises(
        ValueError, match=r"drive.swarm_step returned commands of shape \(2, 3\), expected \(2, n\) = \(2, 4\)"
    ):
        dream.run(Short, backend="fast", steps=2, swarm=True)
