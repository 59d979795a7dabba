"""Machine-parameter files (*.mp): find the one beside the main program and read its values."""

from __future__ import annotations

from decimal import Decimal
from pathlib import Path

from transpiler.diagnostics import Diagnostics, NO_SPAN
from transpiler.frontend.parse import MpParser
from transpiler.frontend.sources import ProjectFolders, read_source


def mp_candidates(main: Path) -> list[Path]:
    """Every machine-parameter file (*.mp) beside the main program."""
    try:
        return sorted(p for p in main.parent.iterdir() if p.suffix.lower() == ".mp" and p.is_file())
    except OSError:
        return []


def find_mp_file(main: Path) -> Path | None:
    """The one machine-parameter file beside the main program, if there is exactly one."""
    found = mp_candidates(main)
    return found[0] if len(found) == 1 else None


def read_mp_file(path: Path, diags: Diagnostics) -> dict[tuple[int, int], Decimal]:
    text = read_source(path, ProjectFolders(path.parent, []), NO_SPAN, diags)
    if text is None:
        return {}
    return {(p.number, p.index): p.value for p in MpParser().parse_lines(text.display, text.lines, diags)}
