"""Robots: the decision-making part, independent of any simulator.

A robot learns its pose only through its sensors' callbacks; until the first one arrives its
pose is unknown (NaN) and it commands zero velocity, whatever order its timers run in.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from dream import kernels, rules
from dream._checks import FloatArray, as_array
from dream._reference.guard import closing_in, in_reach
from dream.kernels import Bounds
from dream.specs import GRITSBOT, ROBOTARIUM, ArenaSpec, RobotSpec
from dream.world import current_world

GUARD_MARGIN = 0.01  #: what :meth:`RobotHRVO.guard` adds to the robot's diameter (m)
SIDESTEP_UPDATES = 10  #: decisions a blocked robot steps aside for (:meth:`RobotHRVO.steer`)
GUARD_HORIZON = 0.25  #: how far ahead :meth:`RobotHRVO.guard` looks (s): beyond the next decision


class Robot:
    """Base robot: parameters, velocity placeholders and the unicycle conversion.

    Parameters
    ----------
    robot_id : int
        Index of the robot in the simulator's pose and velocity arrays.
    tag : str
        Name of the robot.
    vel_gain, ang_gain : float
        Gains of the single-integrator to unicycle conversion (:meth:`dxi_to_dxu`).
    spec : RobotSpec
        Physical limits (default: GRITSbot).

    Attributes
    ----------
    pos_x, pos_y, rot_w : float
        The robot's belief of its pose (m, m, rad); NaN until a sensor reports it.
    dxi : (2,) ndarray
        Single-integrator velocity (m/s) the robot wants.
    dxu : (2,) ndarray
        Unicycle command ``[v, w]`` (m/s, rad/s).
    guard_horizon : float
        How far ahead (s) :meth:`stop_short` looks (default :data:`GUARD_HORIZON`).
    """

    guard_horizon: float = GUARD_HORIZON

    def __init__(
        self,
        robot_id: int,
        tag: str = "robot",
        vel_gain: float = 0.8,
        ang_gain: float = 3.0,
        *,
        spec: RobotSpec = GRITSBOT,
    ) -> None:
        if isinstance(robot_id, bool) or not isinstance(robot_id, (int, np.integer)) or robot_id < 0:
            raise ValueError(f"robot_id must be an integer >= 0, got {robot_id!r}")
        self.robot_id = int(robot_id)
        self.tag = tag
        self.pos_x = math.nan
        self.pos_y = math.nan
        self.rot_w = math.nan
        self.vel_gain = vel_gain
        self.ang_gain = ang_gain
        self.dxi = np.zeros(2)
        self.dxu = np.zeros(2)
        self.spec = spec
        self.v_max = spec.v_max
        self.w_max = spec.w_max
        self.ac_max = spec.ac_max
        self.r_wheel = spec.wheel_radius
        self.r_length = spec.base_length
        self.world = current_world()
        self._limits: tuple[tuple[Any, ...], RobotSpec] | None = None

    def update_odom(self, pose: Any) -> None:
        """Odometry callback: take ``pose`` ``[x, y, theta]`` as the robot's belief of its pose."""
        x, y, theta = pose.tolist() if type(pose) is np.ndarray else pose
        self.pos_x, self.pos_y, self.rot_w = float(x), float(y), float(theta)

    @property
    def has_pose(self) -> bool:
        """Whether a sensor has told the robot where it is."""
        return math.isfinite(self.pos_x) and math.isfinite(self.pos_y) and math.isfinite(self.rot_w)

    def dxi_to_dxu(self) -> None:
        """Convert ``dxi`` to the unicycle command ``dxu`` (zero while the pose is unknown).

        ``v = vel_gain (c dxi_x + s dxi_y)``, ``w = ang_gain atan2(-s dxi_x + c dxi_y, v) / (pi/2)``
        with ``c, s = cos, sin(rot_w)``.
        """
        if not self.has_pose:
            self.dxu[:] = 0.0
            return
        c, s = math.cos(self.rot_w), math.sin(self.rot_w)
        dx, dy = float(self.dxi[0]), float(self.dxi[1])
        v = self.vel_gain * (c * dx + s * dy)
        self.dxu[0] = v
        self.dxu[1] = self.ang_gain * math.atan2(-s * dx + c * dy, v) / (math.pi / 2)

    def command(self, dxu: Any) -> None:
        """Turn ``dxi`` into this robot's limited unicycle command and write it into column
        ``robot_id`` of the swarm's command array ``dxu`` ``(2, n)``."""
        self.dxi_to_dxu()
        self.actuator_limit()
        self.guard()
        dxu[:, self.robot_id] = self.dxu

    def guard(self) -> None:
        """The last check of ``dxu`` before it is sent: nothing here (see :meth:`RobotHRVO.guard`)."""

    def stop_short(self, offsets: Any, near: float) -> None:
        """Set the linear speed to 0 (the robot still turns) when driving along its heading would
        bring it within ``near`` (m) of a robot at ``offsets`` ``(k, 2)`` (its own position less
        theirs, taken as standing still) in the next :attr:`guard_horizon` seconds."""
        speed = float(self.dxu[0])
        if speed == 0.0:
            return
        offsets = np.asarray(offsets, dtype=np.float64).reshape(-1, 2)
        offsets = offsets[in_reach(np.hypot(offsets[:, 0], offsets[:, 1]), abs(speed), near, self.guard_horizon)]
        if not len(offsets):
            return
        moving = speed * np.array([math.cos(self.rot_w), math.sin(self.rot_w)])
        if closing_in(offsets, np.broadcast_to(moving, offsets.shape), near, self.guard_horizon).any():
            self.dxu[0] = 0.0

    def actuator_limit(self) -> None:
        """Keep ``dxu`` within the robot's limits, slowing down rather than turning less.

        ``v`` and ``w`` are clipped to ``v_max`` and ``w_max``; if the faster wheel would then
        exceed ``ac_max`` (``|v|/r + |w| L/(2r) > ac_max``), ``|v|`` becomes
        ``ac_max r - |w| L/2``, keeping its sign. In a world given its simulator's limits
        (:meth:`dream.World.keep_to`) the limits are also those the simulator checks
        (:meth:`dream.specs.RobotSpec.within`).
        """
        limits = self.limits
        v = max(-limits.v_max, min(limits.v_max, float(self.dxu[0])))
        w = max(-limits.w_max, min(limits.w_max, float(self.dxu[1])))
        half = limits.base_length / 2
        if abs(v) / limits.wheel_radius + abs(w) * half / limits.wheel_radius > limits.ac_max:
            speed = max(limits.ac_max * limits.wheel_radius - half * abs(w), 0.0)
            v = speed if v > 0 else -speed
        self.dxu[0] = v
        self.dxu[1] = w

    @property
    def limits(self) -> RobotSpec:
        """The limits :meth:`actuator_limit` keeps to: the robot's own (``v_max``, ``w_max``,
        ``ac_max``, ``r_wheel``, ``r_length``), tightened to the simulator's limits its world was
        given (:meth:`dream.World.keep_to`)."""
        limits = self.world.limits
        key = (self.v_max, self.w_max, self.ac_max, self.r_wheel, self.r_length, limits)
        if self._limits is None or self._limits[0] != key:
            own = RobotSpec(*key[:5], diameter=self.spec.diameter)
            self._limits = (key, own if limits is None else own.within(limits))
        return self._limits[1]


