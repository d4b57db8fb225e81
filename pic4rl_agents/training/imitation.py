"""Expert-guided training: behaviour cloning, then DAgger, on an SB3 off-policy model's actor.

The expert reads the env's decoded frame: the mapless explorer (``pic4rl_bridge.baselines.explorer``)
only what the student's sensors saw, one frame per step, so its choices depend on nothing the
student could not have remembered; the others are privileged at training time only: the
simulated world's map (``pic4rl_bridge.baselines.planner``) or the vineyard row's centre line
(``pic4rl_bridge.baselines.row_followers``) to label any state with the action it would take, while the student acts from its observation alone. Behaviour cloning regresses the actor
on states the expert drove through; DAgger (Ross, Gordon and Bagnell 2011) then lets the
student drive, has the expert label every state the student visits, aggregates the labels and
regresses again, so the student learns to recover from its own mistakes. The actor is the
same SB3 network that RL trains (the MLP on LiDAR, the CNN on depth), so the result is an SB3
model like any other, and RL fine-tunes it: imitation's transitions, with their rewards, stay
in the replay buffer, and the critic is warmed up on them with the actor frozen before RL
starts.

The `imitation` package does this for SB3 policies (``SimpleDAggerTrainer``) but pins
gymnasium 0.29 and SB3 2.2; this module writes the same loop on SB3's policy objects.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback, CallbackList
from stable_baselines3.common.utils import obs_as_tensor
from stable_baselines3.common.vec_env import VecEnv

from pic4rl_agents.runs.config import NODES, ImitationConfig
from pic4rl_base import params_file
from pic4rl_bridge.baselines.registry import Baseline
from pic4rl_bridge.baselines.registry import BASELINE_TABLE, EXPERT_BASELINES
from pic4rl_bridge.baselines.registry import make_expert as baseline_expert
from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.scenario import Scenario
from pic4rl_bridge.settings.baselines import BASELINES_NODE, BaselinesConfig, baselines_config
from pic4rl_bridge.settings.tasks import EXPERT_TASKS

from .callbacks import WallClockLimit
from .envs import set_driver
from .progress import ProgressCallback

log = logging.getLogger(__name__)

EXPERT, STUDENT = 0, 1  # who drove a labelled state
CUT_FIT_S = 30.0  # the longest fit of a round that a budget ended (``_fit_cut_round``)


#: The experts that label states, and the task each drives (each task's ``experts``).
EXPERTS = EXPERT_TASKS


def make_expert(name: str, env: EnvConfig | Scenario, settings: BaselinesConfig | None = None
                ) -> Baseline:
    """The expert ``name`` for envs of ``env``: the baseline that labels under it
    (``pic4rl_bridge.baselines.registry.EXPERT_BASELINES``: the planners on the world's map
    and the mapless explorer goToPose, ``dwa_heading`` personMonitoring, ``centerline``
    vineyard), with the env's action ranges and ``settings``, the ``baselines:`` section
    (defaults when ``None``). ``env``: its ``Scenario`` when resolved already, else its config."""
    given, settings = env, settings or BaselinesConfig()
    env = given.config if isinstance(given, Scenario) else given
    if name not in EXPERTS:
        raise ConfigError(f"imitation.expert: {name!r} is invalid; expected one of "
                          f"{', '.join(EXPERTS)}")
    if env.task != EXPERTS[name]:
        fits = [e for e, task in EXPERTS.items() if task == env.task]
        raise ConfigError(f"imitation.expert: {name} drives {EXPERTS[name]}; the env's task is "
                          f"{env.task!r}" + (f" (use {fits[0]})" if fits else ""))
    scenario = given if isinstance(given, Scenario) else Scenario(env)
    if name == "explorer" and env.goal_input == "explorer":  # the student's plan, the expert's
        theirs = dataclasses.replace(env.explorer, max_linear_m_s=settings.explorer.max_linear_m_s)
        if theirs != settings.explorer:
            raise ConfigError("imitation.expert: explorer plans with the baselines: section's "
                              f"explorer.* ({settings.explorer}), the env's goal_input explorer "
                              f"with nav_env's explorer.* ({env.explorer}); expected the same "
                              "plan settings (all but max_linear_m_s)")
    return baseline_expert(name, env, scenario.robot, scenario.world, settings)


@dataclass
class Demonstrations:
    """Aggregated labelled states: observations (an array, or a dict of arrays, batched along
    the first axis), the expert's actions and who drove (``EXPERT`` or ``STUDENT``)."""

    observations: list[Any] = field(default_factory=list)
    actions: list[np.ndarray] = field(default_factory=list)
    drivers: list[np.ndarray] = field(default_factory=list)
    _joined: tuple[Any, np.ndarray, np.ndarray] | None = field(default=None, repr=False)

    def add(self, obs: Any, actions: np.ndarray, driver: int) -> None:
        self.observations.append(copy.deepcopy(obs))
        self.actions.append(np.asarray(actions, dtype=np.float32))
        self.drivers.append(np.full(len(actions), driver, dtype=np.int8))
        self._joined = None

    def __len__(self) -> int:
        return sum(len(a) for a in self.actions)

    def arrays(self) -> tuple[Any, np.ndarray, np.ndarray]:
        """Everything so far as (observations, actions, drivers), concatenated (once per
        change: RL's cloning term regresses on the same labels again and again)."""
        if self._joined is None:
            first = self.observations[0]
            if isinstance(first, dict):
                obs: Any = {k: np.concatenate([o[k] for o in self.observations]) for k in first}
            else:
                obs = np.concatenate(self.observations)
            self._joined = (obs, np.concatenate(self.actions), np.concatenate(self.drivers))
        return self._joined


