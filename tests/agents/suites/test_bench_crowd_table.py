"""``config/suite_crowd.yaml``'s table (``table: crowd``) carries the social columns beside
success, from the bags: synthetic crowd episodes with known answers are written into two of
its cells' folders (a robot passing a standing person 1.2 m off, or walking into one), and the
suite's row shows the rates, each zone's entries and time, the closest approach, the people
contacts and the speed near people as computed by hand, body to body."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pic4rl_agents.suites import table as benchtable
from pic4rl_agents.suites.suite import load_suite
from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag
from pic4rl_metrics.synthetic.synthetic_crowd import standing

REPO = Path(__file__).resolve().parents[3]
ROBOT_M, PERSON_M, SPEED = 0.2, 0.25, 1.0
BODIES_M = ROBOT_M + PERSON_M
FACTS = {"footprint": {"radius_m": ROBOT_M}, "person_radius_m": PERSON_M}


def _chord_s(offset_m: float, radius_m: float) -> float:
    return 2.0 * math.sqrt(max(radius_m**2 - offset_m**2, 0.0)) / SPEED


def _episode(path: Path, offset_m: float, outcome: str) -> None:
    """The robot drives +x from (-4.8, 0) for 9.6 s past a person standing at (0, offset),
    the goal at (4.8, 0)."""
    robot = straight_line(SPEED, 9.6, 0.02, start=(-4.8, 0.0, 0.0))
    write_episode_bag(path, robot, people=[standing(0.0, offset_m, 9.6, 0.02)], facts=FACTS,
                      goal=(4.8, 0.0), outcome=outcome)


def test_the_crowd_table_has_the_social_columns_beside_success(tmp_path: Path) -> None:
    suite = load_suite(REPO / "config" / "suite_crowd.yaml", bags_dir=tmp_path)
    assert suite.table == "crowd"
    orca = [c for c in suite.cells if c.agent == "orca"]
    # two repetitions of one row: a pass 1.2 m off (a goal) and through a person 0.4 m off,
    # the bodies overlapping by 0.05 m (a collision)
    _episode(suite.root / orca[0].name / "orca" / "episode_0000", 1.2, "goal")
    _episode(suite.root / orca[1].name / "orca" / "episode_0000", 0.4, "collision")
    header, rows, bad = benchtable.build_rows(suite, {})
    assert not bad
    cells = {r[1]: dict(zip(header, r)) for r in rows}
    row = cells["orca"]
    assert [row[c] for c in ("n", "success", "collision", "timeout")] == ["2", "1/2", "1/2",
                                                                           "0/2"]
    far, near = 1.2, 0.4  # centre offsets; the zones' radii grow by both bodies' radii
    expected = {
        "intimate zone entries [count]": (0 + 1) / 2,
        "personal zone entries [count]": (1 + 1) / 2,
        "social zone entries [count]": (1 + 1) / 2,
        "intimate zone time [s]": (0 + _chord_s(near, 0.45 + BODIES_M)) / 2,
        "personal zone time [s]": (_chord_s(far, 1.2 + BODIES_M)
                                   + _chord_s(near, 1.2 + BODIES_M)) / 2,
        "social zone time [s]": (_chord_s(far, 3.6 + BODIES_M)
                                 + _chord_s(near, 3.6 + BODIES_M)) / 2,
        "min person distance [m]": (far - BODIES_M + 0.0) / 2,  # 0 while they overlap
        "people collisions [count]": (0 + 1) / 2,
        "min time to collision [s]": (10.0 + 0.0) / 2,  # never on course (capped); touching
        "speed near people [m/s]": SPEED,
    }
    for column, value in expected.items():
        assert row[column] is not None, column
        assert float(row[column]) == pytest.approx(value, abs=0.006), column
    assert row["status"] == "ok"
    # a row without bags keeps the table's width, its n 0 and its social cells empty
    assert cells["dwa"]["n"] == "0" and cells["dwa"]["min person distance [m]"] is None
    assert all(len(r) == len(header) for r in rows)
