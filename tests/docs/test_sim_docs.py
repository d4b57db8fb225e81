"""docs/sim.md against the code: every parameter, topic, service, config file and built-in
robot is documented, and the tables generated from the code are current. Starts no ROS graph.

After changing a parameter, a robot or an interface, print the tables and paste them into
docs/sim.md:

    .venv/bin/python tests/docs/test_sim_docs.py
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from pic4rl_sim.engine.model import WHEEL_GRIP, yaw_inertia_kg_m2
from pic4rl_sim.config import ParamSpec, parameter_table
from pic4rl_sim.engine.robot_specs import ROBOT_TABLE, JACKAL, Drive, RobotSpec
from pic4rl_sim.engine.sensors import STANDARD_GRAVITY_M_S2
from pic4rl_sim.engine.worlds.generators import WORLD_TABLE
from pic4rl_sim.interfaces import INTERFACE_TABLE, Interface

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "sim.md"
# The sim's interfaces as /work/shared/DESIGN.md lists them. The interface table must include
# these, so that an empty table cannot pass the test.
DESIGN_NAMES = frozenset({
    "cmd_vel", "scan", "odom", "ground_truth", "camera/depth/image_raw",
    "camera/depth/camera_info", "imu/data", "goal_pose", "person/pose", "clock",
    "world/markers", "reset_world", "pause_physics", "unpause_physics", "plan",
})


# -- the generated tables ----------------------------------------------------------------------


def _literal(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_literal(v) for v in value) + "]"
    return repr(value) if isinstance(value, float) else str(value)


def _text(text: str) -> str:
    """Plain text made safe for a Markdown table cell."""
    return text.replace("|", "\\|").replace("*", "\\*")


def _parameter_row(spec: ParamSpec, *, strip: str = "", limits: bool = True) -> str:
    description = _text(spec.description.removeprefix(strip))
    cells = [f"`{spec.name}`", spec.type.value.lower(), f"`{_literal(spec.default)}`"]
    if limits:
        if spec.choices:
            cells.append(", ".join(f"`{c}`" for c in spec.choices))
        elif spec.bounds is not None:
            cells.append(f"`{spec.bounds}`")  # open ends as the checks apply them
        else:
            cells.append("")
    cells.append(description)
    return "| " + " | ".join(cells) + " |"


def parameter_tables(robot: RobotSpec = JACKAL) -> dict[str, list[str]]:
    """The rows of docs/sim.md's parameter tables: node and episode, sensors, then one table
    per world generator."""
    tables: dict[str, list[str]] = {"node": [], "sensors": []}
    tables.update({f"world.{kind}": [] for kind in WORLD_TABLE})
    for spec in parameter_table(robot):
        parts = spec.name.split(".")
        if parts[0] == "world" and len(parts) == 3:
            strip = f"{parts[1]} world: "
            tables[f"world.{parts[1]}"].append(_parameter_row(spec, strip=strip, limits=False))
        elif len(parts) == 2:
            tables["sensors"].append(_parameter_row(spec))
        else:
            tables["node"].append(_parameter_row(spec))
    return tables


PARAMETER_HEADER = ("| name | type | default | range / choices | description |\n"
                    "|---|---|---|---|---|")
WORLD_HEADER = "| name | type | default | description |\n|---|---|---|---|"


def _n(value: float) -> str:
    return f"{value:g}"


def robot_tables() -> dict[str, list[str]]:
    """The rows of docs/sim.md's three robot tables: body, limits, sensors."""
    body, limits, sensors = [], [], []
    for r in ROBOT_TABLE.values():
        fp = r.footprint
        shape = (f"circle, r {_n(fp.radius_m)}" if fp.radius_m is not None
                 else f"{_n(fp.length_m)} × {_n(fp.width_m)}")  # type: ignore[arg-type]
        body.append(f"| `{r.name}` | {r.drive.value} | {shape} | "
                    f"{fp.bounding_radius_m:.3f} | {_n(r.height_m)} | {_n(r.mass_kg)} | "
                    f"{_n(r.wheel_base_m)} | {_n(r.wheel_radius_m)} |")
        weight = r.mass_kg * STANDARD_GRAVITY_M_S2
        lateral_cap = (r.mass_kg * r.max_linear_accel_m_s2 if r.drive is Drive.OMNI
                       else WHEEL_GRIP * weight)
        limits.append(f"| `{r.name}` | {_n(r.max_linear_m_s)} | {_n(r.max_lateral_m_s)} | "
                      f"{_n(r.max_angular_rad_s)} | {_n(r.max_linear_accel_m_s2)} | "
                      f"{_n(r.max_angular_accel_rad_s2)} | "
                      f"{_n(round(r.mass_kg * r.max_linear_accel_m_s2, 2))} | "
                      f"{_n(round(lateral_cap, 1))} | "
                      f"{_n(round(yaw_inertia_kg_m2(r) * r.max_angular_accel_rad_s2, 3))} |")
        lidar = r.lidar
        if lidar is None:
            sensors.append(f"| `{r.name}` | none | | | | |")
        else:
            sensors.append(f"| `{r.name}` | {_literal(tuple(lidar.mount_xyz_m))} | "
                           f"{_n(lidar.mount_yaw_rad)} | {lidar.beams} | {_n(lidar.fov_deg)} | "
                           f"{_n(lidar.range_min_m)}–{_n(lidar.range_max_m)} | "
                           f"{'yes' if r.depth else 'none'} |")
    return {"body": body, "limits": limits, "sensors": sensors}


