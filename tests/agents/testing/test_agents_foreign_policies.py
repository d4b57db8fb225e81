"""Policies from other learning libraries (issue 38 item 2): a TorchScript file with its
sidecar (what CleanRL, RLlib or a lab's own code can export), and SB3 / sb3-contrib zips of
algorithms beyond the training table (RecurrentPPO, its hidden state reset per episode), each
tested in process on tiny models made here; and ``pic4rl-run`` taking a plugin reference."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pic4rl_agents.launch.rosargs import RosArgs
from pic4rl_agents.testing import policies
from pic4rl_agents.testing.plan import TestPlan, resolve_agents
from pic4rl_agents.testing.tester import drive_and_judge
from pic4rl_bridge.errors import ConfigError
from pic4rl_metrics import read_episode

REPO = Path(__file__).resolve().parents[3]
GOTO = str(REPO / "config" / "env_goto_lidar.yaml")
STEPS = 12


def _plan(tmp_path: Path, agent: str, *, episodes: int = 1, algorithm: str = "",
          files: tuple[str, ...] = ()) -> TestPlan:
    return TestPlan(agents=(agent,), algorithm=algorithm, episodes=episodes,
                    bags_dir=tmp_path / "bags", run="r", params_files=files,
                    env_overrides={"episode_max_steps": STEPS}, progress=False)


def _torchscript(tmp_path: Path, action: tuple[float, float], sidecar: dict | None) -> Path:
    """A TorchScript module giving ``action`` whatever it sees (a zero linear layer and a
    bias), with an exported ``reset`` counting episodes, and its sidecar."""
    torch = pytest.importorskip("torch")

    class Constant(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.episodes = 0
            self.register_buffer("bias", torch.tensor([float(a) for a in action]))

        def forward(self, x: torch.Tensor) -> torch.Tensor:
            return torch.zeros(x.shape[0], 2) + self.bias

        @torch.jit.export
        def reset(self) -> None:
            self.episodes += 1

    path = tmp_path / "policy.pt"
    torch.jit.script(Constant()).save(str(path))
    if sidecar is not None:
        (tmp_path / "policy.json").write_text(json.dumps(sidecar))
    return path


def test_a_torchscript_policy_with_its_sidecar_drives_and_is_judged(tmp_path: Path) -> None:
    """Normalised (1, 0.5): the robot's top speed and half its top turn rate, in the env
    the sidecar names."""
    path = _torchscript(tmp_path, (1.0, 0.5), {"env": GOTO, "acts": "normalized",
                                               "observation_shape": None})
    spec = resolve_agents(_plan(tmp_path, str(path)))[0]
    assert (spec.name, spec.model) == ("policy", path) and GOTO in spec.trained
    result = drive_and_judge(_plan(tmp_path, str(path)))
    from pic4rl_bridge.scenario import Scenario

    robot = Scenario(spec.run.env).robot
    cmd = read_episode(next((result.run_dir / "policy").glob("episode_*"))).inputs["cmd"]
    np.testing.assert_allclose(cmd.vx, robot.max_linear_m_s, rtol=1e-6)
    np.testing.assert_allclose(cmd.wz, 0.5 * robot.max_angular_rad_s, rtol=1e-6)


@pytest.mark.bad_input
@pytest.mark.parametrize(("sidecar", "message"), [
    (None, "--agent {p}: a TorchScript policy needs a sidecar policy.yaml with env:"),
    ({"env": "nope.yaml"}, "{d}/policy.json: env: no such file nope.yaml"),
    ({"env": GOTO, "acts": "twist"}, "{d}/policy.json: acts: 'twist' is invalid; expected "
                                     "velocity or normalized"),
    ({"env": GOTO, "obs": [3]}, "{d}/policy.json: unknown key 'obs'; expected env, acts, "
                                "observation_shape"),
])
def test_a_bad_sidecar_is_one_line_naming_it(tmp_path: Path, sidecar: dict | None,
                                            message: str) -> None:
    path = _torchscript(tmp_path, (0.0, 0.0), sidecar)
    with pytest.raises(ConfigError) as err:
        resolve_agents(_plan(tmp_path, str(path)))
    assert str(err.value).startswith(message.format(p=path, d=tmp_path))


def test_a_torchscript_policy_for_another_observation_aborts_at_reset(tmp_path: Path) -> None:
    path = _torchscript(tmp_path, (0.0, 0.0), {"env": GOTO, "observation_shape": [7]})
    from pic4rl_bridge.env import NavEnv

    spec = resolve_agents(_plan(tmp_path, str(path)))[0]
    env = NavEnv(spec.run.env)
    try:
        env.reset(seed=0)
        driver = policies.Driver(spec, env)
        with pytest.raises(ConfigError, match=r"observation_shape \[7\] but the env gives"):
            driver.begin(env)
    finally:
        env.close()


def _model(algorithm: str, tmp_path: Path) -> Path:
    """A tiny ``algorithm`` model on the test env, built and saved untrained (a bare zip)."""
    from pic4rl_bridge.env import NavEnv

    spec = resolve_agents(_plan(tmp_path, f"{REPO}/examples/gap_follower.py:GapFollower",
                                files=(GOTO,)))[0]
    env = NavEnv(spec.run.env)
    try:
        cls = policies.sb3_class(algorithm)
        policy = "MlpLstmPolicy" if algorithm == "RecurrentPPO" else "MlpPolicy"
        kwargs = {"n_steps": 8, "batch_size": 8} if "PPO" in algorithm.upper() else {}
        model = cls(policy, env, policy_kwargs={"net_arch": [8]}, seed=0, device="cpu",
                    **kwargs)
        path = tmp_path / f"{algorithm.lower()}.zip"
        model.save(path)
    finally:
        env.close()
    return path


@pytest.mark.parametrize("algorithm", ["ppo", "RecurrentPPO", "A2C"])
def test_any_sb3_or_contrib_zip_is_tested(tmp_path: Path, algorithm: str) -> None:
    path = _model(algorithm, tmp_path)
    plan = _plan(tmp_path, str(path), episodes=2, algorithm=algorithm, files=(GOTO,))
    result = drive_and_judge(plan)
    name = path.stem
    assert len(result.outcomes[name]) == 2 and name in result.table.index


def test_a_recurrent_policy_starts_each_episode_from_a_fresh_state(tmp_path: Path) -> None:
    """The driver's first action of an episode is the model's from no state with
    ``episode_start``; the state it carries is the one the model returned."""
    from pic4rl_bridge.env import NavEnv

    path = _model("RecurrentPPO", tmp_path)
    spec = resolve_agents(_plan(tmp_path, str(path), algorithm="RecurrentPPO",
                                files=(GOTO,)))[0]
    assert spec.algorithm == "RecurrentPPO"
    env = NavEnv(spec.run.env)
    try:
        driver = policies.Driver(spec, env)
        for _ in range(2):
            obs, _ = env.reset()
            driver.begin(env)
            assert driver.state is None
            action = driver.act(obs, env)
            fresh, state = driver.model.predict(obs, state=None, episode_start=np.array([True]),
                                                deterministic=True)
            np.testing.assert_array_equal(action, fresh)
            assert all(np.array_equal(a, b) for a, b in zip(driver.state, state))
            for _ in range(3):
                obs, *_ = env.step(driver.act(obs, env))
            assert not all(np.array_equal(a, b) for a, b in zip(driver.state, state))
    finally:
        env.close()


@pytest.mark.bad_input
def test_an_unknown_algorithm_is_named(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="^--algorithm PPOO: no such SB3 or sb3-contrib "
                                          "algorithm"):
        policies.sb3_class("PPOO")


def test_pic4rl_run_takes_a_plugin_reference(tmp_path: Path) -> None:
    """``pic4rl-run test --agent FILE.py:NAME``: the env its sim node is started for."""
    from pic4rl_agents.launch import run

    env, n_envs = run._resolve("test", ["--agent", f"{REPO}/examples/gap_follower.py:"
                                                   "GapFollower"],
                               RosArgs(params_files=[GOTO], params={"transport": "ros"}))
    assert (env.transport, env.agent, n_envs) == ("ros", "gap_follower", 1)
