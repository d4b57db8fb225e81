"""The reward curve of a training run, like the paper's Figure 4: each episode's reward and its
moving average, from the runs' Monitor CSVs (one per env)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from stable_baselines3.common.monitor import LoadMonitorResultsError, load_results


def episode_table(monitor_dir: Path) -> pd.DataFrame:
    """Every finished episode of every env in time order: ``r`` (reward), ``l`` (steps),
    ``t`` (s since the start), ``is_success``, ``outcome``; empty when none finished yet."""
    try:
        df = load_results(str(monitor_dir))
    except LoadMonitorResultsError:
        return pd.DataFrame(columns=["r", "l", "t", "is_success", "outcome"])
    return df.sort_values("t").reset_index(drop=True)


def save_reward_curve(monitor_dir: Path, out: Path, *, window: int = 50,
                      title: str = "") -> Path | None:
    """Write ``out`` (PNG); ``None`` (nothing written) before the first finished episode."""
    df = episode_table(monitor_dir)
    if df.empty:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    episodes = range(1, len(df) + 1)
    fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
    ax.plot(episodes, df["r"], color="tab:blue", alpha=0.3, lw=0.8, label="episode reward")
    ax.plot(episodes, df["r"].rolling(window, min_periods=1).mean(), color="tab:blue", lw=2,
            label=f"moving average ({window} episodes)")
    ax.set_xlabel("episode")
    ax.set_ylabel("reward")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
