"""The shared base (``pic4rl_base``) is the bottom room: it imports no other pic4rl package and
loads only numpy and PyYAML, and every package's errors meet in its one ``ConfigError``."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from import_helpers import imports, module_name

ROOT = Path(__file__).resolve().parents[1]
BASE = ROOT / "pic4rl_base"
HEAVY = {"rclpy", "mujoco", "torch", "gymnasium", "stable_baselines3", "pandas", "rosbags",
         "matplotlib"}


def test_the_base_imports_no_other_pic4rl_package() -> None:
    modules = sorted(BASE.rglob("*.py"))
    assert {p.name for p in modules} >= {"errors.py", "geometry.py", "schema.py", "entry.py"}
    above = {str(p.relative_to(ROOT)): sorted(m for m, _, _ in imports(p, module_name(p))
                                              if m.startswith("pic4rl_")
                                              and not m.startswith("pic4rl_base"))
             for p in modules}
    assert {k: v for k, v in above.items() if v} == {}


def test_importing_the_whole_base_loads_only_numpy_and_yaml() -> None:
    names = sorted(f"pic4rl_base.{p.stem}" for p in BASE.glob("*.py") if p.stem != "__init__")
    code = ("import json, sys\n"
            f"before = set(sys.modules)\n"
            f"import {', '.join(names)}\n"
            "roots = {m.split('.')[0] for m in set(sys.modules) - before}\n"
            "print(json.dumps(sorted(r for r in roots if not r.startswith('_'))))\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    loaded = set(json.loads(done.stdout.splitlines()[-1]))
    assert {"pic4rl_base", "numpy", "yaml"} <= loaded
    assert {r for r in loaded if r.startswith("pic4rl")} == {"pic4rl_base"}
    assert not loaded & HEAVY


def test_every_package_raises_the_one_config_error_and_a_console_script_catches_it() -> None:
    from pic4rl_base.entry import EXIT_BAD_INPUT, entry_point
    from pic4rl_base.errors import ConfigError, Pic4rlError
    from pic4rl_bridge.errors import ConfigError as BridgeConfigError
    from pic4rl_metrics.errors import BagError
    from pic4rl_metrics.errors import ConfigError as MetricsConfigError
    from pic4rl_sim.errors import ConfigError as SimConfigError
    from pic4rl_sim.errors import WorldError

    assert ConfigError is MetricsConfigError is SimConfigError is BridgeConfigError
    for err in (ConfigError("k: bad"), BagError("a.db3: truncated"), WorldError("no free cell")):
        @entry_point("prog")
        def main(err: Exception = err) -> int:
            raise err
        assert isinstance(err, Pic4rlError)
        assert main() == EXIT_BAD_INPUT
