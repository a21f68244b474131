"""Robot and arena constants, in one place.

The module-level names are the original DREAM ``dream_specs`` constants (GRITSbot and the
Robotarium arena), kept so that original scripts work unchanged. New code uses the frozen
dataclasses :class:`RobotSpec` and :class:`ArenaSpec`, which a run can override, e.g. a larger
arena for thousands of robots::

    >>> arena = ArenaSpec.centred(width=32.0, height=20.0)
    >>> arena.bounds
    (-16.0, 16.0, -10.0, 10.0)

Units: metres, seconds, radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

# Robot values (GRITSbot).
R_V_MAX: float = 0.2  #: max linear velocity (m/s)
R_W_MAX: float = 3.636363  #: max angular velocity (rad/s)
R_AC_MAX: float = 12.5  #: max wheel (actuator) speed (rad/s)
R_R_WHEEL: float = 0.016  #: wheel radius (m)
R_R_LENGTH: float = 0.105  #: wheel base (m)

# Terrain values (Robotarium arena).
T_WIDTH: float = 3.2
T_HEIGHT: float = 2.0
T_ORIGIN_X: float = 0.0
T_ORIGIN_Y: float = 0.0
T_MAX_WIDTH: float = T_ORIGIN_X + T_WIDTH / 2
T_MIN_WIDTH: float = T_ORIGIN_X - T_WIDTH / 2
T_MAX_HEIGHT: float = T_ORIGIN_Y + T_HEIGHT / 2
T_MIN_HEIGHT: float = T_ORIGIN_Y - T_HEIGHT / 2

TIME_STEP: float = 0.033  #: Robotarium control period (s), 30 Hz


@dataclass(frozen=True)
class RobotSpec:
    """Physical limits of a differential-drive robot; defaults are the GRITSbot's."""

    v_max: float = R_V_MAX
    w_max: float = R_W_MAX
    ac_max: float = R_AC_MAX
    wheel_radius: float = R_R_WHEEL
    base_length: float = R_R_LENGTH
    diameter: float = 0.11  #: rps counts a collision when centres are this close or closer

    @property
    def radius(self) -> float:
        return self.diameter / 2

    def within(self, checked: SimulatorSpec) -> RobotSpec:
        """These limits tightened to those a simulator ``checked`` enforces and validates.

        rps 2.1 models the GRITSbot with a 0.11 m wheel base, rps 0.0.0 and the robot's own
        figures with 0.105 m: a command within the robot's limits can still need a wheel faster
        than 2.1 allows, so robots keep within both.
        """
        return replace(
            self,
            v_max=min(self.v_max, checked.max_linear),
            w_max=min(self.w_max, checked.max_angular),
            ac_max=min(self.ac_max, checked.max_wheel),
            wheel_radius=min(self.wheel_radius, checked.wheel_radius),
            base_length=max(self.base_length, checked.base_length),
        )


@dataclass(frozen=True)
class SimulatorSpec:
    """The limits rps enforces and checks (they differ slightly from the robot's own).

    The defaults are rps 0.0.0's rules (:data:`RPS0`); :data:`RPS2` holds rps 2.1's. The two
    generations differ in how commands are clipped (``v`` and ``w`` separately, or each wheel's
    speed), where the collider sits (the centre, or ``collider_offset`` ahead along the heading)
    and how robots outside the arena are counted (each one, or once per iteration).
    """

    time_step: float = TIME_STEP
    max_linear: float = 0.2
    max_angular: float = 2 * (0.016 / 0.11) * (0.2 / 0.016)
    max_wheel: float = 0.2 / 0.016
    wheel_radius: float = R_R_WHEEL
    base_length: float = R_R_LENGTH
    diameter: float = 0.11  #: colliders closer than this (centre to centre, inclusive) collide
    rules: str = "rps0"  #: the generation's name, as ``make_robotarium(..., rules=...)`` takes it
    collider_offset: float = 0.0  #: how far ahead of the robot's centre its collider sits (m)
    wheel_thresholding: bool = False  #: clip each wheel's speed instead of ``v`` and ``w``
    boundary_per_iteration: bool = False  #: count 1 per iteration with a robot outside, not each robot
    validates_requested: bool = False  #: check the actuator limit on commands before clipping

    def __post_init__(self) -> None:
        positive = ("time_step", "max_linear", "max_angular", "max_wheel", "wheel_radius", "base_length", "diameter")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"`{name}` must be finite and > 0, got {value}")
        if not math.isfinite(self.collider_offset):
            raise ValueError(f"`collider_offset` must be finite, got {self.collider_offset}")


