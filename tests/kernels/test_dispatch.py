"""Dispatch of :mod:`dream.kernels`: one helper picks :mod:`dream._core` or :mod:`dream._reference`,
which take the same arguments, and every public kernel goes through it."""

from __future__ import annotations

import inspect
from types import SimpleNamespace

import numpy as np
import pytest

from dream import _core, _reference, kernels
from dream.kernels import _dispatch
from dream.specs import RPS2
from dream.swarm.engine import Engine

CORE_KERNELS = sorted(set(_core.__all__) - {"__version__"})


@pytest.mark.parametrize("name", CORE_KERNELS)
def test_reference_takes_the_arguments_of_each_core_kernel(name):
    core = inspect.signature(getattr(_core, name))
    reference = inspect.signature(getattr(_reference, name))
    for parameter in core.parameters.values():
        assert parameter.name in reference.parameters, parameter.name
        assert reference.parameters[parameter.name].kind == parameter.kind, parameter.name
    required = {p.name for p in reference.parameters.values() if p.default is inspect.Parameter.empty}
    assert required <= set(core.parameters)


@pytest.mark.parametrize("core", [None, _core])
def test_implementation_reads_the_patched_core(monkeypatch, core):
    monkeypatch.setattr(_dispatch, "_core", core)
    assert _dispatch.implementation("hrvo") is (_reference if core is None else _core).hrvo


class Recorder:
    """A stand-in for ``dream._core`` that answers with the reference and notes what was asked."""

    def __init__(self) -> None:
        self.asked: set[str] = set()

    def __getattr__(self, name: str) -> object:
        self.asked.add(name)
        return getattr(_reference, name)


def test_every_public_kernel_goes_through_the_dispatch(monkeypatch):
    recorder = Recorder()
    monkeypatch.setattr(_dispatch, "_core", recorder)
    poses, commands, points = np.zeros((3, 2)), np.zeros((2, 2)), np.array([[0.0, 0.0], [0.5, 0.0]])
    kernels.unicycle_step(poses, commands)
    kernels.threshold_velocities(commands)
    kernels.threshold_velocities(commands, RPS2)
    kernels.validate(poses, commands)
    kernels.colliding(poses)
    kernels.dxi_to_dxu(commands, poses)
    kernels.dxu_to_dxi(commands, poses[2], 0.05)
    kernels.actuator_limit(commands)
    kernels.hypot(points[:, 0], points[:, 1])
    kernels.neighbours(points, 1.0)
    kernels.far_from(points, points, 0.1)
    kernels.hrvo(points, points, points)
    kernels.HrvoPlanner().velocity(np.zeros((0, 4)), np.zeros(2), np.zeros(2), np.zeros(2))
    kernels.voronoi_cells(points)
    kernels.voronoi_cell(points[0], points[1:])
    kernels.heard_cells(points, np.array([0, 1]), points, points, range=1.0)
    square = (np.array([[1.0, 0.5], [1.2, 0.5], [1.2, 0.7], [1.0, 0.7]]), np.array([0, 4]))
    kernels.virtual_agents(points, square)
    kernels.distance_rays(poses)
    offsets = np.array([0, 1, 2])
    kernels.perceive(
        points, np.zeros(2), np.array([0, 1]), sight=(1.0, 6.0, 0.0), radio_range=1.0, talking=[True, True]
    )
    kernels.linked(np.array([0, 1]), (np.array([0, 1, 2]), np.array([1, 0])), np.array([True, True]))
    kernels.hrvo_rows(points, points, points, np.array([0, 0, 0]), np.zeros((0, 4)))
    kernels.segment_reduce(points, offsets, "sum")
    kernels.segment_any(np.array([True, False]), offsets)
    kernels.segment_nearest(points[:, 0], offsets)
    kernels.segment_nearest_to(points, offsets, points, 1)
    kernels.motion_guard(np.zeros(2), np.zeros(2), offsets, points[:, 0], points[:, 1], near=0.1, horizon=0.2)
    kernels.take_rows([points], [1])
    kernels.put_rows([points], [1], [points[:1]])
    counters, sides = np.zeros(2, dtype=np.int64), np.ones(2)
    kernels.sidestep_ask(points, [0, 1], counters, sides)
    kernels.sidestep_mark(points, points, [0, 1], counters, sides, 10)
    # The swarm engine's random draws and loss bursts, not public kernels.
    engine = SimpleNamespace(n=2, seed=1, lossy=np.zeros(0, dtype=np.int64))
    Engine._burst(engine, 0, np.array([0, 1]), np.array([1, 0]), np.array([1, 2]), (0.5, 0.5))  # type: ignore[arg-type]
    assert recorder.asked == set(CORE_KERNELS)


PLANNER_INPUT = {"detections": np.array([[0.5, 0.0, 0.0, 0.0], [0.3, 1.0, 0.0, 0.0]]), "velocity": np.zeros(2)}
PLANNER_INPUT |= {"preferred": np.array([0.1, 0.0]), "position": np.zeros(2)}


@pytest.mark.parametrize(
    ("name", "row", "bad", "message"),
    [
        ("detections", (1, 0), -0.0028, "`detection distance` must be finite and >= 0, got -0.0028"),
        ("detections", (1, 2), np.nan, r"`detections` contains a non-finite value \(NaN or inf\) at index 1"),
        ("velocity", 1, np.inf, r"`velocity` contains a non-finite value \(NaN or inf\) at index 1"),
        ("position", 0, np.nan, r"`position` contains a non-finite value \(NaN or inf\) at index 0"),
    ],
)
def test_hrvo_planner_refuses_bad_input_alike_on_both_paths(monkeypatch, name, row, bad, message):
    given = {key: value.copy() for key, value in PLANNER_INPUT.items()}
    given[name][row] = bad
    for core in (None, _core):
        monkeypatch.setattr(_dispatch, "_core", core)
        with pytest.raises(ValueError, match=f"^{message}$"):
            kernels.HrvoPlanner().velocity(**given)


@pytest.mark.parametrize("core", [None, _core])
def test_kernel_input_is_read_in_place_by_the_core_and_checked_either_way(monkeypatch, core):
    monkeypatch.setattr(_dispatch, "_core", core)
    poses = np.random.default_rng(0).uniform(-1.0, 1.0, (5, 3)).T  # (3, 5), Fortran order
    got = _dispatch.kernel_input(poses, "poses", (3, None))
    assert np.array_equal(got, poses)
    # The core's bindings read any layout: no copy. The reference gets a C-contiguous copy.
    assert np.shares_memory(got, poses) == (core is not None)
    assert core is not None or got.flags.c_contiguous
    with pytest.raises(ValueError, match=r"`poses` must have shape \(3, n\)"):
        _dispatch.kernel_input(poses.T, "poses", (3, None))
    bad = poses.copy(order="F")
    bad[1, 3] = np.nan
    # A non-finite value is refused, naming the argument: by the wrapper or by the Rust binding.
    with pytest.raises(ValueError, match=r"`poses` contains a non-finite value"):
        kernels.unicycle_step(bad, np.zeros((2, 5)), 0.033)
    with pytest.raises(ValueError, match=r"`positions` contains a non-finite value"):
        kernels.perceive(bad[:2].T, bad[2], [0, 1], radio_range=1.0, talking=np.ones(5, bool))
