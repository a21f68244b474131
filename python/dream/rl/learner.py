"""The learner: the robot a policy drives, and the experiment that gives it its world.

A learning run keeps the experiment's world (its arena, start poses, step cap, success and
faults) and replaces its robots by a :class:`Learner`, a :class:`~dream.swarm.SwarmRobot`
whose decision comes from outside (the policy, through :mod:`dream.rl`'s environments):

- an experiment whose robots are a swarm robot (``swarm_robot(n)``, as in
  ``examples/rendezvous.py``) lends the learner its clock (``period``, start-up delays), its
  movement sensor, its radio's range, graph, loss and latency, its odometry noise and its
  limits;
- a built-in experiment not yet written as a swarm robot lends its world only: the learner
  then has :data:`PERIOD`, a :data:`SIGHT` movement sensor and a :data:`HEARING` radio, and the
  built-in's goal and success come from :data:`BUILT_INS`.

Whatever the experiment's own robots said, the learner's radio carries one message: the
sender's odometry position (fields ``x`` and ``y``), sent at each of its decisions.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from dream.experiments import Experiment, find
from dream.experiments.hrvo_circle import HrvoCircle, circle_goals
from dream.experiments.line_consensus import LineConsensus
from dream.frames import Frame
from dream.rl.observation import Layout
from dream.rl.policy import LinearPolicy
from dream.swarm import Avoid, Movement, Radio, SwarmRobot, View

PERIOD = 5  #: steps between two decisions of a learner lent no clock
SIGHT = Movement(range=0.5)  #: the movement sensor of a learner lent none
HEARING = Radio(range=1.0)  #: the radio of a learner lent none (its fields are always x, y)
FIELDS = ("x", "y")  #: a learner's message: its odometry position (m)


class Learner(SwarmRobot):
    """A swarm robot whose decisions a policy makes (see the module docs).

    Parameters
    ----------
    lent : SwarmRobot, optional
        The experiment's own robot, which lends its clock, sensors, radio and limits.
    avoid : Avoid, optional
        The HRVO safety layer between the policy's wish and the wheels.
    """

    def __init__(self, lent: SwarmRobot | None = None, avoid: Avoid | None = None) -> None:
        self.lent = lent
        self.avoid = avoid
        self.period = PERIOD if lent is None else lent.period
        self.movement = SIGHT if lent is None else lent.movement
        radio = HEARING if lent is None or lent.radio is None else lent.radio
        self.radio = dataclasses.replace(radio, fields=FIELDS)
        if lent is not None:
            self.spec, self.odometry_noise = lent.spec, lent.odometry_noise
            self.vel_gain, self.ang_gain = lent.vel_gain, lent.ang_gain

    def start(self, ids: np.ndarray) -> np.ndarray:
        """The lent robot's start-up delays; without one, every robot decides from step 0."""
        return np.full(len(ids), -1, dtype=np.int64) if self.lent is None else self.lent.start(ids)

    def decide(self, view: View) -> np.ndarray:
        raise RuntimeError("a Learner's decisions come from a policy: step it through dream.rl's environments")


class Driven(Learner):
    """A learner whose decisions a :class:`~dream.rl.policy.LinearPolicy` makes on its own view: how a
    trained policy runs robot by robot, in ``dream run`` or a lab bundle, without an environment."""

    def __init__(self, lent: SwarmRobot | None, policy: LinearPolicy, goals: np.ndarray | None) -> None:
        super().__init__(lent, Avoid() if policy.avoid else None)
        self.policy, self.goals = policy, goals
        self.layout = Layout(policy.k, goals is not None)
        if self.layout.size != policy.size:
            raise ValueError(
                f"the policy takes observations of {policy.size} values, but this experiment's robots observe "
                f"{self.layout.size} (k={policy.k}, {'with' if goals is not None else 'without'} goals)"
            )

    def decide(self, view: View) -> np.ndarray:
        view.send(x=view.pose[:, 0], y=view.pose[:, 1])
        return self.policy(self.layout.rows(view, self.goals)) * self.spec.v_max


@dataclasses.dataclass(frozen=True)
class BuiltIn:
    """What a built-in experiment not yet written as a swarm robot gives a learner: each robot's
    goal ``goals(exp, n)`` ``(n, 2)`` (or none) and the success ``done(exp, step, poses)``."""

    goals: Callable[[Any, int], np.ndarray] | None
    done: Callable[[Any, int, np.ndarray], bool]


