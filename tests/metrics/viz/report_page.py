"""A parser of the report's page for its tests: headings, images, links, scripts and table
rows by table id."""

from __future__ import annotations

from html.parser import HTMLParser


class Page(HTMLParser):
    """The page's headings, images, links, scripts and table rows by table id."""

    def __init__(self) -> None:
        super().__init__()
        self.h2: list[str] = []
        self.images: list[str] = []
        self.links: list[tuple[str, str]] = []
        self.external: list[str] = []
        self.rows: dict[str, list[list[str]]] = {}
        self._table: str | None = None
        self._cell: list[str] | None = None
        self._in_h2 = False
        self.section = ""  # the id of the section being read
        self.section_images: dict[str, list[str]] = {}  # each section's images' alt texts
        self.text: list[str] = []  # every piece of text, in order
        self.anchors: list[dict[str, str | None]] = []  # every link's attributes
        self.folded: set[str] = set()  # ids of the tables inside a <details>
        self._details = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if tag == "h2":
            self._in_h2 = True
            self.h2.append("")
        elif tag == "section":
            self.section = str(a.get("id"))
        elif tag == "img":
            self.images.append(str(a.get("src")))
            self.section_images.setdefault(self.section, []).append(str(a.get("alt")))
        elif tag == "a":
            self.links.append((str(a.get("class") or ""), str(a.get("href"))))
            self.anchors.append(a)
        elif tag == "details":
            self._details += 1
        elif tag in ("script", "link", "iframe") and (a.get("src") or a.get("href")):
            self.external.append(f"{tag} {a}")
        elif tag == "table":
            self._table = str(a.get("id"))
            self.rows[self._table] = []
            if self._details:
                self.folded.add(self._table)
        elif tag == "tr" and self._table:
            self.rows[self._table].append([])
        elif tag in ("td", "th") and self._table:
            self._cell = []

    def handle_endtag(self, tag: str) -> None:
        if tag == "details":
            self._details -= 1
        if tag == "h2":
            self._in_h2 = False
        elif tag in ("td", "th") and self._cell is not None and self._table:
            self.rows[self._table][-1].append("".join(self._cell).strip())
            self._cell = None
        elif tag == "table":
            self._table = None

    def handle_data(self, data: str) -> None:
        self.text.append(data)
        if self._in_h2:
            self.h2[-1] += data
        if self._cell is not None:
            self._cell.append(data)
