"""Unicycle dynamics and rps validation: the Rust kernels against the NumPy reference and
hand-written formulas, through :mod:`dream.kernels` and through :mod:`dream._core` directly."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from dream import _core, _reference, kernels
from dream.sensors import PROJECTION_DISTANCE, seen_velocity
from dream.specs import ROBOTARIUM, RPS, ArenaSpec, RobotSpec, SimulatorSpec

SIZES = [0, 1, 2, 500]
TOL = dict(rtol=1e-12, atol=1e-12)  # libm sin/cos/atan2 may differ in the last bit
FAST = settings(max_examples=40, deadline=None)

# The keyword arguments of the raw kernels, from the constants (not from DREAM's wrappers).
WHEELS = dict(diameter=0.11, wheel_radius=0.016, base_length=0.105, max_wheel=0.2 / 0.016)
LIMITS = dict(max_linear=0.2, max_angular=3.636363, wheel_radius=0.016, base_length=0.105, max_wheel=12.5)
RPS_MAX_ANGULAR = 2 * (0.016 / 0.11) * (0.2 / 0.016)  # rps's max_angular_velocity
BOUNDS = (-1.6, 1.6, -1.0, 1.0)


# -- independent oracles: one robot at a time, with the math module -----------------------------
def step_by_hand(poses, velocities, dt):
    out = np.array(poses, dtype=float)
    for i in range(out.shape[1]):
        x, y, th = poses[:, i]
        v, w = velocities[:, i]
        turned = th + dt * w
        out[:, i] = (
            x + dt * math.cos(th) * v,
            y + dt * math.sin(th) * v,
            math.atan2(math.sin(turned), math.cos(turned)),
        )
    return out


def threshold_by_hand(velocities, max_linear, max_angular):
    out = np.array(velocities, dtype=float)
    for i in range(out.shape[1]):
        for row, limit in ((0, max_linear), (1, max_angular)):
            if abs(out[row, i]) > limit:
                out[row, i] = math.copysign(limit, out[row, i])
    return out


def validate_by_hand(poses, velocities, bounds=BOUNDS, diameter=0.11, r=0.016, length=0.105, max_wheel=12.5):
    xmin, xmax, ymin, ymax = bounds
    n = poses.shape[1]
    boundary = sum(1 for i in range(n) if not (xmin <= poses[0, i] <= xmax and ymin <= poses[1, i] <= ymax))
    collision = sum(
        1
        for i in range(n)
        for j in range(i + 1, n)
        if math.hypot(poses[0, i] - poses[0, j], poses[1, i] - poses[1, j]) <= diameter
    )
    wheels = [(2 * v - length * w) / (2 * r) for v, w in velocities.T] + [
        (2 * v + length * w) / (2 * r) for v, w in velocities.T
    ]
    actuator = int(any(abs(s) > max_wheel for s in wheels))
    return boundary, collision, actuator


def dxu_by_hand(dxi, poses, kv, kw):
    out = np.zeros_like(dxi, dtype=float)
    for i in range(dxi.shape[1]):
        c, s = math.cos(poses[2, i]), math.sin(poses[2, i])
        v = kv * (c * dxi[0, i] + s * dxi[1, i])
        out[:, i] = v, kw * math.atan2(-s * dxi[0, i] + c * dxi[1, i], v) / (math.pi / 2)
    return out


def limit_by_hand(dxu, v_max=0.2, w_max=3.636363, r=0.016, length=0.105, ac_max=12.5):
    out = np.zeros_like(dxu, dtype=float)
    for i in range(dxu.shape[1]):
        v = min(max(dxu[0, i], -v_max), v_max)
        w = min(max(dxu[1, i], -w_max), w_max)
        if abs(v) / r + abs(w) * length / (2 * r) > ac_max:
            v = math.copysign(ac_max * r - abs(w) * length / 2, v)
        out[:, i] = v, w
    return out


def wheel_speeds(dxu, r=0.016, length=0.105):
    """rps's ``_uni_to_diff``: left and right wheel speeds ``(2, n)``."""
    return np.vstack(((2 * dxu[0] - length * dxu[1]) / (2 * r), (2 * dxu[0] + length * dxu[1]) / (2 * r)))


def random_poses(rng, n, spread=2.0):
    return np.vstack((rng.uniform(-spread, spread, (2, n)), rng.uniform(-10.0, 10.0, (1, n))))


def random_commands(rng, n):
    # Beyond the limits on purpose, so that the clipping branches run.
    return np.vstack((rng.uniform(-0.5, 0.5, n), rng.uniform(-8.0, 8.0, n)))


# -- unicycle_step --------------------------------------------------------------------------------
@pytest.mark.parametrize("n", SIZES)
def test_unicycle_step_matches_reference_and_formula(rng, n):
    poses, commands = random_poses(rng, n), random_commands(rng, n)
    expected = step_by_hand(poses, commands, 0.033)
    for got in (kernels.unicycle_step(poses, commands), _core.unicycle_step(poses, commands, 0.033)):
        assert got.shape == (3, n) and got.dtype == np.float64
        assert_allclose(got, expected, **TOL)
    assert_allclose(_reference.unicycle_step(poses, commands, 0.033), expected, **TOL)


def test_unicycle_step_does_not_modify_its_input(rng):
    poses, commands = random_poses(rng, 5), random_commands(rng, 5)
    before = poses.copy(), commands.copy()
    _core.unicycle_step(poses, commands, 0.033)
    kernels.unicycle_step(poses, commands)
    assert_array_equal(poses, before[0])
    assert_array_equal(commands, before[1])


