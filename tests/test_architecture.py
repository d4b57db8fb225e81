"""docs/architecture.md against the tree: every path it writes in backticks exists, every package
directory is named, and the bridge's door (no torch, SB3 or agents) holds."""

from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest
from import_helpers import imports, module_name

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "architecture.md"
PACKAGES = ("pic4rl_base", "pic4rl_sim", "pic4rl_bridge", "pic4rl_agents", "pic4rl_metrics")
#: Roots of the repository paths the doc may write; a token with a placeholder is no path.
PATH = re.compile(r"(?:pic4rl_\w+|tests|docs|config)(?:/[\w.]+)*/?")
BRIDGE_NEVER = ("torch", "stable_baselines3", "sb3_contrib", "optuna", "pic4rl_agents")


def _tokens() -> list[str]:
    return re.findall(r"`([^`\n]+)`", DOC.read_text(encoding="utf-8"))


def _module_exists(dotted: str) -> bool:
    """``pic4rl_x.a.b``: each part a package, until a module; what follows a module is an
    attribute and not checked."""
    path = ROOT
    for part in dotted.split("."):
        if (path / f"{part}.py").is_file():
            return True
        path = path / part
        if not (path / "__init__.py").is_file():
            return False
    return True


def test_every_path_the_doc_names_exists() -> None:
    paths = [t for t in _tokens() if PATH.fullmatch(t)]
    modules = [t for t in _tokens() if re.fullmatch(r"pic4rl_\w+(\.\w+)+", t)]
    assert len(paths) > 30, "the doc names too few paths; did the backticks change?"
    missing = sorted({p for p in paths if not (ROOT / p).exists()}
                     | {m for m in modules if not _module_exists(m)})
    assert not missing, f"docs/architecture.md names paths that do not exist: {missing}"


def test_every_package_directory_is_named() -> None:
    named = {t.rstrip("/") for t in _tokens()}
    directories = sorted(
        str(d.relative_to(ROOT)) for package in PACKAGES
        for d in [ROOT / package, *(ROOT / package).rglob("*")]
        if d.is_dir() and d.name != "__pycache__")
    assert len(directories) >= len(PACKAGES)
    unnamed = [d for d in directories if d not in named]
    assert not unnamed, f"docs/architecture.md does not name {unnamed}"


def _imported_roots(path: Path) -> set[str]:
    roots = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            roots |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split(".")[0])
    return roots


@pytest.mark.parametrize("path", sorted((ROOT / "pic4rl_bridge").rglob("*.py")),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_the_bridge_imports_no_torch_sb3_or_agents(path: Path) -> None:
    assert not _imported_roots(path) & set(BRIDGE_NEVER)


# -- the places for a new piece -----------------------------------------------------------------

#: The most places each piece may take (issue 39); every other piece takes one or two.
MOST_PLACES = {"a sensor": 3, "a task": 3, "a metric": 1}
#: The pieces added from outside the packages by ``tests/places/test_places.py``: their places
#: are the files of their folder there.
EXECUTED = {"a metric": "metric", "a baseline": "baseline", "a task": "task", "a sensor": "sensor"}
#: A place: a backticked repository file, then optionally ``: `Symbol```.
PLACE = re.compile(r"`([^`]+)`(?::\s*`([^`]+)`)?")
FILE = re.compile(r"(?:pic4rl_\w+|config|scripts|tools|benchmarks|tests/places)/[\w./<>-]*\.\w+")


def _places_rows() -> dict[str, tuple[int, list[list[tuple[str, str | None]]], str]]:
    """``to add`` → (the count the doc gives, its places, its docs cell) of the "Places"
    table. Every backticked file of the "where" cell is a place's, parentheses or not; the
    files of one ``;`` item are one place's alternatives."""
    text = DOC.read_text(encoding="utf-8").split("## Places for a new piece", 1)[1]
    rows = {}
    for line in text.split("\n## ", 1)[0].splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or not cells[1].isdigit():
            continue
        places = []
        for item in cells[2].split(";"):
            files = [(m[1], m[2]) for m in PLACE.finditer(item) if FILE.fullmatch(m[1])]
            if files:
                places.append(files)
        rows[cells[0]] = (int(cells[1]), places, cells[3])
    return rows


def _defines(path: Path, symbol: str) -> bool:
    """``symbol`` (``Name`` or ``Class.member``) is defined or assigned at the start of a line
    of ``path``."""
    name = symbol.rsplit(".", 1)[-1]
    return re.search(rf"^\s*(?:class |def )?{re.escape(name)}\b\s*[:=(]", path.read_text(),
                     re.M) is not None


def test_the_places_for_a_new_piece_are_counted_and_exist() -> None:
    rows = _places_rows()
    wanted = {"a sim parameter", "an env parameter", "a trainer parameter", "a recorded topic",
              "a topic the metrics read", "an episode fact", "a sensor",
              "a sensor a task observes", "a task", "a robot", "a world", "a metric",
              "a baseline", "an algorithm"}
    assert wanted <= set(rows), f"the Places table lacks {sorted(wanted - set(rows))}"
    for piece, (count, places, docs) in rows.items():
        assert count == len(places), f"{piece}: the count says {count}, the cell lists {places}"
        most = MOST_PLACES.get(piece, 2)
        assert count <= most, f"{piece}: {count} places, at most {most}"
        code = [m[1] for m in PLACE.finditer(docs) if FILE.fullmatch(m[1])]
        assert not code, f"{piece}: the docs cell names code files {code}; they are places"
        for files in places:
            for path, symbol in files:
                if "<" in path:  # a new file: its folder exists and holds others of its kind
                    pattern = re.sub(r"<[^>]+>", "*", path)
                    assert list(ROOT.glob(pattern)), f"{piece}: nothing matches {pattern}"
                    continue
                assert (ROOT / path).is_file(), f"{piece}: {path} does not exist"
                assert symbol is None or _defines(ROOT / path, symbol), \
                    f"{piece}: {path} defines no {symbol}"


def test_an_executed_piece_is_placed_in_the_files_its_test_wrote() -> None:
    """A metric's, a baseline's, a task's and a sensor's places are exactly the files of its
    folder under ``tests/places/`` (which ``tests/places/test_places.py`` installs and runs),
    so that their counts are what adding one from outside took."""
    rows = _places_rows()
    for piece, folder in EXECUTED.items():
        named = sorted(path for files in rows[piece][1] for path, _ in files)
        written = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tests" / "places" / folder)
                         .rglob("*") if p.is_file() and "__pycache__" not in p.parts)
        assert named == written, f"{piece}: the table places {named}; the test wrote {written}"


