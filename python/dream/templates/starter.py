"""NAME: a starter experiment written by `dream new`. Run it with

    dream run FILE
    dream run FILE -n 20 --param spacing=0.4 --video FILE_STEM.gif

Every robot decides on its own: it knows its pose (odometry), hears the positions of the robots
within radio range, and sees the robots around it (movement sensor). Here each robot moves
away from the robots it hears that are closer than `spacing`, and HRVO keeps it from running
into anyone on the way. Change the robot's `update` to try your own algorithm.
"""

from __future__ import annotations

import math

import numpy as np

from dream import Experiment, MovementSensor, OdometrySensor, RangeRadio, RobotHRVO, create_timer, param


class SpreadingRobot(RobotHRVO):
    """Moves away from the robots it hears within `spacing`."""

    def __init__(self, robot_id: int, spacing: float, **kwargs) -> None:
        super().__init__(robot_id, f"robot_{robot_id}", **kwargs)
        self.spacing = spacing
        self.heard: list[tuple[float, float]] = []

    # Radio callback: receives the messages of the robots in range, returns what this robot sends.
    def update_radio(self, messages: list[tuple[float, float]]) -> tuple[float, float] | None:
        self.heard = messages
        return (self.pos_x, self.pos_y) if self.has_pose else None

    # Controller: choose a velocity and write this robot's command into the swarm's array.
    def update(self, dxu: np.ndarray) -> None:
        push = np.zeros(2)
        if self.has_pose:
            for x, y in self.heard:
                away = np.array([self.pos_x - x, self.pos_y - y])
                distance = math.hypot(*away)
                if 0 < distance < self.spacing:
                    push += away / distance * (self.spacing - distance)
            speed = math.hypot(*push)
            if speed > self.v_max:
                push *= self.v_max / speed
        self.steer(self.detections, push)  # HRVO, stepping aside when blocked
        self.command(dxu)


class Spread(Experiment):
    name = "NAME"
    default_n = 10
    success = "every two robots at least `spacing` apart, zero collisions"
    spacing: float = param(0.5, "the distance every robot keeps from the others (m)", gt=0)

    # Build the robots, their sensors and radios, and the timer that runs them.
    def build(self, n: int) -> None:
        for i in range(n):
            robot = SpreadingRobot(i, self.spacing, arena=self.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=1.0)
            radio = RangeRadio(i, f"radio_{i}", robot.update_radio, range=2 * self.spacing)
            create_timer(  # start after 10 steps; each entry runs every `delay` steps
                i,
                10,
                [
                    {"delay": 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3, "tag": "movement", "call": movement.update},
                    {"delay": 5, "tag": "radio", "call": radio.update},
                    {"delay": 4, "tag": "robot", "call": robot.update},
                ],
            )
            self.robots.append(robot)

    def closest_pair(self, poses: np.ndarray) -> float:
        """The smallest distance between two robots (m)."""
        xy = poses[:2].T
        gaps = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
        np.fill_diagonal(gaps, np.inf)
        return float(gaps.min())

    # Success test: the run stops as soon as it holds.
    def done(self, step: int, poses: np.ndarray) -> bool:
        return self.closest_pair(poses) >= self.spacing

    # The experiment's own figures, printed and written to --json.
    def measures(self) -> dict[str, float]:
        return {"closest_pair": self.closest_pair(self.sim.poses)}
