"""A learned frontier choice for the explore task (issue 42): PPO picks the frontier explorer's
next target among its candidates (``pic4rl_bridge.baselines.frontier_choice``).

``FrontierChoiceEnv`` is the decision-level env: it wraps an explore env (any transport; its
bags are recorded as every env's), and one of its steps is one choice: the ``ChoosingExplorer``
drives to the candidate chosen, a control step at a time, until its next target is due (the
explorer's arrival rule) or the episode ends. Its observation is the candidates' features, its
action the candidate's index (``Discrete(CHOICES)``; one beyond those offered: the nearest),
its reward the explore task's over those control steps (the area newly seen, the time cost
``reward.step`` per step, the collision's), so its return is the area seen less the time
taken. PPO (SB3) learns it; its action head starts biased to the first candidate, the nearest,
so the untrained policy is close to Yamauchi's explorer.

``FrontierPPO`` is the trained policy as a policy plugin (``pic4rl_bridge.control.plugin``):
``pic4rl-test --agent pic4rl_agents.training.frontier_choice:FrontierPPO`` and a suite's
``agents:`` entry run it on any explore env, through ROS 2 or in process.

    python -m pic4rl_agents.training.frontier_choice --minutes 50 --out runs/explore_frontier_ppo
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from pic4rl_bridge.baselines.frontier_choice import CHOICES, OBSERVATION_SIZE, ChoosingExplorer
from pic4rl_bridge.control.actions import normalized_action
from pic4rl_bridge.control.plugin import Policy, RobotInfo, SensorFrame, TaskInfo
from pic4rl_bridge.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]  # the checkout's
#: The shipped policy and the env it trains in.
CHECKPOINT = ROOT / "checkpoints" / "explore_frontier_ppo"
RUN = Path("runs") / "explore_frontier_ppo"  # the training's default folder
ENV_CONFIG = str(ROOT / "config" / "env_explore_rooms.yaml")
#: Layouts the training draws from (the rooms family's 0-999 less the validation ones) and
#: the validation layouts its summary reports; the test layouts 1000-1019 no run draws.
TRAIN_VARIANTS, VALIDATION_VARIANTS = "0:900", (900, 910)
FIRST_BIAS = 2.0  # the action head's bias toward the nearest candidate at the start
#: The time cost: the training env's ``reward.step`` (per 0.1 s step; 1 per s against 1 per m²).
TIME_COST = {"reward.step": -0.1}


class FrontierChoiceEnv(gym.Env):
    """The decision-level explore env (see the module's docstring) over ``env`` (an explore
    ``NavEnv``, possibly wrapped)."""

    def __init__(self, env: gym.Env) -> None:
        self.env = env
        self.nav = env.unwrapped
        self.explorer = ChoosingExplorer(self.nav.scenario.robot)
        self.observation_space = gym.spaces.Box(-1.0, 1.0, (OBSERVATION_SIZE,), np.float32)
        self.action_space = gym.spaces.Discrete(CHOICES)

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        _, info = self.env.reset(seed=seed, options=options)
        self.explorer.reset()
        observation = self.explorer.due(self.nav.frame)
        assert observation is not None  # no target yet: one is due
        return observation, info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        robot, choice, total, steps = self.nav.scenario.robot, int(action), 0.0, 0
        while True:
            v, w = self.explorer.drive(self.nav.frame, choice)
            _, reward, terminated, truncated, info = self.env.step(normalized_action(robot, v, w))
            total, steps, choice = total + float(reward), steps + 1, None
            if terminated or truncated:
                info = {**info, "control_steps": steps}
                return self.explorer.offer(self.nav.frame)[1], total, terminated, truncated, info
            observation = self.explorer.due(self.nav.frame)
            if observation is not None and self.explorer.candidates:
                return observation, total, False, False, {**info, "control_steps": steps}
            if observation is not None:
                choice = 0  # nothing to choose from: the explorer waits and looks again

    def close(self) -> None:
        self.env.close()


def make_choice_env(config: str = ENV_CONFIG, variants: str = TRAIN_VARIANTS,
                    **overrides: Any) -> FrontierChoiceEnv:
    """A ``FrontierChoiceEnv`` over ``pic4rl/ExploreLidar-v0`` with ``config``, drawing its
    layouts from ``variants``."""
    import pic4rl_bridge  # noqa: F401  (registers the envs)

    env = gym.make("pic4rl/ExploreLidar-v0", config=config,
                   overrides={"episodes.world_variants": variants, **TIME_COST, **overrides})
    return FrontierChoiceEnv(env)


class FrontierPPO(Policy):
    """The trained frontier choice (``CHECKPOINT``'s ``model.zip``) driving the frontier
    explorer: each frame integrated, a candidate chosen when a new target is due."""

    observes = "frame"
    acts = "velocity"
    name = "frontier_ppo"
    checkpoint = CHECKPOINT

    def __init__(self) -> None:
        self.zip_path = Path(self.checkpoint) / "model.zip"
        if not self.zip_path.is_file():
            raise ConfigError(f"{type(self).__name__}: no such file {self.zip_path}")
        self.model: Any = None
        self.explorer: ChoosingExplorer | None = None

    def reset(self, robot: RobotInfo, task: TaskInfo) -> None:
        if task.name != "explore":
            raise ConfigError(f"{self.name}: drives the explore task, not {task.name}")
        if self.model is None:
            # loaded where it drives: a suite checks the plugin in its parent and forks
            # workers, and torch's threads started in a parent deadlock a forked child
            import torch
            from stable_baselines3 import PPO

            torch.set_num_threads(1)
            self.model = PPO.load(self.zip_path, device="cpu")
        self.explorer = ChoosingExplorer(robot)

    def act(self, frame: SensorFrame) -> tuple[float, float]:
        assert self.explorer is not None
        observation = self.explorer.due(frame)
        choice = None
        if observation is not None:
            choice = int(self.model.predict(observation, deterministic=True)[0])
        return self.explorer.drive(frame, choice)


def _episode(model: Any, variant: int) -> dict[str, Any]:
    """One validation episode on ``variant`` (start from seed ``variant``), the greedy choice."""
    env = make_choice_env(variants=f"{variant}:{variant + 1}")
    observation, _ = env.reset(seed=variant)
    done, steps, info = False, 0, {}
    while not done:
        action = int(model.predict(observation, deterministic=True)[0])
        observation, _, terminated, truncated, info = env.step(action)
        steps += info["control_steps"]
        done = terminated or truncated
    context = env.nav._context.extra
    env.close()
    outcome = info.get("outcome")
    return {"variant": variant, "outcome": str(getattr(outcome, "value", outcome)), "steps": steps,
            "coverage": context["seen"].grid.area_m2 / context["free_area_m2"]}


def save_curve(run: Path, out: Path, window: int = 10) -> Path | None:
    """Write ``out`` (PNG): the episodes' return and the share that reached the coverage
    target (moving averages over ``window`` episodes) against training wall-clock and
    decisions, from ``run``'s monitor CSVs; ``None`` before the first finished episode."""
    from pic4rl_agents.training.curves import episode_table

    df = episode_table(run)
    if df.empty:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = {"training wall-clock (min)": df["t"] / 60.0, "decisions": df["l"].cumsum()}
    ys = {"episode return": df["r"],
          "reached 90 % coverage": df["is_success"].astype(str).eq("True").astype(float)}
    fig, axes = plt.subplots(2, 2, figsize=(9, 5), layout="constrained", sharey="row")
    for col, (xlabel, xs) in enumerate(x.items()):
        for row, (ylabel, y) in enumerate(ys.items()):
            ax = axes[row, col]
            ax.plot(xs, y, ".", alpha=0.35, ms=4)
            ax.plot(xs, y.rolling(window, min_periods=1).mean(), lw=2,
                    label=f"moving average ({window} episodes)")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize="small")
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def new_model(env: Any, seed: int = 0) -> Any:
    """The untrained PPO on ``env`` (a decision-level env or a vector of them), its action
    head biased by ``FIRST_BIAS`` to the first candidate, the nearest."""
    import torch
    from stable_baselines3 import PPO

    model = PPO("MlpPolicy", env, n_steps=128, batch_size=64, n_epochs=10, gamma=0.99,
                learning_rate=3e-4, ent_coef=0.01, seed=seed, device="cpu",
                policy_kwargs={"net_arch": [64, 64]})
    with torch.no_grad():
        model.policy.action_net.bias[0] += FIRST_BIAS
    return model


