"""``dream.make_robotarium`` and the backend protocol shared by Robotarium and Fast."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

import dream
from dream.backends import Fast, Robotarium, make_robotarium
from dream.specs import ArenaSpec

BACKENDS = ["robotarium", "fast"]
RPS_MAX_ANGULAR = 2 * (0.016 / 0.11) * (0.2 / 0.016)  # rps's max_angular_velocity


def pairwise_distances(poses):
    xy = poses[:2].T
    return np.linalg.norm(xy[:, None] - xy[None], axis=2)


def run(backend, commands, steps):
    for _ in range(steps):
        backend.get_poses()
        backend.set_velocities(np.arange(backend.number_of_robots), commands)
        backend.step()


# -- choosing a backend ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("n", "arena", "name", "cls"),
    [
        (1, None, "robotarium", Robotarium),
        (10, None, "robotarium", Robotarium),
        (50, None, "robotarium", Robotarium),  # rps's limit, inclusive
        (51, None, "fast", Fast),
        (200, ArenaSpec.centred(10.0, 6.0), "fast", Fast),
        (5, ArenaSpec.centred(6.0, 4.0), "fast", Fast),  # rps only has its own arena
        (5, ArenaSpec(), "robotarium", Robotarium),  # equal to the default arena
    ],
)
def test_make_robotarium_auto_picks_backend(n, arena, name, cls):
    backend = make_robotarium(n, arena=arena, seed=0)
    assert type(backend) is cls
    assert backend.name == name
    assert backend.number_of_robots == n
    assert backend.get_poses().shape == (3, n)
    assert backend.arena == (ArenaSpec() if arena is None else arena)


def test_make_robotarium_is_exported_at_top_level():
    assert dream.make_robotarium is make_robotarium


@pytest.mark.parametrize("name", ["bogus", "rps", "Fast", ""])
def test_make_robotarium_rejects_unknown_backend(name):
    with pytest.raises(ValueError, match=re.escape(repr(name))):
        make_robotarium(3, backend=name, seed=0)


def test_make_robotarium_refuses_more_than_50_real_robots():
    with pytest.raises(ValueError, match="51"):
        make_robotarium(51, backend="robotarium", seed=0)
    assert make_robotarium(51, backend="fast", seed=0).number_of_robots == 51


def test_make_robotarium_refuses_a_custom_arena_on_rps():
    with pytest.raises(ValueError, match="arena"):
        make_robotarium(3, backend="robotarium", arena=ArenaSpec.centred(6.0, 4.0), seed=0)


@pytest.mark.parametrize("n", [-1, 2.5, True, "3"])
def test_make_robotarium_rejects_bad_counts(n):
    with pytest.raises(ValueError):
        make_robotarium(n, backend="fast", seed=0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_make_robotarium_uses_given_initial_conditions(backend):
    start = np.array([[0.1, -0.4], [0.2, 0.5], [0.3, -2.0]])
    b = make_robotarium(2, backend=backend, initial_conditions=start)
    assert_array_equal(b.get_poses(), start)
    with pytest.raises(ValueError, match=r"`initial_conditions` must have shape \(3, 3\)"):
        make_robotarium(3, backend=backend, initial_conditions=start)


# -- seeded initial poses -------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("n", "arena"), [(1, None), (10, None), (50, None), (84, None), (300, ArenaSpec.centred(12.0, 8.0))]
)
def test_make_robotarium_seeded_poses_are_reproducible_inside_and_spaced(n, arena):
    first = make_robotarium(n, arena=arena, seed=42).get_poses()
    again = make_robotarium(n, arena=arena, seed=42).get_poses()
    assert_array_equal(first, again)
    a = ArenaSpec() if arena is None else arena
    assert np.all((a.xmin < first[0]) & (first[0] < a.xmax) & (a.ymin < first[1]) & (first[1] < a.ymax))
    assert np.all(np.abs(first[2]) <= np.pi)
    if n > 1:
        gaps = pairwise_distances(first) + 10 * np.eye(n)
        assert gaps.min() >= 0.2 - 1e-9
    if n >= 10:
        assert not np.array_equal(first, make_robotarium(n, arena=arena, seed=43).get_poses())


def test_make_robotarium_reads_no_world_generator(world):
    # Its starts come from its own arguments: the current world's generator is left untouched,
    # so a script's world draws the same whether or not it made a simulator first.
    before = world.rng.bit_generator.state
    seeded = make_robotarium(8, backend="fast", seed=3).get_poses()
    unseeded = make_robotarium(8, backend="fast").get_poses()
    assert world.rng.bit_generator.state == before
    assert_array_equal(seeded, make_robotarium(8, backend="fast", rng=np.random.default_rng(3)).get_poses())
    assert not np.array_equal(seeded, unseeded)  # no seed: drawn afresh


def test_make_robotarium_too_many_robots_for_the_arena():
    with pytest.raises(ValueError, match="larger arena"):
        make_robotarium(85, backend="fast", seed=0)  # 12 x 7 grid points at 0.2 m


# -- the Robotarium call protocol -----------------------------------------------------------------
@pytest.fixture(params=BACKENDS)
def backend(request):
    start = np.array([[-1.0, 0.0, 1.0], [0.0, 0.5, -0.5], [0.0, np.pi / 2, np.pi]])
    return make_robotarium(3, backend=request.param, initial_conditions=start)


def test_get_poses_twice_without_step_is_an_error(backend):
    backend.get_poses()
    with pytest.raises(RuntimeError, match="get_poses"):
        backend.get_poses()


def test_step_without_get_poses_is_an_error(backend):
    with pytest.raises(RuntimeError, match="get_poses"):
        backend.step()
    backend.get_poses()
    backend.step()
    with pytest.raises(RuntimeError, match="get_poses"):
        backend.step()  # once per step
    assert backend.iterations == 1


def test_poses_property_does_not_count_as_get_poses(backend):
    before = backend.poses
    backend.get_poses()
    assert_array_equal(backend.poses, before)
    backend.step()


def test_poses_property_is_a_read_only_snapshot(backend):
    """``poses`` cannot be written, and a step leaves the poses it gave as they were."""
    before = backend.poses
    kept = before.copy()
    with pytest.raises(ValueError, match="read-only"):
        before[0, 0] = 1.0
    backend.get_poses()
    backend.set_velocities(np.arange(3), np.array([[0.1, 0.1, 0.1], [0.5, 0.5, 0.5]]))
    backend.step()
    assert_array_equal(before, kept)
    assert not np.array_equal(backend.poses, kept)
    writable = backend.get_poses()  # the Robotarium's call gives an array of the caller's own
    writable[0, 0] = 9.0
    assert backend.poses[0, 0] != 9.0
    backend.step()


@pytest.mark.parametrize("bad", [3, 7, -1])
def test_set_velocities_rejects_ids_out_of_range(backend, bad):
    with pytest.raises(IndexError, match=f"robot id {bad}"):
        backend.set_velocities([0, bad], np.zeros((2, 2)))


@pytest.mark.parametrize(
    ("ids", "commands", "message"),
    [
        ([0, 1], np.zeros((2, 3)), r"`velocities` must have shape \(2, 2\), got \(2, 3\)"),
        ([0, 1, 2], np.zeros((3, 3)), r"`velocities` must have shape \(2, 3\)"),
        ([0, 1, 2], np.zeros(6), r"`velocities`"),
        ([0, 1], np.array([[0.1, np.nan], [0.0, 0.0]]), r"`velocities`.*non-finite"),
        ([0], np.array([[0.1], [np.inf]]), r"`velocities`.*non-finite"),
        ([0.5, 1.0], np.zeros((2, 2)), r"`ids`"),
        ([[0, 1]], np.zeros((2, 2)), r"`ids`"),
    ],
)
def test_set_velocities_rejects_bad_commands(backend, ids, commands, message):
    with pytest.raises(ValueError, match=message):
        backend.set_velocities(ids, commands)


def test_set_velocities_on_a_subset_keeps_the_others(backend):
    backend.set_velocities(np.arange(3), np.array([[0.1, 0.05, -0.1], [0.5, -0.5, 1.0]]))
    backend.set_velocities([2, 0], np.array([[0.02, 0.03], [0.0, 0.2]]))
    assert_allclose(backend.velocities, [[0.03, 0.05, 0.02], [0.2, -0.5, 0.0]])
    backend.set_velocities(1, np.array([[0.0], [0.0]]))  # a scalar id
    assert_allclose(backend.velocities, [[0.03, 0.0, 0.02], [0.2, 0.0, 0.0]])
    # and the kept commands are the ones applied in the step
    start = backend.get_poses()
    backend.step()
    moved = backend.poses
    assert moved[0, 0] == pytest.approx(start[0, 0] + 0.033 * 0.03)
    assert_allclose(moved[:2, 1], start[:2, 1])
    assert moved[0, 2] == pytest.approx(start[0, 2] + 0.033 * np.cos(np.pi) * 0.02)


def test_set_velocities_of_every_robot_in_any_order_goes_by_id(backend):
    """Every robot in id order (a swarm's step) and the same robots in another order command each
    robot by its id; the caller's array is not kept."""
    commands = np.array([[0.1, 0.05, -0.1], [0.5, -0.5, 1.0]])
    backend.set_velocities(np.arange(3), commands)
    assert_allclose(backend.velocities, commands)
    commands[0, 0] = 0.0  # changed after the call: not the backend's
    assert backend.velocities[0, 0] == 0.1
    backend.set_velocities(np.array([2, 0, 1]), np.array([[0.02, 0.03, 0.04], [0.0, 0.2, 0.3]]))
    assert_allclose(backend.velocities, [[0.03, 0.04, 0.02], [0.2, 0.3, 0.0]])


def test_set_velocities_clips_commands_beyond_the_limits(backend):
    commands = np.array([[1.0, -0.25, 0.1], [10.0, 0.5, -4.0]])
    backend.set_velocities(np.arange(3), commands)
    assert_allclose(
        backend.velocities, [[0.2, -0.2, 0.1], [RPS_MAX_ANGULAR, 0.5, -RPS_MAX_ANGULAR]], rtol=0, atol=1e-15
    )
    assert_array_equal(commands, [[1.0, -0.25, 0.1], [10.0, 0.5, -4.0]])  # the caller's array is untouched
    start = backend.get_poses()
    backend.step()
    assert backend.poses[0, 0] == pytest.approx(start[0, 0] + 0.033 * 0.2)  # moved at 0.2, not 1.0


def test_velocities_start_at_zero_and_robots_stay_put(backend):
    assert_array_equal(backend.velocities, np.zeros((2, 3)))
    start = backend.get_poses()
    backend.step()
    assert_allclose(backend.poses, start, atol=1e-15)


@pytest.mark.parametrize("name", BACKENDS)
def test_backend_time_step_and_arena(name):
    b = make_robotarium(2, backend=name, seed=1)
    assert b.time_step == 0.033
    assert b.arena.bounds == (-1.6, 1.6, -1.0, 1.0)


# -- drawing and the end-of-script report --------------------------------------------------------
def test_axes_accept_patches_headless(backend):
    from matplotlib.patches import Circle, Rectangle

    circle = backend.axes.add_patch(Circle((0.0, 0.0), 0.1, color="r"))
    rect = backend.axes.add_patch(Rectangle((-0.5, -0.5), 0.2, 0.3))
    assert circle in backend.axes.patches and rect in backend.axes.patches
    assert backend.figure is backend.axes.figure
    buffer = io.BytesIO()
    backend.figure.savefig(buffer, format="png")  # renders without a display
    assert buffer.getvalue().startswith(b"\x89PNG")
    xmin, xmax = backend.axes.get_xlim()
    assert xmin < -1.6 and xmax > 1.6  # the whole arena is in view


@pytest.mark.parametrize("name", BACKENDS)
def test_call_at_scripts_end_prints_the_counts(name, capsys):
    # Robots 0 and 1 overlap for the whole run, robot 2 leaves through the right wall, and
    # in the last 7 steps it also turns at full speed (v = 0.2 with w != 0: a wheel beyond 12.5).
    start = np.array([[0.0, 0.05, 1.55], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    b = make_robotarium(3, backend=name, initial_conditions=start)
    run(b, np.array([[0.0, 0.0, 0.2], [0.0, 0.0, 0.0]]), 10)  # robot 2 crosses x = 1.6 in step 8
    run(b, np.array([[0.0, 0.0, 0.2], [1.0, 1.0, 1.0]]), 7)
    boundary, collision, actuator = b.violations
    assert (collision, actuator) == (17, 7)
    # x_k = 1.55 + 0.0066 k > 1.6 from k = 8 on: boundary counted before steps 9..17
    assert boundary == 9
    b.call_at_scripts_end()
    out = capsys.readouterr().out
    assert "17 iterations" in out
    assert re.search(r"\b9\b[^\n]*outside", out)
    assert re.search(r"\b17\b[^\n]*collided", out)
    assert re.search(r"\b7\b[^\n]*actuator", out)


@pytest.mark.parametrize("name", BACKENDS)
def test_call_at_scripts_end_without_errors(name, capsys):
    b = make_robotarium(4, backend=name, seed=3)
    run(b, np.array([[0.05] * 4, [0.1] * 4]), 5)
    assert tuple(b.violations) == (0, 0, 0)
    b.call_at_scripts_end()
    out = capsys.readouterr().out
    assert "5 iterations" in out
    assert "No errors" in out
    assert not re.search(r"outside|collided", out)