def test_a_place_with_several_files_names_them_as_alternatives() -> None:
    """One ``;`` item may name several files only as "or" alternatives, so that no second
    place hides in a first one's item."""
    text = DOC.read_text(encoding="utf-8").split("## Places for a new piece", 1)[1]
    for line in text.split("\n## ", 1)[0].splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or not cells[1].isdigit():
            continue
        for item in cells[2].split(";"):
            spans = [m.span() for m in PLACE.finditer(item) if FILE.fullmatch(m[1])]
            for (_, end), (start, _) in zip(spans, spans[1:]):
                assert re.search(r"\bor\b", item[end:start]), \
                    f"{cells[0]}: {item[end:start]!r} joins two files of one place without 'or'"


# -- module sizes and import circles ------------------------------------------------------------

def _package_modules() -> list[Path]:
    return sorted(p for package in PACKAGES for p in (ROOT / package).rglob("*.py"))


def test_no_package_module_is_over_350_lines() -> None:
    long = {str(p.relative_to(ROOT)): n for p in _package_modules()
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 350}
    assert not long, f"modules over 350 lines: {long}"


def test_no_package_folder_holds_more_than_12_modules() -> None:
    """A folder past a dozen modules is a room waiting to be named (issue 31)."""
    folders: dict[str, int] = {}
    for p in _package_modules():
        if p.name != "__init__.py":
            folder = str(p.parent.relative_to(ROOT))
            folders[folder] = folders.get(folder, 0) + 1
    crowded = {f: n for f, n in folders.items() if n > 12}
    assert len(folders) > 20 and not crowded, f"folders over 12 modules: {crowded}"


def _imports(path: Path, name: str) -> set[str]:
    """Every package module ``path`` imports, wherever the import stands (in a function, under
    ``TYPE_CHECKING``): a circle that only types or late imports keep apart is still one."""
    return {m for base, names, _ in imports(path, name)
            for m in (base, *(f"{base}.{n}" for n in names))}


def test_no_two_package_modules_import_each_other_in_a_circle() -> None:
    modules = {module_name(p): p for p in _package_modules()}
    graph = {name: {m for m in _imports(path, name) if m in modules and m != name}
             for name, path in modules.items()}
    # a package's __init__ re-exporting its own modules is no circle of theirs
    graph = {n: {m for m in deps if not n.startswith(m + ".")} for n, deps in graph.items()}
    circles = []
    state: dict[str, int] = {}

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for dep in sorted(graph[node]):
            if state.get(dep) == 1:
                circles.append(stack[stack.index(dep):] + [dep])
            elif dep not in state:
                visit(dep, [*stack, dep])
        state[node] = 2

    for name in sorted(graph):
        if name not in state:
            visit(name, [name])
    assert not circles, f"import circles: {circles}"


#: What the metrics' math may not reach, directly or through another module: reading bags,
#: tables, pictures and the command line sit above it.
CORE_NEVER = tuple(f"pic4rl_metrics.{room}" for room in ("bags", "tables", "viz", "cli", "testing"))


def test_the_metrics_core_reaches_no_reading_table_picture_or_cli_module() -> None:
    modules = {module_name(p): p for p in _package_modules()}
    core = sorted(m for m in modules if m.startswith("pic4rl_metrics.core"))
    assert len(core) > 5
    reached, todo = set(core), list(core)
    while todo:
        name = todo.pop()
        for dep in _imports(modules[name], name):
            if dep in modules and dep not in reached:
                reached.add(dep)
                todo.append(dep)
    above = sorted(m for m in reached if m.startswith(CORE_NEVER))
    assert not above, f"pic4rl_metrics/core/ reaches {above}"


# -- sub-package exports --------------------------------------------------------------------------

#: Sub-packages whose ``__init__`` lists its public names (``pic4rl_base.lazy.lazy_exports``).
LAZY = sorted(module_name(p) for package in PACKAGES for p in (ROOT / package).rglob("__init__.py")
              if "lazy_exports(" in p.read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", LAZY)
def test_every_name_a_sub_package_exports_resolves(name: str) -> None:
    module = importlib.import_module(name)
    missing = [n for n in module.__all__ if not hasattr(module, n)]
    assert not missing, f"{name} exports {missing}, which its modules do not define"


def test_importing_the_sub_packages_loads_no_mujoco_or_rclpy() -> None:
    code = (f"import sys\nimport {', '.join(LAZY)}\n"
            "print(sorted({'mujoco', 'rclpy', 'torch'} & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT).stdout.strip()
    assert len(LAZY) >= 6 and out == "[]", out
