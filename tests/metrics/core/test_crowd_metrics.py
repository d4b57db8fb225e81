"""Social metrics against analytic answers: a robot at constant speed passes standing people at
known offsets (zone times are chords over the speed, the zones measured body to body: a zone's
radius plus both bodies' radii between centres), meets a walking one head-on (the time to
collision is the surface gap over the closing speed) or drives a circle (path irregularity
1/r); a robot brushing a person is in its intimate zone; a tracker's bag on its own topic,
people coming and going and no recorded person radius (the default), is judged the same way."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from metrics_helpers import EXACT
from metrics_helpers import row as _row
from rosbags.rosbag2 import Reader, Writer

from pic4rl_metrics import compute
from pic4rl_metrics.bags.topics import TopicMap
from pic4rl_metrics.cli.commands import main
from pic4rl_metrics.contract import PEOPLE_TOPIC, typestore
from pic4rl_metrics.core.tasks.crowd import PERSON_RADIUS_M, TTC_HORIZON_S, time_to_collision
from pic4rl_metrics.synthetic.synthetic import (
    Obstacles,
    Track,
    circle,
    straight_line,
    write_episode_bag,
)
from pic4rl_metrics.synthetic.synthetic_crowd import standing
from pic4rl_metrics.tables.aggregate import aggregate

ROBOT_RADIUS_M = 0.2
PERSON_M = 0.3  # the person_radius_m fact these bags record (the default is 0.25)
BODIES_M = ROBOT_RADIUS_M + PERSON_M  # centre to centre, the bodies touch at this
FACTS = {"footprint": {"radius_m": ROBOT_RADIUS_M}, "person_radius_m": PERSON_M}
#: Zone times cross the curved distance d(x) = sqrt(x² + h²) with a line between samples
#: Δx = 0.016 m apart: off by at most d''·Δx²/8 / d' / v per crossing, 5.4e-5 s at the
#: tightest case here (h = 0.3 m, the 0.45 m zone, 0.8 m/s), two crossings.
CHORD = 1.2e-4
ZONES = {"intimate": 0.45, "personal": 1.2, "social": 3.6}


def _chord_s(offset_m: float, radius_m: float, speed_mps: float) -> float:
    """Time a straight pass ``offset_m`` off a centre spends within ``radius_m`` of it."""
    return 2.0 * math.sqrt(max(radius_m**2 - offset_m**2, 0.0)) / speed_mps


def _passing(tmp_path: Path, name: str, offsets: list[float], speed: float = 1.0):
    """The robot drives +x from (-4.8, 0) at ``speed`` for 10.8 / speed s past people
    standing at (0, offset), beside them at a sample (4.8 / speed s)."""
    duration = 10.8 / speed
    robot = straight_line(speed, duration, 0.02, start=(-4.8, 0.0, 0.0))
    people = [standing(0.0, h, duration, 0.02) for h in offsets]
    return _row(write_episode_bag(tmp_path / name, robot, people=people, facts=FACTS,
                                  goal=(5.0, 0.0)))


@pytest.mark.parametrize("offset", [0.3, 1.0, 2.5])
def test_passing_a_standing_person_at_an_offset(tmp_path: Path, offset: float) -> None:
    speed = 0.8
    m = _passing(tmp_path, "pass", [offset], speed)
    for zone, radius in ZONES.items():
        assert m[f"{zone}_intrusion_count"] == float(offset < radius + BODIES_M), zone
        assert m[f"{zone}_intrusion_time_s"] == pytest.approx(
            _chord_s(offset, radius + BODIES_M, speed), abs=CHORD), zone
    assert m["people_dist_min_m"] == pytest.approx(max(offset - BODIES_M, 0.0), abs=1e-9)
    near = m["speed_near_people_mean_mps"]  # while someone is within 1.2 m
    assert near == pytest.approx(speed, abs=1e-9) if offset < 1.2 + BODIES_M else math.isnan(near)
    touching = offset < BODIES_M + 0.05
    assert m["people_collision_count"] == float(touching)
    assert m["path_irregularity_radpm"] == pytest.approx(0.0, abs=EXACT)
    if not touching:  # a standing person beside a straight path: no collision course
        assert m["people_ttc_min_s"] == TTC_HORIZON_S


def test_two_people_abreast_count_twice_but_time_once(tmp_path: Path) -> None:
    """Both at 1.2 m either side (0.7 m body to body) enter the personal zone together: two
    entries, and the robot's time in someone's personal zone is one chord,
    2 sqrt(1.7² - 1.2²) / 1 m/s."""
    m = _passing(tmp_path, "abreast", [1.2, -1.2])
    assert m["personal_intrusion_count"] == 2.0
    assert m["personal_intrusion_time_s"] == pytest.approx(_chord_s(1.2, 1.7, 1.0), abs=CHORD)
    assert m["intimate_intrusion_count"] == 0.0


def test_brushing_past_a_person_is_an_intimate_intrusion(tmp_path: Path) -> None:
    """Centres 0.52 m apart at the closest, bodies 0.02 m apart: a contact within the
    collision tolerance, in the intimate zone (centre to centre it would read 0.52 > 0.45:
    never intimate); with the default radius 0.25 m the bodies are 0.07 m apart."""
    m = _passing(tmp_path, "brush", [0.52])
    assert m["intimate_intrusion_count"] == 1.0 and m["people_collision_count"] == 1.0
    assert m["people_dist_min_m"] == pytest.approx(0.02, abs=1e-9)
    robot = straight_line(1.0, 10.0, 0.02, start=(-4.0, 0.0, 0.0))
    bag = write_episode_bag(tmp_path / "default", robot, goal=(5.0, 0.0),
                            people=[standing(0.0, 0.52, 10.0, 0.02)],
                            facts={"footprint": FACTS["footprint"]})
    m = _row(bag)
    assert m["people_dist_min_m"] == pytest.approx(0.52 - ROBOT_RADIUS_M - PERSON_RADIUS_M,
                                                   abs=1e-9)
    assert m["intimate_intrusion_count"] == 1.0 and m["people_collision_count"] == 0.0


def _head_on(tmp_path: Path, duration: float):
    """Robot from (0, 0) at +0.5 m/s, a person from (6, 0) at -1 m/s: the centre gap is
    6 - 1.5 t, the bodies' 6 - 1.5 t - 0.5, the time to collision of discs 0.2 + 0.3 m
    (6 - 1.5 t - 0.5) / 1.5."""
    robot = straight_line(0.5, duration, 0.1)
    person = straight_line(1.0, duration, 0.1, start=(6.0, 0.0, math.pi))
    return _row(write_episode_bag(tmp_path / f"head_on_{duration:g}", robot, people=[person],
                                  facts=FACTS))


def test_a_head_on_approach_has_the_gap_over_the_closing_speed(tmp_path: Path) -> None:
    m = _head_on(tmp_path, 2.0)  # ends 3 m apart (bodies 2.5 m): TTC (3 - 0.5) / 1.5
    assert m["people_ttc_min_s"] == pytest.approx(2.5 / 1.5, abs=1e-9)
    assert m["people_dist_min_m"] == pytest.approx(2.5, abs=1e-9)
    # bodies 3.6 m apart at 1.9 / 1.5 s: in the social zone for the rest, not the personal one
    assert m["social_intrusion_time_s"] == pytest.approx(2.0 - 1.9 / 1.5, abs=1e-9)
    assert (m["social_intrusion_count"], m["personal_intrusion_count"]) == (1.0, 0.0)
    assert m["people_collision_count"] == 0.0


def test_running_into_a_person_is_a_people_collision(tmp_path: Path) -> None:
    """Through each other (nothing stops them): in contact while the gap is under 0.2 + 0.3 +
    0.05 m (the collision tolerance), once; intimate zone while the centres are within
    0.45 + 0.5 m, 2 x 0.95 / 1.5 s; TTC 0."""
    m = _head_on(tmp_path, 6.0)
    assert m["people_collision_count"] == 1.0
    assert m["people_ttc_min_s"] == 0.0
    assert m["intimate_intrusion_count"] == 1.0
    assert m["intimate_intrusion_time_s"] == pytest.approx(1.9 / 1.5, abs=1e-9)
    assert m["people_dist_min_m"] == pytest.approx(0.0, abs=1e-9)
    assert math.isnan(m["collision_count"])  # no scan: the static count knows nothing


def test_people_collisions_are_counted_apart_from_the_scan_s(tmp_path: Path) -> None:
    """A post 0.3 m right of the path at x = 3 (radius 0.1: the footprint's margin 0 m) and a
    person 0.3 m left of it at x = 0: one collision each, in their own columns."""
    robot = straight_line(1.0, 10.0, 0.02, start=(-4.0, 0.0, 0.0))
    post = Obstacles(circles=((3.0, -0.3, 0.1),))
    bag = write_episode_bag(tmp_path / "both", robot, obstacles=post, scan_every=5,
                            people=[standing(0.0, 0.3, 10.0, 0.02)], facts=FACTS)
    m = _row(bag)
    assert (m["collision_count"], m["people_collision_count"]) == (1.0, 1.0)


def test_a_comparison_counts_the_episodes_that_touched_a_person(tmp_path: Path) -> None:
    """Two contacts in one episode and none in another: 1 episode of 2, as collisions."""
    robot = straight_line(1.0, 10.0, 0.1, start=(-4.0, 0.0, 0.0))
    twice = [standing(0.0, 0.3, 10.0), standing(2.0, -0.3, 10.0)]
    bags = [write_episode_bag(tmp_path / "run" / name, robot, people=people, facts=FACTS)
            for name, people in (("touch", twice), ("clear", [standing(0.0, 2.0, 10.0)]))]
    table = aggregate(compute(bags).frame)
    assert table["people_collision_count_episodes"].tolist() == [1]
    assert table["people_collision_count_mean"].tolist() == [1.0]  # (2 + 0) / 2 contacts


def test_without_a_footprint_the_body_columns_are_nan(tmp_path: Path) -> None:
    """Distances between bodies need the robot's: only the path irregularity is left."""
    robot = straight_line(1.0, 4.0, 0.1, start=(-2.0, 0.0, 0.0))
    m = _row(write_episode_bag(tmp_path / "bare", robot, people=[standing(0, 1, 4.0)]))
    for name in ("people_ttc_min_s", "people_collision_count", "people_dist_min_m",
                 "intimate_intrusion_count", "personal_intrusion_time_s",
                 "speed_near_people_mean_mps"):
        assert math.isnan(m[name]), name
    assert m["path_irregularity_radpm"] == pytest.approx(0.0, abs=EXACT)


def test_path_irregularity_is_the_turning_per_metre(tmp_path: Path) -> None:
    """A circle of radius 2 m at 1 m/s turns 0.5 rad/s: 2.5 rad in 5 s, all of it counted
    without a goal, over the sampled path, 50 chords 2 r sin(Δφ/2) (Δφ = 0.05 rad; the arc
    would give 1/r = 0.5 rad/m)."""
    robot = circle(2.0, 1.0, 5.0)
    m = _row(write_episode_bag(tmp_path / "circle", robot,
                               people=[standing(10.0, 10.0, 5.0)]))
    chords_m = 50 * 2 * 2.0 * math.sin(0.025)
    assert m["path_irregularity_radpm"] == pytest.approx(2.5 / chords_m, abs=1e-9)


def test_a_bag_without_people_has_no_social_columns(tmp_path: Path) -> None:
    m = _row(write_episode_bag(tmp_path / "empty", straight_line(1.0, 2.0), facts=FACTS))
    for name in ("personal_intrusion_time_s", "people_dist_min_m", "people_ttc_min_s",
                 "path_irregularity_radpm"):
        assert math.isnan(m[name]), name


def test_a_tracker_s_bag_with_people_coming_and_going(tmp_path: Path) -> None:
    """A real robot's tracker on its own topic (a topic map names it), no person radius
    recorded (0.25 m, the default): the second person is tracked for the first 2 s only
    (shorter arrays after), standing 0.5 m off the path at x = 1, where the robot is at 4 s:
    never met; the first stands 1 m off at x = 4 (bodies 0.55 m apart)."""
    robot = straight_line(1.0, 9.0, 0.1, start=(-3.0, 0.0, 0.0))
    second = standing(1.0, 0.5, 9.0)
    lost = np.where(second.t_s < 2.0, second.x, np.nan)
    second = Track(second.t_s, lost, second.y, second.yaw, second.vx, second.vy, second.wz)
    bag = write_episode_bag(tmp_path / "sim", robot, people=[standing(4.0, 1.0, 9.0), second],
                            facts={"footprint": FACTS["footprint"]})
    ts, moved = typestore(), tmp_path / "tracker"
    with Reader(bag) as reader, Writer(moved, version=9) as writer:
        conns = {c.id: writer.add_connection(
            "/tracker/people" if c.topic == PEOPLE_TOPIC else c.topic, c.msgtype, typestore=ts)
            for c in reader.connections}
        for conn, t_ns, raw in reader.messages():
            writer.write(conns[conn.id], t_ns, bytes(raw))
    m = _row(moved, topic_map=TopicMap(people="/tracker/people"))
    bodies = ROBOT_RADIUS_M + PERSON_RADIUS_M
    assert m["people_dist_min_m"] == pytest.approx(1.0 - bodies, abs=1e-9)
    assert m["personal_intrusion_count"] == 1.0
    assert m["intimate_intrusion_count"] == 0.0
    assert m["personal_intrusion_time_s"] == pytest.approx(_chord_s(1.0, 1.2 + bodies, 1.0),
                                                           abs=0.01)
    assert math.isnan(_row(moved)["people_dist_min_m"])  # the default topic is not there


def test_time_to_collision_of_discs() -> None:
    rel = np.array([[3.0, 0.0], [0.0, 2.0], [0.2, 0.0], [3.0, 1.0]])
    vel = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, 0.0], [-1.0, 0.0]])
    tau = time_to_collision(rel, vel, 0.5)
    assert tau[0] == pytest.approx(2.5) and tau[1] == math.inf and tau[2] == 0.0
    assert tau[3] == math.inf  # passes 1 m off: the discs never touch


def test_compute_shows_the_social_columns_only_for_bags_with_people(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    robot = straight_line(1.0, 10.0, 0.02, start=(-5.0, 0.0, 0.0))
    crowd = write_episode_bag(tmp_path / "crowd", robot, people=[standing(0, 1, 10.0, 0.02)],
                              facts=FACTS)
    assert main(["compute", str(crowd)]) == 0
    out = capsys.readouterr().out
    assert "personal zone" in out and "min person" in out and "people coll." in out
    assert f"{_chord_s(1.0, 1.2 + BODIES_M, 1.0):.2f}" in out
    plain = write_episode_bag(tmp_path / "plain", robot, facts=FACTS)
    assert main(["compute", str(plain)]) == 0
    assert "personal zone" not in capsys.readouterr().out
