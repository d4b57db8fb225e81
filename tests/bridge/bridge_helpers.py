"""What the bridge's tests share: the shipped env configs, one per registered env id."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
LIDAR_CONFIG = REPO / "config" / "env_goto_lidar.yaml"
ENV_CONFIGS = {
    "pic4rl/GoToPoseLidar-v0": LIDAR_CONFIG,
    "pic4rl/GoToPoseDepth-v0": REPO / "config" / "env_goto_depth.yaml",
    "pic4rl/GoToPoseLidarDepth-v0": REPO / "config" / "env_goto_lidar_depth.yaml",
    "pic4rl/Vineyard-v0": REPO / "config" / "env_vineyard_depth.yaml",
    "pic4rl/PersonMonitoring-v0": REPO / "config" / "env_person_omni.yaml",
    "pic4rl/ExploreLidar-v0": REPO / "config" / "env_explore.yaml",
    "pic4rl/ExploreDepth-v0": REPO / "config" / "env_explore_depth.yaml",
}
