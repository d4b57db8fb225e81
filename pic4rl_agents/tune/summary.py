"""The summary of a ``pic4rl-tune`` study, in its folder, rewritten after every trial:
``trials.csv`` (with the trainer parameters each trial used), ``best_trial.yaml``, ``best_params.yaml`` (a params file ``pic4rl-train``
takes as it is), and at the end ``importances.yaml`` and ``eval_curves.png``; and each
trial's line as it ends."""

from __future__ import annotations

import logging
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import optuna
import yaml

from pic4rl_base import atomic

if TYPE_CHECKING:
    import pandas as pd

    from .settings import TuneSettings

log = logging.getLogger(__name__)
trial_log = logging.getLogger("pic4rl_agents.tune.search")  # the trials' lines, on stdout


def log_trial(study: Any, trial: Any) -> None:
    """One line for a finished trial: its state, its last evaluation (or why it failed), and
    the best trial so far."""
    attrs = trial.user_attrs
    if "success_rate" in attrs:
        what = (f"success {attrs['success_rate']:.2f}, reward {attrs['mean_reward']:.1f}, "
                f"length {attrs['mean_length']:.0f} at {attrs['steps']:.0f} steps, "
                f"{attrs['train_wall_s']:.0f} s")
    else:
        what = attrs.get("error", "no evaluation")
    try:
        best = f"; best so far: trial {study.best_trial.number} ({study.best_value:.3g})"
    except ValueError:  # no completed trial yet
        best = ""
    trial_log.info("trial %d %s: %s%s", trial.number, trial.state.name.lower(), what, best)


def write_summary(study: Any, settings: TuneSettings, *, final: bool = False) -> None:
    """The study folder's summary (rewritten): trials.csv, best_trial.yaml, best_params.yaml;
    with ``final``, importances.yaml (when Optuna can compute them) and eval_curves.png."""
    from optuna.trial import TrialState

    folder = settings.study_dir
    _write(folder / "trials.csv", trials_table(study).to_csv(index=False))
    complete = study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
    if not complete:
        return
    best = study.best_trial
    _write(folder / "best_trial.yaml", yaml.safe_dump(
        {"study": settings.study_name, "objective": settings.objective, "number": best.number,
         "value": best.value, "params": best.params, "user_attrs": best.user_attrs},
        sort_keys=False))
    hyperparams = best.user_attrs.get("hyperparams")
    if hyperparams is not None:
        _write(folder / "best_params.yaml", settings.best_run(hyperparams).to_yaml())
    if final:
        _write_importances(study, folder)
        _write_curves(complete, folder)


def trials_table(study: Any) -> pd.DataFrame:
    """Optuna's table of the trials, each trial's trainer parameters as it used them (drawn or
    fixed by ``--hyperparams``) in columns ``hyperparams.<key>`` instead of one dict."""
    import pandas as pd

    frame = study.trials_dataframe()
    if "user_attrs_hyperparams" not in frame:
        return frame
    used = [h if isinstance(h, dict) else {} for h in frame.pop("user_attrs_hyperparams")]
    values = pd.DataFrame([{k: str(v) if isinstance(v, (list, dict)) else v
                            for k, v in h.items()} for h in used], index=frame.index)
    return pd.concat([frame, values.add_prefix("hyperparams.")], axis=1)


def _write_importances(study: Any, folder: Path) -> None:
    try:  # PED-ANOVA: numpy only (fANOVA needs scikit-learn); too few trials warn: none then
        with warnings.catch_warnings():
            warnings.simplefilter("error", UserWarning)
            importances = optuna.importance.get_param_importances(
                study, evaluator=optuna.importance.PedAnovaImportanceEvaluator())
    except (ValueError, RuntimeError, UserWarning) as err:
        log.warning("no parameter importances (%s)", err)
        return
    _write(folder / "importances.yaml",
           yaml.safe_dump({k: round(float(v), 4) for k, v in importances.items()},
                          sort_keys=False))


def _write_curves(complete: list[Any], folder: Path, top: int = 8) -> None:
    from pic4rl_agents.training.curves import eval_curves, save_eval_curves

    curves = {}
    for trial in sorted(complete, key=lambda t: t.value, reverse=True)[:top]:
        run_dir = Path(trial.user_attrs.get("run_dir", ""))
        if (run_dir / "eval").is_dir():
            curves.update(eval_curves(run_dir, f"trial {trial.number} ({trial.value:.3g})"))
    if curves:
        save_eval_curves(curves, folder / "eval_curves.png",
                         title=f"{folder.name}: the best {len(curves)} trials")


def _write(path: Path, text: str) -> None:
    """Written whole, so a reader (or another worker) never sees half."""
    atomic.write_text(path, text)
