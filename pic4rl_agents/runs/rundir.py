"""The layout of a run directory, ``<runs_dir>/<run>/``, in one place.

    config.yaml, config-2.yaml, ...    the run's params file, one more per resume
    model.zip, replay_buffer.pkl       the final (or interrupted) model and its experience
    checkpoints/model_<steps>_steps.zip, model_replay_buffer_<steps>_steps.pkl
    monitor/<session>_<rank>.monitor.csv                    one row per training episode
    logs/<session>/    eval/<session>/evaluations.csv    best/<session>/best_model.zip
    reward_curve.png, summary.yaml, summary-2.yaml, ...
    videos/eval_<steps>_steps_episode_<i>.mp4          with eval.video_episodes > 0

A session is one ``pic4rl-train`` process on the run: 0, then one more per resume. Files that
every session writes anew (``config``, ``summary``) are named after it (``session_file``):
session 1 writes ``config-2.yaml`` and ``summary-2.yaml``, and nothing is overwritten.
Every file is written whole or not at all (``pic4rl_base.atomic``).
"""

from __future__ import annotations

import pickle
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pic4rl_base import atomic
from pic4rl_base.params_file import ENV_NODE
from pic4rl_bridge.errors import ConfigError

CONFIG = "config.yaml"
MODEL = "model.zip"
REPLAY_BUFFER = "replay_buffer.pkl"
SUMMARY = "summary.yaml"
REWARD_CURVE = "reward_curve.png"
EVALUATIONS = "evaluations.csv"
CHECKPOINT_PREFIX = "model"  # SB3's CheckpointCallback name_prefix