def guard_distance(diameter: float, safety: float) -> float:
    """How close (centre to centre, m) the motion guard of an HRVO robot of ``diameter`` (m) lets it
    drive to a robot it sees: its body and :data:`GUARD_MARGIN`, or less where HRVO's combined
    ``safety`` radius (m) allows robots closer (tight formations)."""
    return min(diameter + GUARD_MARGIN, safety)


def stopping(
    speeds: np.ndarray, headings: np.ndarray, owners: np.ndarray, offsets: np.ndarray, near: float
) -> np.ndarray:
    """The motion guard of a whole swarm (:meth:`RobotHRVO.guard`): whether each robot, driving at
    ``speeds`` ``(n,)`` (m/s) along ``headings`` ``(n,)``, comes within ``near`` (m) of a robot it
    sees in the next :data:`GUARD_HORIZON` seconds, ``(n,)`` bool. ``owners`` ``(k,)`` and
    ``offsets`` ``(k, 2)``: who sees each other robot, and its position less that robot's (m).
    The rows of :func:`dream.kernels.motion_guard`."""
    if np.any(owners[1:] < owners[:-1]):
        order = np.argsort(owners, kind="stable")
        owners, offsets = owners[order], offsets[order]
    rows = np.concatenate(([0], np.cumsum(np.bincount(owners, minlength=len(speeds)))))
    return kernels.motion_guard(
        speeds, headings, rows, -offsets[:, 0], -offsets[:, 1], near=near, horizon=GUARD_HORIZON
    )


def guard_swarm(
    dxu: np.ndarray, poses: np.ndarray, near: float, seen: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
) -> np.ndarray:
    """``dxu`` ``(2, n)`` with no linear speed for the robots that :func:`stopping` stops, seeing
    the others at their positions ``poses`` ``(3, n)``.

    ``seen``, optional: :func:`dream.kernels.neighbours` of the positions within some radius at
    least the guard's reach, to share one search with HRVO; the rows within the reach are kept.
    """
    p = poses[:2].T
    reach = near + GRITSBOT.v_max * GUARD_HORIZON
    if seen is None:
        indptr, indices, _ = kernels.neighbours(p, reach)
        owners = np.repeat(np.arange(len(p)), np.diff(indptr))
    else:  # the pairs a search within `reach` finds: it decides `distance <= reach` alike
        indptr, indices, distances = seen
        kept = distances <= reach
        owners, indices = np.repeat(np.arange(len(p)), np.diff(indptr))[kept], indices[kept]
    out = dxu.copy()
    out[0, stopping(dxu[0], poses[2], owners, p[owners] - p[indices], near)] = 0.0
    return out


