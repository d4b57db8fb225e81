"""Moving obstacles tracked from the scan against a known map: what the ``predictive`` baseline
predicts. The returns the map does not explain (farther than ``static_m`` from every static
obstacle of the world) are the movers'; they are split into clusters where consecutive beams'
points lie more than ``gap_m`` apart (laser segmentation), and a cluster no wider than a
mover is one: its centre lies a mover's radius beyond its point nearest the sensor, on the
beam's line (a cylinder's nearest point faces the sensor). Detections are matched to the
tracks' predictions nearest first within ``gate_m``; each track's position and velocity follow
an alpha-beta filter; a track unseen for ``keep_s`` (hidden behind the field) is dropped, and
until then coasts at its velocity. A new track's velocity is unknown until it is seen again:
zero. Pure numpy; the same on a real robot with a map, given the movers' radius.

People come tracked already (the env's ``people`` reading: the crowd's topic, or a people
tracker's on a real robot): ``PeopleMotion`` gives their velocities by finite difference.
"""

from __future__ import annotations

import math

import numpy as np

from pic4rl_sim.engine.worlds.spec import WorldSpec

from ..readings.frame import SensorFrame
from .occupancy import to_world


def scan_clusters(points: np.ndarray, gap_m: float) -> list[np.ndarray]:
    """Indices of ``points`` (n × 2, in beam order) split where consecutive points lie more
    than ``gap_m`` apart."""
    if not len(points):
        return []
    breaks = np.flatnonzero(np.hypot(*np.diff(points, axis=0).T) > gap_m) + 1
    return np.split(np.arange(len(points)), breaks)


def fit_circle(points: np.ndarray, sensor: np.ndarray, radius_m: float) -> np.ndarray:
    """The centre of a circle of ``radius_m`` through ``points`` (k × 2) seen from ``sensor``:
    least squares (Gauss-Newton from a radius beyond the nearest point, on the beam's line)."""
    ray = points - sensor
    near = points[int(np.argmin(np.hypot(*ray.T)))]
    centre = near + radius_m * (near - sensor) / max(float(np.hypot(*(near - sensor))), 1e-9)
    for _ in range(5):
        rel = points - centre
        dist = np.maximum(np.hypot(*rel.T), 1e-9)
        jac = -rel / dist[:, None]
        step, *_ = np.linalg.lstsq(jac, -(dist - radius_m), rcond=None)
        centre = centre + step
    return centre


