"""README.md of an output folder for a target whose import creates no task (CODESYS, TwinCAT): what each file is,
how to load it, and the task to create by hand (task_setup.py). Formats with templates/readme; decides nothing."""

from __future__ import annotations

from collections.abc import Iterable
from types import MappingProxyType
from typing import TYPE_CHECKING

from transpiler.backends.st.dialect import TargetProject
from transpiler.backends.st.task_setup import task_lines
from transpiler.backends.templating import template_environment

if TYPE_CHECKING:   # (an annotation only: a translation imports the TwinCAT layout when it plans such a project)
    from transpiler.backends.twincat.layout import TcProject

README_FILE = "README.md"
# How the user knows each IDE.
IDE_NAMES = MappingProxyType({"codesys": "CODESYS V3", "twincat": "TwinCAT 3"})


def _context(target: TargetProject, files: Iterable[str], twincat: TcProject | None) -> dict:
    names = set(files)
    return dict(project=target.project, dialect=target.dialect, gvls=target.gvls, task_lines=task_lines(target),
                ide=IDE_NAMES.get(target.dialect.name, target.dialect.name), has=lambda name: name in names,
                plcproj=str(twincat.folder / twincat.plcproj) if twincat is not None else None)


def render_readme(target: TargetProject, files: Iterable[str], twincat: TcProject | None = None) -> str:
    """The README of an output folder holding `files` (names inside it); `twincat` is the PLC project folder written
    beside them, if any."""
    text = template_environment("readme", {}).get_template("gvl_target.md.j2").render(_context(target, files, twincat))
    return text.rstrip("\n") + "\n"


def render_loading(target: TargetProject, files: Iterable[str], twincat: TcProject | None = None,
                   heading: str = "###") -> str:
    """The README's two sections on loading the files and creating the task, under `heading` (for report.md)."""
    text = template_environment("readme", {}).get_template("gvl_loading.md.j2").render(
        heading=heading, **_context(target, files, twincat))
    return text.rstrip("\n") + "\n"
