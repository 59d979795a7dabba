"""README.md of an output folder for a target whose import creates no task (CODESYS, TwinCAT): what each file is,
how to load it, and the task to create by hand (task_setup.py). Formats with templates/readme; decides nothing."""

from __future__ import annotations

from collections.abc import Iterable
from types import MappingProxyType

from transpiler.backends.st.dialect import TargetProject
from transpiler.backends.st.task_setup import task_lines
from transpiler.backends.templating import template_environment
from transpiler.backends.twincat.layout import TcProject

README_FILE = "README.md"
# How the user knows each IDE.
IDE_NAMES = MappingProxyType({"codesys": "CODESYS V3", "twincat": "TwinCAT 3"})


def render_readme(target: TargetProject, files: Iterable[str], twincat: TcProject | None = None) -> str:
    """The README of an output folder holding `files` (names inside it); `twincat` is the PLC project folder written
    beside them, if any."""
    names = set(files)
    env = template_environment("readme", {})
    text = env.get_template("gvl_target.md.j2").render(
        project=target.project, dialect=target.dialect, ide=IDE_NAMES.get(target.dialect.name, target.dialect.name),
        gvls=target.gvls, task_lines=task_lines(target), has=lambda name: name in names,
        plcproj=str(twincat.folder / twincat.plcproj) if twincat is not None else None)
    return text.rstrip("\n") + "\n"
