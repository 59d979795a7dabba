"""The house rules of the package, read from its import statements: arrows only downward, no cycles, the
library never imports the command line, and every stage package says what it does."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "transpiler"

# Floors from the bottom up: a module may import its own floor or lower ones, never a higher one.
FLOORS = [
    ("transpiler.diagnostics", "transpiler.atomic", "transpiler.resources", "transpiler.records"),
    ("transpiler.language",),
    ("transpiler.ir",),
    ("transpiler.frontend",),
    ("transpiler.backends",),
    ("transpiler.exec",),
    ("transpiler.verify",),
    ("transpiler.api",),
    ("transpiler.cli",),
]
STAGE_PACKAGES = ["frontend", "language", "backends", "backends/st", "backends/plcopen", "backends/report",
                  "backends/twincat", "exec",
                  "exec/interp", "exec/stexec", "exec/compiled", "verify", "cli"]


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """Every module of the package that `name` imports, at module level or inside functions."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
        else:
            continue
        for target in targets:
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target.startswith("transpiler") and target != name and target != "transpiler":
                found.add(target)
    return found


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def _floor(module: str) -> int:
    for level, prefixes in enumerate(FLOORS):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return level
    raise AssertionError(f"{module} stands on no floor: add its package to FLOORS")


def test_the_graph_is_read():
    graph = _graph()
    assert len(graph) > 60 and sum(map(len, graph.values())) > 150


def test_library_never_imports_the_cli():
    offenders = sorted(f"{m} -> {t}" for m, ts in _graph().items() if not m.startswith("transpiler.cli")
                       for t in ts if t.startswith("transpiler.cli"))
    assert offenders == []


def test_imports_only_run_downward():
    offenders = sorted(f"{m} -> {t}" for m, ts in _graph().items() for t in ts if _floor(t) > _floor(m))
    assert offenders == []


def test_no_import_cycles():
    graph = _graph()
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:      # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert cycles == []


def test_the_checker_sees_a_cycle_and_an_upward_arrow(tmp_path):
    """The rules above can fail: a package with a cycle and a library module importing the CLI is caught."""
    root = tmp_path / "transpiler"
    (root / "cli").mkdir(parents=True)
    (root / "verify").mkdir()
    for folder in (root, root / "cli", root / "verify"):
        (folder / "__init__.py").write_text('"""x."""\n')
    (root / "verify" / "a.py").write_text("from transpiler.verify import b\nfrom transpiler.cli import app\n")
    (root / "verify" / "b.py").write_text("def f():\n    from transpiler.verify.a import g\n")
    (root / "cli" / "app.py").write_text("")
    global PACKAGE
    saved, PACKAGE = PACKAGE, root
    try:
        graph = _graph()
        assert graph["transpiler.verify.a"] == {"transpiler.verify.b", "transpiler.cli.app"}
        assert graph["transpiler.verify.b"] == {"transpiler.verify.a"}
        with pytest.raises(AssertionError):
            test_no_import_cycles()
        with pytest.raises(AssertionError):
            test_library_never_imports_the_cli()
        with pytest.raises(AssertionError):
            test_imports_only_run_downward()
    finally:
        PACKAGE = saved


@pytest.mark.parametrize("folder", STAGE_PACKAGES)
def test_every_stage_package_says_what_it_does(folder):
    init = PACKAGE / folder / "__init__.py"
    assert init.is_file(), f"{folder} is not a package"
    doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8")))
    assert doc and len(doc.split()) >= 15 and "TODO" not in doc, f"{folder}/__init__.py needs its docstring"


LONG_FUNCTION = 80


def test_no_long_function_without_a_reason():
    """A function over ~80 lines says why it is kept whole in a comment at the top of its body ("Kept whole ...")."""
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        lines = path.read_text(encoding="utf-8").splitlines()
        for node in ast.walk(ast.parse("\n".join(lines))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            if node.end_lineno - node.lineno + 1 <= LONG_FUNCTION:
                continue
            head = "\n".join(lines[node.lineno - 1: node.lineno + 4])
            if "Kept whole" not in head:
                offenders.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {node.name} "
                                 f"({node.end_lineno - node.lineno + 1} lines)")
    assert offenders == []