def test_unicycle_step_wraps_heading_into_minus_pi_pi():
    # Heading 3.1 turned by 0.33 rad passes pi and comes back as 3.43 - 2 pi.
    got = kernels.unicycle_step(np.array([[0.0], [0.0], [3.1]]), np.array([[0.1], [10.0]]), 0.033)
    assert_allclose(
        got[:, 0], [0.1 * 0.033 * math.cos(3.1), 0.1 * 0.033 * math.sin(3.1), 3.1 + 0.33 - 2 * math.pi], **TOL
    )


@given(
    x=st.floats(-5, 5),
    y=st.floats(-5, 5),
    th=st.floats(-20, 20),
    v=st.floats(-1, 1),
    w=st.floats(-10, 10),
    dt=st.floats(1e-4, 1.0),
)
@FAST
def test_unicycle_step_property_single_robot(x, y, th, v, w, dt):
    poses, commands = np.array([[x], [y], [th]]), np.array([[v], [w]])
    got = _core.unicycle_step(poses, commands, dt)
    assert_allclose(got[:2], step_by_hand(poses, commands, dt)[:2], **TOL)
    assert -math.pi <= got[2, 0] <= math.pi
    # the same heading modulo 2 pi
    assert abs(math.sin(got[2, 0] - (th + dt * w))) < 1e-9 and math.cos(got[2, 0] - (th + dt * w)) > 0
    assert math.hypot(got[0, 0] - x, got[1, 0] - y) == pytest.approx(abs(v) * dt, rel=1e-9, abs=1e-14)


# -- threshold_velocities -------------------------------------------------------------------------
@pytest.mark.parametrize("n", SIZES)
def test_threshold_velocities_matches_reference_and_formula(rng, n):
    commands = random_commands(rng, n)
    expected = threshold_by_hand(commands, 0.2, RPS_MAX_ANGULAR)
    assert_allclose(kernels.threshold_velocities(commands), expected, rtol=0, atol=0)
    assert_allclose(_core.threshold_velocities(commands, 0.2, RPS_MAX_ANGULAR), expected, rtol=0, atol=0)
    assert_allclose(_reference.threshold_velocities(commands, 0.2, RPS_MAX_ANGULAR), expected, rtol=0, atol=0)


def test_threshold_velocities_keeps_commands_exactly_at_the_limits():
    at = np.array([[0.2, -0.2, 0.0, 0.2], [0.0, RPS_MAX_ANGULAR, -RPS_MAX_ANGULAR, -RPS_MAX_ANGULAR]])
    assert_array_equal(kernels.threshold_velocities(at), at)
    assert_array_equal(_core.threshold_velocities(at, 0.2, RPS_MAX_ANGULAR), at)


@given(v=st.floats(-1e6, 1e6), w=st.floats(-1e6, 1e6))
@example(v=0.2, w=RPS_MAX_ANGULAR)
@example(v=-0.2, w=-RPS_MAX_ANGULAR)
@example(v=np.nextafter(0.2, 1), w=np.nextafter(-RPS_MAX_ANGULAR, -4))
@FAST
def test_threshold_velocities_property_clips_and_keeps_signs(v, w):
    got = _core.threshold_velocities(np.array([[v], [w]]), 0.2, RPS_MAX_ANGULAR)[:, 0]
    for value, limit, out in ((v, 0.2, got[0]), (w, RPS_MAX_ANGULAR, got[1])):
        assert abs(out) <= limit
        assert out == (value if abs(value) <= limit else math.copysign(limit, value))


# -- validate -------------------------------------------------------------------------------------
def assert_same_validation(got, counts, poses, bounds=BOUNDS, rules=WHEELS):
    """The kernel's ``(boundary, collision, actuator, robots)``: ``counts`` and the reference's."""
    reference = _reference.validate(poses, np.zeros((2, poses.shape[1])), bounds, **rules)
    assert got[:3] == tuple(counts)
    assert got[3].dtype == np.int64 and np.all(np.diff(got[3]) > 0)
    assert_array_equal(got[3], reference[3])


@pytest.mark.parametrize("n", SIZES)
def test_validate_matches_reference_and_brute_force(rng, n):
    # 2 x 1.2 m around the arena's corner: some robots outside, plenty of close pairs at n = 500.
    poses = np.vstack((rng.uniform(0.6, 2.6, n), rng.uniform(0.0, 1.2, n), rng.uniform(-3, 3, n)))
    commands = np.vstack((rng.uniform(-0.2, 0.2, n), rng.uniform(-0.6, 0.6, n)))
    expected = validate_by_hand(poses, commands)
    assert tuple(kernels.validate(poses, commands)) == expected
    assert_same_validation(_core.validate(poses, commands, BOUNDS, **WHEELS), expected, poses)
    if n == 500:
        assert all(count > 0 for count in expected[:2])  # the test exercises both counts


def test_large_swarms_step_and_validate_on_every_core_as_the_reference(rng):
    # From 4,096 robots the Rust kernels split the swarm across threads: same poses, same counts.
    n = 6000
    poses = np.vstack((rng.uniform(-4.0, 4.0, (2, n)), rng.uniform(-3, 3, (1, n))))
    commands = random_commands(rng, n)
    assert_allclose(
        _core.unicycle_step(poses, commands, 0.033), _reference.unicycle_step(poses, commands, 0.033), **TOL
    )
    bounds = (-3.5, 3.5, -3.5, 3.5)
    expected = _reference.validate(poses, commands, bounds, **WHEELS)
    assert expected[0] > 0 and expected[1] > 100
    assert_same_validation(_core.validate(poses, commands, bounds, **WHEELS), expected[:3], poses, bounds)
    dxu = _core.dxi_to_dxu(commands / 10, poses, 0.8, 3.0)
    assert_allclose(dxu, _reference.dxi_to_dxu(commands / 10, poses, 0.8, 3.0), **TOL)
    limits = dict(max_linear=0.2, max_angular=3.6, wheel_radius=0.016, base_length=0.105, max_wheel=12.5)
    assert_array_equal(_core.actuator_limit(dxu * 5, **limits), _reference.actuator_limit(dxu * 5, **limits))
    assert_array_equal(
        _core.threshold_velocities(dxu * 5, 0.2, 3.6), _reference.threshold_velocities(dxu * 5, 0.2, 3.6)
    )


