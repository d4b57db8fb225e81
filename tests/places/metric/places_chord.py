"""A user's metric, written outside pic4rl: the chord of the episode (the straight distance
from its first pose to its last), placed in the paper's table after pic4rl's columns. Its one
file is the whole piece: ``@metric`` registers it when the user's program imports it
(``tests/places/test_places.py`` holds that it takes one file and reaches the table)."""

import math

from pic4rl_metrics import metric


@metric("chord_m", unit="m", label="chord", needs=("pose",), table=("paper", 99))
def chord(d):
    """Straight distance (m) from the first pose to the last."""
    return math.hypot(d.pose.x[-1] - d.pose.x[0], d.pose.y[-1] - d.pose.y[0])
