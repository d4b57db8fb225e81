"""The policy plugin protocol: how an agent of your own drives the benchmark's episodes.

Public and stable: a plugin imports this module only. ``pic4rl-test --agent FILE.py:NAME``
(or ``package.module:NAME``, or a name in the ``pic4rl.policies`` entry-point group) loads
``NAME``, a ``Policy`` subclass (made with no arguments) or an object with the same members::

    from pic4rl_bridge.control.plugin import Policy

    class Straight(Policy):
        observes = "frame"      # act() gets the SensorFrame (or "observation": the task's)
        acts = "velocity"       # act() returns (v m/s, ω rad/s) (or "normalized": [-1, 1]²)

        def reset(self, robot, task):          # at each episode's start
            self.v = robot.max_linear_m_s

        def act(self, frame):
            return self.v, 0.0

``reset(robot, task)`` gets the ``RobotInfo`` (speed limits, footprint, sensor mounts,
control period) and the ``TaskInfo``; ``act`` gets the same ``SensorFrame`` the shipped
baselines get (``frame.scan``: a ``ScanData`` with its angles, ``frame.depth``,
``frame.pose``, ``frame.goal``, ``frame.plan`` where the task gives one) or the task's
observation, as ``observes`` says. An ``act`` that raises or returns NaN or the wrong shape
ends that episode ``aborted``, the plugin's name and error in the log and the bag
(``end_reason``); the next episode runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..errors import ConfigError
from ..robot_info import RobotInfo
from ..readings.frame import ScanData, SensorFrame
from .actions import normalized_action

__all__ = ["ACTS", "OBSERVES", "Policy", "PolicyFailure", "RobotInfo", "ScanData",
           "SensorFrame", "TaskInfo", "check_policy", "command_of"]

OBSERVES = ("frame", "observation")  # what ``act`` is given
ACTS = ("velocity", "normalized")  # what ``act`` returns: (v, ω) in m/s, rad/s; or [-1, 1]^n


@dataclass(frozen=True)
class TaskInfo:
    """The episode's task as a plugin sees it: its name and sensor, the goal and collision
    tolerances (m), the time budget (steps of ``control_dt_s`` s), the shapes of the task's
    observation (``None`` for a Dict observation) and normalised action."""

    name: str
    sensor: str
    goal_tolerance_m: float
    collision_tolerance_m: float
    max_steps: int
    control_dt_s: float
    observation_shape: tuple[int, ...] | None
    action_shape: tuple[int, ...]

    @property
    def time_budget_s(self) -> float:
        return self.max_steps * self.control_dt_s


class Policy:
    """A plugin's base class: declare ``observes`` and ``acts``, override ``act`` (and
    ``reset`` when the policy keeps state across steps). ``name`` is its row in the tables
    (default: the class name)."""

    observes: ClassVar[str] = "frame"
    acts: ClassVar[str] = "velocity"
    name: str = ""

    def reset(self, robot: RobotInfo, task: TaskInfo) -> None:
        """Called at each episode's start; the default keeps nothing."""

    def act(self, observation: Any) -> Any:
        raise NotImplementedError(f"{type(self).__name__}.act")


class PolicyFailure(Exception):
    """A plugin's ``reset``/``act`` raised or gave an unusable action: the episode aborts."""


def check_policy(policy: Any, where: str) -> str:
    """``policy``'s name, after checking its declarations; ``ConfigError`` naming ``where``
    (the reference it came from) and the member at fault otherwise."""
    for member in ("reset", "act"):
        if not callable(getattr(policy, member, None)):
            raise ConfigError(f"{where}: {type(policy).__name__} has no {member}() method; "
                              "expected a pic4rl_bridge.control.plugin.Policy")
    for member, choices in (("observes", OBSERVES), ("acts", ACTS)):
        value = getattr(policy, member, None)
        if value not in choices:
            raise ConfigError(f"{where}: {member} = {value!r} is invalid; expected "
                              f"{' or '.join(repr(c) for c in choices)}")
    return str(getattr(policy, "name", "") or type(policy).__name__)


def command_of(policy: Any, name: str, raw: Any, robot: RobotInfo,
               action_shape: tuple[int, ...]) -> np.ndarray:
    """The env's normalised action from what ``policy`` (named ``name``) returned:
    (v, ω) through ``normalized_action``, or a normalised action of ``action_shape``.
    ``PolicyFailure`` naming the plugin for a wrong shape or a non-finite value."""
    try:
        action = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise PolicyFailure(f"policy {name}: act() returned {raw!r}, not numbers") from err
    velocity = policy.acts == "velocity"
    shape = (2,) if velocity else tuple(action_shape)
    if action.size != math.prod(shape):
        want = "(v, ω)" if velocity else f"a normalized action of shape {shape}"
        raise PolicyFailure(f"policy {name}: act() returned shape {action.shape}; expected "
                            f"{want}")
    if not np.all(np.isfinite(action)):
        raise PolicyFailure(f"policy {name}: act() returned a non-finite action {raw!r}")
    if velocity:
        return normalized_action(robot, float(action.flat[0]), float(action.flat[1]))
    return np.clip(action.reshape(shape), -1.0, 1.0).astype(np.float32)
