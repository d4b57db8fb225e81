"""The ``barn`` world: the 300 static worlds of BARN (Perille et al. 2020; the BARN Challenge),
read from data shipped in the package, so a user installs nothing else.

``data/barn_worlds.json.gz`` holds each world's cylinder centres (radius 0.075 m, 1 m high, in
the Gazebo world frame, which is kept), its reference path and that path's length (what sets
the BARN score's optimal time), the challenge's start pose, goal and 50 test worlds. It was
extracted from the challenge's repository (github.com/Daffan/the-barn-challenge), MIT License,
Copyright (c) 2022 Zifan Xu: ``data/LICENSE-BARN`` beside it. ``world_variant`` is the world's
index (0-299). The world carries the challenge's start and goal as its one spawn pose and goal
point, so an env's own episodes there are the challenge's; its ``params`` keep the index and
``reference_path_length_m``, which the env writes into each bag as an episode fact.
"""

from __future__ import annotations

import gzip
import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, ClassVar

from pic4rl_base.errors import require
from pic4rl_base.schema import check

from pic4rl_base.geometry import Pose2D
from .arena import walls
from .spec import Cylinder, WorldSpec

DATA = Path(__file__).with_name("data") / "barn_worlds.json.gz"
LICENSE = DATA.with_name("LICENSE-BARN")
WORLDS = 300
#: The bounds: the cylinders, the start and the goal with this much around them (m).
_MARGIN_M = 2.0


@dataclass(frozen=True)
class BarnParams:
    """The ``barn`` world: BARN world ``world_variant`` (0-299) as data; no parameters."""

    KIND: ClassVar[str] = "barn"

    def __post_init__(self) -> None:
        check(self, "world.barn.")


@lru_cache(maxsize=1)
def barn_data() -> dict[str, Any]:
    """The shipped BARN data, read once (its keys: see the module's docstring)."""
    with gzip.open(DATA, "rt", encoding="utf-8") as f:
        return json.load(f)


def start_and_goal() -> tuple[Pose2D, tuple[float, float]]:
    """The challenge's start pose (m, rad) and goal (m), the same in every world."""
    data = barn_data()
    x, y, yaw = data["start_pose"]
    dx, dy = data["goal_offset_m"]
    return Pose2D(float(x), float(y), float(yaw)), (float(x + dx), float(y + dy))


def challenge_test_worlds() -> tuple[int, ...]:
    """The challenge's 50 test worlds (0, 6, ..., 294): never train on them."""
    return tuple(int(i) for i in barn_data()["test_worlds"])


def barn(seed: int, p: BarnParams) -> WorldSpec:
    """BARN world ``seed`` (its index): the cylinders as written, bounds 2 m around them, the
    start and the goal, walled like every generated world (Gazebo's world has no walls; they
    keep a robot that leaves the field from wandering off the map), the challenge's start as
    the spawn pose and its goal as the goal point."""
    require(isinstance(seed, int) and not isinstance(seed, bool) and 0 <= seed < WORLDS,
            "world_variant", seed, f"a BARN world index in [0, {WORLDS - 1}] (world: barn)")
    data = barn_data()
    world = data["worlds"][seed]
    radius, height = float(data["cylinder_radius_m"]), float(data["cylinder_height_m"])
    cylinders = tuple(Cylinder(float(x), float(y), radius, height) for x, y in world["cylinders"])
    start, goal = start_and_goal()
    xs = [c.x for c in cylinders] + [start.x, goal[0]]
    ys = [c.y for c in cylinders] + [start.y, goal[1]]
    bounds = (min(xs) - _MARGIN_M, min(ys) - _MARGIN_M, max(xs) + _MARGIN_M, max(ys) + _MARGIN_M)
    params = {"index": float(seed),
              "reference_path_length_m": float(world["reference_path_length_m"])}
    return WorldSpec("barn", bounds, tuple(walls(bounds)), cylinders,
                     spawn_poses=(start,), goal_points=(goal,),
                     seed=seed, params=params)
