"""The engine's timing and episode set-up rules, apart from the engine so that the sim's
parameters (``pic4rl_sim.config``) read their defaults without loading MuJoCo."""

from __future__ import annotations

from dataclasses import dataclass

from pic4rl_base.errors import require

from .crowd.params import CrowdParams

__all__ = ["EngineConfig"]


@dataclass(frozen=True)
class EngineConfig:
    """Timing and episode set-up rules (s, m), and the crowd."""

    physics_dt_s: float = 0.005
    control_dt_s: float = 0.1
    clearance_m: float = 0.2  # free space around the footprint for sampled starts and goals
    min_goal_distance_m: float = 1.0
    crowd: CrowdParams = CrowdParams()  # the people walking in the world (none by default)

    def __post_init__(self) -> None:
        require(0 < self.physics_dt_s <= 0.05, "physics_dt_s", self.physics_dt_s,
                "a time step in (0, 0.05] s")
        require(self.control_dt_s >= self.physics_dt_s, "control_dt_s", self.control_dt_s,
                f"at least physics_dt_s={self.physics_dt_s}")
        ratio = self.control_dt_s / self.physics_dt_s
        require(abs(ratio - round(ratio)) < 1e-6, "control_dt_s", self.control_dt_s,
                f"a whole multiple of physics_dt_s={self.physics_dt_s}")
        require(self.clearance_m >= 0, "clearance_m", self.clearance_m, "a distance >= 0")
        require(self.min_goal_distance_m >= 0, "min_goal_distance_m", self.min_goal_distance_m,
                "a distance >= 0")

    @property
    def substeps(self) -> int:
        return round(self.control_dt_s / self.physics_dt_s)
