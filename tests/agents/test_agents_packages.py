"""The agents' rooms: each sub-package exports its public names, imported when first read, so
importing a room or the configuration loads no torch, SB3 or Optuna (``pic4rl-train --help``
and the config checks stay light)."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

ROOMS = ("models", "training", "testing", "tune", "suites")
HEAVY = ("torch", "stable_baselines3", "optuna", "ray")


@pytest.mark.parametrize("room", ROOMS)
def test_every_exported_name_is_there(room: str) -> None:
    package = importlib.import_module(f"pic4rl_agents.{room}")
    assert package.__doc__ and package.__all__
    for name in package.__all__:
        assert getattr(package, name) is not None, f"pic4rl_agents.{room}.{name}"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        package.nothing  # noqa: B018


def test_the_rooms_and_the_config_import_no_torch_sb3_or_optuna() -> None:
    rooms = "; ".join(f"import pic4rl_agents.{room}" for room in ROOMS)
    code = (f"import sys, json; {rooms}; import pic4rl_agents.runs.config; "
            "import pic4rl_agents.models.algorithm_table; import pic4rl_agents.tune.space; "
            f"print(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert json.loads(done.stdout) == []
