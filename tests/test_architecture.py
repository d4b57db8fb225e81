"""docs/architecture.md against the tree: every path it writes in backticks exists, every package
directory is named, and the bridge's door (no torch, SB3 or agents) holds."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "architecture.md"
PACKAGES = ("pic4rl_sim", "pic4rl_bridge", "pic4rl_agents", "pic4rl_metrics")
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