@dataclass(frozen=True)
class ArenaSpec:
    """An axis-aligned rectangular arena (m); the defaults are the Robotarium's (3.2 m x 2 m).

    An experiment returns one from :meth:`dream.Experiment.arena_for` to give its robots room
    beyond the Robotarium's (the simulators then count a robot outside it as a boundary
    violation); ``dream.specs.ROBOTARIUM`` is the Robotarium's own.

    Parameters
    ----------
    xmin, xmax, ymin, ymax : float
        The bounds (m), finite, with ``xmin < xmax`` and ``ymin < ymax``.

    Raises
    ------
    ValueError
        Bounds that are not finite or not in that order.

    Examples
    --------
    >>> from dream import ArenaSpec
    >>> arena = ArenaSpec.centred(6.4, 4.0)  # twice the Robotarium's size, centred on the origin
    >>> arena.bounds, arena.width
    ((-3.2, 3.2, -2.0, 2.0), 6.4)
    >>> ArenaSpec(-1.6, 1.6, -1.0, 1.0) == ArenaSpec()
    True
    """

    xmin: float = T_MIN_WIDTH
    xmax: float = T_MAX_WIDTH
    ymin: float = T_MIN_HEIGHT
    ymax: float = T_MAX_HEIGHT

    def __post_init__(self) -> None:
        values = (self.xmin, self.xmax, self.ymin, self.ymax)
        if not all(math.isfinite(v) for v in values) or self.xmin >= self.xmax or self.ymin >= self.ymax:
            raise ValueError(f"arena bounds must be finite with xmin < xmax and ymin < ymax, got {values}")

    @classmethod
    def centred(cls, width: float, height: float) -> ArenaSpec:
        """An arena of the given size centred on the origin."""
        return cls(-width / 2, width / 2, -height / 2, height / 2)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)``."""
        return (self.xmin, self.xmax, self.ymin, self.ymax)

    @property
    def width(self) -> float:
        return self.xmax - self.xmin

    @property
    def height(self) -> float:
        return self.ymax - self.ymin

    def shrunk(self, margin: float) -> tuple[float, float, float, float]:
        """Bounds moved inwards by ``margin`` on every side (e.g. the robot radius)."""
        return (self.xmin + margin, self.xmax - margin, self.ymin + margin, self.ymax - margin)


@dataclass(frozen=True)
class OnboardSpec:
    """The GRITSbot's onboard sensors as rps 2.1 models them (SI units unless stated).

    The seven infrared distance sensors sit at ``rays[:2, k]`` in the body frame of a centre
    ``centre_offset`` ahead of the robot's pose, pointing at ``rays[2, k]`` from its heading.
    They see line-segment walls and other robots as discs of ``robot_diameter`` (rps 2.1 uses the
    body's 0.11 m here, not the 0.135 m collider: its recorded readings agree), not the arena's
    edges. A reading is the distance when something is within ``range``, else -1; with noise
    on, a hit is dropped (-1) with probability ``dropout``, otherwise replaced by a uniform value
    in ``[0, range)`` with probability ``outlier``, otherwise perturbed by Gaussian noise of
    std ``distance_error`` times the distance and clipped to ``[0, range]``.
    """

    rays: tuple[tuple[float, ...], ...] = (
        (-0.04, 0.0, 0.04, 0.05, 0.04, 0.0, -0.04),
        (0.04, 0.06, 0.05, 0.0, -0.05, -0.06, -0.04),
        (math.pi, math.pi / 2, math.pi / 4, 0.0, -math.pi / 4, -math.pi / 2, -math.pi),
    )
    centre_offset: float = 0.01
    robot_diameter: float = 0.11
    range: float = 1.2
    distance_error: float = 0.03  #: Gaussian std as a fraction of the distance
    dropout: float = 0.035
    outlier: float = 0.014
    counts_per_revolution: int = 28
    gear_ratio: float = 100.37
    encoder_noise: float = 0.25  #: counts; the std of a step's count is this times sqrt(max(|counts|, 1))
    imu_position: tuple[float, float] = (0.0594 - 0.00319, 0.0344628 - 0.0475)  #: from the axle centre (m)
    accelerometer_noise: tuple[float, float, float] = (0.012929, 0.012127, 0.052979)  #: m/s^2
    gyro_noise: tuple[float, float, float] = (0.001663, 0.001216, 0.002372)  #: rad/s
    magnetometer_noise: tuple[float, float, float] = (3.275843, 2.365798, 5.232685)  #: uT
    magnetic_xy: float = 6.0712  #: horizontal field strength (uT)
    magnetic_z: float = -39.8594  #: vertical field (uT)
    compass_noise: float = 0.310830  #: degrees
    gravity: float = 9.81  #: m/s^2

    def noiseless(self) -> OnboardSpec:
        """The same sensors with every noise, dropout and outlier rate set to zero."""
        return replace(
            self,
            distance_error=0.0,
            dropout=0.0,
            outlier=0.0,
            encoder_noise=0.0,
            accelerometer_noise=(0.0, 0.0, 0.0),
            gyro_noise=(0.0, 0.0, 0.0),
            magnetometer_noise=(0.0, 0.0, 0.0),
            compass_noise=0.0,
        )


GRITSBOT = RobotSpec()
ROBOTARIUM = ArenaSpec()
RPS = SimulatorSpec()
#: rps 0.0.0 (PyPI, 2017): the default rules.
RPS0 = RPS
#: rps 2.1 (the lab's simulator since April 2026): wheel base 0.11, wheel-speed clipping,
#: colliders of 0.135 m placed 0.025 m ahead, boundary counted once per iteration, and the
#: actuator limit checked on the commands as given (before clipping).
RPS2 = SimulatorSpec(
    base_length=0.11,
    diameter=0.135,
    rules="rps2",
    collider_offset=0.025,
    wheel_thresholding=True,
    boundary_per_iteration=True,
    validates_requested=True,
)
#: Each generation's rules by name.
RULES: dict[str, SimulatorSpec] = {"rps0": RPS0, "rps2": RPS2}
#: The GRITSbot's onboard sensors (rps 2.1's constants).
ONBOARD = OnboardSpec()
