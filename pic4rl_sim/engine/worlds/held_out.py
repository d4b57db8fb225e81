"""The benchmarks' held-out test worlds, by generator, in one table: nothing is trained or
chosen on them (``pic4rl_agents.training.envs.check_no_test_world`` refuses a training or
evaluation env whose world variants hold one; a test env runs them)."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

from .barn import challenge_test_worlds
from .dynbarn import TEST_SCENES
from .rooms import TEST_LAYOUTS


class HeldOut(NamedTuple):
    """A benchmark's test worlds: its name, their ``world_variant``s, and what to train on."""

    name: str
    variants: Callable[[], tuple[int, ...]]
    instead: str


#: Each generator's held-out test worlds (its ``world_variant``s), by the generator's kind.
HELD_OUT: dict[str, HeldOut] = {
    "barn": HeldOut("BARN", challenge_test_worlds, "train and evaluate on the 250 others (the "
                    "test worlds are 0, 6, ..., 294)"),
    "dynbarn": HeldOut("dynamic BARN", lambda: TEST_SCENES, "train and evaluate on other "
                       "variants (the 60 test scenes are 0, 5, ..., 295)"),
    "rooms": HeldOut("rooms", lambda: TEST_LAYOUTS, "train and evaluate on layouts 0-999 (the "
                     "20 test layouts are 1000-1019)"),
}