class MoverTracker:
    """Tracks of ``world``'s moving obstacles, discs of ``radius_m``, from each frame's scan."""

    def __init__(self, world: WorldSpec, radius_m: float, *, static_m: float = 0.06,
                 gap_m: float = 0.15, gate_m: float = 0.4, keep_s: float = 1.0,
                 alpha: float = 0.6, beta: float = 0.3, top_speed_m_s: float = math.inf) -> None:
        self.world, self.radius_m, self.top_speed_m_s = world, radius_m, top_speed_m_s
        self.static_m, self.gap_m, self.gate_m, self.keep_s = static_m, gap_m, gate_m, keep_s
        self.alpha, self.beta = alpha, beta
        self.reset()

    def reset(self) -> None:
        """Forget every track."""
        self.pos = np.empty((0, 2))  # (n, 2) m, world frame
        self.vel = np.empty((0, 2))  # (n, 2) m/s
        self._seen_ns = np.empty(0, dtype=np.int64)  # each track's last detection
        self._stamp_ns: int | None = None

    def detect(self, frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
        """The movers' centres seen in ``frame`` (k × 2, world frame) and which of the scan's
        points (``frame.scan.points()`` order) are theirs."""
        if frame.scan is None:
            return np.empty((0, 2)), np.zeros(0, dtype=bool)
        local = frame.scan.points()
        world = to_world(local, frame.pose)
        moving = self.world.clearance(world) > self.static_m if len(world) else np.zeros(0, bool)
        idx = np.flatnonzero(moving)
        mount = frame.scan.mount
        sensor = to_world(np.array([[mount.x, mount.y]]), frame.pose)[0]
        centres, theirs = [], np.zeros(len(world), dtype=bool)
        for cluster in scan_clusters(world[idx], self.gap_m):
            pts = world[idx[cluster]]
            if np.hypot(*(pts.max(axis=0) - pts.min(axis=0))) > 2.0 * self.radius_m + self.gap_m:
                continue  # wider than a mover: left to the scan's static points
            centres.append(fit_circle(pts, sensor, self.radius_m))
            theirs[idx[cluster]] = True
        return np.asarray(centres, dtype=float).reshape(-1, 2), theirs

    def update(self, frame: SensorFrame) -> np.ndarray:
        """The tracks after ``frame`` (their ``pos`` and ``vel``); returns which of the scan's
        points are the movers' (the rest are the static field's)."""
        centres, theirs = self.detect(frame)
        stamp = frame.stamp_ns
        dt = 0.0 if self._stamp_ns is None else max(0.0, (stamp - self._stamp_ns) * 1e-9)
        self._stamp_ns = stamp
        predicted = self.pos + self.vel * dt
        matched_track = np.zeros(len(predicted), dtype=bool)
        matched_det = np.zeros(len(centres), dtype=bool)
        if len(predicted) and len(centres):
            gap = np.hypot(*(centres[:, None, :] - predicted[None, :, :]).transpose(2, 0, 1))
            for flat in np.argsort(gap, axis=None):
                d, t = divmod(int(flat), len(predicted))
                if gap[d, t] > self.gate_m:
                    break
                if matched_det[d] or matched_track[t]:
                    continue
                matched_det[d] = matched_track[t] = True
                residual = centres[d] - predicted[t]
                predicted[t] = predicted[t] + self.alpha * residual
                if dt > 0:
                    vel = self.vel[t] + self.beta * residual / dt
                    speed = float(np.hypot(*vel))  # no faster than a mover can be
                    self.vel[t] = vel * min(1.0, self.top_speed_m_s / max(speed, 1e-9))
                self._seen_ns[t] = stamp
        alive = (stamp - self._seen_ns) * 1e-9 <= self.keep_s
        new = centres[~matched_det]
        self.pos = np.vstack((predicted[alive], new))
        self.vel = np.vstack((self.vel[alive], np.zeros_like(new)))
        self._seen_ns = np.concatenate((self._seen_ns[alive],
                                        np.full(len(new), stamp, dtype=np.int64)))
        return theirs

    def predict(self, times_s: np.ndarray) -> np.ndarray:
        """The tracks' positions at ``times_s`` from now at constant velocity (K × n × 2)."""
        return self.pos[None, :, :] + np.asarray(times_s)[:, None, None] * self.vel[None, :, :]


class PeopleMotion:
    """The ``people`` reading's positions and velocities: each velocity the difference of a
    person's positions over the last two frames' stamps, the array's order their identity
    (zero at first, or when the crowd's size changed)."""

    def __init__(self) -> None:
        self._last: tuple[int, np.ndarray] | None = None

    def reset(self) -> None:
        """Forget the people seen: their velocities start again from zero."""
        self._last = None

    def update(self, frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
        """The people's positions (n × 2, world frame) and velocities (n × 2, m/s) in
        ``frame`` (none without a ``people`` reading)."""
        people = frame.readings.get("people")
        xy = np.empty((0, 2)) if people is None else np.asarray(people, dtype=float)[:, :2]
        velocity = np.zeros_like(xy)
        if self._last is not None and self._last[1].shape == xy.shape:
            dt_s = (frame.stamp_ns - self._last[0]) * 1e-9
            if dt_s > 0.0:
                velocity = (xy - self._last[1]) / dt_s
        self._last = (frame.stamp_ns, xy)
        return xy, velocity
