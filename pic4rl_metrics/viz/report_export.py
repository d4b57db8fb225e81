"""The report's leaderboard as files to download from the page: CSV and LaTeX, exactly the
tables ``pic4rl-metrics compare --format csv|latex`` writes for the same episodes (one table
per task and world set, the paper's Table 1 layout in LaTeX), carried in ``data:`` URIs so the
page stays one self-contained file.
"""

from __future__ import annotations

import pandas as pd

from ..core.registry import METRICS
from ..tables.groups import render_groups
from ..tables.results import table_columns
from . import html_page as hp

#: The formats offered: (``compare``'s format, link label, file name, MIME type).
EXPORTS = (("csv", "CSV", "leaderboard.csv", "text/csv"),
           ("latex", "LaTeX", "leaderboard.tex", "application/x-tex"))


def _columns(rows: pd.DataFrame) -> list[str]:
    """``compare``'s numeric columns for these episodes (its ``_shown`` with every metric)."""
    return [c for c in table_columns(rows) if c == "success" or not METRICS[c].text]


def leaderboard_table(frame: pd.DataFrame, fmt: str) -> str:
    """``frame``'s per-agent table in ``fmt`` (``csv``, ``latex``), as ``compare`` writes it."""
    return render_groups(frame, fmt, columns=_columns)


def leaderboard_downloads(frame: pd.DataFrame) -> str:
    """The links that save ``frame``'s leaderboard as CSV and LaTeX."""
    links = [hp.download(label, name, mime, leaderboard_table(frame, fmt))
             for fmt, label, name, mime in EXPORTS]
    return ('<p class="exports">Save the leaderboard: ' + "".join(links)
            + "(the tables <code>pic4rl-metrics compare --format csv|latex</code> writes)</p>")
