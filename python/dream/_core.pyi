"""Types of the compiled kernels (dream-py). Poses are (3, n), commands (2, n), float64."""

import numpy as np
from numpy.typing import NDArray

__version__: str
__all__ = ["__version__", "unicycle_step", "threshold_velocities", "validate", "dxi_to_dxu", "actuator_limit"]

def unicycle_step(poses: NDArray[np.float64], velocities: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
    """Poses (3, n) after one forward-Euler unicycle step with commands (2, n)."""

def threshold_velocities(velocities: NDArray[np.float64], max_linear: float, max_angular: float) -> NDArray[np.float64]:
    """Commands (2, n) clipped to |v| <= max_linear and |w| <= max_angular, signs kept."""

def validate(
    poses: NDArray[np.float64],
    velocities: NDArray[np.float64],
    bounds: tuple[float, float, float, float],
    *,
    diameter: float,
    wheel_radius: float,
    base_length: float,
    max_wheel: float,
) -> tuple[int, int, int]:
    """(boundary, collision, actuator) counts of one iteration by rps's criteria."""

def dxi_to_dxu(
    dxi: NDArray[np.float64], poses: NDArray[np.float64], vel_gain: float, ang_gain: float
) -> NDArray[np.float64]:
    """Unicycle commands (2, n) from single-integrator velocities (2, n) at poses (3, n)."""

def actuator_limit(
    dxu: NDArray[np.float64],
    *,
    max_linear: float,
    max_angular: float,
    wheel_radius: float,
    base_length: float,
    max_wheel: float,
) -> NDArray[np.float64]:
    """Commands (2, n) within the speed limits, slowed so that no wheel is too fast."""