ROBOT_HEADERS = {
    "body": ("| robot | drive | footprint (m) | bounding radius (m) | height (m) | mass (kg) "
             "| wheel base (m) | wheel radius (m) |\n|---|---|---|---:|---:|---:|---:|---:|"),
    "limits": ("| robot | max v (m/s) | max lateral (m/s) | max ω (rad/s) | max accel (m/s²) "
               "| max angular accel (rad/s²) | forward force cap (N) | lateral force cap (N) "
               "| yaw torque cap (N m) |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|"),
    "sensors": ("| robot | LiDAR mount xyz (m) | mount yaw (rad) | beams | fov (deg) "
                "| range (m) | depth camera |\n|---|---|---:|---:|---:|---|---|"),
}


def interface_cells(interface: Interface) -> list[str]:
    """docs/sim.md's interface row of ``interface``, but for its hand-written frame cell."""
    qos = str(interface.qos.value) if interface.qos is not None else "services default"
    return [interface.direction.value, f"`{interface.name}`", f"`{interface.type}`", qos,
            interface.content, interface.published]


INTERFACE_HEADER = ("| dir | name | type | QoS (reliability, durability, depth) "
                    "| frame_id → child_frame_id | content | published |\n"
                    "|---|---|---|---|---|---|---|")
FRAME = 4  # the frame cell's index in a row


def doc_interface_rows(doc: str) -> dict[str, list[str]]:
    """docs/sim.md's interface table: the cells of each row, by name cell."""
    rows = {}
    for line in doc.splitlines():
        if line.startswith(("| pub |", "| sub |", "| srv |")):
            cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
            rows[cells[1]] = cells
    return rows


# -- what the code declares ------------------------------------------------------------------


def node_interface_names() -> set[str]:
    """Every topic and service name of the node: its interface table's."""
    return {interface.name for interface in INTERFACE_TABLE}


@pytest.fixture(scope="module")
def doc() -> str:
    return DOC.read_text(encoding="utf-8")


def _missing(doc: str, rows: list[str]) -> list[str]:
    lines = set(doc.splitlines())
    return [row for row in rows if row not in lines]


def test_every_parameter_is_named_in_the_doc(doc):
    missing = [s.name for s in parameter_table(JACKAL) if f"`{s.name}`" not in doc]
    assert not missing, f"docs/sim.md does not name these parameters: {missing}"


def test_the_parameter_tables_are_current(doc):
    stale = [row for rows in parameter_tables().values() for row in _missing(doc, rows)]
    assert not stale, ("docs/sim.md's parameter tables differ from the code; regenerate them "
                       f"with `python tests/docs/test_sim_docs.py`. Rows not found: {stale}")


def test_every_topic_and_service_of_the_node_is_in_the_doc(doc):
    names = node_interface_names()
    assert names >= DESIGN_NAMES, f"interfaces.py lacks {sorted(DESIGN_NAMES - names)}"
    missing = sorted(n for n in names if f"`{n}`" not in doc)
    assert not missing, f"docs/sim.md does not name these interfaces: {missing}"


def test_the_interface_table_is_current(doc):
    rows = doc_interface_rows(doc)
    expected = {f"`{i.name}`": interface_cells(i) for i in INTERFACE_TABLE}
    assert list(rows) == list(expected), "docs/sim.md's interface rows differ from interfaces.py"
    stale = [name for name, cells in rows.items()
             if cells[:FRAME] + cells[FRAME + 1:] != expected[name]]
    assert not stale, ("docs/sim.md's interface table differs from interfaces.py; regenerate "
                       f"it with `python tests/docs/test_sim_docs.py`. Rows: {stale}")


def test_every_config_file_is_in_the_doc(doc):
    configs = sorted(p.name for p in (ROOT / "config").glob("sim_*.yaml"))
    assert configs
    missing = [name for name in configs if f"config/{name}" not in doc]
    assert not missing, f"docs/sim.md does not mention {missing}"


def test_every_built_in_robot_and_world_is_in_the_doc(doc):
    missing = [name for name in (*ROBOT_TABLE, *WORLD_TABLE) if f"`{name}`" not in doc]
    assert not missing, f"docs/sim.md does not name {missing}"


def test_the_robot_tables_are_current(doc):
    stale = [row for rows in robot_tables().values() for row in _missing(doc, rows)]
    assert not stale, ("docs/sim.md's robot tables differ from robot_specs.py; regenerate them "
                       f"with `python tests/docs/test_sim_docs.py`. Rows not found: {stale}")


def test_the_doc_links_resolve(doc):
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", doc)
    broken = [t for t in targets if "://" not in t and not (DOC.parent / t).exists()]
    assert not broken, f"docs/sim.md links to missing files: {broken}"


if __name__ == "__main__":
    for name, rows in parameter_tables().items():
        print(f"<!-- {name} -->")
        print(WORLD_HEADER if name.startswith("world.") else PARAMETER_HEADER)
        print("\n".join(rows), end="\n\n")
    for name, rows in robot_tables().items():
        print(f"<!-- robots: {name} -->")
        print(ROBOT_HEADERS[name])
        print("\n".join(rows), end="\n\n")
    frames = {name: cells[FRAME] for name, cells in doc_interface_rows(DOC.read_text()).items()}
    print("<!-- interfaces (frame cells from the doc) -->")
    print(INTERFACE_HEADER)
    for interface in INTERFACE_TABLE:
        cells = interface_cells(interface)
        cells.insert(FRAME, frames.get(cells[1], "?"))
        print("| " + " | ".join(cells) + " |")