@pytest.mark.parametrize("offset", [0.0, 0.025])
def test_validate_counts_a_large_swarm_spread_thin_as_the_reference(rng, offset):
    # 6,000 robots in pairs along a ring 400 m across: too many cells for a dense table, so the
    # grid lists its cells column by column; the counts are still every pair's, on every core.
    n = 6000
    angle = np.repeat(rng.uniform(0, 2 * np.pi, n // 2), 2)
    radius = 200 + np.tile([0.0, 0.1], n // 2) + rng.uniform(0, 0.02, n)
    poses = np.vstack((radius * np.cos(angle), radius * np.sin(angle), rng.uniform(-3, 3, n)))
    commands = random_commands(rng, n)
    rules = dict(WHEELS, collider_offset=offset, boundary_per_iteration=False)
    bounds = (-150.0, 210.0, -210.0, 210.0)
    expected = _reference.validate(poses, commands, bounds, **rules)
    assert expected[0] > 0 and expected[1] > 1000
    assert_same_validation(_core.validate(poses, commands, bounds, **rules), expected[:3], poses, bounds, rules)


@pytest.mark.parametrize("n", [0, 1, 9, 500, 4500])
@pytest.mark.parametrize("offset", [0.0, 0.025])
def test_colliding_flags_the_robots_of_the_pairs_validate_counts(rng, n, offset):
    # 4,500 robots: the Rust kernel's cells on every core; the reference compares every pair.
    side = math.sqrt(n / 9) + 0.5  # 9 robots a square metre: about a third of them collide
    poses = np.vstack((rng.uniform(0.0, side, (2, n)), rng.uniform(-3, 3, (1, n))))
    got = _core.colliding(poses, diameter=0.11, collider_offset=offset)
    assert_array_equal(got, _reference.colliding(poses, diameter=0.11, collider_offset=offset))
    colliders = poses[:2] + offset * np.vstack((np.cos(poses[2]), np.sin(poses[2])))
    gaps = np.hypot(*(colliders[:, :, None] - colliders[:, None, :])) if n <= 500 else None
    if gaps is not None:  # by hand: a robot with another collider within the diameter
        np.fill_diagonal(gaps, np.inf)
        assert_array_equal(got, (gaps <= 0.11).any(axis=1))
    spec = dataclasses.replace(RPS, collider_offset=offset, diameter=0.11)
    assert_array_equal(kernels.colliding(poses, spec), got)
    # the simulator's own count lists the same robots, from the same search
    counts, robots = kernels.validate_each(poses, np.zeros((2, n)), spec=spec)
    assert_array_equal(robots, np.flatnonzero(got))
    assert counts.collision >= (len(robots) + 1) // 2
    if n >= 500:
        assert 0 < got.sum() < n  # some robots collide, not all


@pytest.mark.parametrize("n", [2, 7, 30, 50])
def test_validate_matches_rps_own_validate(rng, n):
    # rps's `_validate` is the definition; pass it a fresh dict (its default one is shared).
    from rps.robotarium import Robotarium as Rps

    for _ in range(5):
        poses = np.vstack((rng.uniform(-1.8, 1.8, n), rng.uniform(-1.2, 1.2, n), rng.uniform(-3, 3, n)))
        commands = np.vstack((rng.uniform(-0.2, 0.2, n), rng.uniform(-RPS_MAX_ANGULAR, RPS_MAX_ANGULAR, n)))
        sim = Rps(number_of_robots=n, show_figure=False, sim_in_real_time=False, initial_conditions=poses.copy())
        sim.velocities = commands.copy()
        errors = sim._validate(errors={})
        expected = tuple(errors.get(key, 0) for key in ("boundary", "collision", "actuator"))
        assert tuple(kernels.validate(poses, commands)) == expected


@pytest.mark.parametrize(("columns", "rows"), [(1, 1), (1, 5), (4, 3), (20, 25)])
def test_validate_counts_every_adjacent_pair_of_a_lattice_at_exactly_one_diameter(columns, rows):
    # Spacing 0.125 is exact in binary, so neighbours on the lattice are exactly one diameter
    # apart (inclusive: they collide) and diagonals are not: a lattice has c(r-1) + r(c-1) pairs.
    gx, gy = np.meshgrid(0.125 * np.arange(columns) - 1.0, 0.125 * np.arange(rows) - 0.5)
    poses = np.vstack((gx.ravel(), gy.ravel(), np.zeros(gx.size)))
    commands = np.zeros((2, gx.size))
    expected = columns * (rows - 1) + rows * (columns - 1)
    sim = SimulatorSpec(diameter=0.125)
    assert kernels.validate(poses, commands, spec=sim).collision == expected
    assert _core.validate(poses, commands, BOUNDS, **{**WHEELS, "diameter": 0.125})[1] == expected
    # a hair smaller diameter: no pair at all
    assert _core.validate(poses, commands, BOUNDS, **{**WHEELS, "diameter": np.nextafter(0.125, 0)})[1] == 0


def test_validate_finds_pairs_among_far_flung_robots():
    # Robots spread over 1e12 m make the grid use its sparse table; pairs must still be found.
    xs = np.array([0.0, 1e12, -1e12, 1e12 + 0.05, 0.1, -1e12, 1e6])
    ys = np.array([0.0, 1e12, 0.0, 1e12, 0.0, 0.11, 1e6])
    poses = np.vstack((xs, ys, np.zeros(7)))
    got = _core.validate(poses, np.zeros((2, 7)), BOUNDS, **WHEELS)
    assert got[:3] == validate_by_hand(poses, np.zeros((2, 7)))
    assert got[1] == 3 and got[3].tolist() == [0, 1, 2, 3, 4, 5]


@given(
    x=st.floats(-1.4, 1.4),
    y=st.floats(-0.8, 0.8),
    along_x=st.booleans(),
    sign=st.sampled_from([-1.0, 1.0]),
)
@example(x=0.0, y=-1e-18, along_x=False, sign=1.0)  # straddles two cell boundaries of the grid
@FAST
def test_validate_property_one_diameter_apart_collides(x, y, along_x, sign):
    # Place the second robot so that the computed centre distance is exactly 0.11 (then one ulp more).
    def pair(gap):
        other = (x + sign * gap, y) if along_x else (x, y + sign * gap)
        return np.array([[x, other[0]], [y, other[1]], [0.0, 0.0]])

    poses = pair(0.11)
    assume(math.hypot(poses[0, 0] - poses[0, 1], poses[1, 0] - poses[1, 1]) == 0.11)
    still = np.zeros((2, 2))
    assert kernels.validate(poses, still).collision == 1
    assert _core.validate(poses, still, BOUNDS, **WHEELS)[1] == 1
    apart = pair(0.11)
    apart[0 if along_x else 1, 1] = np.nextafter(apart[0 if along_x else 1, 1], sign * np.inf)
    assume(math.hypot(apart[0, 0] - apart[0, 1], apart[1, 0] - apart[1, 1]) > 0.11)
    assert kernels.validate(apart, still).collision == 0
    assert _core.validate(apart, still, BOUNDS, **WHEELS)[1] == 0


@pytest.mark.parametrize("first", [-1e-18, -1e-45])
@pytest.mark.parametrize("axis", [0, 1])
def test_validate_counts_a_pair_one_diameter_apart_across_cell_boundaries(first, axis):
    # The second robot is 0.11 further: rps's norm gives exactly 0.11 (a collision), although the
    # exact distance is a hair more and the two centres lie two grid cells (of side 0.11) apart.
    poses = np.zeros((3, 2))
    poses[axis] = first, first + 0.11
    assert float(np.linalg.norm(poses[:2, 0] - poses[:2, 1])) <= 0.11  # rps's test
    still = np.zeros((2, 2))
    assert _reference.validate(poses, still, BOUNDS, **WHEELS)[1] == 1
    assert _core.validate(poses, still, BOUNDS, **WHEELS)[1] == 1
    assert kernels.validate(poses, still).collision == 1


@given(side=st.sampled_from(range(4)), t=st.floats(-1.0, 1.0))
@FAST
def test_validate_property_border_is_inside(side, t):
    xmin, xmax, ymin, ymax = ROBOTARIUM.bounds
    x, y = [(xmin, t), (xmax, t), (1.6 * t, ymin), (1.6 * t, ymax)][side]
    on = np.array([[x], [y], [0.0]])
    assert kernels.validate(on, np.zeros((2, 1))).boundary == 0
    assert _core.validate(on, np.zeros((2, 1)), BOUNDS, **WHEELS)[0] == 0
    outward = on.copy()
    row, towards = [(0, -np.inf), (0, np.inf), (1, -np.inf), (1, np.inf)][side]
    outward[row, 0] = np.nextafter(outward[row, 0], towards)
    assert kernels.validate(outward, np.zeros((2, 1))).boundary == 1
    assert _core.validate(outward, np.zeros((2, 1)), BOUNDS, **WHEELS)[0] == 1


@pytest.mark.parametrize(
    ("v", "w", "exceeded"),
    [
        (0.2, 0.0, 0),  # both wheels exactly at 12.5: not beyond
        (-0.2, 0.0, 0),
        (0.2, 0.01, 1),
        (0.1, 1.5, 0),  # faster wheel: 0.1/0.016 + 1.5*0.0525/0.016 = 6.25 + 4.921875
        (0.1, 2.0, 1),  # 6.25 + 6.5625
        (0.1, 3.0, 1),  # 6.25 + 9.84375
    ],
)
def test_validate_actuator_criterion_is_rps_wheel_formula(v, w, exceeded):
    commands = np.array([[v], [w]])
    # the hand-computed verdict agrees with rps's wheel formula
    assert int(np.any(np.abs(wheel_speeds(commands)) > 0.2 / 0.016)) == exceeded
    poses = np.zeros((3, 1))
    assert kernels.validate(poses, commands).actuator == exceeded
    assert _core.validate(poses, commands, BOUNDS, **WHEELS)[2] == exceeded


def test_validate_actuator_counts_one_per_iteration_not_per_robot():
    commands = np.array([[0.2, 0.2, 0.2], [3.0, -3.0, 3.0]])
    poses = np.array([[-1.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert kernels.validate(poses, commands) == kernels.Violations(0, 0, 1)


# -- dxi_to_dxu -----------------------------------------------------------------------------------
@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize(("kv", "kw"), [(0.8, 3.0), (1.0, 1.0), (0.5, 7.0)])
def test_dxi_to_dxu_matches_reference_and_formula(rng, n, kv, kw):
    dxi, poses = rng.uniform(-0.3, 0.3, (2, n)), random_poses(rng, n)
    expected = dxu_by_hand(dxi, poses, kv, kw)
    assert_allclose(kernels.dxi_to_dxu(dxi, poses, kv, kw), expected, **TOL)
    assert_allclose(_core.dxi_to_dxu(dxi, poses, kv, kw), expected, **TOL)
    assert_allclose(_reference.dxi_to_dxu(dxi, poses, kv, kw), expected, **TOL)


@pytest.mark.parametrize(
    ("dxi", "theta", "expected"),
    [
        ((0.1, 0.0), 0.0, (0.08, 0.0)),  # straight ahead: no turning
        ((0.0, 0.1), 0.0, (0.0, 3.0)),  # to the left at 90 degrees: atan2(0.1, 0) = pi/2
        ((0.0, -0.1), 0.0, (0.0, -3.0)),
        ((-0.1, 0.0), 0.0, (-0.08, 6.0)),  # behind: atan2(+0, -0.08) = pi -> 2 * kw
        ((0.1, 0.1), math.pi / 4, (0.8 * 0.1 * math.sqrt(2), 0.0)),
        ((0.0, 0.0), 1.0, (0.0, 0.0)),
    ],
)
def test_dxi_to_dxu_hand_worked_cases(dxi, theta, expected):
    d, p = np.array(dxi, dtype=float).reshape(2, 1), np.array([[0.3], [-0.2], [theta]])
    assert_allclose(kernels.dxi_to_dxu(d, p)[:, 0], expected, rtol=1e-12, atol=1e-12)
    assert_allclose(_core.dxi_to_dxu(d, p, 0.8, 3.0)[:, 0], expected, rtol=1e-12, atol=1e-12)


@given(
    dx=st.floats(-1, 1),
    dy=st.floats(-1, 1),
    th=st.floats(-7, 7),
    kv=st.floats(0.01, 5),
    kw=st.floats(0.01, 10),
)
@FAST
def test_dxi_to_dxu_property_matches_formula(dx, dy, th, kv, kw):
    c, s = math.cos(th), math.sin(th)
    # Away from the atan2 branch cut (v ~ 0 behind the robot) where one rounding flips the sign.
    assume(abs(c * dx + s * dy) > 1e-9 or abs(-s * dx + c * dy) > 1e-9)
    d, p = np.array([[dx], [dy]]), np.array([[0.0], [0.0], [th]])
    expected = dxu_by_hand(d, p, kv, kw)
    got = _core.dxi_to_dxu(d, p, kv, kw)
    assert_allclose(got[0], expected[0], rtol=1e-12, atol=1e-15)
    if abs(c * dx + s * dy) > 1e-9 or abs(-s * dx + c * dy) > 1e-6:
        assert_allclose(got[1], expected[1], rtol=1e-9, atol=1e-9)
    assert abs(got[1, 0]) <= 2 * kw * (1 + 1e-12)


# -- dxu_to_dxi -----------------------------------------------------------------------------------
def dxi_by_hand(dxu, headings, projection):
    out = np.zeros_like(dxu, dtype=float)
    for i in range(dxu.shape[1]):
        c, s = math.cos(headings[i]), math.sin(headings[i])
        v, ahead = dxu[0, i], projection * dxu[1, i]
        out[:, i] = v * c - ahead * s, v * s + ahead * c
    return out


@pytest.mark.parametrize("n", [*SIZES, 5000])  # 5000: on every core
@pytest.mark.parametrize("projection", [0.05, 0.0, -0.2])
def test_dxu_to_dxi_matches_reference_and_formula(rng, n, projection):
    dxu, headings = random_commands(rng, n), rng.uniform(-10.0, 10.0, n)
    expected = dxi_by_hand(dxu, headings, projection)
    # The kernel calls the libm that `math` calls, in the same order: the same bits.
    assert_array_equal(_core.dxu_to_dxi(dxu, headings, projection), expected)
    assert_allclose(_reference.dxu_to_dxi(dxu, headings, projection), expected, **TOL)
    assert_allclose(kernels.dxu_to_dxi(dxu, headings, projection), expected, **TOL)


@pytest.mark.parametrize(
    ("dxu", "theta", "expected"),
    [
        ((0.2, 0.0), 0.0, (0.2, 0.0)),  # straight ahead
        ((0.0, 1.0), 0.0, (0.0, 0.05)),  # turning on the spot: the point ahead moves sideways
        ((0.1, 0.0), math.pi, (-0.1, 0.0)),
        ((0.1, 2.0), math.pi / 2, (-0.1, 0.1)),  # facing +y, turning left: the point sweeps to -x
        ((0.1, 0.0), math.pi / 4, (0.1 / math.sqrt(2), 0.1 / math.sqrt(2))),
    ],
)
def test_dxu_to_dxi_hand_worked_cases(dxu, theta, expected):
    u, headings = np.array(dxu, dtype=float).reshape(2, 1), np.array([theta])
    assert_allclose(kernels.dxu_to_dxi(u, headings, 0.05)[:, 0], expected, rtol=1e-12, atol=1e-15)
    assert_allclose(_core.dxu_to_dxi(u, headings, 0.05)[:, 0], expected, rtol=1e-12, atol=1e-15)


def test_seen_velocity_is_the_point_ahead_to_the_bit(rng):
    dxu, headings = random_commands(rng, 300), rng.uniform(-4.0, 4.0, 300)
    vx, vy = seen_velocity(dxu, headings)
    expected = dxi_by_hand(dxu, headings, PROJECTION_DISTANCE)
    if kernels.IMPLEMENTATION == "rust":
        assert_array_equal(np.vstack((vx, vy)), expected)
    assert_allclose(np.vstack((vx, vy)), expected, **TOL)


@pytest.mark.parametrize("dxu_to_dxi", [_core.dxu_to_dxi, kernels.dxu_to_dxi], ids=["core", "kernels"])
def test_dxu_to_dxi_rejects_bad_input_naming_it(dxu_to_dxi):
    with pytest.raises(ValueError, match=r"`dxu` must have shape \(2, n\), " + SHAPE_GOT.format("3, 4")):
        dxu_to_dxi(np.zeros((3, 4)), np.zeros(4), 0.05)
    with pytest.raises(ValueError, match=r"`headings` must have shape \(4,\), " + SHAPE_GOT.format("3,?")):
        dxu_to_dxi(np.zeros((2, 4)), np.zeros(3), 0.05)
    for bad in (np.nan, np.inf):
        commands, headings = np.zeros((2, 3)), np.zeros(3)
        commands[1, 2] = bad
        with pytest.raises(ValueError, match=r"`dxu`.*non-finite"):
            dxu_to_dxi(commands, np.zeros(3), 0.05)
        headings[1] = bad
        with pytest.raises(ValueError, match=r"`headings`.*non-finite"):
            dxu_to_dxi(np.zeros((2, 3)), headings, 0.05)
        with pytest.raises(ValueError, match=r"`projection`.*finite"):
            dxu_to_dxi(np.zeros((2, 3)), np.zeros(3), bad)


# -- actuator_limit -------------------------------------------------------------------------------
@pytest.mark.parametrize("n", SIZES)
def test_actuator_limit_matches_reference_and_formula(rng, n):
    dxu = random_commands(rng, n)
    expected = limit_by_hand(dxu)
    assert_allclose(kernels.actuator_limit(dxu), expected, **TOL)
    assert_allclose(_core.actuator_limit(dxu, **LIMITS), expected, **TOL)
    assert_allclose(_reference.actuator_limit(dxu, **LIMITS), expected, **TOL)
    assert np.all(np.abs(wheel_speeds(expected)) <= 12.5 + 1e-9)


@pytest.mark.parametrize(
    ("dxu", "expected"),
    [
        ((0.1, 1.0), (0.1, 1.0)),  # 6.25 + 3.28 rad/s: within every limit, unchanged
        ((0.5, 0.0), (0.2, 0.0)),  # clipped to v_max; both wheels exactly 12.5
        ((-0.5, -9.0), (-(0.2 - 3.636363 * 0.0525), -3.636363)),  # w clipped, then v slowed
        ((0.2, 3.0), (0.2 - 3.0 * 0.0525, 3.0)),  # w kept, v = 12.5 r - |w| L / 2
        ((-0.2, 3.0), (-(0.2 - 3.0 * 0.0525), 3.0)),  # the sign of v is kept
        ((0.0, 50.0), (0.0, 3.636363)),  # turning in place never needs v
        ((0.2, 3.636363), (0.2 - 3.636363 * 0.0525, 3.636363)),  # exactly at both limits
    ],
)
def test_actuator_limit_hand_worked_cases(dxu, expected):
    d = np.array(dxu, dtype=float).reshape(2, 1)
    assert_allclose(kernels.actuator_limit(d)[:, 0], expected, rtol=1e-12, atol=1e-15)
    assert_allclose(_core.actuator_limit(d, **LIMITS)[:, 0], expected, rtol=1e-12, atol=1e-15)


@given(v=st.floats(-2, 2), w=st.floats(-20, 20))
@example(v=0.2, w=3.636363)
@example(v=-0.2, w=0.0)
@FAST
def test_actuator_limit_property_no_wheel_too_fast(v, w):
    got = _core.actuator_limit(np.array([[v], [w]]), **LIMITS)
    lv, lw = got[:, 0]
    assert abs(lv) <= 0.2 and abs(lw) <= 3.636363
    assert lw == min(max(w, -3.636363), 3.636363)  # turning is never sacrificed
    assert lv * v >= 0  # v keeps its sign (or becomes 0)
    assert abs(lv) <= abs(v)
    assert np.all(np.abs(wheel_speeds(got)) <= 12.5 * (1 + 1e-12))
    assert_allclose(got, limit_by_hand(np.array([[v], [w]])), rtol=1e-12, atol=1e-15)
    # limiting twice changes nothing more
    assert_allclose(_core.actuator_limit(got, **LIMITS), got, rtol=1e-12, atol=1e-15)


def test_actuator_limit_uses_the_robot_spec(rng):
    slow = RobotSpec(v_max=0.1, w_max=1.0)
    dxu = random_commands(rng, 50)
    got = kernels.actuator_limit(dxu, slow)
    assert_allclose(got, limit_by_hand(dxu, v_max=0.1, w_max=1.0), **TOL)
    assert np.abs(got[0]).max() <= 0.1 and np.abs(got[1]).max() <= 1.0


# -- memory layout ----------------------------------------------------------------------------------
def _layouts(array):
    """The same values as a C array, a Fortran array, a strided view and a reversed view."""
    wide = np.zeros((array.shape[0], 2 * array.shape[1]))
    wide[:, ::2] = array
    reversed_twice = np.ascontiguousarray(array[:, ::-1])[:, ::-1]
    return [np.ascontiguousarray(array), np.asfortranarray(array), wide[:, ::2], reversed_twice]


LAYOUTS = pytest.mark.parametrize("layout", range(4), ids=["C", "F", "strided", "negative-stride"])


def _inputs(rng, layout):
    n = 40
    poses, commands = random_poses(rng, n, spread=1.8), random_commands(rng, n)
    dxi = rng.uniform(-0.3, 0.3, (2, n))
    views = _layouts(poses)[layout], _layouts(commands)[layout], _layouts(dxi)[layout]
    assert all(np.array_equal(a, b) for a, b in zip(views, (poses, commands, dxi)))
    assert layout == 0 or not views[0].flags.c_contiguous
    return (poses, commands, dxi), views


@LAYOUTS
def test_core_kernels_accept_any_memory_layout(rng, layout):
    (poses, commands, dxi), (p, u, d) = _inputs(rng, layout)
    assert_allclose(_core.unicycle_step(p, u, 0.033), step_by_hand(poses, commands, 0.033), **TOL)
    assert_array_equal(_core.unicycle_step(p, u, 0.033), _core.unicycle_step(poses, commands, 0.033))
    assert_array_equal(_core.threshold_velocities(u, 0.2, 3.0), threshold_by_hand(commands, 0.2, 3.0))
    assert _core.validate(p, u, BOUNDS, **WHEELS)[:3] == validate_by_hand(poses, commands)
    assert_array_equal(_core.dxi_to_dxu(d, p, 0.8, 3.0), _core.dxi_to_dxu(dxi, poses, 0.8, 3.0))
    assert_array_equal(_core.actuator_limit(u, **LIMITS), _core.actuator_limit(commands, **LIMITS))


@LAYOUTS
def test_public_kernels_accept_any_memory_layout(rng, layout):
    (poses, commands, dxi), (p, u, d) = _inputs(rng, layout)
    assert_allclose(kernels.unicycle_step(p, u), step_by_hand(poses, commands, 0.033), **TOL)
    assert_array_equal(kernels.threshold_velocities(u), threshold_by_hand(commands, 0.2, RPS_MAX_ANGULAR))
    assert tuple(kernels.validate(p, u)) == validate_by_hand(poses, commands)
    assert_allclose(kernels.dxi_to_dxu(d, p), dxu_by_hand(dxi, poses, 0.8, 3.0), **TOL)
    assert_allclose(kernels.actuator_limit(u), limit_by_hand(commands), **TOL)


def test_kernels_accept_lists_and_integers():
    assert_allclose(kernels.unicycle_step([[0], [0], [0]], [[1], [0]], 0.5), [[0.5], [0.0], [0.0]])


# -- errors ---------------------------------------------------------------------------------------
SHAPE_GOT = r"got [\[(]{}[\])]"  # the bindings print lists, the Python checks tuples


def _core_calls(poses, commands, dxi=None):
    dxi = commands if dxi is None else dxi
    return {
        "unicycle_step": lambda: _core.unicycle_step(poses, commands, 0.033),
        "validate": lambda: _core.validate(poses, commands, BOUNDS, **WHEELS),
        "dxi_to_dxu": lambda: _core.dxi_to_dxu(dxi, poses, 0.8, 3.0),
    }


def _kernel_calls(poses, commands, dxi=None):
    dxi = commands if dxi is None else dxi
    return {
        "unicycle_step": lambda: kernels.unicycle_step(poses, commands),
        "validate": lambda: kernels.validate(poses, commands),
        "dxi_to_dxu": lambda: kernels.dxi_to_dxu(dxi, poses),
    }


@pytest.mark.parametrize("calls", [_core_calls, _kernel_calls], ids=["core", "kernels"])
@pytest.mark.parametrize("kernel", ["unicycle_step", "validate", "dxi_to_dxu"])
def test_kernels_reject_poses_of_wrong_shape(calls, kernel):
    with pytest.raises(ValueError, match=r"`poses` must have shape \(3, .*" + SHAPE_GOT.format("2, 4")):
        calls(np.zeros((2, 4)), np.zeros((2, 4)))[kernel]()


@pytest.mark.parametrize("calls", [_core_calls, _kernel_calls], ids=["core", "kernels"])
@pytest.mark.parametrize("kernel", ["unicycle_step", "validate"])
def test_kernels_reject_commands_of_wrong_shape_or_count(calls, kernel):
    with pytest.raises(ValueError, match=r"`velocities` must have shape \(2, .*" + SHAPE_GOT.format("3, 4")):
        calls(np.zeros((3, 4)), np.zeros((3, 4)))[kernel]()
    # n differs between poses and commands: the message gives the expected n
    with pytest.raises(ValueError, match=r"`velocities` must have shape \(2, 4\), " + SHAPE_GOT.format("2, 5")):
        calls(np.zeros((3, 4)), np.zeros((2, 5)))[kernel]()


@pytest.mark.parametrize("calls", [_core_calls, _kernel_calls], ids=["core", "kernels"])
def test_dxi_to_dxu_rejects_mismatched_counts(calls):
    with pytest.raises(ValueError, match=r"`dxi` must have shape \(2, n\), " + SHAPE_GOT.format("3, 4")):
        calls(np.zeros((3, 4)), None, dxi=np.zeros((3, 4)))["dxi_to_dxu"]()
    with pytest.raises(ValueError, match=r"`poses` must have shape \(3, 4\), " + SHAPE_GOT.format("3, 2")):
        calls(np.zeros((3, 2)), None, dxi=np.zeros((2, 4)))["dxi_to_dxu"]()


@pytest.mark.parametrize(
    "call",
    [
        lambda u: _core.threshold_velocities(u, 0.2, 3.0),
        lambda u: _core.actuator_limit(u, **LIMITS),
        lambda u: kernels.threshold_velocities(u),
        lambda u: kernels.actuator_limit(u),
    ],
    ids=["core-threshold", "core-limit", "kernels-threshold", "kernels-limit"],
)
def test_command_kernels_reject_wrong_shape(call):
    with pytest.raises(ValueError, match=r"must have shape \(2, n\), " + SHAPE_GOT.format("3, 1")):
        call(np.zeros((3, 1)))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("calls", [_core_calls, _kernel_calls], ids=["core", "kernels"])
@pytest.mark.parametrize("kernel", ["unicycle_step", "validate", "dxi_to_dxu"])
@pytest.mark.parametrize("where", ["poses", "commands"])
def test_kernels_reject_non_finite_values(calls, kernel, where, bad):
    poses, commands = np.zeros((3, 3)), np.zeros((2, 3))
    (poses if where == "poses" else commands)[1, 2] = bad
    name = "poses" if where == "poses" else ("dxi" if kernel == "dxi_to_dxu" else "velocities")
    with pytest.raises(ValueError, match=rf"`{name}`.*non-finite"):
        calls(poses, commands)[kernel]()


@pytest.mark.parametrize("bad", [np.nan, np.inf])
@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda u: _core.threshold_velocities(u, 0.2, 3.0), "velocities"),
        (lambda u: kernels.threshold_velocities(u), "velocities"),
        (lambda u: kernels.actuator_limit(u), "dxu"),
        (lambda u: _core.actuator_limit(u, **LIMITS), "dxu"),  # the binding's own argument name
    ],
    ids=["core-threshold", "kernels-threshold", "kernels-limit", "core-limit"],
)
def test_command_kernels_reject_non_finite_values(call, name, bad):
    with pytest.raises(ValueError, match=rf"`{name}`.*non-finite"):
        call(np.array([[0.0, bad], [0.0, 0.0]]))


@pytest.mark.parametrize("dt", [0.0, -0.033, np.nan, np.inf])
def test_unicycle_step_rejects_non_positive_dt(dt):
    poses, commands = np.zeros((3, 2)), np.zeros((2, 2))
    with pytest.raises(ValueError, match="`dt`"):
        kernels.unicycle_step(poses, commands, dt)
    with pytest.raises(ValueError, match="`dt`"):
        _core.unicycle_step(poses, commands, dt)


@pytest.mark.parametrize(("speed", "dt"), [(10.0, 1e308), (1e10, 1e300)], ids=["1e308", "1e300"])
def test_unicycle_step_refuses_a_dt_that_overflows_the_poses(speed, dt):
    commands = np.array([[0.0, speed], [0.0, 0.0]])
    with pytest.raises(ValueError, match=r"`dt` = .* overflows: robot 1's pose is no longer finite"):
        kernels.unicycle_step(np.zeros((3, 2)), commands, dt)


@pytest.mark.parametrize("gain", ["vel_gain", "ang_gain"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_dxi_to_dxu_refuses_non_finite_gains_naming_them(gain, bad):
    with pytest.raises(ValueError, match=rf"`{gain}` must be finite, got {bad}"):
        kernels.dxi_to_dxu(np.ones((2, 3)), np.zeros((3, 3)), **{gain: bad})


@pytest.mark.parametrize(
    "bounds", [(1.0, 1.0, -1.0, 1.0), (1.0, -1.0, -1.0, 1.0), (-1.0, 1.0, 2.0, 1.0), (-1.0, np.nan, -1.0, 1.0)]
)
def test_validate_rejects_invalid_bounds(bounds):
    poses, commands = np.zeros((3, 2)), np.zeros((2, 2))
    with pytest.raises(ValueError, match="bounds"):
        _core.validate(poses, commands, bounds, **WHEELS)
    with pytest.raises(ValueError, match="bounds"):
        kernels.validate(poses, commands, ArenaSpec(*bounds))


@pytest.mark.parametrize("name", ["diameter", "wheel_radius", "base_length", "max_wheel"])
@pytest.mark.parametrize("value", [0.0, -1.0, np.nan])
def test_validate_rejects_non_positive_parameters(name, value):
    with pytest.raises(ValueError, match=f"`{name}`"):
        _core.validate(np.zeros((3, 2)), np.zeros((2, 2)), BOUNDS, **{**WHEELS, name: value})


@pytest.mark.parametrize("name", ["max_linear", "max_angular", "wheel_radius", "base_length", "max_wheel"])
def test_actuator_limit_rejects_non_positive_parameters(name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        _core.actuator_limit(np.zeros((2, 2)), **{**LIMITS, name: -1.0})


@given(
    rows=st.integers(0, 4),
    n=st.integers(0, 4),
    m=st.integers(0, 4),
    poison=st.sampled_from([None, np.nan, np.inf]),
    dt=st.sampled_from([0.033, 0.0, -1.0, np.nan]),
)
@settings(max_examples=60, deadline=None)
def test_core_never_panics_on_bad_input(rows, n, m, poison, dt):
    # Whatever the shapes and values, the bindings raise ValueError (never PanicException,
    # which is a BaseException and would escape `pytest.raises(Exception)`).
    poses = np.zeros((rows, n))
    commands = np.zeros((2, m))
    if poison is not None and poses.size:
        poses.flat[-1] = poison
    calls = [
        lambda: _core.unicycle_step(poses, commands, dt),
        lambda: _core.validate(poses, commands, BOUNDS, **WHEELS),
        lambda: _core.dxi_to_dxu(commands, poses, 0.8, 3.0),
        lambda: _core.threshold_velocities(poses, 0.2, 3.0),
        lambda: _core.actuator_limit(poses, **LIMITS),
    ]
    finite = poison is None or poses.size == 0
    robots = rows == 3 and n == m and finite
    accepts = [robots and dt == 0.033, robots, robots, rows == 2 and finite, rows == 2 and finite]
    for k, call in enumerate(calls):
        try:
            call()
        except BaseException as err:  # noqa: BLE001 - the point is to see what escapes
            assert type(err) is ValueError, f"call {k} raised {type(err).__name__}: {err}"
            assert not accepts[k], f"call {k} refused valid input: {err}"
        else:
            assert accepts[k], f"call {k} accepted invalid input"


@pytest.mark.parametrize("bad", [np.zeros(3), np.zeros((3, 2), dtype=np.float32), np.zeros((3, 2, 1))])
def test_core_rejects_wrong_dimensions_or_dtype_without_panic(bad):
    # rust-numpy refuses these at extraction (TypeError); the public wrappers convert or say ValueError.
    with pytest.raises((TypeError, ValueError)):
        _core.unicycle_step(bad, np.zeros((2, 2)), 0.033)
    if bad.ndim != 2:
        with pytest.raises(ValueError, match=r"`poses` must have shape \(3, n\)"):
            kernels.unicycle_step(bad, np.zeros((2, 2)))
    else:  # float32 is converted by the public wrapper
        assert_array_equal(kernels.unicycle_step(bad, np.zeros((2, 2))), np.zeros((3, 2)))


def test_validate_returns_named_counts():
    got = kernels.validate(
        np.array([[0.0, 0.05, 5.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), np.array([[0.2, 0, 0], [1.0, 0, 0]])
    )
    assert (got.boundary, got.collision, got.actuator) == (1, 1, 1)
    assert got == (1, 1, 1)
    assert RPS.diameter == 0.11