def train(out: Path, *, minutes: float, n_envs: int, seed: int,
          validation: int = 10) -> dict[str, Any]:
    """Train PPO for ``minutes`` of wall-clock on ``n_envs`` processes; save ``out``/model.zip,
    the monitor files, ``curve.png`` (``save_curve``) and ``summary.json`` (with
    ``validation`` episodes, on the first layouts of ``VALIDATION_VARIANTS``). ``out`` must be
    new or empty: nothing a run recorded is overwritten, nor two runs' monitors mixed."""
    import torch
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv

    if out.is_dir() and any(out.iterdir()):
        raise ConfigError(f"--out {out}: not empty; a training run writes into a new folder")
    torch.set_num_threads(1)
    out.mkdir(parents=True, exist_ok=True)
    vec = make_vec_env(make_choice_env, n_envs=n_envs, seed=seed, monitor_dir=str(out),
                       vec_env_cls=SubprocVecEnv if n_envs > 1 else None,
                       monitor_kwargs={"info_keywords": ("is_success",)})
    model = new_model(vec, seed)
    deadline, began = time.monotonic() + 60.0 * minutes, time.monotonic()

    class _Clock(BaseCallback):
        def _on_step(self) -> bool:
            for info in self.locals["infos"]:
                if "episode" in info:
                    print(f"[{(time.monotonic() - began) / 60:5.1f} min] decisions "
                          f"{self.num_timesteps}: episode return {info['episode']['r']:.1f}, "
                          f"success {info.get('is_success')}", flush=True)
            return time.monotonic() < deadline

    model.learn(total_timesteps=10**9, callback=_Clock())
    vec.close()
    model.save(out / "model.zip")
    save_curve(out, out / "curve.png")
    summary = {"wall_min": (time.monotonic() - began) / 60, "decisions": model.num_timesteps,
               "validation": [_episode(model, v) for v in range(VALIDATION_VARIANTS[0],
                                                    VALIDATION_VARIANTS[0] + validation)]}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m pic4rl_agents.training.frontier_choice",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=RUN,
                        help="a new folder (the shipped policy is CHECKPOINT's model.zip)")
    parser.add_argument("--minutes", type=float, default=40.0)
    parser.add_argument("--n-envs", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--validation", type=int, default=10,
                        help="validation episodes after training (layouts 900-909)")
    args = parser.parse_args(argv)
    try:
        summary = train(args.out, minutes=args.minutes, n_envs=args.n_envs, seed=args.seed,
                        validation=args.validation)
    except ConfigError as err:
        print(f"error: {err}")
        return 2
    reached = sum(e["coverage"] >= 0.9 for e in summary["validation"])
    print(f"validation: {reached}/{len(summary['validation'])} reached 90 %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
