"""Resolver driver: symbols, then per-file lowering, linking, flow checks and the call graph; builds the IR program.

The jobs live in modules of their own: `symbols` (symbol tables, auto-assignment), `addresses` and `operands`
(operand checks), `lowering` with `chain` and `structure` (statements to ops), `calls` (exports, linking, call
graph) and `flow` (successors, subprogram bodies, fall-off and unreachable checks).
"""

from __future__ import annotations

from typing import Mapping

from transpiler.diagnostics import Diagnostics
from transpiler.frontend.calls import call_graph, exports_of, link
from transpiler.frontend.flow import (LOST_LINE_CODES, RoutineBodies, check_flow, check_module_starts, flow_is_complete,
                                      routine_body, successors)
from transpiler.frontend.load import ParsedProject
from transpiler.frontend.lowering import FileLowering
from transpiler.frontend.mask_refs import resolve_masks
from transpiler.frontend.symbols import build_symbols
from transpiler.ir import FileCode, Program
from transpiler.language.semantics import Semantics

__all__ = ["resolve", "routine_body", "successors"]


def resolve(project: ParsedProject, semantics: Semantics, diags: Diagnostics,
            overrides: Mapping[str, object] | None = None) -> Program:
    """The resolved program; `overrides` are the command line's -D values, recorded for the report."""
    overrides = overrides or {}
    symbols, auto = build_symbols(project, semantics, diags)
    lowerings = [FileLowering(i, src, symbols, semantics, diags) for i, src in enumerate(project.src_files)]
    for low in lowerings:
        low.run()
    exports = exports_of(lowerings, diags)
    for low in lowerings:
        link(low, lowerings, exports, diags, project.labels_incomplete)
    files = tuple(FileCode(low.src.path, tuple(low.ops), dict(low.labels), low.src.line_count) for low in lowerings)
    lost_lines = {d.span.file for d in diags.errors if d.code in LOST_LINE_CODES}
    bodies = RoutineBodies(files)
    for i, (f, low) in enumerate(zip(files, lowerings)):
        if flow_is_complete(low, lost_lines):
            check_flow(i, f, diags, bodies.ends(i))
    check_module_starts(files, lowerings, diags)
    routines, depth = call_graph(files, semantics, diags, bodies)
    masks = resolve_masks(project.masks, symbols, semantics, diags)
    modules = sorted(set().union(*(low.chain.modules_called for low in lowerings)))
    return Program(files, symbols.all_symbols(), semantics, routines, depth, tuple(modules), project.files_read,
                   dict(project.defines), project.inactive, tuple(auto), project.line_count, project.config_file,
                   tuple(sorted(overrides.items())), masks, routine_bodies=bodies.worked_out())
