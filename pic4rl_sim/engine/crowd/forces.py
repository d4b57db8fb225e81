"""The social force model's equations, vectorised over the crowd (numpy, no state).

Helbing & Molnár, "Social force model for pedestrian dynamics", Phys. Rev. E 51 (1995):

- driving: ``(v0 e - v) / tau``, relaxation to the desired velocity (``TAU_S`` 0.5 s);
- another walker b: ``-grad V(b)`` with ``V(b) = V0 exp(-b / sigma)`` (``V0`` 2.1 m²/s²,
  ``sigma`` 0.3 m) and ``b`` the semi-minor axis of the ellipse through a's position with foci
  at b's position and b's next step (``STEP_TIME_S`` 2 s): ``2b = sqrt((|r| + |r - s|)² -
  |s|²)``, ``s = v_b dt``. The paper's walkers are points; here ``r`` runs between the two
  bodies' surfaces (the centres' vector shortened by both radii), so a wide robot is kept
  off as far as a person is;
- walls: ``(U0 / R) exp(-d / R)`` away from each obstacle's nearest point at centre distance
  ``d`` (``U0`` 10 m²/s², ``R`` 0.2 m);
- field of view: a force whose source is behind (outside ``2 phi`` = 200° round the
  desired direction) weighs ``C`` = 0.5;
- speed capped at ``MAX_SPEED_FACTOR`` (1.3) times the desired one.

Groups, Moussaïd et al., "The walking behaviour of pedestrian social groups", PLoS ONE 5
(2010): attraction ``beta2 U_i`` towards the others' centre of mass beyond ``(n - 1) / 2`` m,
repulsion ``beta3 n_ik`` between members that overlap (surfaces closer than
``GROUP_GAP_M``), and the gaze term ``-beta1 alpha v`` with ``alpha`` the angle by which the
centre of mass lies outside the 90° half field of view. Forces are per unit mass (m/s²).
"""

from __future__ import annotations

import math

import numpy as np

TAU_S = 0.5
V0_M2_S2 = 2.1
SIGMA_M = 0.3
STEP_TIME_S = 2.0
U0_M2_S2 = 10.0
R_M = 0.2
PHI_RAD = math.radians(100.0)
BEHIND_WEIGHT = 0.5
MAX_SPEED_FACTOR = 1.3
GAZE_BETA = 4.0
ATTRACTION_BETA = 3.0
GROUP_REPULSION_BETA = 1.0
GROUP_GAP_M = 0.1
GAZE_HALF_FOV_RAD = math.radians(90.0)
MIN_GAP_M = 0.01  # the surfaces' distance that overlapping bodies are given
_EPS = 1e-9


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``v`` (…, 2) normalised along its last axis, and the norms (0-vectors stay 0)."""
    norm = np.hypot(v[..., 0], v[..., 1])
    return v / np.maximum(norm, _EPS)[..., None], norm


def driving(velocity: np.ndarray, direction: np.ndarray, speed: np.ndarray,
            tau_s: float = TAU_S) -> np.ndarray:
    """Relaxation to the desired velocity: ``(v0 e - v) / tau`` (n × 2)."""
    return (speed[:, None] * direction - velocity) / tau_s


def semi_minor_axis(r: np.ndarray, step: np.ndarray) -> np.ndarray:
    """``b`` of the 1995 paper for vectors ``r`` (from b to a) and steps ``s`` (…, 2)."""
    r_len = np.hypot(r[..., 0], r[..., 1])
    rs_len = np.hypot(r[..., 0] - step[..., 0], r[..., 1] - step[..., 1])
    s_len = np.hypot(step[..., 0], step[..., 1])
    return 0.5 * np.sqrt(np.maximum((r_len + rs_len) ** 2 - s_len**2, _EPS))


def potential(r: np.ndarray, step: np.ndarray) -> np.ndarray:
    """``V(b) = V0 exp(-b / sigma)`` (m²/s²), whose negative gradient is ``pair_forces``."""
    return V0_M2_S2 * np.exp(-semi_minor_axis(r, step) / SIGMA_M)


def pair_forces(r: np.ndarray, step: np.ndarray) -> np.ndarray:
    """``-grad_r V(b(r, s))`` (…, 2) for the vectors ``r`` from b to a and b's steps ``s``."""
    b = semi_minor_axis(r, step)
    r_hat, r_len = _unit(r)
    rs_hat, rs_len = _unit(r - step)
    scale = (V0_M2_S2 / SIGMA_M) * np.exp(-b / SIGMA_M) * (r_len + rs_len) / (4.0 * b)
    return scale[..., None] * (r_hat + rs_hat)


