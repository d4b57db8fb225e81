"""The ``crowd.*`` parameters: how many people walk, in which groups, how fast.

Apart from the model so that the sim's parameter table (``pic4rl_sim.config``) and
``EngineConfig`` read them without loading the crowd. The model's constants (relaxation time,
potentials' strengths and ranges) are the published ones and not parameters: see
``forces``.
"""

from __future__ import annotations

from dataclasses import dataclass

from pic4rl_base.errors import require
from pic4rl_base.schema import Range, check, param

MAX_PEOPLE = 30


@dataclass(frozen=True)
class CrowdParams:
    """A crowd of ``count`` people walking between goals among the world's obstacles."""

    count: int = param(0, doc="number of people walking in the world (0: none, no people "
                       "topic)", range=Range(0, MAX_PEOPLE))
    max_group_size: int = param(1, doc="people walk in groups of 1 to this many (sizes drawn "
                                "uniformly), sharing their goals (Moussaid et al. 2010)",
                                range=Range(1, 5))
    speed_mean_m_s: float = param(1.34, doc="mean desired walking speed (Helbing & Molnar "
                                  "1995: 1.34)", unit="m/s", range=Range(0.1, 2.5))
    speed_std_m_s: float = param(0.26, doc="standard deviation of the desired speeds, each "
                                 "drawn per person and clipped to [0.3, 1.5] x the mean",
                                 unit="m/s", range=Range(0.0, 1.0))
    radius_m: float = param(0.25, doc="radius of each person's cylinder", unit="m",
                            range=Range(0.1, 0.5))
    height_m: float = param(1.7, doc="height of each person's cylinder", unit="m",
                            range=Range(0.5, 2.5))

    def __post_init__(self) -> None:
        check(self, "crowd.")
        require(self.max_group_size <= max(self.count, 1), "crowd.max_group_size",
                self.max_group_size, f"an integer in [1, crowd.count={self.count}]")
