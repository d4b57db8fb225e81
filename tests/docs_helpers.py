"""What the docs-vs-code tests share (tests/docs): a config dataclass's
parameter rows as the docs write them, and reading Markdown sections, tables, anchors and
links."""

from __future__ import annotations

import re
from pathlib import Path

from pic4rl_base.schema import TYPE_NAMES, literal, specs


def parameter_rows(cls: type) -> dict[str, tuple[str, str]]:
    """Every dotted parameter of the config dataclass ``cls`` → (type, `default`) as the code
    has them."""
    return {spec.name: (TYPE_NAMES[spec.type], f"`{literal(spec.default)}`")
            for spec in specs(cls)}


def section(doc: str, heading: str) -> str:
    """The text under the Markdown heading ``heading``, up to the next heading of the same or a
    higher level (lines inside code blocks are not headings)."""
    level = len(heading) - len(heading.lstrip("#"))
    lines = doc.splitlines()
    try:
        start = lines.index(heading)
    except ValueError:
        raise AssertionError(f"no heading {heading!r} in the doc") from None
    end, fenced = len(lines), False
    for i in range(start + 1, len(lines)):
        if lines[i].startswith("```"):
            fenced = not fenced
        match = re.match(r"(#+) ", lines[i])
        if match and not fenced and len(match.group(1)) <= level:
            end = i
            break
    return "\n".join(lines[start + 1:end])


def table_rows(text: str) -> dict[str, list[str]]:
    """Rows of the Markdown tables in ``text`` whose first cell is one backticked name: name →
    the other cells. A name listed twice is an error."""
    rows: dict[str, list[str]] = {}
    for line in text.splitlines():
        match = re.match(r"\| `([^`]+)` \|(.*)\|\s*$", line)
        if match is None:
            continue
        name = match.group(1)
        assert name not in rows, f"the doc lists {name!r} twice in one section"
        rows[name] = [cell.strip() for cell in re.split(r"(?<!\\)\|", match.group(2))]
    return rows


def anchors(path: Path) -> set[str]:
    """GitHub's anchors of the headings of ``path`` (outside code blocks)."""
    out, fenced = set(), False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            fenced = not fenced
        match = re.match(r"#+ (.+)", line)
        if match and not fenced:
            text = re.sub(r"[^\w\- ]", "", match.group(1).lower())
            out.add(text.replace(" ", "-"))
    return out


def broken_links(path: Path) -> tuple[int, list[str]]:
    """How many relative links ``path`` has, and those whose file or heading does not exist."""
    links = [link for link in re.findall(r"\]\(([^)\s]+)\)", path.read_text(encoding="utf-8"))
             if "://" not in link]
    broken = []
    for link in links:
        target, _, anchor = link.partition("#")
        file = path if not target else path.parent / target
        if not file.exists() or (anchor and anchor not in anchors(file)):
            broken.append(link)
    return len(links), broken