def surface_vectors(pos: np.ndarray, radius: np.ndarray, others: np.ndarray,
                    other_radius: np.ndarray) -> np.ndarray:
    """Vectors (n × m × 2) from each other body's surface to each body's surface along the
    line of centres (the centres' vector shortened by both radii); bodies that overlap keep
    ``MIN_GAP_M`` along that line, so they are pushed apart, never lose the direction."""
    r = pos[:, None, :] - others[None, :, :]
    r_hat, r_len = _unit(r)
    gap = np.maximum(r_len - radius[:, None] - other_radius[None, :], MIN_GAP_M)
    return r_hat * gap[..., None]


def field_of_view(direction: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Weights (n × m): 1 for a force whose source is seen in front, else ``BEHIND_WEIGHT``.

    The paper's ``w(e, f)`` weighs "situations in the desired direction of motion" more; a
    repulsion points away from its source, so the source lies along ``-f`` and is seen when
    ``e · (-f) >= |f| cos phi`` (as ``pysocialforce`` calls it, with ``-f_ab``). A walker
    ahead pushes back and weighs 1; one behind pushes forward and weighs ``BEHIND_WEIGHT``."""
    seen = -np.einsum("nk,nmk->nm", direction, forces) >= (
        np.hypot(forces[..., 0], forces[..., 1]) * math.cos(PHI_RAD))
    return np.where(seen, 1.0, BEHIND_WEIGHT)


def wall_forces(away: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """Sum over obstacles (n × 2) of ``(U0 / R) exp(-d / R)`` along ``away`` (n × k × 2,
    unit vectors from each obstacle's nearest point), ``distance`` (n × k, m)."""
    magnitude = (U0_M2_S2 / R_M) * np.exp(-distance / R_M)
    return (magnitude[..., None] * away).sum(axis=1)


def group_forces(pos: np.ndarray, velocity: np.ndarray, radius: float,
                 group: np.ndarray) -> np.ndarray:
    """Moussaïd's three group forces (n × 2) for people with group labels ``group`` (n);
    a group of one feels none."""
    n = len(pos)
    same = (group[:, None] == group[None, :]) & ~np.eye(n, dtype=bool)
    size = same.sum(axis=1)
    force = np.zeros_like(pos)
    if not size.any():
        return force
    others = np.where(size[:, None] > 0, (same @ pos) / np.maximum(size, 1)[:, None], pos)
    to_com, com_dist = _unit(others - pos)
    attract = (size > 0) & (com_dist > size / 2.0)  # (n_group - 1) / 2 with n_group = size + 1
    force += ATTRACTION_BETA * attract[:, None] * to_com
    heading, speed = _unit(velocity)
    angle = np.arccos(np.clip(np.einsum("nk,nk->n", heading, to_com), -1.0, 1.0))
    alpha = np.where((size > 0) & (speed > _EPS), np.maximum(angle - GAZE_HALF_FOV_RAD, 0.0), 0)
    force -= GAZE_BETA * alpha[:, None] * velocity
    r = pos[:, None, :] - pos[None, :, :]
    r_hat, r_len = _unit(r)
    overlap = same & (r_len - 2 * radius < GROUP_GAP_M)
    force += GROUP_REPULSION_BETA * (overlap[..., None] * r_hat).sum(axis=1)
    return force


def cap_speed(velocity: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """``velocity`` (n × 2) with each norm capped at ``MAX_SPEED_FACTOR`` × its desired speed."""
    _, norm = _unit(velocity)
    cap = MAX_SPEED_FACTOR * speed
    return velocity * np.minimum(1.0, cap / np.maximum(norm, _EPS))[:, None]
