"""Who closed the gap: each episode's first contact with a person, from its bag alone.

For every bag with a people topic whose robot touched a person (the ``people collisions``
metric's contact: a body within the collision tolerance of the footprint), the person's
bearing in the robot's frame at that moment (0° ahead, ±180° behind), the robot's speed, and
the closing speed split into the robot's part (its speed along the line to the person; a
differential drive moves along its heading) and the person's (the rest). A person behind the
robot who closes faster than it drives walked into it; a robot driving at a person ahead
walked into them. The folders are the metrics CLI's: bag folders or folders of them.

    .venv/bin/python tools/crowd_contacts.py bags/crowd/crowd-planner-*/planner bags/crowd/crowd-dwa-*/dwa
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pic4rl_metrics.bags.inputs import discover
from pic4rl_metrics.bags.reader import read_episode
from pic4rl_metrics.core.derived import Derived
from pic4rl_metrics.core.tasks.crowd import crowd
from pic4rl_metrics.errors import MetricsError

BEHIND_DEG = 90.0


@dataclass(frozen=True)
class Contact:
    bag: str
    t_s: float  # since the episode's first pose
    bearing_deg: float  # the person in the robot's frame
    speed_mps: float  # the robot's
    robot_closing_mps: float
    person_closing_mps: float

    @property
    def behind(self) -> bool:
        return abs(self.bearing_deg) > BEHIND_DEG


def first_contact(bag: Path) -> Contact | None:
    """The episode's first contact with a person, or None (no people, no contact)."""
    d = Derived(read_episode(bag))
    c = crowd(d)
    if c is None:
        return None
    touching = np.nan_to_num(c.gap_m, nan=np.inf) < d.facts.collision_tolerance_m
    hits = np.argwhere(touching)
    if not len(hits):
        return None
    i, k = hits[0]
    to_person = c.rel[i, k] / np.linalg.norm(c.rel[i, k])
    closing = -float(np.dot(c.rel_vel[i, k], to_person))
    bearing = math.atan2(c.body[i, k, 1], c.body[i, k, 0])
    robot = float(c.speed_mps[i]) * math.cos(bearing)
    return Contact(str(bag), float(c.t_s[i] - d.t_s[0]), math.degrees(bearing),
                   float(c.speed_mps[i]), robot, closing - robot)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+")
    args = parser.parse_args(argv)
    found = discover(args.folders)
    for item, why in found.unmatched:
        print(f"{item}: {why}", file=sys.stderr)
    contacts, episodes = [], 0
    for bag in found.bags:
        try:
            contact = first_contact(bag)
        except MetricsError as err:  # one bad bag: said, and the batch goes on
            print(f"{bag}: {err}", file=sys.stderr)
            continue
        episodes += 1
        if contact is not None:
            contacts.append(contact)
            print(f"{contact.bag}: t {contact.t_s:5.1f} s, bearing {contact.bearing_deg:5.0f}°, "
                  f"speed {contact.speed_mps:.2f} m/s, closing: robot "
                  f"{contact.robot_closing_mps:5.2f} m/s, person "
                  f"{contact.person_closing_mps:5.2f} m/s")
    behind = sum(c.behind for c in contacts)
    faster = sum(c.person_closing_mps > c.robot_closing_mps for c in contacts)
    print(f"{episodes} episodes, {len(contacts)} with a contact: {behind} with the person behind "
          f"the robot (|bearing| > {BEHIND_DEG:g}°), {faster} with the person closing faster "
          "than the robot")
    return 0 if found.bags else 2


if __name__ == "__main__":
    sys.exit(main())
