"""pic4rl_metrics stands alone: no ROS, MuJoCo, torch or sibling pic4rl package behind it, only
the shared base (``pic4rl_base``)."""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

import tomllib

REPO = Path(__file__).resolve().parents[2]
PACKAGE = REPO / "pic4rl_metrics"
HEAVY = ("rclpy", "mujoco", "torch", "gymnasium", "stable_baselines3")
SIBLINGS = ("pic4rl_sim", "pic4rl_bridge", "pic4rl_agents")


def test_importing_the_package_cli_plots_and_videos_pulls_in_no_heavy_module() -> None:
    code = (
        "import json, sys\n"
        "import pic4rl_metrics, pic4rl_metrics.cli.commands, pic4rl_metrics.viz.plots\n"
        "import pic4rl_metrics.viz.video, pic4rl_metrics.viz.video_batch\n"
        "import pic4rl_metrics.viz.html_report\n"
        "pic4rl_metrics.viz.video_batch.ffmpeg_writer()\n"
        f"heavy = {HEAVY!r}\n"
        "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in heavy)))\n"
        "ours = ('pic4rl_metrics.cli.commands', 'pic4rl_metrics.viz.plots',\n"
        "        'pic4rl_metrics.viz.video_batch')\n"
        "print(json.dumps(all(m in sys.modules for m in ours)))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    loaded, imported = (json.loads(line) for line in done.stdout.splitlines()[-2:])
    assert imported is True
    assert loaded == []


def test_core_dependencies_name_no_ros_sim_or_rl_package() -> None:
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    names = [
        re.split(r"[\s\[<>=!~;]", dep.strip(), maxsplit=1)[0].lower()
        for dep in project["dependencies"]
    ]
    assert "rosbags" in names  # the parse found the real list
    forbidden = (
        "rclpy",
        "ros-jazzy",
        "mujoco",
        "torch",
        "stable-baselines3",
        "stable_baselines3",
        "gymnasium",
    )
    offending = [n for n in names if any(bad in n for bad in forbidden)]
    assert offending == []


def _imported_modules(path: Path) -> set[str]:
    """Absolute module names a file imports (relative imports resolve inside the package)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                names.add(f"pic4rl_metrics.{node.module or ''}".rstrip("."))
            elif node.module:
                names.add(node.module)
        elif isinstance(node, ast.Call) and getattr(
            node.func, "attr", getattr(node.func, "id", "")
        ) in (
            "import_module",
            "__import__",
        ):
            names.update(
                arg.value
                for arg in node.args[:1]
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str)
            )
    return names


def test_no_module_of_pic4rl_metrics_imports_another_pic4rl_package_or_heavy_dependency() -> None:
    files = sorted(PACKAGE.rglob("*.py"))
    assert len(files) > 5
    offending = {
        str(path.relative_to(REPO)): sorted(
            name
            for name in _imported_modules(path)
            if name.split(".")[0] in (*SIBLINGS, *HEAVY)
            or (name.split(".")[0].startswith("pic4rl")
                and name.split(".")[0] not in ("pic4rl_metrics", "pic4rl_base"))
        )
        for path in files
    }
    assert {k: v for k, v in offending.items() if v} == {}


def test_the_import_scan_sees_imports_it_should_forbid(tmp_path: Path) -> None:
    """The AST scan above would catch a sibling import written in any of the usual ways."""
    sample = tmp_path / "sample.py"
    sample.write_text(
        "import pic4rl_sim.engine.core\n"
        "from pic4rl_agents import tester\n"
        "def f():\n"
        "    import torch\n"
        "    importlib.import_module('rclpy')\n"
        "from . import series\n"
    )
    assert _imported_modules(sample) >= {
        "pic4rl_sim.engine.core",
        "pic4rl_agents",
        "torch",
        "rclpy",
        "pic4rl_metrics",
    }
