"""The house rules (docs/architecture.md), checked on robotkit's own source: no import circle
(imports inside functions count), no function over 80 lines, no private name imported from
another module, and the import-linter layers contract.  ruff runs in .ci/run beside them."""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "robotkit"
MAX_LINES = 80


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _owner(name: str) -> str | None:
    """The robotkit module that ``name`` (a module or a name inside one) belongs to."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _imports(module: str, tree: ast.AST):
    """(imported module, imported name or None) of every import statement, at any depth."""
    package = module if MODULES[module].name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from ((a.name, None) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([node.module] if node.module else []))
            for a in node.names:
                full = f"{base}.{a.name}"
                yield (full, None) if full in MODULES else (base, a.name)


def _trees():
    return {m: ast.parse(p.read_text(encoding="utf-8")) for m, p in MODULES.items()}


TREES = _trees()


def test_no_import_circle():
    graph = nx.DiGraph()
    for module, tree in TREES.items():
        for target, _ in _imports(module, tree):
            owner = _owner(target)
            if owner and owner != module:
                graph.add_edge(module, owner)
    circles = [sorted(c) for c in nx.strongly_connected_components(graph) if len(c) > 1]
    assert circles == []


def test_no_function_over_80_lines():
    long = [f"{m}::{n.name} ({n.end_lineno - n.lineno + 1} lines)"
            for m, tree in TREES.items() for n in ast.walk(tree)
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.end_lineno - n.lineno + 1 > MAX_LINES]
    assert long == []


def test_no_private_name_imported_across_modules():
    private = [f"{m} imports {target}.{name}" for m, tree in TREES.items() for target, name in _imports(m, tree)
               if name and name.startswith("_") and not name.startswith("__") and _owner(target) not in (None, m)]
    assert private == []


def test_layers_contract():
    """cli -> commands -> pipeline/check/importer/picture -> emit/world/mesh -> model -> recipe -> the bottom."""
    lint = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
    if lint is None:
        pytest.fail("lint-imports (import-linter) is not installed: bash scripts/setup.sh --test installs it")
    run = subprocess.run([lint], cwd=PACKAGE.parent, capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-3000:]
