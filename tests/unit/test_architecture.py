"""The package keeps its shape: imports run one way between subpackages, and no module cycle exists.

Every ``import``/``from ... import`` in src/slipchain (top level or inside functions) is parsed
with ``ast``. A subpackage may import only the subpackages listed in ALLOWED (docs/architecture.md,
"Architecture"); the package root (``slipchain/__init__``, the public API) may import anything,
and nothing inside may import it. The module graph must have no cycle.
"""

import ast
import sys
from pathlib import Path

import pytest

from slipchain.results.schema import schema_markdown

SRC = Path(__file__).resolve().parents[2] / "src" / "slipchain"
DOCS = Path(__file__).resolve().parents[2] / "docs"

ALLOWED = {
    "model": set(),
    "results": {"model"},
    "engine": {"model", "results"},
    "sweeps": {"model", "results", "engine"},
    "tester": {"results"},
    "analysis": {"model", "results", "engine", "sweeps", "tester"},
    "plots": {"model", "results", "analysis", "tester"},
    "workflows": {"model", "results", "engine", "sweeps", "tester", "analysis", "plots"},
    "cli": {"model", "results", "engine", "sweeps", "tester", "analysis", "plots", "workflows"},
}
SHARED = {"slipchain._version"}  # importable from anywhere


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in SRC.rglob("*.py")}


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The slipchain modules that module ``name`` imports (relative imports resolved)."""
    is_pkg = path.name == "__init__.py"
    package = name if is_pkg else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("slipchain")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("slipchain"):
                continue
            subs = {f"{target}.{a.name}" for a in node.names} & known  # `from pkg import module`
            out |= subs or {target}
            if subs != {f"{target}.{a.name}" for a in node.names}:
                out.add(target)
    return out & known


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    known = set(mods)
    return {name: _imports(name, path, known) - {name} for name, path in mods.items()}


def _layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in ALLOWED else "root"


def test_every_subpackage_is_in_the_layer_table_and_has_a_docstring():
    for p in SRC.iterdir():
        if p.is_dir() and (p / "__init__.py").exists():
            assert p.name in ALLOWED, f"subpackage {p.name} is missing from ALLOWED (and docs/architecture.md)"
            doc = ast.get_docstring(ast.parse((p / "__init__.py").read_text()))
            assert doc and "\n" not in doc.split("\n\n")[0], f"{p.name}/__init__.py needs a one-line summary docstring"


def test_imports_run_one_way():
    bad = []
    for mod, targets in _graph().items():
        src = _layer(mod)
        for t in targets:
            dst = _layer(t)
            if t in SHARED or dst == src or src == "root" and mod in ("slipchain", "slipchain.__main__"):
                continue
            if dst == "root" or dst not in ALLOWED.get(src, set()):
                bad.append(f"{mod} -> {t} ({src} may import {sorted(ALLOWED.get(src, set()))})")
    assert not bad, "upward or sideways imports:\n" + "\n".join(sorted(bad))


def test_no_import_cycles():
    graph = _graph()
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                pytest.fail("import cycle: " + " -> ".join(stack[stack.index(nxt):] + [nxt]))
            if nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)


def test_the_checker_sees_an_upward_import_and_a_cycle(tmp_path, monkeypatch):
    # The checks above can fail: a model module importing the engine, and two modules importing each other.
    fake = tmp_path / "slipchain"
    (fake / "model").mkdir(parents=True)
    (fake / "engine").mkdir()
    for d in (fake, fake / "model", fake / "engine"):
        (d / "__init__.py").write_text('"""x."""\n')
    (fake / "model" / "a.py").write_text("from ..engine import b\n")
    (fake / "engine" / "b.py").write_text("from ..model import a\n")
    monkeypatch.setattr(sys.modules[__name__], "SRC", fake)
    with pytest.raises(AssertionError, match="slipchain.model.a -> slipchain.engine.b"):
        test_imports_run_one_way()
    with pytest.raises(pytest.fail.Exception, match="import cycle"):
        test_no_import_cycles()


def test_docs_run_schema_is_the_code():
    assert (DOCS / "run-schema.md").read_text() == schema_markdown(), \
        "regenerate: python -m slipchain.results.schema > docs/run-schema.md"
