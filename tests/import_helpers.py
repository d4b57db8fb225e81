"""What the architecture tests share (tests/test_architecture.py, tests/bridge/test_layers.py):
a module's dotted name, and every import a module makes, wherever it stands (in a function,
under ``TYPE_CHECKING``), with relative imports resolved."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def module_name(path: Path) -> str:
    """``pic4rl_bridge/control/__init__.py`` → ``pic4rl_bridge.control``."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, name: str) -> Iterator[tuple[str, tuple[str, ...], int]]:
    """(module, names imported from it, line) for each import of ``path`` (module ``name``):
    ``import a.b`` gives ``("a.b", (), line)``, ``from .x import y`` the resolved ``x``
    and ``("y",)``."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, (), node.lineno
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1]
                                + ([node.module] if node.module else []))
            yield base, tuple(a.name for a in node.names), node.lineno
