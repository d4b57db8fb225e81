"""What drives a test episode (``Driver``), and the agents ``--agent`` names beyond a model zip:
a policy plugin (``FILE.py:NAME``, ``package.module:NAME`` or a name in the ``pic4rl.policies``
entry-point group; the protocol: ``pic4rl_bridge.control.plugin``), a TorchScript policy
(``.pt`` with a sidecar naming its env) and any SB3 or sb3-contrib algorithm's zip.

A plugin is loaded by its reference in the process that drives it (a bench worker imports it
again by the same reference), a fresh instance per ``Driver``. A plugin or TorchScript policy
that raises, or gives NaN or the wrong shape, raises ``PolicyFailure``: the tester ends that
episode ``aborted`` with the error and goes on.
"""

from __future__ import annotations

import difflib
import hashlib
import importlib
import importlib.util
import sys
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

import numpy as np

from pic4rl_base.schema import read_yaml
from pic4rl_bridge.control.plugin import (ACTS, Policy, PolicyFailure, TaskInfo, check_policy,
                                          command_of)
from pic4rl_bridge.errors import ConfigError

ENTRY_POINTS = "pic4rl.policies"  # name → a Policy class or object, for installed packages
SIDECARS = (".yaml", ".yml", ".json")  # model.pt's sidecar: model.yaml (or model.pt.yaml)
SIDECAR_KEYS = ("env", "acts", "observation_shape")


def _entry_point(name: str) -> Any:
    found = [ep for ep in entry_points(group=ENTRY_POINTS) if ep.name == name]
    return found[0] if found else None


def is_plugin(location: str) -> bool:
    """Whether an ``--agent`` location names a plugin: ``FILE.py:NAME``,
    ``package.module:NAME``, or (no such path) an entry point of ``pic4rl.policies``."""
    target, sep, attr = location.rpartition(":")
    if sep and attr.isidentifier() and (
            target.endswith(".py") or all(p.isidentifier() for p in target.split("."))):
        return True
    return ":" not in location and not Path(location).exists() and (
        _entry_point(location) is not None)


def _module(target: str, where: str) -> Any:
    if target.endswith(".py"):
        path = Path(target).expanduser().resolve()
        if not path.is_file():
            raise ConfigError(f"{where}: no such file {target}")
        # One module per file, whatever its folder; a worker loads it again by path.
        name = f"pic4rl_plugin_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:8]}"
        if name in sys.modules:
            return sys.modules[name]
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)  # type: ignore[union-attr]
        except Exception as err:
            del sys.modules[name]
            raise ConfigError(f"{where}: importing {path} failed: "
                              f"{type(err).__name__}: {err}") from err
        return module
    try:
        return importlib.import_module(target)
    except ImportError as err:
        raise ConfigError(f"{where}: cannot import {target}: {err}") from err


def load_plugin(location: str) -> tuple[Any, str]:
    """A fresh instance of the plugin ``location`` names (a class is made with no arguments)
    and its name; ``ConfigError`` naming the reference otherwise."""
    where = f"--agent {location}"
    target, sep, attr = location.rpartition(":")
    if sep:
        module = _module(target, where)
        if not hasattr(module, attr):
            names = [n for n in vars(module) if not n.startswith("_")]
            near = difflib.get_close_matches(attr, names, n=1)
            raise ConfigError(f"{where}: {target} has no {attr!r}"
                              + (f"; did you mean {near[0]!r}?" if near else ""))
        obj = getattr(module, attr)
    else:
        ep = _entry_point(location)
        if ep is None:
            raise ConfigError(f"{where}: no entry point {location!r} in group {ENTRY_POINTS}")
        try:
            obj = ep.load()
        except Exception as err:
            raise ConfigError(f"{where}: loading entry point {ep.value} failed: "
                              f"{type(err).__name__}: {err}") from err
    if isinstance(obj, type):
        try:
            obj = obj()
        except Exception as err:
            raise ConfigError(f"{where}: {attr or location}() failed: "
                              f"{type(err).__name__}: {err}") from err
    return obj, check_policy(obj, where)