def actor_loss(model: Any, obs: Any, actions: torch.Tensor) -> torch.Tensor:
    """The regression loss of ``model``'s actor on (obs, expert actions): squared error of the
    deterministic action, and for a Gaussian actor (SAC, TQC) also the expert action's
    negative log-likelihood, so that its spread shrinks where the expert is consistent."""
    actor = model.actor
    if hasattr(actor, "get_action_dist_params"):
        mean, log_std, kwargs = actor.get_action_dist_params(obs)
        dist = actor.action_dist.proba_distribution(mean, log_std, **kwargs)
        nll = -dist.log_prob(actions.clamp(-0.999, 0.999)).mean() / actions.shape[1]
        return torch.mean((torch.tanh(mean) - actions) ** 2) + 0.01 * nll
    return torch.mean((actor(obs) - actions) ** 2)


class Imitation:
    """Behaviour cloning then DAgger on ``model`` (an SB3 off-policy model on ``env``), each
    env step counted in ``model.num_timesteps`` and passed to ``callback`` (evaluations,
    checkpoints, the clock); ``run`` returns False when a callback ended training or the
    steps reached ``max_steps``."""

    def __init__(self, config: ImitationConfig, env: VecEnv, env_config: EnvConfig | Scenario,
                 model: Any, callback: CallbackList, *, batch_size: int, seed: int = 0,
                 max_steps: int | None = None, sources: tuple[str, ...] = ()) -> None:
        self.config, self.env, self.model, self.callback = config, env, model, callback
        self.max_steps = max_steps
        section = params_file.load(sources, (BASELINES_NODE, *NODES))[BASELINES_NODE]  # experts'
        settings = baselines_config(section, where=" + ".join(sources))  # tuning, as baselines'
        # Resolved once, for every env's expert (the trainer's, when it hands it down).
        scenario = env_config if isinstance(env_config, Scenario) else Scenario(env_config)
        self.experts = [make_expert(config.expert, scenario, settings) for _ in range(env.num_envs)]
        # A map-aware expert drives each episode's world when the env draws one per episode.
        self._maps = (scenario, settings) if scenario.variants and BASELINE_TABLE[
            EXPERT_BASELINES[config.expert]].one_world else None
        self.data = Demonstrations()
        self.batch_size = batch_size
        self.rng = np.random.default_rng(seed)
        self.optimizer = torch.optim.Adam(model.actor.parameters(), lr=config.learning_rate)
        self._obs: Any = None
        self.losses: list[float] = []  # the mean regression loss of each round
        self._fitted = 0  # labelled states at the last fit
        self.refitted = False  # a budget ended a round, whose states were then fitted

    def run(self) -> bool:
        """Behaviour cloning, the DAgger rounds, then the critic's warm-up; False when a
        callback stopped it (the clock, an evaluation's target)."""
        c = self.config
        rounds = [(EXPERT, c.bc_steps, "cloning")] if c.bc_steps else []
        rounds += [(STUDENT, c.dagger_steps, f"DAgger round {k + 1}/{c.dagger_rounds}")
                   for k in range(c.dagger_rounds)]
        if rounds:
            self._show(rounds[0][2])  # before the bar opens
        self.callback.on_training_start(locals(), globals())
        try:
            for number, (driver, steps, phase) in enumerate(rounds):
                set_driver(self.env, "expert" if driver == EXPERT else "student")
                self._show(phase, log_it=True)
                if not self.collect(steps, driver):
                    self._fit_cut_round()
                    return False
                self.fit(c.gradient_steps)
                log.info("imitation round %d/%d (%s): %d labelled states, loss %.4f",
                         number + 1, len(rounds), "expert" if driver == EXPERT else "student",
                         len(self.data), self.losses[-1])
            self._show("critic warm-up", log_it=True)
            return self.warm_up_critic(c.critic_warmup_steps)
        finally:
            set_driver(self.env, "rl")  # what drives after imitation
            self.callback.on_training_end()

    def _show(self, phase: str, *, log_it: bool = False) -> None:
        """Name the phase now running (``cloning``, ``DAgger round k/n``, ``critic
        warm-up``) in the progress bar, and in the log when ``log_it``."""
        for callback in self.callback.callbacks:
            if isinstance(callback, ProgressCallback):
                callback.set_phase(phase)
        if log_it:
            log.info("imitation: %s", phase)

    def collect(self, steps: int, driver: int) -> bool:
        """Drive ``steps`` env steps (the expert or the student), labelling every state;
        False when a callback asked to stop or ``max_steps`` is reached."""
        env, model = self.env, self.model
        if self._obs is None:
            self._obs = env.reset()
            for i in range(env.num_envs):
                self._begin(i)
        for _ in range(max(1, steps // env.num_envs)):
            if self._out_of_steps():
                return False
            frames = env.get_attr("frame")
            labels = np.stack([e.action(f) for e, f in zip(self.experts, frames)])
            if driver == EXPERT:
                actions = labels
            else:
                actions, _ = model.predict(self._obs, deterministic=True)
            self.data.add(self._obs, labels, driver)
            new_obs, rewards, dones, infos = env.step(actions)
            if self.config.replay and getattr(model, "replay_buffer", None) is not None:
                model.replay_buffer.add(self._obs, _next_obs(new_obs, dones, infos), actions,
                                        rewards, dones, infos)
            for i in np.flatnonzero(dones):
                self._begin(int(i))
            self._obs = new_obs
            model.num_timesteps += env.num_envs
            self.callback.update_locals({"dones": dones, "infos": infos, "rewards": rewards})
            if not self.callback.on_step():
                return False
        return True

    def _begin(self, i: int) -> None:
        """Env ``i``'s expert reset at its episode's start; a map-aware one made anew on a new
        world (its reset's ``world_variant``; ``Scenario.world_at`` builds each world once)."""
        if self._maps is not None:
            scenario, settings = self._maps
            world = scenario.world_at(self.env.unwrapped.reset_infos[i].get("world_variant"))
            if getattr(self.experts[i], "world", None) is not world:
                self.experts[i] = baseline_expert(self.config.expert, scenario.config,
                                                  scenario.robot, world, settings)
        self.experts[i].reset()

    def _out_of_steps(self) -> bool:
        return self.max_steps is not None and self.model.num_timesteps >= self.max_steps

    def _fit_cut_round(self) -> None:
        """When ``max_steps`` or ``max_wall_s`` ended a round, fit the actor on its labels (at
        most ``imitation.gradient_steps`` steps, ``CUT_FIT_S`` s and a tenth of ``max_wall_s``):
        the saved actor is the clone. Not after a signal or an evaluation's stop."""
        clocks = [cb for cb in self.callback.callbacks if isinstance(cb, WallClockLimit)]
        spent = self._out_of_steps() or any(c.over() for c in clocks)
        if spent and len(self.data) > self._fitted:
            done = self.fit(self.config.gradient_steps,
                            max_s=min([CUT_FIT_S, *(0.1 * c.limit_s for c in clocks)]))
            self.refitted = True
            log.info("imitation cut short at %d steps: the actor fitted on %d labelled states "
                     "(%d gradient steps)", self.model.num_timesteps, len(self.data), done)

    def fit(self, gradient_steps: int, max_s: float = float("inf")) -> int:
        """Regress the actor on every labelled state so far (minibatches drawn uniformly):
        ``gradient_steps`` steps, fewer once ``max_s`` seconds have passed; the steps taken."""
        obs, actions, _ = self.data.arrays()
        policy, device = self.model.policy, self.model.device
        policy.set_training_mode(True)
        total, steps, until = 0.0, 0, time.perf_counter() + max_s
        while steps < gradient_steps and (steps == 0 or time.perf_counter() < until):
            steps += 1
            idx = self.rng.integers(0, len(actions), self.batch_size)
            batch = ({k: v[idx] for k, v in obs.items()} if isinstance(obs, dict) else obs[idx])
            loss = actor_loss(self.model, obs_as_tensor(batch, device),
                              torch.as_tensor(actions[idx], device=device))
            self.optimizer.zero_grad()
            loss.backward()
            self.optimizer.step()
            total += float(loss.detach())
        policy.set_training_mode(False)
        target = getattr(self.model, "actor_target", None)
        if target is not None:  # TD3, DDPG: RL's targets start from the imitated actor
            target.load_state_dict(self.model.actor.state_dict())
        self.losses.append(total / max(steps, 1))
        self._fitted = len(self.data)
        return steps

    def warm_up_critic(self, gradient_steps: int, chunk: int = 250) -> bool:
        """``gradient_steps`` of the algorithm's own updates with the actor frozen: a critic
        fitted to the imitated policy before its gradient reaches the actor. Run ``chunk``
        updates at a time, so that the run's wall-clock budget (``WallClockLimit``) ends it
        between chunks; False when it did."""
        model = self.model
        if gradient_steps <= 0 or model.replay_buffer.size() < self.batch_size:
            return True
        clocks = [cb for cb in self.callback.callbacks if isinstance(cb, WallClockLimit)]
        frozen = list(model.actor.parameters())
        for p in frozen:
            p.requires_grad_(False)
        done = 0
        try:
            while done < gradient_steps:
                if any(clock.over() for clock in clocks):
                    log.info("critic warm-up stopped by the wall-clock budget after %d of %d "
                             "gradient steps", done, gradient_steps)
                    return False
                steps = min(chunk, gradient_steps - done)
                model.train(gradient_steps=steps, batch_size=self.batch_size)
                done += steps
        finally:
            for p in frozen:
                p.requires_grad_(True)
        log.info("critic warmed up: %d gradient steps on %d transitions", gradient_steps,
                 model.replay_buffer.size() * model.replay_buffer.n_envs)
        return True


class DecayingCloning(BaseCallback):
    """During RL, every 1000 env steps: ``imitation.rl_gradient_steps`` regression steps on the
    labels, times ``1 - t / rl_decay_steps`` (t: RL's env steps so far), so that the
    actor stays near the expert while the critic learns, and RL alone takes over."""

    def __init__(self, imitation: Imitation) -> None:
        super().__init__()
        self.imitation = imitation
        self._start: int | None = None
        self._due = 0

    def _on_step(self) -> bool:
        c = self.imitation.config
        if self._start is None:
            self._start = self._due = self.num_timesteps
        if self.num_timesteps < self._due:
            return True
        self._due += 1000
        share = 1.0 - (self.num_timesteps - self._start) / c.rl_decay_steps
        steps = round(c.rl_gradient_steps * share)
        if steps > 0:
            self.imitation.fit(steps)
            self.logger.record("imitation/rl_gradient_steps", steps)
        return True


def _next_obs(new_obs: Any, dones: np.ndarray, infos: list[dict[str, Any]]) -> Any:
    """The observations each transition led to: a finished episode's last one (the vec env has
    already reset it), as SB3's own collection stores them."""
    if not dones.any():
        return new_obs
    out = copy.deepcopy(new_obs)
    for i in np.flatnonzero(dones):
        last = infos[i].get("terminal_observation")
        if last is None:
            continue
        if isinstance(out, dict):
            for key in out:
                out[key][i] = last[key]
        else:
            out[i] = last
    return out
