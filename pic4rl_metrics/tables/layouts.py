"""Text layouts of a table: header rows and text cells (``None`` = missing) as one string in
one of ``FORMATS`` (fixed-width text, markdown, CSV, a booktabs LaTeX tabular, JSON). The
reports (``report``) and pic4rl's benchmark tables lay out their cells through these.
"""

from __future__ import annotations

import csv
import difflib
import io
import json
from collections.abc import Sequence

from pic4rl_base.errors import ConfigError

from .aggregate import DASH

FORMATS: tuple[str, ...] = ("table", "csv", "json", "markdown", "latex")

_LATEX_SPECIAL = {c: "\\" + c for c in "&%$#_{}"}
_LATEX_SPECIAL.update({"\\": r"\textbackslash{}", "~": r"\textasciitilde{}", "^": r"\^{}"})


def check_format(fmt: str) -> str:
    if fmt not in FORMATS:
        close = difflib.get_close_matches(str(fmt), FORMATS, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        msg = f"format {fmt!r} is not supported; expected one of {', '.join(FORMATS)}{hint}"
        raise ConfigError(msg)
    return fmt


def latex_escape(text: str) -> str:
    """``text`` with LaTeX's special characters (``_``, ``%``, ``&``, ...) escaped."""
    return "".join(_LATEX_SPECIAL.get(c, c) for c in str(text))


def _fill(rows: list[list[str | None]], missing: str) -> list[list[str]]:
    return [[missing if c is None else c for c in row] for row in rows]


def fixed_width(headers: list[list[str]], rows: list[list[str | None]], right: list[bool]) -> str:
    body = _fill(rows, DASH)
    widths = [max(len(r[i]) for r in headers + body) for i in range(len(right))]

    def line(cells: list[str]) -> str:
        parts = [c.rjust(w) if r else c.ljust(w) for c, w, r in zip(cells, widths, right)]
        return "  ".join(parts).rstrip()

    rule = "  ".join("-" * w for w in widths)
    return "\n".join([*(line(h) for h in headers), rule, *(line(r) for r in body)]) + "\n"


def markdown(header: list[str], rows: list[list[str | None]], right: list[bool]) -> str:
    def line(cells: list[str]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"

    rule = "|" + "|".join("---:" if r else ":---" for r in right) + "|"
    return "\n".join([line(header), rule, *(line(r) for r in _fill(rows, DASH))]) + "\n"


def tabular(headers: list[list[str]], rows: list[list[str | None]]) -> list[str]:
    """Booktabs tabular lines; cells must already be LaTeX."""
    lines = [rf"\begin{{tabular}}{{@{{}}{'c' * len(headers[0])}@{{}}}}", r"\toprule"]
    lines += [" & ".join(h) + r" \\" for h in headers]
    lines.append(r"\midrule")
    lines += [" & ".join(r) + r" \\" for r in _fill(rows, "--")]
    return [*lines, r"\bottomrule", r"\end{tabular}"]


def csv_text(header: list[str], rows: list[list[str | None]]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerows([header, *_fill(rows, "")])
    return buf.getvalue()


def render_rows(header: Sequence[str], rows: Sequence[Sequence[str | None]], fmt: str) -> str:
    """A plain table of text cells (None = missing) in table, markdown, csv or latex (a
    booktabs tabular, cells escaped): for tables whose columns are not metrics alone."""
    if check_format(fmt) == "json":
        return json.dumps([dict(zip(header, r)) for r in rows], indent=2, ensure_ascii=False) + "\n"
    head, body = list(header), [list(r) for r in rows]
    right = [False] * len(head)
    if fmt == "csv":
        return csv_text(head, body)
    if fmt == "markdown":
        return markdown(head, body, right)
    if fmt == "table":
        return fixed_width([head], body, right)
    tex = [[None if c is None else latex_escape(c) for c in r] for r in body]
    return "\n".join(tabular([[latex_escape(h) for h in head]], tex)) + "\n"
