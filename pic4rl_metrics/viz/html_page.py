"""The HTML report's page: one self-contained file, its style, its plain JavaScript (tables
sorted by a click on a column's header, filtered by the words typed above them, each figure's
save link pointed at its image) and the tables', figures' and downloads' markup. Tables wrap
to fit a laptop's width (text at spaces, links and long cells anywhere, numbers never). No
server, no CDN, no network: what ``html_report`` writes opens offline and travels as an e-mail
attachment.
"""

from __future__ import annotations

import html
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from urllib.parse import quote

_CSS = """
body{font:14px/1.4 system-ui,-apple-system,'Segoe UI',sans-serif;margin:0 auto;max-width:1280px;
padding:0 16px 40px;color:#222}
h1{font-size:1.6em;margin:18px 0 4px}h2{margin-top:32px;border-bottom:1px solid #ddd}
nav a{margin-right:12px}.note{color:#555;font-size:.92em;max-width:60em}
table{border-collapse:collapse;margin:8px 0;font-size:.92em;max-width:100%}
th,td{border:1px solid #ddd;padding:3px 6px;text-align:left;vertical-align:top;
overflow-wrap:break-word}td.num{white-space:nowrap}
th{background:#f3f3f3;position:sticky;top:0;font-weight:600;overflow-wrap:normal}
table.sortable th{cursor:pointer;user-select:none}
th[data-dir=asc]::after{content:' \\25B2'}th[data-dir=desc]::after{content:' \\25BC'}
td.num{text-align:right;font-variant-numeric:tabular-nums}
tr.error td{background:#fdecea}.maps{display:flex;flex-wrap:wrap;gap:12px}
figure{margin:0;border:1px solid #ddd;padding:4px}figcaption{font-size:.85em;max-width:280px}
a.save{margin-left:6px;font-size:.9em}.provenance{color:#555;margin:0 0 6px}
details summary{cursor:pointer;color:#333}.exports a{margin-right:10px}
.key span{display:inline-block;margin-right:12px}.sw{display:inline-block;width:11px;height:11px;
margin-right:4px;vertical-align:middle}input.filter{width:28em;padding:3px}
.scroll{max-height:70vh;overflow:auto}
#inputs td,#errors td,#episodes td:last-child,td a{overflow-wrap:anywhere}
"""

_JS = """
'use strict';
function sortValue(td) {
  const raw = td.dataset.v !== undefined ? td.dataset.v : td.textContent.trim();
  if (raw === '' || raw === '\\u2013') return null;
  const n = Number(raw);
  return Number.isNaN(n) ? raw.toLowerCase() : n;
}
function compare(x, y) {
  if (x === null || y === null) return x === y ? 0 : (x === null ? 1 : -1);
  if (typeof x !== typeof y) return typeof x === 'number' ? -1 : 1;
  return x < y ? -1 : (x > y ? 1 : 0);
}
function sortBy(th) {
  const table = th.closest('table');
  const col = Array.prototype.indexOf.call(th.parentNode.cells, th);
  const asc = th.dataset.dir !== 'asc';
  table.querySelectorAll('th').forEach(function (h) { delete h.dataset.dir; });
  th.dataset.dir = asc ? 'asc' : 'desc';
  const body = table.tBodies[0];
  const rows = Array.from(body.rows);
  rows.sort(function (a, b) {
    const x = sortValue(a.cells[col]), y = sortValue(b.cells[col]);
    if (x === null || y === null) return compare(x, y);
    return asc ? compare(x, y) : compare(y, x);
  });
  rows.forEach(function (r) { body.appendChild(r); });
}
function filterRows(input) {
  const table = document.getElementById(input.dataset.table);
  const words = input.value.toLowerCase().split(/\\s+/).filter(Boolean);
  let shown = 0;
  Array.from(table.tBodies[0].rows).forEach(function (tr) {
    const text = tr.textContent.toLowerCase();
    tr.hidden = !words.every(function (w) { return text.includes(w); });
    if (!tr.hidden) shown += 1;
  });
  const count = document.getElementById(input.dataset.table + '-count');
  if (count) count.textContent = shown + ' of ' + table.tBodies[0].rows.length + ' rows';
}
document.querySelectorAll('table.sortable th').forEach(function (th) {
  th.addEventListener('click', function () { sortBy(th); });
});
document.querySelectorAll('input.filter').forEach(function (input) {
  input.addEventListener('input', function () { filterRows(input); });
});
document.querySelectorAll('figure').forEach(function (fig) {
  const img = fig.querySelector('img'), save = fig.querySelector('a.save');
  if (img && save) save.href = img.src;  // the image's own data: URI, not a second copy
});
"""


