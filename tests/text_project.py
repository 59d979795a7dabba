"""Small projects written as text for co-simulation tests: the files go into a folder, the program is translated,
and its ST runs against the reference on the built-in executor or on matiec (where iec2c is found)."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, NamedTuple

import pytest

from transpiler.backends.report.report import io_map_of
from transpiler.backends.st.check import find_iec2c
from transpiler.backends.transpile import Transpiled, transpile_program
from transpiler.diagnostics import Diagnostics
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.ir import Program
from transpiler.language.semantics import make_semantics
from transpiler.verify.cosim import builtin_side_factory, cosimulate
from transpiler.verify.scenario import NameTable, Scenario, load_scenario
from transpiler.verify.simulate import project_names

# The executors of the translated side; matiec only where iec2c is found.
BACKENDS = ["builtin", pytest.param("matiec", marks=pytest.mark.skipif(
    find_iec2c() is None, reason="iec2c not found ($MATIEC_HOME/iec2c or PATH)"))]


class TextProject(NamedTuple):
    program: Program
    out: Transpiled
    names: NameTable
    scenario: Scenario


def translate(folder: Path, program: str, scenario: str, files: Mapping[str, str] | None = None,
              semantics: Mapping[str, object] | None = None, formats: frozenset[str] = frozenset({"st"})) -> TextProject:
    """`program` as main.src (and `files` beside it), translated with `semantics`; `scenario` loaded for it."""
    (folder / "main.src").write_text(program)
    for name, text in (files or {}).items():
        (folder / name).write_text(text)
    (folder / "scenario.yaml").write_text(scenario)
    compiled = compile_project(ProjectOptions(main=folder / "main.src"), make_semantics("itnc530", semantics or {}))
    out = transpile_program(compiled.program, Diagnostics(), {}, set(formats))
    names = project_names(compiled.program)
    return TextProject(compiled.program, out, names, load_scenario(folder / "scenario.yaml", names))


def side_factory(out: Transpiled, st_text: str, backend: str = "builtin"):
    """The translated side for `st_text` (the translation's own or a broken copy of it) on `backend`."""
    if backend == "matiec":
        from transpiler.exec.compiled.matiec_side import matiec_side_factory
        return matiec_side_factory(st_text, out.result.project, find_iec2c())
    return builtin_side_factory(st_text)


def cosim(project: TextProject, st_text: str | None = None, backend: str = "builtin"):
    """The co-simulation of the project's scenario with `st_text` (default: the translation) on `backend`."""
    st = project.out.st_text if st_text is None else st_text
    return cosimulate(project.program, side_factory(project.out, st, backend), io_map_of(project.out.result),
                      project.scenario, project.names)
