"""``tools/crowd_contacts.py`` on synthetic bags whose contacts are known by hand: a robot that
drives into a person ahead, and one that a faster person walks into from behind."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

from pic4rl_metrics.synthetic.synthetic import straight_line, write_episode_bag

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("crowd_contacts", ROOT / "tools" / "crowd_contacts.py")
assert SPEC is not None and SPEC.loader is not None
crowd_contacts = sys.modules.setdefault(SPEC.name, importlib.util.module_from_spec(SPEC))
SPEC.loader.exec_module(crowd_contacts)

#: Footprint disc 0.2 m and person 0.3 m: the bodies touch (within the 0.05 m tolerance) when
#: the centres are closer than 0.55 m.
FACTS = {"footprint": {"radius_m": 0.2}, "person_radius_m": 0.3}


def bag(tmp_path: Path, name: str, person_start: tuple[float, float, float],
        person_speed: float) -> Path:
    """The robot drives +x from (0, 0) at 0.5 m/s for 8 s; one person walks a straight line."""
    robot = straight_line(0.5, 8.0, 0.1)
    person = straight_line(person_speed, 8.0, 0.1, start=person_start)
    return write_episode_bag(tmp_path / name, robot, people=[person], facts=FACTS)


def test_a_robot_driving_into_a_person_ahead(tmp_path: Path) -> None:
    """A person standing 3 m ahead: the robot closes at 0.5 m/s, the person not at all; the
    centres are 0.55 m apart at (3 - 0.55) / 0.5 = 4.9 s, sampled every 0.1 s."""
    contact = crowd_contacts.first_contact(bag(tmp_path, "ahead", (3.0, 0.0, 0.0), 0.0))
    assert contact.bearing_deg == pytest.approx(0.0, abs=1e-6) and not contact.behind
    assert contact.t_s == pytest.approx(5.0, abs=0.11)  # the first sample with a gap < 0.05 m
    assert contact.robot_closing_mps == pytest.approx(0.5, abs=1e-6)
    assert contact.person_closing_mps == pytest.approx(0.0, abs=1e-6)


def test_a_faster_person_walking_into_the_robot_from_behind(tmp_path: Path) -> None:
    """A person 3 m behind at 1.5 m/s the same way: the robot opens the gap at 0.5 m/s, the
    person closes it at 1.5 m/s; contact at (3 - 0.55) / 1 = 2.45 s."""
    contact = crowd_contacts.first_contact(bag(tmp_path, "behind", (-3.0, 0.0, 0.0), 1.5))
    assert abs(contact.bearing_deg) == pytest.approx(180.0, abs=1e-6) and contact.behind
    assert contact.t_s == pytest.approx(2.5, abs=0.11)
    assert contact.robot_closing_mps == pytest.approx(-0.5, abs=1e-6)
    assert contact.person_closing_mps == pytest.approx(1.5, abs=1e-6)


def test_no_contact_no_row_and_the_summary_counts(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    bag(tmp_path / "run", "beside", (0.0, 2.0, 0.0), 0.5)  # 2 m to the left all along
    bag(tmp_path / "run", "behind", (-3.0, 0.0, 0.0), 1.5)
    assert crowd_contacts.first_contact(tmp_path / "run" / "beside") is None
    assert crowd_contacts.main([str(tmp_path / "run")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and "behind" in out[0]
    assert out[1] == ("2 episodes, 1 with a contact: 1 with the person behind the robot "
                      "(|bearing| > 90°), 1 with the person closing faster than the robot")


@pytest.mark.bad_input
def test_a_bag_that_does_not_read_is_named_and_the_rest_go_on(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag(tmp_path / "run", "behind", (-3.0, 0.0, 0.0), 1.5)
    broken = tmp_path / "run" / "broken"
    broken.mkdir()
    (broken / "metadata.yaml").write_text("not: a rosbag2 metadata\n")
    assert crowd_contacts.main([str(tmp_path / "run"), str(tmp_path / "nowhere")]) == 0
    captured = capsys.readouterr()
    assert f"{broken}: " in captured.err and f"{tmp_path / 'nowhere'}: " in captured.err
    assert captured.out.splitlines()[-1].startswith("1 episodes, 1 with a contact")
