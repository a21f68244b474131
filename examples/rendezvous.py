"""Rendezvous: robots meet without a meeting point, each moving to the mean of what it hears.

Written only on DREAM's public API, as a researcher writes a new experiment. Every robot knows
its own pose (odometry), hears the positions of the robots within radio range (range radio),
and heads for the mean of those positions and its own; HRVO keeps it off the robots its
movement sensor sees. Nobody knows where the meeting point is, or how many robots there are.
Success: every robot within ``radius`` of the team's centre (by default, a disc that holds
the team at HRVO's safety distance: 0.53 m for 10 robots, 0.75 m for 20), zero collisions.

    dream run examples/rendezvous.py -n 20 --json out.json
    dream run examples/rendezvous.py --param radio_range=0.6 --video rendezvous.gif
"""

from __future__ import annotations

import math

import numpy as np

from dream import Experiment, MovementSensor, OdometrySensor, RangeRadio, RobotHRVO, create_timer, param


class MeetingRobot(RobotHRVO):
    """Heads for the mean of its own position and the positions it hears."""

    def __init__(self, robot_id: int, gain: float, **kwargs) -> None:
        super().__init__(robot_id, f"robot_{robot_id}", **kwargs)
        self.gain = gain
        self.meeting_point: np.ndarray | None = None

    def update_radio(self, messages: list[tuple[float, float]]) -> tuple[float, float] | None:
        if not self.has_pose:
            return None
        here = (self.pos_x, self.pos_y)
        self.meeting_point = np.mean([here, *messages], axis=0)
        return here

    def update(self, dxu: np.ndarray) -> None:
        desired = np.zeros(2)
        if self.has_pose and self.meeting_point is not None:
            desired = self.gain * (self.meeting_point - (self.pos_x, self.pos_y))
            speed = math.hypot(*desired)
            if speed > self.v_max:
                desired *= self.v_max / speed
        self.steer(self.detections, desired)
        self.command(dxu)


class Rendezvous(Experiment):
    name = "rendezvous"
    default_n = 10
    success = "every robot within `radius` of the team's centre, zero collisions"
    radius: float = param(0.0, "the team has met when every robot is this close to its centre (m; 0: met_radius(n))")
    radio_range: float = param(1.0, "how far a robot hears the others (m)")
    gain: float = param(0.5, "proportional gain towards the meeting point (1/s)")
    safety: float = param(0.2, "HRVO safety distance between robot centres (m)")

    def met_radius(self, n: int) -> float:
        """The default ``radius``: 1.6 times that of the smallest disc holding n robots ``safety``
        apart (hexagonal packing). HRVO without a time horizon keeps robots out of each other's
        safety disc along their whole way, so the team settles looser than the densest packing."""
        return 1.6 * self.safety / 2 * math.sqrt(n / 0.9069)

    def build(self, n: int) -> None:
        for i in range(n):
            robot = MeetingRobot(i, self.gain, safety=self.safety, arena=self.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=0.5)
            radio = RangeRadio(i, f"radio_{i}", robot.update_radio, range=self.radio_range)
            create_timer(
                i,
                10 + i % 5,
                [
                    {"delay": 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3, "tag": "movement", "call": movement.update},
                    {"delay": 10, "tag": "radio", "call": radio.update},
                    {"delay": 4, "tag": "robot", "call": robot.update},
                ],
            )
            self.robots.append(robot)

    def check(self, n: int, backend: str) -> None:
        if self.radius == 0.0:
            self.radius = self.met_radius(n)

    def spread(self, poses: np.ndarray) -> float:
        """The largest distance of a robot from the team's centre (m)."""
        offsets = poses[:2] - poses[:2].mean(axis=1, keepdims=True)
        return float(np.hypot(*offsets).max())

    def done(self, step: int, poses: np.ndarray) -> bool:
        return self.spread(poses) <= self.radius

    def measures(self) -> dict[str, float]:
        return {"spread": self.spread(self.sim.poses)}
