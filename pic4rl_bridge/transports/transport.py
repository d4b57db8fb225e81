"""The one interface both transports offer the env: start an episode, send a command, get the
decoded sensor data it causes; and, for recording, every message of the episode as on the wire.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

from pic4rl_base.goal import Goal
from pic4rl_base.geometry import Pose2D
from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.interfaces import QosSettings

from ..readings.frame import SensorFrame


class RawMessage(NamedTuple):
    """One message as on the wire: ``topic`` absolute (``/scan``), ``msgtype`` as rosbag2
    names it (``sensor_msgs/msg/LaserScan``), CDR ``data``, and the bag timestamp (ns): sim time
    for a simulator, the receive time for a real robot."""

    topic: str
    msgtype: str
    data: bytes
    stamp_ns: int


#: Receives every message of the current episode (the recorder's ``write``).
Tap = Callable[[RawMessage], None]

#: How a topic's publisher offers it, as a bag's metadata records it: the interface table's
#: QoS settings (reliable, transient-local, history depth; 0: not known).
OfferedQos = QosSettings


@dataclass(frozen=True)
class EpisodeRequest:
    """The next episode: its seed (sampling and sensor noise), a start and goal in the world
    frame (``None``: the simulator samples them from the seed; a goal given as a pair, a file's
    or a sampler's, becomes a ``Goal``), and the variant of the sim's world it runs in
    (``None``: the sim's ``world_variant``; ``episodes.world_variants``)."""

    seed: int
    start: Pose2D | None = None
    goal: Goal | None = None
    world_variant: int | None = None

    def __post_init__(self) -> None:
        if self.goal is not None:
            object.__setattr__(self, "goal", Goal.of(self.goal))


class Transport(ABC):
    """Moves a robot, simulated or real. ``tap``, when set, receives every message of the
    current episode from the reset on (messages stamped at or after the episode's first stamp),
    including the commands sent."""

    tap: Tap | None = None
    #: Why the episode cannot go on after the last step (the simulator's physics diverged and
    #: it put the robot back at its start), or ``None``; cleared by ``reset``.
    fault: str | None = None

    @abstractmethod
    def reset(self, request: EpisodeRequest) -> SensorFrame:
        """Start an episode; return its first frame. ``EpisodeRejected`` when the start or
        goal is refused (the episode in progress goes on), ``TransportError`` on silence."""

    @abstractmethod
    def step(self, command: Twist2D) -> SensorFrame:
        """Send ``command`` (body frame) for one control period; return the frame it causes."""

    def offered_qos(self, topic: str) -> OfferedQos | None:
        """How the publisher of ``topic`` (absolute) offers it; ``None`` when not known."""
        return None

    def flush(self) -> None:  # noqa: B027 - nothing to wait for by default
        """Deliver to ``tap`` every message stamped up to the last frame (the episode ends)."""

    @abstractmethod
    def close(self) -> None:
        """Stop the robot and release everything; safe to call twice."""

    @property
    def world_name(self) -> str:
        """How the world is named in the bags' facts (``indoor:0``, or ``""`` if unknown)."""
        return ""
