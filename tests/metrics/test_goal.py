"""``Goal``: the position a pair every reader indexes, the heading beside it, and both through
pickling (vector envs), equality and the facts' list form."""

from __future__ import annotations

import pickle

import numpy as np

from pic4rl_base.goal import Goal


def test_a_goal_is_its_position_pair_and_keeps_its_heading() -> None:
    goal = Goal(1, 2.5)
    x, y = goal
    assert (x, y) == (1.0, 2.5) and goal.x == 1.0 and goal.y == 2.5 and goal.yaw is None
    assert goal == (1.0, 2.5) and (1.0, 2.5) == goal
    assert np.asarray(goal).tolist() == [1.0, 2.5]
    docking = Goal(1.0, 2.5, -0.5)
    assert docking != goal and docking != (1.0, 2.5) and docking.as_list() == [1.0, 2.5, -0.5]
    assert goal.as_list() == [1.0, 2.5]


def test_of_a_pair_a_triple_or_a_goal() -> None:
    assert Goal.of((3, 4)) == Goal(3.0, 4.0)
    assert Goal.of([3, 4, 1.0]).yaw == 1.0
    goal = Goal(1.0, 2.0, 0.25)
    assert Goal.of(goal) is goal


def test_a_goal_survives_pickling_with_its_heading() -> None:
    for goal in (Goal(1.0, 2.0), Goal(1.0, 2.0, 0.3)):
        back = pickle.loads(pickle.dumps(goal))
        assert type(back) is Goal and back == goal and back.yaw == goal.yaw
