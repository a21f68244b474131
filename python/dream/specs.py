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
from dataclasses import dataclass

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


@dataclass(frozen=True)
class SimulatorSpec:
    """The limits rps enforces and checks (they differ slightly from the robot's own)."""

    time_step: float = TIME_STEP
    max_linear: float = 0.2
    max_angular: float = 2 * (0.016 / 0.11) * (0.2 / 0.016)
    max_wheel: float = 0.2 / 0.016
    wheel_radius: float = R_R_WHEEL
    base_length: float = R_R_LENGTH
    diameter: float = 0.11


@dataclass(frozen=True)
class ArenaSpec:
    """Axis-aligned rectangular arena (m); defaults are the Robotarium's."""

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


GRITSBOT = RobotSpec()
ROBOTARIUM = ArenaSpec()
RPS = SimulatorSpec()
