"""``summary.yaml``: what a training session did (docs/agents.md, "The run directory").

It leads with the session's last evaluation (the seeded evaluation episodes: success,
collisions, timeouts, at which step and wall time; the trainer evaluates the saved model at the
end of a session, ``SeededEvalCallback.evaluate_saved``) and which models were saved, because the
training episodes do not judge the agent: during imitation the expert drives them. Those
episodes are then counted per driver (``envs.DRIVERS``), and the agent's own success rate
(the student's and RL's episodes) is never the expert's.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from .envs import DRIVER_KEY, DRIVERS

if TYPE_CHECKING:
    from pic4rl_agents.runs.config import RunConfig

#: The drivers whose episodes are the agent's own: its actor drove them.
AGENT_DRIVERS = ("student", "rl")
#: How many of the latest episodes the success rates and mean rewards are over.
LAST = 100


def _rate(values: pd.Series, digits: int = 3) -> float | None:
    return round(float(values.mean()), digits) if len(values) else None


def evaluation_summary(evaluations: pd.DataFrame | None, saved_steps: int) -> dict[str, Any] | None:
    """The last row of a session's ``evaluations.csv`` (``callbacks.CSV_COLUMNS``): its
    step and clock, episodes, success rate and every outcome's rate, and
    ``steps_before_saved``: how many env steps the saved ``model.zip`` trained past it
    (0: it judged the model as saved); None without an evaluation."""
    if evaluations is None or evaluations.empty:
        return None
    row = evaluations.iloc[-1]
    out: dict[str, Any] = {"steps": int(row["steps"]), "wall_s": round(float(row["wall_s"]), 1),
                           "episodes": int(row["episodes"]),
                           "success_rate": round(float(row["success_rate"]), 3)}
    for column in evaluations.columns:
        if column.endswith("_rate") and column != "success_rate":
            out[column] = round(float(row[column]), 3)
    out["mean_reward"] = round(float(row["mean_reward"]), 1)
    out["steps_before_saved"] = max(int(saved_steps) - out["steps"], 0)
    return out


def best_evaluation(evaluations: pd.DataFrame | None) -> dict[str, Any] | None:
    """The evaluation whose model ``best/<session>/best_model.zip`` is: SB3 keeps the first
    with the highest mean reward."""
    if evaluations is None or evaluations.empty:
        return None
    row = evaluations.loc[evaluations["mean_reward"].idxmax()]
    return {"steps": int(row["steps"]), "success_rate": round(float(row["success_rate"]), 3),
            "mean_reward": round(float(row["mean_reward"]), 1)}


def driver_summary(episodes: pd.DataFrame) -> dict[str, dict[str, Any]]:
    """Per driver present (``envs.DRIVERS``, then ``unrecorded`` for monitor files older than
    the driver column): its episodes, and the success rate and mean reward of its last
    ``LAST``."""
    out: dict[str, dict[str, Any]] = {}
    drivers = [d for d in DRIVERS if d in set(episodes[DRIVER_KEY])]
    drivers += sorted(set(episodes[DRIVER_KEY]) - set(DRIVERS))
    for driver in drivers:
        own = episodes[episodes[DRIVER_KEY] == driver]
        last = own.tail(LAST)
        out[driver] = {"episodes": len(own),
                       f"last_{LAST}_success_rate": _rate(last["is_success"].astype(float)),
                       f"last_{LAST}_mean_reward": _rate(last["r"], 1)}
    return out


def session_summary(run: RunConfig, session: int, total_steps: int, session_steps: int,
                    wall_s: float, episodes: pd.DataFrame,
                    evaluations: pd.DataFrame | None = None,
                    best_model: Path | None = None, model: Path | None = None) -> dict[str, Any]:
    """``summary.yaml``'s keys, in order: ``evaluation`` (``evaluation_summary``), the saved
    models (``model``: the last, ``best_model``: the best evaluation's, paths as given), the
    run and session, then ``episodes`` (every finished training episode of the run:
    ``curves.episode_table``) per driver, and the agent's own last ``LAST`` (its student's
    and RL's episodes; None when it drove none)."""
    saved: dict[str, Any] = {"last": {"file": str(model) if model else None,
                                      "steps": int(total_steps)}}
    best = best_evaluation(evaluations)
    if best is not None and best_model is not None:
        saved["best"] = {"file": str(best_model), **best}
    agent = episodes[episodes[DRIVER_KEY].isin(AGENT_DRIVERS)].tail(LAST)
    return {"evaluation": evaluation_summary(evaluations, total_steps), "saved_models": saved,
            "run": run.name, "algorithm": run.train.algorithm, "sensor": run.env.sensor,
            "transport": run.env.transport, "n_envs": run.train.n_envs, "session": session,
            "total_steps": int(total_steps), "session_steps": int(session_steps),
            "session_wall_s": round(wall_s, 1),
            "steps_per_s": round(session_steps / wall_s, 1) if wall_s > 0 else None,
            "episodes": len(episodes),
            "episodes_by_driver": driver_summary(episodes),
            f"agent_last_{LAST}_success_rate": _rate(agent["is_success"].astype(float)),
            f"agent_last_{LAST}_mean_reward": _rate(agent["r"], 1)}
