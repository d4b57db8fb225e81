"""The engine stands without ROS: rclpy only in the node's modules, never torch or SB3; of the
other pic4rl packages only the shared base (``pic4rl_base``: errors, geometry, the goal, the
parameter machinery), never the metrics."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PACKAGE = REPO / "pic4rl_sim"
ROS_PACKAGE = "node"  # pic4rl_sim/node/: rclpy and messages at any level
ROS_ROOTS = ("rclpy", "geometry_msgs", "nav_msgs", "sensor_msgs", "std_srvs", "rosgraph_msgs",
             "visualization_msgs", "rcl_interfaces", "builtin_interfaces", "std_msgs",
             "stereo_msgs", "tf2_msgs", "diagnostic_msgs")
NEVER = ("torch", "stable_baselines3", "gymnasium", "pic4rl_metrics", "pic4rl_bridge",
         "pic4rl_agents")
#: What the metrics' doors must not load: the metrics' heavy libraries.
METRICS_HEAVY = ("pandas", "rosbags", "matplotlib")


def imported_modules(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


def imported_roots(path: Path) -> set[str]:
    return {name.split(".")[0] for name in imported_modules(path)}


#: A sensor kind's own module (its spec, reader and step messages in one place) builds its
#: messages with imports inside those functions only: importing it loads no ROS.
SENSOR_KINDS = "engine/sensor_kinds"


def top_level_roots(path: Path) -> set[str]:
    """The roots a module imports at its top level (not inside a function or class)."""
    names = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Import):
            names |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_only_the_node_modules_import_ros_and_none_imports_rl_or_siblings() -> None:
    modules = sorted(PACKAGE.rglob("*.py"))
    names = {str(p.relative_to(PACKAGE)) for p in modules}
    assert names >= {"engine/core.py", "node/sim_node.py", "engine/sensors.py"}
    for path in modules:
        roots = imported_roots(path)
        assert not roots & set(NEVER), f"{path.name} imports {sorted(roots & set(NEVER))}"
        where = path.relative_to(PACKAGE)
        if where.parts[0] == ROS_PACKAGE:
            continue
        if str(where.parent) == SENSOR_KINDS:
            roots = top_level_roots(path)
        ros = sorted(roots & set(ROS_ROOTS))
        assert not ros, f"{path.name} imports {ros}"


def _loaded(modules: str) -> tuple[list[str], bool]:
    """The ROS, RL, sibling and heavy metrics modules, and whether MuJoCo, that importing
    ``modules`` (in a fresh interpreter) loads."""
    code = (
        "import json, sys\n"
        f"import {modules}\n"
        f"heavy = {ROS_ROOTS + NEVER + METRICS_HEAVY!r}\n"
        "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in heavy)))\n"
        "print(json.dumps('mujoco' in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    loaded, has_mujoco = (json.loads(line) for line in done.stdout.splitlines()[-2:])
    return loaded, has_mujoco


def test_importing_the_engine_loads_no_ros_or_rl_module() -> None:
    assert _loaded("pic4rl_sim.engine.core") == ([], True)


def test_reading_parameters_and_worlds_needs_no_mujoco() -> None:
    """A params file is read, checked and its worlds generated without MuJoCo (only a user's
    MJCF world loads it)."""
    assert _loaded("pic4rl_sim.config, pic4rl_base.params_file, pic4rl_base.schema, "
                   "pic4rl_sim.engine.worlds.generators") == ([], False)
