"""goToPose toward a UWB tag through both transports (issue 40): the sim node of
``config/env_goto_uwb.yaml`` (four anchors on the robot, dropouts raised to 20 %) publishes each
anchor's range to the goal's tag on ``uwb/a<i>``; the bridge over ROS 2 makes the same observations,
the goal part's estimate and its dropout mask included, as the in-process engine for one seed and
one command sequence."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pic4rl_bridge.recording import make_env

CONFIG = Path(__file__).resolve().parents[2] / "config" / "env_goto_uwb.yaml"
DROPOUT = 0.2


def _observations(env) -> list[np.ndarray]:
    """The observations of one 15-step seeded episode under fixed random commands."""
    rng = np.random.default_rng(8)
    try:
        obs, _ = env.reset(seed=21)
        seen = [obs]
        for _ in range(15):
            obs, _, terminated, truncated, _ = env.step(
                rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            seen.append(obs)
            if terminated or truncated:
                break
        return seen
    finally:
        env.close()


def test_the_tags_goal_part_is_the_same_through_both_transports(domain: int,
                                                                 start_sim) -> None:
    start_sim(domain, "--params-file", str(CONFIG), "-p", f"uwb.dropout_prob:={DROPOUT}")
    overrides = {"episode_max_steps": 15}
    ros = _observations(make_env(CONFIG, transport="ros",
                                 overrides={**overrides, "ros.domain_id": domain}))
    local = _observations(make_env(CONFIG, overrides=overrides,
                                   sim={"uwb.dropout_prob": DROPOUT}))
    assert len(ros) == len(local) >= 10
    for i, (a, b) in enumerate(zip(ros, local)):
        np.testing.assert_array_equal(a, b, err_msg=f"observations differ at step {i}")
    masks = np.stack(ros)[:, 38:42]
    assert (masks == 0).any() and (masks == 1).mean() > 0.6  # dropouts seen, most received