class RobotHRVO(Robot):
    """A robot that avoids the others with Hybrid Reciprocal Velocity Obstacles.

    Parameters
    ----------
    safety : float
        Combined safety radius (m): the closest two robots' centres should come.
    check_boundaries : bool
        Only choose velocities that keep ``position + v`` inside the arena, shrunk by
        ``boundary_margin`` (default: the robot's radius, so its body stays inside; the
        original used no margin).
    arena : ArenaSpec, optional
        The arena (default: that of the simulator in the robot's world, see :attr:`arena`).
    n_angles, n_speeds : int
        Candidate velocity grid (see :func:`dream.kernels.hrvo`).
    include_preferred : bool
        Also try the desired velocity itself before the grid (the original did not).
    """

    def __init__(
        self,
        robot_id: int,
        tag: str = "robot",
        vel_gain: float = 0.8,
        ang_gain: float = 3.0,
        safety: float = 0.24,
        check_boundaries: bool = True,
        *,
        spec: RobotSpec = GRITSBOT,
        arena: ArenaSpec | None = None,
        boundary_margin: float | None = None,
        n_angles: int = 20,
        n_speeds: int = 10,
        include_preferred: bool = True,
    ) -> None:
        super().__init__(robot_id, tag, vel_gain, ang_gain, spec=spec)
        if not (math.isfinite(safety) and safety >= 0):
            raise ValueError(f"safety must be finite and >= 0, got {safety}")
        self.safety = safety
        self.check_boundaries = check_boundaries
        self._arena = arena
        self._margin = spec.radius if boundary_margin is None else boundary_margin
        self.include_preferred = include_preferred
        self._sampling = {"n_angles": n_angles, "n_speeds": n_speeds, "include_preferred": include_preferred}
        self._planners: tuple[tuple[Bounds, float], kernels.HrvoPlanner, kernels.HrvoPlanner] | None = None
        self._warned_outside = False
        self.detections: FloatArray = np.zeros((0, 4))
        self.sidestep = 0  # decisions left stepping aside (see `steer`)
        self.side = 1.0  # 1: to the right, -1: to the left

    def update_sensor(self, detections: Any) -> None:
        """Movement-sensor callback: keep the latest ``detections`` for :meth:`HRVO`."""
        self.detections = detections

    def HRVO(self, detections: Any, desired_velocity: Any) -> FloatArray:  # noqa: N802 (original name)
        """Choose a collision-free velocity close to ``desired_velocity`` and store it in ``dxi``.

        Parameters
        ----------
        detections : (k, 4) array_like
            Rows ``[distance, angle, vx, vy]`` from a :class:`~dream.sensors.MovementSensor`;
            ``angle`` points from the detected robot towards this one (original convention).
        desired_velocity : (2,) array_like
            Preferred single-integrator velocity (m/s).

        Returns
        -------
        (2,) ndarray
            The chosen velocity (also stored in ``dxi``): zero while the pose is unknown or
            when every candidate is forbidden.
        """
        if not self.has_pose:
            self.dxi = np.zeros(2)
            return self.dxi
        # The original sensor reported "nothing detected" as an empty 1-D array: accept it.
        empty = np.ndim(detections) <= 1 and np.size(detections) == 0
        d = np.zeros((0, 4)) if empty else as_array(detections, "detections", (None, 4))
        preferred = as_array(desired_velocity, "desired_velocity", (2,))
        bounded, free = self._planner()
        self._check_inside()
        planner = bounded if self.check_boundaries else free
        self.dxi = planner.velocity(
            d, np.asarray(self.dxi, dtype=np.float64), preferred, np.array([self.pos_x, self.pos_y])
        )
        return self.dxi

    @property
    def arena(self) -> ArenaSpec:
        """The arena the robot keeps to: the one given, else its simulator's as its world was given
        it (:meth:`dream.World.keep_to`; the Robotarium's until then)."""
        if self._arena is not None:
            return self._arena
        return ROBOTARIUM if self.world.arena is None else self.world.arena

    @arena.setter
    def arena(self, arena: ArenaSpec) -> None:
        self._arena = arena

    @property
    def bounds(self) -> Bounds:
        """``(xmin, xmax, ymin, ymax)`` the robot's centre keeps within: the arena less the margin."""
        return self.arena.shrunk(self._margin)

    @property
    def bound_x(self) -> list[float]:
        return [self.bounds[0], self.bounds[1]]

    @property
    def bound_y(self) -> list[float]:
        return [self.bounds[2], self.bounds[3]]

    def _planner(self) -> tuple[kernels.HrvoPlanner, kernels.HrvoPlanner]:
        """HRVO planners with and without the boundary check, rebuilt when the arena or the
        safety radius changes."""
        key = (self.bounds, self.safety)
        if self._planners is None or self._planners[0] != key:
            options: dict[str, Any] = {"safety": self.safety, "v_max": self.v_max, **self._sampling}
            bounded, free = kernels.HrvoPlanner(bounds=key[0], **options), kernels.HrvoPlanner(**options)
            self._planners = (key, bounded, free)
        return self._planners[1], self._planners[2]

    def _check_inside(self) -> None:
        """Warn once when the robot decides from outside its arena: HRVO would keep it there."""
        xmin, xmax, ymin, ymax = self.arena.bounds
        inside = xmin <= self.pos_x <= xmax and ymin <= self.pos_y <= ymax
        if self.check_boundaries and not inside and not self._warned_outside:
            self._warned_outside = True
            warnings.warn(
                f"robot {self.robot_id} is at ({self.pos_x:.2f}, {self.pos_y:.2f}), outside its arena "
                f"x {xmin:g}..{xmax:g}, y {ymin:g}..{ymax:g}, and will not move: give it the simulator's "
                "arena (leave `arena` unset, or pass arena=sim.arena)",
                stacklevel=3,
            )

    def guard(self) -> None:
        """Drive no further (turn only) when the unicycle's motion would bring its body within
        :data:`GUARD_MARGIN` of where a detected robot's is (at most the safety radius apart), in
        the next :attr:`guard_horizon` seconds.

        HRVO chooses a safe ``dxi``, but a unicycle moves along its heading, not along ``dxi``:
        while it turns, the part of ``dxi`` it carries out can close in on a neighbour that
        ``dxi`` itself avoided. It guards the bodies only: rps 2.1's colliders, which reach
        further ahead, are the safety radius's business (a guard that wide stops robots in
        tight formations for good). The neighbours are taken as standing still: the sensor's
        velocities are those of a point ahead of each robot, which a robot turning in place
        moves sideways, and each robot's own guard checks its own motion.
        """
        if not self.has_pose or not len(self.detections) or self.dxu[0] == 0.0:
            return
        near = guard_distance(self.spec.diameter, self.safety)
        rows = np.asarray(self.detections)
        # The sensor's distances tell who is within reach (the margin covers their rounding).
        rows = rows[in_reach(rows[:, 0], abs(float(self.dxu[0])), near, self.guard_horizon)]
        if len(rows):
            offsets = rows[:, :1] * np.column_stack((np.cos(rows[:, 1]), np.sin(rows[:, 1])))
            self.stop_short(offsets, near)

    def steer(self, detections: Any, desired_velocity: Any, sidestep_updates: int = SIDESTEP_UPDATES) -> FloatArray:
        """:meth:`HRVO`, for a robot that must not wait forever.

        A robot that HRVO stops while it wants to move steps aside for the next
        ``sidestep_updates`` decisions (the rule is :func:`dream.rules.sidestep_update`, shared
        with the swarm loops).
        """
        desired = as_array(desired_velocity, "desired_velocity", (2,))
        wanted, sidestep = rules.sidestep_preference(desired, self.sidestep, self.side)
        chosen = self.HRVO(detections, wanted)
        sidestep, side = rules.sidestep_update(chosen, desired, sidestep, self.side, sidestep_updates)
        self.sidestep, self.side = int(sidestep), float(side)
        return chosen

    def settle_or_steer(
        self, desired: Any, fine: float, clearance: float, sidestep_updates: int = SIDESTEP_UPDATES
    ) -> None:
        """Set :attr:`dxi`: ``desired`` itself when slower than ``fine`` (m/s) with no detected robot
        closer than ``clearance`` (m) (:func:`dream.rules.settles`); else :meth:`steer`.

        A robot this slow is within centimetres of its place, and velocity obstacles (no time
        horizon) forbid every velocity towards a neighbour inside the cone, however slow: on a
        line 0.3 m apart that is the very direction of the last centimetres, so HRVO would push
        the robot sideways, off the line, for ever. The clearance keeps HRVO in charge when two
        places still nearly coincide: without it two such robots creep into each other. (A swarm
        robot does this with :meth:`dream.swarm.View.direct`.)
        """
        detections = np.asarray(self.detections)
        nearest = float(detections[:, 0].min()) if detections.size else math.inf
        if rules.settles(desired, nearest, fine, clearance):
            self.dxi = desired
        else:
            self.steer(self.detections, desired, sidestep_updates)