def _at_goals(exp: Any, step: int, poses: np.ndarray) -> bool:
    """Every correct robot within the arrival tolerance of its goal."""
    gaps = np.hypot(*(poses[:2] - exp.goals(exp.n).T))
    return bool(np.all(gaps[exp.correct] <= exp.layout.arrival))


#: The built-ins a learner can take the world of, and what they give it. hrvo-circle: reach the
#: first goal on the circle (one crossing, not three); line-consensus: its own success (the line,
#: from the poses alone). voronoi-coverage and affine-formation judge success from their own
#: robots' state (cells, leaders' bars), which a learner does not keep: not offered yet.
BUILT_INS: dict[type[Experiment], BuiltIn] = {
    HrvoCircle: BuiltIn(lambda exp, n: circle_goals(n, exp.grow)[:, 0], _at_goals),
    LineConsensus: BuiltIn(None, LineConsensus.done),
}


def learning_class(experiment: type[Experiment] | str) -> type[Experiment]:
    """The experiment ``experiment`` (a class, a built-in's name or a ``.py`` file) with its robots
    replaced by a :class:`Learner` (see the module docs); its ``avoid`` attribute (an
    :class:`~dream.swarm.Avoid` or ``None``) sets the learner's safety layer, and its ``policy``
    attribute (a :class:`~dream.rl.policy.LinearPolicy`), if set, makes the robots
    :class:`Driven` by it.

    Raises
    ------
    ValueError
        A built-in that a learner cannot take the world of yet, or an experiment with neither a
        swarm robot nor a built-in's adaptation.
    """
    cls = find(experiment) if isinstance(experiment, str) else experiment
    builtin = BUILT_INS.get(cls)
    if builtin is None and cls.swarm_robot is Experiment.swarm_robot:
        offered = ", ".join(sorted(c.name for c in BUILT_INS))
        raise ValueError(
            f"{cls.label()} has no swarm robot for a learner to take the clock and sensors of, and is not a built-in "
            f"a learner can take the world of ({offered}): write its robots as a dream.swarm.SwarmRobot returned "
            "by swarm_robot(n) (see docs/swarm-robots.md)"
        )

    def swarm_robot(self: Any, n: int) -> Learner:
        lent = None if builtin is not None else cls.swarm_robot(self, n)
        if self.policy is not None:
            return Driven(lent, self.policy, goals_of(self, n))
        return Learner(lent, self.avoid)

    body: dict[str, Any] = {"swarm_robot": swarm_robot, "avoid": None, "policy": None, "__module__": cls.__module__}
    if builtin is not None:  # the built-in's own robots are gone: so are its hooks that read them
        body.update(
            done=builtin.done,
            measures=lambda self: {},
            frame=_frame,
            before_step=Experiment.before_step,
            after_step=Experiment.after_step,
        )
        if builtin.goals is not None:
            body["goals"] = lambda self, n: builtin.goals(self, n)
    return type(f"Learning{cls.__name__}", (cls,), body)


def goals_of(exp: Experiment, n: int) -> np.ndarray | None:
    """Each robot's goal ``(n, 2)`` from the experiment's ``goals(n)`` hook, or ``None``."""
    hook = getattr(exp, "goals", None)
    if hook is None:
        return None
    goals = np.asarray(hook(n), dtype=np.float64)
    if goals.shape != (n, 2) or not np.isfinite(goals).all():
        raise ValueError(
            f"{exp.label()}.goals(n) must return finite goals of shape (n, 2) = ({n}, 2), got {goals.shape}"
        )
    return goals


def _frame(exp: Any, step: int, poses: np.ndarray) -> Frame:
    """The default frame, with the goals if the experiment has them."""
    frame = Experiment.frame(exp, step, poses)
    frame.goals = goals_of(exp, exp.n)
    return frame


def driven(experiment: type[Experiment] | str, policy: LinearPolicy) -> type[Experiment]:
    """``experiment`` with its robots driven by ``policy`` (:class:`Driven`): it runs as any
    experiment does (``dream.run``, a lab bundle), robot by robot or as one swarm."""
    return type(f"Driven{learning_class(experiment).__name__}", (learning_class(experiment),), {"policy": policy})
