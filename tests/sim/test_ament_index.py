"""`ros2 run pic4rl_sim sim` without the ros2 CLI: the package is in the ament index of the
environment it is installed in, and its executable there starts the node."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
from ament_index_python import get_package_prefix, get_package_share_directory
from rosgraph_msgs.msg import Clock

NOT_INDEXED = (
    "pic4rl_sim is not in the ament index of {prefix}: pyproject.toml's "
    "[tool.setuptools.data-files] were not installed. setuptools leaves them out of editable "
    "installs (its editable_wheel asks Distribution.has_data(), which does not exist); build "
    "through a backend that aliases has_data to has_data_files, or install without -e."
)


@pytest.fixture
def ament_prefix(monkeypatch: pytest.MonkeyPatch) -> Path:
    """This environment as the only ament prefix (what a sourced setup script would give)."""
    monkeypatch.setenv("AMENT_PREFIX_PATH", sys.prefix)
    return Path(sys.prefix)


def test_the_package_is_in_the_ament_index(ament_prefix):
    marker = ament_prefix / "share" / "ament_index" / "resource_index" / "packages" / "pic4rl_sim"
    assert marker.is_file(), NOT_INDEXED.format(prefix=ament_prefix)
    assert Path(get_package_prefix("pic4rl_sim")) == ament_prefix
    share = Path(get_package_share_directory("pic4rl_sim"))
    assert "<name>pic4rl_sim</name>" in (share / "package.xml").read_text()
    executable = ament_prefix / "lib" / "pic4rl_sim" / "sim"
    assert executable.is_file() and os.access(executable, os.X_OK)


@pytest.mark.integration
def test_the_indexed_executable_starts_the_sim(ament_prefix, start_sim, ros_client, domain,
                                               arena_mjcf):
    # As `ros2 run pic4rl_sim sim --ros-args ...` does: find lib/<package>/<executable> under
    # the package's prefix and run it, with the environment's python first on PATH.
    executable = Path(get_package_prefix("pic4rl_sim")) / "lib" / "pic4rl_sim" / "sim"
    path = os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")])
    start_sim([str(executable), "--ros-args", "-p", f"world:={arena_mjcf}",
               "-p", "clock_mode:=realtime", "-p", "real_time_factor:=5.0"],
              domain, {"PATH": path})
    client = ros_client(domain)
    clock = client.collect("/clock", Clock, timeout_s=30.0)
    assert client.spin_until(lambda: len(clock) >= 3, 10.0)
    stamps = [m.clock.sec * 1_000_000_000 + m.clock.nanosec for m in clock]
    assert stamps == sorted(set(stamps)) and stamps[-1] > stamps[0]  # sim time advances