def agent_sections(sections: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """A trained agent's saved sections without its run's ``record.*`` choices: a test records
    what its own files ask (topics added since the agent was trained included)."""
    return {node: {k: v for k, v in params.items()
                   if not (node == ENV_NODE and k.startswith("record."))}
            for node, params in sections.items()}


_CHECKPOINT = re.compile(rf"^{CHECKPOINT_PREFIX}_(\d+)_steps\.zip$")


def free_path(path: Path, *, keep_suffix: bool = False, start: int = 1) -> Path:
    """The first of ``atomic.numbered(path, start)``, ``atomic.numbered(path, start + 1)``,
    ... that does not exist, so nothing is overwritten."""
    n = start
    while atomic.numbered(path, n, keep_suffix=keep_suffix).exists():
        n += 1
    return atomic.numbered(path, n, keep_suffix=keep_suffix)


def session_file(path: Path, session: int) -> Path:
    """What session ``session`` names a file every session writes anew: ``config.yaml`` for
    session 0, ``config-2.yaml`` for session 1, ... (the next free one if that is taken)."""
    return free_path(path, keep_suffix=True, start=session + 1)


def run_config_file(folder: Path) -> Path | None:
    """A run folder's latest params file: ``config.yaml`` or its newest ``config-N.yaml``."""
    found = {n: p for p in folder.glob("config*.yaml")
             if (n := atomic.series_index(p, folder / CONFIG)) is not None}
    return found[max(found)] if found else None


def trained_model(path: str | Path, *, where: str) -> Path:
    """The model a trained agent's ``path`` names: a model zip, or a folder's ``model.zip``
    (a run's, a checkpoint folder's); ``ConfigError`` naming ``where`` when there is none."""
    path = Path(path)
    model = path / MODEL if path.is_dir() else path
    if not model.is_file():
        raise ConfigError(f"{where}: {path}: no such model (expected a model .zip or a folder "
                          f"holding {MODEL})")
    return model


def run_of(model_zip: Path) -> Path | None:
    """The run directory a model zip belongs to: the nearest folder with a run config, the
    zip's own or up to two above it (``checkpoints/``, ``best/<session>/``)."""
    return next((d for d in (model_zip.parent, model_zip.parent.parent,
                             model_zip.parent.parent.parent)
                 if run_config_file(d) is not None), None)


def checkpoint_steps(model_zip: Path) -> int | None:
    """The steps in a checkpoint's name (``model_<steps>_steps.zip``); None for another zip."""
    match = _CHECKPOINT.match(model_zip.name)
    return int(match.group(1)) if match else None


def replay_buffer_of(model_zip: Path) -> Path:
    """Where the replay buffer saved with ``model_zip`` is (it may not exist)."""
    steps = checkpoint_steps(model_zip)
    if steps is None:
        return model_zip.with_name(REPLAY_BUFFER)
    return model_zip.with_name(f"{CHECKPOINT_PREFIX}_replay_buffer_{steps}_steps.pkl")


def evaluation_files(run_dir: Path) -> list[Path]:
    """Each session's ``eval/<session>/evaluations.csv``, in session order."""
    return sorted((run_dir / "eval").glob(f"*/{EVALUATIONS}"),
                  key=lambda f: int(f.parent.name) if f.parent.name.isdigit() else -1)


def run_of_evaluations(path: Path) -> str:
    """The run's name of an ``evaluations.csv`` (in ``<run>/eval/<session>/`` or not)."""
    return path.parents[2].name if path.parent.parent.name == "eval" else path.parent.name


@dataclass(frozen=True)
class RunDir:
    """A run directory, seen from one session of it."""

    path: Path
    session: int = 0

    @classmethod
    def new(cls, runs_dir: Path, name: str) -> RunDir:
        """A fresh run folder ``<runs_dir>/<name>`` (``<name>-2``, ... when that is taken),
        claimed atomically: two runs started at once never share one."""
        return cls(atomic.claim_dir(runs_dir / name))

    @classmethod
    def resume(cls, path: Path) -> RunDir:
        """An existing run, in its next session (one per ``logs/<session>``)."""
        path.mkdir(parents=True, exist_ok=True)
        logs = path / "logs"
        return cls(path, len(list(logs.iterdir())) if logs.is_dir() else 0)

    @property
    def model(self) -> Path:
        return self.path / MODEL

    @property
    def replay_buffer(self) -> Path:
        return self.path / REPLAY_BUFFER

    @property
    def checkpoints(self) -> Path:
        return self.path / "checkpoints"

    @property
    def monitor(self) -> Path:
        return self.path / "monitor"

    @property
    def reward_curve(self) -> Path:
        return self.path / REWARD_CURVE

    @property
    def logs(self) -> Path:
        """SB3's progress.csv and TensorBoard events of this session."""
        return self.path / "logs" / str(self.session)

    @property
    def eval(self) -> Path:
        """This session's ``evaluations.csv`` (and SB3's evaluations.npz)."""
        return self.path / "eval" / str(self.session)

    @property
    def videos(self) -> Path:
        """Videos of evaluation episodes (every session's: their names hold the steps)."""
        return self.path / "videos"

    @property
    def best(self) -> Path:
        """This session's best evaluated model."""
        return self.path / "best" / str(self.session)

    def write_config(self, text: str) -> Path:
        return atomic.write_text(session_file(self.path / CONFIG, self.session), text)

    def write_summary(self, text: str) -> Path:
        return atomic.write_text(session_file(self.path / SUMMARY, self.session), text)

    def checkpoint_files(self) -> list[tuple[int, Path]]:
        """The checkpoints' models and their steps."""
        return [(steps, p) for p in self.checkpoints.glob(f"{CHECKPOINT_PREFIX}_*.zip")
                if (steps := checkpoint_steps(p)) is not None]


@dataclass(frozen=True)
class Resume:
    """A checkpoint to continue from: the model, its replay buffer (if saved), its run dir,
    and the newer checkpoints passed over because they do not load (``<file>: <why>``)."""

    model: Path
    replay_buffer: Path | None
    run_dir: Path
    skipped: tuple[str, ...] = ()
    trained: str = ""  # the run's training config, in words (set with the session's config)


#: What reading a truncated or corrupt zip or pickle raises.
_UNREADABLE = (ValueError, KeyError, RuntimeError, OSError, EOFError, pickle.UnpicklingError,
               zipfile.BadZipFile)


def find_resume(path: str | Path) -> Resume:
    """The checkpoint named by ``path``: a model zip, or a run directory (its newest
    checkpoint or final ``model.zip`` that loads, with its replay buffer)."""
    path = Path(path)
    if path.is_dir():
        return _newest_loadable(path)
    if not path.is_file() or path.suffix != ".zip":
        raise ConfigError(f"--resume {path}: no such checkpoint (expected a model .zip or a "
                          "run directory)")
    why = _unloadable(path)
    if why is not None:
        raise ConfigError(f"--resume {path}: {why}; give the run directory to resume from its "
                          "newest checkpoint that loads")
    return _resume_of(path)


def _resume_of(model_zip: Path, skipped: tuple[str, ...] = ()) -> Resume:
    checkpoint = checkpoint_steps(model_zip) is not None
    default = model_zip.parent.parent if checkpoint else model_zip.parent
    buffer = replay_buffer_of(model_zip)
    return Resume(model_zip, buffer if buffer.is_file() else None,
                  run_of(model_zip) or default, skipped)


def _newest_loadable(run_dir: Path) -> Resume:
    """The run's newest checkpoint (by steps, then time; ``model.zip`` too) that loads."""
    candidates = RunDir(run_dir).checkpoint_files()
    skipped: list[str] = []
    final = run_dir / MODEL
    if final.is_file():
        try:
            candidates.append((steps_in(final), final))
        except _UNREADABLE as err:
            skipped.append(f"{MODEL}: the model does not load ({_reason(err, final)})")
    if not candidates and not skipped:
        raise ConfigError(f"--resume {run_dir}: no checkpoint in it (expected {MODEL} or "
                          f"checkpoints/{CHECKPOINT_PREFIX}_<steps>_steps.zip)")
    for _, model in sorted(candidates, key=lambda c: (c[0], c[1].stat().st_mtime),
                           reverse=True):
        why = _unloadable(model)
        if why is None:
            return _resume_of(model, tuple(skipped))
        skipped.append(f"{model.relative_to(run_dir)}: {why}")
    raise ConfigError(f"--resume {run_dir}: none of its {len(skipped)} checkpoints loads "
                      f"(newest: {skipped[0]})")


def _unloadable(model_zip: Path) -> str | None:
    """Why ``model_zip`` or the replay buffer saved with it does not load; None when both do
    (or the model does and has no buffer)."""
    from stable_baselines3.common.save_util import load_from_pkl

    try:
        _model_data(model_zip)
    except _UNREADABLE as err:
        return f"the model does not load ({_reason(err, model_zip)})"
    buffer = replay_buffer_of(model_zip)
    if buffer.is_file():
        try:
            load_from_pkl(buffer)
        except _UNREADABLE as err:
            return f"its replay buffer {buffer.name} does not load ({_reason(err, buffer)})"
    return None


def _reason(err: BaseException, path: Path) -> str:
    """What reading ``path`` raised, on one line, the path by its name alone."""
    return " ".join(f"{type(err).__name__}: {err}".replace(str(path), path.name).split())


def _model_data(model_zip: Path) -> dict[str, Any]:
    """A saved model's data (its class parameters), its weights read too; ``ValueError`` when
    the zip holds none (a truncated SB3 zip can open as the torch zip nested in it)."""
    from stable_baselines3.common.save_util import load_from_zip_file

    data, params, _ = load_from_zip_file(model_zip, load_data=True, device="cpu")
    if not data or "policy" not in params:
        raise ValueError("no SB3 model in it (cut short?)")
    return data


def steps_in(model_zip: Path) -> int:
    """The env steps a saved model had trained for (its ``num_timesteps``)."""
    return int(_model_data(model_zip).get("num_timesteps", 0))
