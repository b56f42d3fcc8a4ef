"""The house rules of the code, checked on the source (docs/architecture.md).

- Imports go one way: ground floor → raster → geometry → project → domains → processing
  declarations → faces; the domains among themselves form no cycle.
- No function in ``algorithms/`` or ``plugin/`` is longer than 120 lines, except the few listed
  in ``docs/architecture.md`` with their reason.
- An import inside a function says why it is there (``# lazy: …``, ``# optional: …``, a
  platform or version check); modules that ``photodem list`` loads may say it once at the top.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import Dict, Iterator, List, Set, Tuple

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("algorithms", "plugin")
MAX_LINES = 120

#: Layer of each top-level unit of ``algorithms/`` (a package or a module), low to high.
GROUND = ("errors", "compat", "feedback", "jsonable", "linalg", "memory", "output_policy",
          "input_errors", "crs_check", "proj_env")
LAYERS: Dict[str, int] = {
    **dict.fromkeys(GROUND, 0),
    "raster": 1,
    "geometry": 2,
    "project": 3,
    **dict.fromkeys(("quality", "surface", "filtering", "matching", "ortho", "georef",
                     "synthetic"), 4),
    "processing": 5,
    **dict.fromkeys(("cli", "cli_entry", "cli_feedback", "demo", "plugin"), 6),
}


def _modules() -> Iterator[Path]:
    for top in SOURCES:
        yield from sorted((ROOT / top).rglob("*.py"))


def _unit(path: Path) -> str:
    """The top-level unit a source file belongs to (``plugin`` for all of ``plugin/``)."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    return "plugin" if parts[0] == "plugin" else parts[1]


def _imported_units(path: Path, tree: ast.AST) -> Iterator[Tuple[str, int]]:
    """Units of ``algorithms`` that ``path`` imports, with the line of each import."""
    package = list(path.relative_to(ROOT).with_suffix("").parts[:-1])
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            base = package[: len(package) - (node.level - 1)]
            target = base + (node.module.split(".") if node.module else [])
            if target[:1] == ["algorithms"] and len(target) > 1:
                yield target[1], node.lineno
            elif target[:1] == ["algorithms"]:  # ``from .. import x`` at the root
                for alias in node.names:
                    yield alias.name, node.lineno
        elif node.module and node.module.startswith("photodem.algorithms."):
            yield node.module.split(".")[2], node.lineno


def _graph() -> Dict[str, Set[str]]:
    edges: Dict[str, Set[str]] = {}
    for path in _modules():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        src = _unit(path)
        for dst, _ in _imported_units(path, tree):
            if dst != src:
                edges.setdefault(src, set()).add(dst)
    return edges


def test_every_unit_has_a_layer() -> None:
    units = {_unit(p) for p in _modules()} - {"__init__"}
    assert units <= set(LAYERS), f"give these a layer: {sorted(units - set(LAYERS))}"


def test_imports_go_down_the_layers() -> None:
    wrong: List[str] = []
    for path in _modules():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        src = _unit(path)
        for dst, line in _imported_units(path, tree):
            if dst in LAYERS and src in LAYERS and LAYERS[dst] > LAYERS[src]:
                wrong.append(f"{path.relative_to(ROOT)}:{line} imports {dst}")
    assert not wrong, "imports against the layers:\n" + "\n".join(wrong)


def test_no_cycle_between_units() -> None:
    edges = _graph()
    state: Dict[str, int] = {}
    stack: List[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == 1:
                cycle = stack[stack.index(nxt):] + [nxt]
                pytest.fail("import cycle: " + " → ".join(cycle))
            if nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for unit in sorted(edges):
        if unit not in state:
            visit(unit)


def _allowed_long() -> Set[str]:
    """``module:function`` names that docs/architecture.md allows above the limit."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text.split("## Long functions", 1)[-1].split("\n## ", 1)[0]
    return set(re.findall(r"`([\w/.]+\.py:\w+)`", section))


def test_functions_are_short() -> None:
    allowed = _allowed_long()
    long: List[str] = []
    for path in _modules():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                name = f"{path.relative_to(ROOT).as_posix()}:{node.name}"
                if lines > MAX_LINES and name not in allowed:
                    long.append(f"{name} ({lines} lines)")
    assert not long, "functions over 120 lines:\n" + "\n".join(long)


#: Modules ``photodem list`` loads: they may say once, at the top, that their function-level
#: imports are lazy (the declarations import their domain modules inside ``run``).
LIST_MODULES = ("algorithms/cli.py", "algorithms/processing/")
_REASON = re.compile(r"#.*\b(lazy|optional|platform|version)\b")
_MODULE_REASON = re.compile(r"photodem list")


def _header_says_lazy(path: Path, lines: List[str]) -> bool:
    rel = path.relative_to(ROOT).as_posix()
    return rel.startswith(LIST_MODULES) and any(_MODULE_REASON.search(ln) for ln in lines[:40])


def test_imports_inside_functions_say_why() -> None:
    silent: List[str] = []
    for path in _modules():
        source = path.read_text(encoding="utf-8")
        lines = source.splitlines()
        if _header_says_lazy(path, lines):
            continue
        tree = ast.parse(source)
        for func in ast.walk(tree):
            if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(func):
                if not isinstance(node, (ast.Import, ast.ImportFrom)):
                    continue
                # The reason is on the import, or on a comment line just above the block.
                above = lines[max(0, node.lineno - 6): node.end_lineno]
                if not any(_REASON.search(ln) for ln in above):
                    silent.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not silent, "imports inside functions without a reason:\n" + "\n".join(silent)
