"""The HTML report's section on logs without a goal: real-robot bags (and any episode whose facts
give no goal) have no success to rank and no failure to map, so the report shows what their
bags do have — per log its time, path, speeds and obstacle distances, and its trajectory from
the pose stream on the map its scans build (``report_maps``).
"""

from __future__ import annotations

import html
from collections.abc import Callable

import pandas as pd

from ..contract import Outcome
from ..tables.text import short_bag
from . import html_page as hp
from .report_maps import PALETTE, Sketch, pair_map, png_uri

#: The logs table's metric columns (time and path over the whole log: there is no success).
LOG_COLUMNS = ("clearance_time_s", "path_length_m", "net_displacement_m", "lin_vel_mean_mps",
               "lin_vel_std_mps", "ang_vel_mean_radps", "obstacle_dist_min_m",
               "footprint_clearance_min_m", "obstacle_dist_mean_m")
#: Columns shown only where some log has a value: the clearance needs a footprint.
WHERE_DEFINED = frozenset({"footprint_clearance_min_m"})
#: At most this many logs get a trajectory map (the rest are counted).
MAX_LOG_MAPS = 200


def goal_less(frame: pd.DataFrame) -> pd.Series:
    """Per row: a read episode whose end nothing can judge (no goal known: ``unknown``)."""
    return (frame["error"].fillna("") == "") & (frame["outcome"] == Outcome.UNKNOWN.value)


def _caption(agent: object, bag: object, row: pd.Series) -> str:
    parts = [f"{row[c]:.2f} {unit}" for c, unit in (("clearance_time_s", "s"),
                                                     ("path_length_m", "m"))
             if c in row and pd.notna(row[c])]
    return (f"<b>{html.escape(str(agent))}</b> · {html.escape(short_bag(bag))}<br>"
            + html.escape(", ".join(parts) or "no time or path"))


def logs_section(frame: pd.DataFrame, names: pd.Series, sketches: dict[int, Sketch],
                 label: Callable[[str], str]) -> str | None:
    """The section's markup, None when every episode has a goal. ``names``: each row's agent;
    ``sketches``: the drawn episodes by row; ``label``: a column's header."""
    rows_of = frame.index[goal_less(frame)]
    if not len(rows_of):
        return None
    columns = [c for c in LOG_COLUMNS if c in frame and (
        c not in WHERE_DEFINED or frame.loc[rows_of, c].notna().any())]
    header = ["agent", "bag", *(label(c) for c in columns)]
    rows = [[hp.text(names[i]), hp.text(short_bag(frame.at[i, "bag"])),
             *(hp.number(frame.at[i, c]) for c in columns)] for i in rows_of]
    agents = list(dict.fromkeys(names[rows_of]))
    colour = {a: PALETTE[k % len(PALETTE)] for k, a in enumerate(agents)}
    drawn = [i for i in rows_of if i in sketches]
    figures = [hp.figure(png_uri(pair_map([(sketches[i], colour[names[i]])])),
                         _caption(names[i], frame.at[i, "bag"], frame.loc[i]),
                         f"trajectory of {short_bag(frame.at[i, 'bag'])}")
               for i in drawn[:MAX_LOG_MAPS]]
    more = len(drawn) - MAX_LOG_MAPS
    tail = f"<p class=note>{more} more logs are not drawn.</p>" if more > 0 else ""
    note = ("<p class=note>Episodes whose facts give no goal (real-robot logs, unless a topic "
            "map or <code>--goal</code> gives one): nothing to succeed or fail at, so they are "
            "out of the leaderboard and the failures. Time and path over the whole log (the "
            "pose stream's span and length), mean and std of the speed, mean yaw rate, "
            "nearest and mean obstacle distance from the scans; each trajectory from the "
            "pose stream (ring: the first pose, dot: the last), on the map its scans build.</p>")
    return (note + hp.table("logs", header, rows)
            + f'<div class="maps">{"".join(figures)}</div>' + tail)