def torchscript_env(path: Path) -> Path:
    """The env file that the sidecar of TorchScript policy ``path`` names (its observation
    layout: the params file it was trained in), relative to the sidecar."""
    sidecar = _sidecar(path)
    env = _read_sidecar(sidecar)["env"]
    file = Path(env) if Path(env).is_absolute() else sidecar.parent / env
    if not file.is_file():
        raise ConfigError(f"{sidecar}: env: no such file {env}")
    return file


def _sidecar(path: Path) -> Path:
    candidates = [path.with_suffix(s) for s in SIDECARS] + [
        path.with_name(path.name + s) for s in SIDECARS]
    found = next((c for c in candidates if c.is_file()), None)
    if found is None:
        raise ConfigError(f"--agent {path}: a TorchScript policy needs a sidecar "
                          f"{path.with_suffix('.yaml').name} with env: (the params file of "
                          "its observation layout) and acts: normalized|velocity")
    return found


def _read_sidecar(sidecar: Path) -> dict[str, Any]:
    data = read_yaml(sidecar, "TorchScript sidecar")  # JSON is YAML
    if not isinstance(data, dict) or not isinstance(data.get("env"), str):
        raise ConfigError(f"{sidecar}: expected a mapping with env: FILE (and acts, "
                          "observation_shape)")
    unknown = sorted(set(data) - set(SIDECAR_KEYS))
    if unknown:
        raise ConfigError(f"{sidecar}: unknown key {unknown[0]!r}; expected "
                          f"{', '.join(SIDECAR_KEYS)}")
    if data.get("acts", "normalized") not in ACTS:
        raise ConfigError(f"{sidecar}: acts: {data['acts']!r} is invalid; expected "
                          f"{' or '.join(ACTS)}")
    return data


class TorchScriptPolicy(Policy):
    """A TorchScript module as a plugin: the task's observation (a float32 batch of one) in,
    an action out, as its sidecar's ``acts`` says; a module's exported ``reset()`` (a
    recurrent one's hidden state) is called at each episode's start."""

    observes = "observation"

    def __init__(self, path: Path) -> None:
        import torch

        sidecar = _sidecar(path)
        data = _read_sidecar(sidecar)
        self.acts = data.get("acts", "normalized")  # type: ignore[misc]
        self.name = path.stem
        self._shape = tuple(data["observation_shape"]) if data.get("observation_shape") else None
        try:
            self.module = torch.jit.load(str(path), map_location="cpu").eval()
        except (RuntimeError, ValueError) as err:
            raise ConfigError(f"--agent {path}: cannot load it as TorchScript: {err}") from err
        self._where = f"{path} ({sidecar.name})"

    def reset(self, robot: Any, task: TaskInfo) -> None:
        if task.observation_shape is None:
            raise ConfigError(f"{self._where}: a Dict observation; a TorchScript policy takes "
                              "a Box observation (one vector or image)")
        if self._shape is not None and self._shape != task.observation_shape:
            raise ConfigError(f"{self._where}: observation_shape {list(self._shape)} but the "
                              f"env gives {list(task.observation_shape)}")
        if hasattr(self.module, "reset"):
            self.module.reset()

    def act(self, observation: Any) -> Any:
        import torch

        with torch.no_grad():
            x = torch.as_tensor(np.asarray(observation, dtype=np.float32)).unsqueeze(0)
            return self.module(x).squeeze(0).numpy()


def sb3_class(algorithm: str) -> Any:
    """The SB3 or sb3-contrib algorithm class named ``algorithm`` (any case: ``ppo``,
    ``RecurrentPPO``, ``sb3_contrib.TQC``)."""
    import sb3_contrib
    import stable_baselines3
    from stable_baselines3.common.base_class import BaseAlgorithm

    name = algorithm.rpartition(".")[2].lower()
    for package in (stable_baselines3, sb3_contrib):
        for attr in dir(package):
            cls = getattr(package, attr)
            if (attr.lower() == name and isinstance(cls, type)
                    and issubclass(cls, BaseAlgorithm)):
                return cls
    raise ConfigError(f"--algorithm {algorithm}: no such SB3 or sb3-contrib algorithm")


