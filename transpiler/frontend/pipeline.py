"""Runs the front-end stages in order: load and parse the project, then resolve it into the IR program."""

from __future__ import annotations

import contextlib
import dataclasses
import gc

from transpiler.diagnostics import NO_SPAN, Diagnostics
from transpiler.frontend.datatables import read_tables
from transpiler.frontend.load import ParsedProject, Parsers, ProjectOptions, load_project
from transpiler.ir import Program
from transpiler.frontend.resolve import resolve
from transpiler.language.semantics import Semantics


@dataclasses.dataclass(frozen=True)
class CompileResult:
    program: Program | None          # None only when no source file could be read; check `ok` before use
    diagnostics: Diagnostics

    @property
    def ok(self) -> bool:
        return self.program is not None and not self.diagnostics.has_errors()


@contextlib.contextmanager
def cyclic_gc_paused():
    """Pause CPython's cyclic collector for one compile (or one translation), then restore it.

    The front end allocates millions of small, acyclic objects (lines, spans, AST nodes, ops); the collector
    would rescan the growing heap again and again for nothing: about 40 % of the run time on a 100 000-line
    project (tests/bench_frontend.py); the back ends likewise (statement trees, expressions, text), about 15 %.
    Reference counting still frees everything as usual.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def compile_project(options: ProjectOptions, semantics: Semantics, diags: Diagnostics | None = None,
                    parsers: Parsers | None = None) -> CompileResult:
    diags = diags or Diagnostics()
    with cyclic_gc_paused():
        parsed = load_project(options, semantics, diags, parsers)
        if not parsed.src_files:
            return CompileResult(None, diags)
        program = resolve(parsed, project_semantics(semantics, parsed), diags, options.defines)
        rows = read_tables(options.main, options.data_tables, program.symbols, program.semantics.profile.string_len,
                           diags, options.encoding)
        if rows:
            program = dataclasses.replace(program, data_rows=rows)
    if options.werror and diags.warnings and not diags.has_errors():
        diags.report("E-WERROR", NO_SPAN, f"{len(diags.warnings)} warning(s) and --werror")
    return CompileResult(program, diags)


def project_semantics(semantics: Semantics, parsed: ParsedProject) -> Semantics:
    """The semantics with the project's own settings: NUMBERMP4111 from its configuration (A-37), unless the
    command line set another value than the default (`-S number_mp4111=n` wins)."""
    if parsed.number_mp4111 is None or semantics["number_mp4111"] != semantics.profile.defaults["number_mp4111"]:
        return semantics
    return dataclasses.replace(semantics, values={**semantics.values, "number_mp4111": parsed.number_mp4111})
