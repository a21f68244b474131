"""DREAM — Distributed Robotics Execution and Management.

Simulate distributed multi-robot algorithms: each robot decides from its own sensors, radio
messages and clock. Robots, sensors, radios and timers keep the original DREAM API (``from
dream import *`` gives the original names); simulators are backends (the Robotarium's ``rps``
and DREAM's Fast simulator); :mod:`dream.kernels` holds the vectorised geometry.

Units are SI in the world frame: metres, seconds, radians. Poses of n robots are ``(3, n)``
arrays ``[x; y; theta]``, unicycle commands ``(2, n)`` arrays ``[v; w]`` (the Robotarium's
convention); positions given to geometry kernels are ``(n, 2)``.
"""

import os

# The Rust kernels' allocator (mimalloc) keeps freed memory for 10 s before it goes back to the
# OS (its default: 1 s), unless the environment says otherwise: a swarm step's arrays, megabytes
# each at scale, are then reused from one step to the next instead of faulted in afresh (half
# the system time of a 300,000-robot run). Set before the extension loads, which reads it.
os.environ.setdefault("MIMALLOC_PURGE_DELAY", "10000")
# Nor does it commit a thread's whole arena up front (its default where the OS overcommits):
# with 16 rayon threads, the rendezvous example at 10,000 robots peaked at 328 MiB so and at
# 160 MiB with memory committed as it is used (and stepped 2.4 times faster, 2-core AMD, 2026-11-27).
os.environ.setdefault("MIMALLOC_ARENA_EAGER_COMMIT", "0")

from dream import _version, kernels, specs  # noqa: E402 -- after the allocator's setting
from dream.backends import Backend, Fast, Robotarium, initial_poses, make_robotarium
from dream.errors import GeometryError
from dream.experiments import Experiment, ExperimentResult, Param, param, resume, run
from dream.faults import Faults
from dream.obstacles import Obstacle
from dream.onboard import DistanceSensor, EncoderSensor, ImuReading, ImuSensor
from dream.radios import GraphRadio, Radio, RangeRadio
from dream.robot import Robot, RobotHRVO
from dream.sensors import MovementSensor, ObstacleSensor, OdometrySensor, Sensor
from dream.specs import (
    R_AC_MAX,
    R_R_LENGTH,
    R_R_WHEEL,
    R_V_MAX,
    R_W_MAX,
    T_HEIGHT,
    T_MAX_HEIGHT,
    T_MAX_WIDTH,
    T_MIN_HEIGHT,
    T_MIN_WIDTH,
    T_ORIGIN_X,
    T_ORIGIN_Y,
    T_WIDTH,
    ArenaSpec,
)
from dream.sweep import sweep
from dream.timers import Timer
from dream.world import World, create_timer, current_world, reset_default_world, update_timers

__version__ = _version.version()

# The original names, for scripts written for the prototype.
Robot_hrvo = RobotHRVO
Movement_sensor = MovementSensor
Odometry_sensor = OdometrySensor
Radio_range = RangeRadio

# `from dream import *` gives every public name: the original ones, for scripts written for the
# prototype, and the PEP 8 ones.
__all__ = [
    "ArenaSpec",
    "ImuSensor",
    "ImuReading",
    "EncoderSensor",
    "DistanceSensor",
    "Backend",
    "Experiment",
    "ExperimentResult",
    "Fast",
    "Faults",
    "GeometryError",
    "GraphRadio",
    "Movement_sensor",
    "MovementSensor",
    "Obstacle",
    "ObstacleSensor",
    "Odometry_sensor",
    "OdometrySensor",
    "Param",
    "R_AC_MAX",
    "R_R_LENGTH",
    "R_R_WHEEL",
    "R_V_MAX",
    "R_W_MAX",
    "Radio",
    "Radio_range",
    "RangeRadio",
    "Robot",
    "Robot_hrvo",
    "RobotHRVO",
    "Robotarium",
    "Sensor",
    "T_HEIGHT",
    "T_MAX_HEIGHT",
    "T_MAX_WIDTH",
    "T_MIN_HEIGHT",
    "T_MIN_WIDTH",
    "T_ORIGIN_X",
    "T_ORIGIN_Y",
    "T_WIDTH",
    "Timer",
    "World",
    "create_timer",
    "current_world",
    "initial_poses",
    "kernels",
    "make_robotarium",
    "param",
    "reset_default_world",
    "resume",
    "run",
    "specs",
    "sweep",
    "update_timers",
]