@dataclass(frozen=True)
class Cell:
    """A table cell: its markup (already escaped) and the value it sorts by (``data-v``)."""

    markup: str
    sort: str | None = None
    numeric: bool = False


def text(value: object) -> Cell:
    """A text cell; None and NaN (a missing fact of a pandas row) are "–"."""
    missing = value is None or (isinstance(value, float) and math.isnan(value))
    return Cell("–" if missing else html.escape(str(value)))


def number(value: object, digits: int = 2, suffix: str = "") -> Cell:
    """A right-aligned number sorting by its full value; missing (None, NaN) is "–"."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return Cell("–", "", numeric=True)
    v = float(value)  # type: ignore[arg-type]
    shown = f"{v:.{digits}f}{suffix}" if digits else f"{int(round(v))}{suffix}"
    return Cell(html.escape(shown), repr(v), numeric=True)


def shown_as(markup_text: str, sort: float | str | None) -> Cell:
    """A right-aligned cell showing ``markup_text`` (escaped here) that sorts by ``sort``."""
    missing = sort is None or (isinstance(sort, float) and math.isnan(sort))
    return Cell(html.escape(markup_text), "" if missing else str(sort), numeric=True)


def link(label: str, href: str | None, cls: str = "", title: str | None = None) -> Cell:
    """A relative link (no link when ``href`` is None); ``title``: shown on hover, sorted by
    (default ``label``)."""
    if href is None:
        return Cell("–")
    attr = (f' class="{cls}"' if cls else "") + (
        f' title="{html.escape(title)}"' if title else "")
    return Cell(f'<a{attr} href="{html.escape(href)}">{html.escape(label)}</a>', title or label)


def _td(c: Cell) -> str:
    num = " class=num" if c.numeric else ""
    sort = "" if c.sort is None else f' data-v="{html.escape(c.sort)}"'
    return f"<td{num}{sort}>{c.markup}</td>"


def table(table_id: str, header: Sequence[str], rows: Sequence[Sequence[Cell]], *,
          filterable: bool = False, row_classes: Sequence[str] | None = None,
          scroll: bool = False) -> str:
    """A sortable table (and, with ``filterable``, a filter box above it)."""
    parts = []
    if filterable:
        parts.append(f'<p><input class="filter" type="search" data-table="{table_id}" '
                     f'placeholder="filter: words every shown row contains" '
                     f'aria-label="filter {table_id}"> <span id="{table_id}-count">'
                     f'{len(rows)} of {len(rows)} rows</span></p>')
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        cls = f' class="{row_classes[i]}"' if row_classes and row_classes[i] else ""
        cells = "".join(_td(c) for c in row)
        body.append(f"<tr{cls}>{cells}</tr>")
    markup = (f'<table id="{table_id}" class="sortable"><thead><tr>{head}</tr></thead>'
              f'<tbody>{"".join(body)}</tbody></table>')
    parts.append(f'<div class="scroll">{markup}</div>' if scroll else markup)
    return "\n".join(parts)


def figure(uri: str, caption: str, alt: str) -> str:
    """An inline image with its caption (``caption`` is markup, already escaped) and a link
    that saves it as ``<alt>.png`` (its address is the image's, set by the page's script)."""
    name = re.sub(r"[^\w.-]+", "_", alt).strip("_") or "figure"
    return (f'<figure><img src="{uri}" alt="{html.escape(alt)}">'
            f'<figcaption>{caption} <a class="save" download="{html.escape(name)}.png" '
            f'title="save this figure">PNG</a></figcaption></figure>')


def download(label: str, name: str, mime: str, content: str) -> str:
    """A link that saves ``content`` as the file ``name`` (a ``data:`` URI: no server)."""
    href = f"data:{mime};charset=utf-8,{quote(content)}"
    return (f'<a class="export" download="{html.escape(name)}" href="{html.escape(href)}">'
            f"{html.escape(label)}</a>")


def swatch(rgb: tuple[int, int, int], label: str) -> str:
    r, g, b = rgb
    return (f'<span><i class="sw" style="background:rgb({r},{g},{b})"></i>'
            f"{html.escape(label)}</span>")


def page(title: str, sections: Sequence[tuple[str, str, str]], intro: str = "") -> str:
    """The whole page: a title, a table of contents, ``sections`` (id, heading, markup)."""
    nav = "".join(f'<a href="#sec-{sid}">{html.escape(head)}</a>' for sid, head, _ in sections)
    body = "\n".join(f'<section id="sec-{sid}"><h2>{html.escape(head)}</h2>\n{markup}</section>'
                     for sid, head, markup in sections)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{html.escape(title)}</title><style>{_CSS}</style></head>\n<body>"
            f"<h1>{html.escape(title)}</h1>{intro}<nav>{nav}</nav>\n{body}\n"
            f"<script>{_JS}</script></body></html>\n")
