"""Runs the front-end stages in order: load and parse the project, then resolve it into the IR program."""

from __future__ import annotations

import dataclasses

from .diagnostics import Diagnostics
from .frontend import ProjectOptions, load_project
from .ir import Program
from .resolve import resolve
from .semantics import Semantics


@dataclasses.dataclass(frozen=True)
class CompileResult:
    program: Program | None          # None only when no source file could be read; check `ok` before use
    diagnostics: Diagnostics

    @property
    def ok(self) -> bool:
        return self.program is not None and not self.diagnostics.has_errors()


def compile_project(options: ProjectOptions, semantics: Semantics, diags: Diagnostics | None = None) -> CompileResult:
    diags = diags or Diagnostics()
    parsed = load_project(options, semantics, diags)
    if not parsed.src_files:
        return CompileResult(None, diags)
    program = resolve(parsed, semantics, diags)
    return CompileResult(program, diags)