def task_info(env: Any) -> TaskInfo:
    """The ``TaskInfo`` of ``env`` (a ``NavEnv``) for a plugin's ``reset``."""
    c = env.config
    shape = getattr(env.observation_space, "shape", None)
    return TaskInfo(name=str(getattr(c.task, "value", c.task)),
                    sensor=str(getattr(c.sensor, "value", c.sensor)),
                    goal_tolerance_m=c.goal_tolerance_m,
                    collision_tolerance_m=c.collision_tolerance_m,
                    max_steps=c.episode_max_steps, control_dt_s=env.scenario.robot.control_dt_s,
                    observation_shape=tuple(shape) if shape else None,
                    action_shape=tuple(env.action_space.shape))


class Driver:
    """What drives an episode of ``spec`` (a ``plan.AgentSpec``): ``begin(env)`` at its start,
    then ``act(obs, env)`` → a normalised action. A plugin's failure is ``PolicyFailure``
    naming it."""

    def __init__(self, spec: Any, env: Any) -> None:
        self.spec = spec
        self.model: Any = None
        self.controller: Any = None
        self.plugin: Any = None
        self.state: Any = None
        self.first = True
        if spec.plugin:
            self.plugin, self.name = load_plugin(spec.plugin)
        elif spec.model is not None and spec.model.suffix == ".pt":
            self.plugin, self.name = TorchScriptPolicy(spec.model), spec.name
        elif spec.model is not None:
            self.model = _sb3_model(spec, env)
        else:
            from pic4rl_bridge.baselines import make_baseline

            self.controller = make_baseline(spec.baseline, env.config, env.scenario.robot,
                                            env.scenario.world, spec.settings)

    def _call(self, method: str, *args: Any) -> Any:
        try:
            return getattr(self.plugin, method)(*args)
        except (ConfigError, KeyboardInterrupt):
            raise
        except Exception as err:
            raise PolicyFailure(f"policy {self.name}: {method}() raised "
                                f"{type(err).__name__}: {err}") from err

    def begin(self, env: Any) -> None:
        self.state, self.first = None, True  # a recurrent model's hidden state, per episode
        if self.controller is not None:
            self.controller.reset()
        if self.plugin is not None:
            self._call("reset", env.scenario.robot, task_info(env))

    def act(self, obs: Any, env: Any) -> np.ndarray:
        if self.plugin is not None:
            raw = self._call("act", env.frame if self.plugin.observes == "frame" else obs)
            return command_of(self.plugin, self.name, raw, env.scenario.robot,
                              tuple(env.action_space.shape))
        if self.model is not None:
            action, self.state = self.model.predict(
                obs, state=self.state, episode_start=np.array([self.first]),
                deterministic=True)
            self.first = False
            return np.asarray(action)
        return self.controller.action(env.frame)


def _sb3_model(spec: Any, env: Any) -> Any:
    """``spec``'s SB3 zip: an algorithm of the table (its checks) or, named by ``--algorithm``,
    any other SB3 or sb3-contrib one (``RecurrentPPO``, ``A2C``, ...)."""
    import torch

    from pic4rl_agents.models.algorithms import check_spaces, load_model

    if spec.run.train.torch_threads > 0:  # as trained: a policy call is small
        torch.set_num_threads(spec.run.train.torch_threads)
    where = f"--agent {spec.model} ({spec.trained})"
    if spec.algorithm:
        try:
            model = sb3_class(spec.algorithm).load(spec.model, device="cpu")
        except (ValueError, KeyError, RuntimeError, TypeError, OSError) as err:
            raise ConfigError(f"{where}: cannot load it as a {spec.algorithm} model: "
                              f"{err}") from err
    else:
        model = load_model(spec.model, spec.run.train.algorithm)
    check_spaces(model.observation_space, model.action_space, env, model=where,
                 env_from=f"its test env ({spec.run.origin})")
    return model
