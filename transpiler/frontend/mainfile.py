"""Which file of a project is the main program: a folder given as MAIN, and a module file given as MAIN."""

from __future__ import annotations

import re
from pathlib import Path

from transpiler.frontend import ast
from transpiler.frontend.sources import decode_text

_GLOBAL = re.compile(r"^[ \t]*GLOBAL[ \t]", re.IGNORECASE | re.MULTILINE)
_USES = re.compile(r"^[ \t]*USES[ \t]+\"?([^\";\s]+)", re.IGNORECASE | re.MULTILINE)


def is_module(source: ast.SourceFile) -> bool:
    """A module file: it exports labels with GLOBAL and has no code before its first LBL (its code runs only when
    called). Given as the main program it would run nothing and every symbol of the main program's .def files
    would be missing."""
    exports = False
    for stmt in source.statements:
        if isinstance(stmt, ast.Global):
            exports = True
        elif isinstance(stmt, ast.Label):
            return exports
        elif isinstance(stmt, (ast.Instr, ast.KField)):
            return False
    return exports


def main_candidates(folder: Path) -> list[Path]:
    """The .src files of `folder` that could be the main program: no GLOBAL export, and no other .src file of the
    folder USES them."""
    sources = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".src" and p.is_file())
    used: set[str] = set()
    exporting: set[Path] = set()
    for path in sources:
        try:
            text = decode_text(path.read_bytes()[:4 * 1024 * 1024])
        except OSError:
            continue
        used.update(Path(name.replace("\\", "/")).name.lower() for name in _USES.findall(text))
        if _GLOBAL.search(text):
            exporting.add(path)
    return [p for p in sources if p not in exporting and p.name.lower() not in used]
