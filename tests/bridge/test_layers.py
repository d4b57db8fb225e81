"""The bridge flows one way: its rooms stacked bottom to top, and no module imports one above.

Settings and shared types → perception → control laws → baselines and planners → tasks →
transports → the env (``/work/shared/DESIGN.md``'s "Inside the bridge: one way down",
``docs/architecture.md``'s module table). Every import counts, wherever it stands (in a
function, under ``TYPE_CHECKING``): a late import that reaches up is still a door opened the
wrong way. With no import up, nothing reaches up through another module either.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from import_helpers import imports, module_name

ROOT = Path(__file__).resolve().parents[2]
BRIDGE = ROOT / "pic4rl_bridge"

#: The bridge's rooms, bottom to top: each a name and the modules or sub-packages it holds.
#: A module may import one of its own room or of a room below it.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("settings and shared types", (
        "pic4rl_bridge.errors", "pic4rl_bridge.settings", "pic4rl_bridge.config",
        "pic4rl_bridge.robot_info", "pic4rl_bridge.scenario", "pic4rl_bridge.readings")),
    ("perception", ("pic4rl_bridge.perception",)),
    ("control", ("pic4rl_bridge.control",)),
    ("baselines and planners", ("pic4rl_bridge.baselines",)),
    ("tasks", ("pic4rl_bridge.tasks",)),
    ("transports", ("pic4rl_bridge.transports",)),
    ("env", ("pic4rl_bridge", "pic4rl_bridge.env", "pic4rl_bridge.env_facts",
             "pic4rl_bridge.recording", "pic4rl_bridge.recorder", "pic4rl_bridge.episodes",
             "pic4rl_bridge.render")),
)


MODULES = {module_name(p): p for p in sorted(BRIDGE.rglob("*.py"))}


def layer_of(module: str) -> int | None:
    """The index in ``LAYERS`` of the room that holds ``module`` (its longest declared
    prefix), or ``None`` when no room names it."""
    best, index = -1, None
    for i, (_, members) in enumerate(LAYERS):
        for member in members:
            if (module == member or module.startswith(member + ".")) and len(member) > best:
                best, index = len(member), i
    return index


def bridge_imports(path: Path, name: str) -> list[tuple[str, int]]:
    """(bridge module, line) for each import of ``path`` (module ``name``), wherever it
    stands; ``from package import name`` counts as the module ``package.name`` when there is
    one, else as ``package``."""
    found = []
    for base, names, line in imports(path, name):
        found += [(f"{base}.{n}" if f"{base}.{n}" in MODULES else base, line) for n in names]
        found += [(base, line)] if not names else []
    return [(m, line) for m, line in found if m.split(".")[0] == "pic4rl_bridge"]


def upward_imports(modules: dict[str, Path] = MODULES) -> list[str]:
    """Every import of a module of a higher room among ``modules`` (name → file), as
    ``module:line → module (room → room)``."""
    up = []
    for name, path in modules.items():
        here = layer_of(name)
        for target, line in bridge_imports(path, name):
            there = layer_of(target)
            if here is not None and there is not None and there > here:
                up.append(f"{name}:{line} → {target} ({LAYERS[here][0]} → {LAYERS[there][0]})")
    return sorted(set(up))


def test_every_bridge_module_has_a_room() -> None:
    homeless = [name for name in MODULES if layer_of(name) is None]
    assert len(MODULES) > 30 and not homeless, f"modules in no room of LAYERS: {homeless}"


def test_every_room_exists() -> None:
    missing = [m for _, members in LAYERS for m in members if m not in MODULES]
    assert not missing, f"LAYERS names modules that do not exist: {missing}"


def test_no_bridge_module_imports_one_of_a_higher_room() -> None:
    up = upward_imports()
    assert not up, "imports up the bridge's rooms:\n" + "\n".join(up)


@pytest.mark.parametrize(("source", "expected"), [
    ("from ..tasks.goto import build\n", ["pic4rl_bridge.tasks.goto"]),
    ("def f():\n    from ..env import NavEnv\n", ["pic4rl_bridge.env"]),
    ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
     "    from pic4rl_bridge.transports import inprocess\n",
     ["pic4rl_bridge.transports.inprocess"]),
    ("import numpy\nfrom pic4rl_sim.engine import core\n", []),
])
def test_the_check_sees_every_kind_of_import(tmp_path: Path, source: str,
                                             expected: list[str]) -> None:
    """A lazy import in a function and a ``TYPE_CHECKING`` one are imports too."""
    path = BRIDGE / "perception" / "collision.py"
    fake = tmp_path / "collision.py"
    fake.write_text(source, encoding="utf-8")
    assert path.is_file()
    assert [m for m, _ in bridge_imports(fake, "pic4rl_bridge.perception.collision")] == expected


def test_a_room_reaching_up_is_refused(tmp_path: Path) -> None:
    """The order is the one the docs give, and an import up, even a late one, is reported with
    its line and rooms (as ``perception/explorer_plan.py``'s of the baselines' settings was)."""
    assert [name for name, _ in LAYERS] == [
        "settings and shared types", "perception", "control", "baselines and planners",
        "tasks", "transports", "env"]
    fake = tmp_path / "collision.py"
    fake.write_text("from ..settings.tasks import TASK_TABLE\n\n\ndef f():\n"
                    "    from ..baselines.planner import PlannerController\n", encoding="utf-8")
    assert upward_imports({"pic4rl_bridge.perception.collision": fake}) == [
        "pic4rl_bridge.perception.collision:5 → pic4rl_bridge.baselines.planner "
        "(perception → baselines and planners)"]
