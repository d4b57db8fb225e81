"""Moving obstacles (``WorldSpec.moving``, the ``dynbarn`` world): cylinders on smooth random
trajectories, stepped like the crowd as mocap bodies that the ray casts see and the robot
touches, but blind to everything: no forces, they pass through the static field and each other.

Each obstacle keeps its speed and turn rate as two Ornstein-Uhlenbeck processes of correlation
time ``turn_time_s`` (sampled exactly at each step: ``x' = m + (x - m) e^(-dt/T) + s sqrt(1 -
e^(-2dt/T)) N``): the turn rate about 0 with a standard deviation of one radian per
``turn_time_s``, the speed about the obstacle's mean with a tenth of the speed range, reflected
into the range. Heading and position integrate them, so a trajectory has no corners but at the
field's edge, where it bounces like light off a mirror. The draws come from a stream seeded by
the world's variant and the episode's seed: the same scene and seed give the same motion.
"""

from __future__ import annotations

import math

import numpy as np

from ..worlds.spec import MovingObstacles

MAX_DT_S = 0.05  # the integration step, at most
SPEED_STD_FRACTION = 0.1  # the speeds' standard deviation, a fraction of the speed range
TURN_STD_RAD = 1.0  # the turn rate's standard deviation times turn_time_s


def _reflect(value: np.ndarray, lo: float | np.ndarray,
             hi: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``value`` folded into [lo, hi] (one fold: steps are short), and where it was folded."""
    below, above = value < lo, value > hi
    return np.where(below, 2 * lo - value, np.where(above, 2 * hi - value, value)), below | above


class Movers:
    """The obstacles of ``moving``, whose mocap bodies are ``mocap`` (in the same order)."""

    def __init__(self, moving: MovingObstacles, mocap: tuple[int, ...]) -> None:
        self.moving, self.mocap = moving, list(mocap)
        n = len(moving.starts)
        self.pos = np.zeros((n, 2))
        self.heading = np.zeros(n)
        self.speed = np.zeros(n)
        self._turn = np.zeros(n)
        self._rng = np.random.default_rng(0)

    @property
    def velocity(self) -> np.ndarray:
        """World velocities (n × 2, m/s)."""
        return self.speed[:, None] * np.column_stack((np.cos(self.heading), np.sin(self.heading)))

    def place(self, data: object, world_seed: int, episode_seed: int) -> None:
        """Back to their starts, headings and mean speeds, not turning, with the random stream
        of (``world_seed``, ``episode_seed``); their mocap bodies in ``data`` put there."""
        m = self.moving
        self._rng = np.random.default_rng([world_seed, episode_seed])
        self.pos = np.array(m.starts, dtype=float).reshape(-1, 2)
        self.heading = np.array(m.headings_rad, dtype=float)
        self.speed = np.array(m.speeds_m_s, dtype=float)
        self._turn = np.zeros(len(self.pos))
        data.mocap_pos[self.mocap, :2] = self.pos  # type: ignore[attr-defined]

    def advance(self, duration_s: float) -> None:
        """Move ``duration_s`` in steps of at most ``MAX_DT_S``."""
        steps = max(1, math.ceil(duration_s / MAX_DT_S - 1e-9))
        for _ in range(steps):
            self._integrate(duration_s / steps)

    def walk(self, data: object, duration_s: float,
             substeps: int) -> tuple[list[int], np.ndarray, np.ndarray]:
        """The engine's walk over one control period of ``duration_s``: the mocap indices,
        their positions in ``data`` now and their change per substep (straight within it)."""
        start = data.mocap_pos[self.mocap].copy()  # type: ignore[attr-defined]
        self.advance(duration_s)
        end = np.column_stack((self.pos, np.zeros(len(self.pos))))
        return self.mocap, start, (end - start) / substeps

    def _integrate(self, dt: float) -> None:
        m, n = self.moving, len(self.pos)
        decay = math.exp(-dt / m.turn_time_s)
        spread = math.sqrt(1.0 - decay**2)
        lo, hi = m.speed_range_m_s
        mean = np.array(m.speeds_m_s)
        noise = self._rng.standard_normal((2, n))
        turn_std = TURN_STD_RAD / m.turn_time_s
        self._turn = self._turn * decay + turn_std * spread * noise[0]
        speed_std = SPEED_STD_FRACTION * (hi - lo)
        speed = mean + (self.speed - mean) * decay + speed_std * spread * noise[1]
        self.speed = np.clip(_reflect(speed, lo, hi)[0], lo, hi)
        self.heading = self.heading + self._turn * dt
        xmin, ymin, xmax, ymax = m.field
        r = m.radius_m
        pos = self.pos + self.velocity * dt
        x, off_x = _reflect(pos[:, 0], xmin + r, xmax - r)
        y, off_y = _reflect(pos[:, 1], ymin + r, ymax - r)
        self.pos = np.column_stack((np.clip(x, xmin + r, xmax - r), np.clip(y, ymin + r, ymax - r)))
        self.heading = np.where(off_x, math.pi - self.heading, self.heading)
        self.heading = np.where(off_y, -self.heading, self.heading)
        self._turn = np.where(off_x ^ off_y, -self._turn, self._turn)
        self.heading = np.arctan2(np.sin(self.heading), np.cos(self.heading))
