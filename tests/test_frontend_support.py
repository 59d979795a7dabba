"""Shared helpers of the front-end tests: write a project into a folder, compile it, summarise diagnostics (no tests here)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Mapping

from transpiler.diagnostics import Diagnostic
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import CompileResult, compile_project
from transpiler.language.semantics import make_semantics


def write_project(folder: Path, files: Mapping[str, str | bytes]) -> None:
    """Write name -> text (Latin-1) or bytes; names may contain sub-folders."""
    for name, text in files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(text if isinstance(text, bytes) else text.encode("latin-1"))


def compile_files(folder: Path, files: Mapping[str, str | bytes], main: str = "main.src", profile: str = "itnc530",
                  semantics: Mapping[str, object] | None = None, **options) -> CompileResult:
    """Write the files and run the whole front end (load, preprocess, parse, resolve)."""
    write_project(folder, files)
    return compile_project(ProjectOptions(main=folder / main, **options), make_semantics(profile, semantics or {}))


@dataclasses.dataclass(frozen=True)
class Found:
    code: str
    file: str
    line: int
    col: int


def found(diags: list[Diagnostic]) -> list[Found]:
    return [Found(d.code, d.span.file, d.span.line, d.span.col) for d in diags]


def errors(result: CompileResult) -> list[Found]:
    return found(result.diagnostics.errors)


def warnings(result: CompileResult) -> list[Found]:
    return found(result.diagnostics.warnings)


def program_ops(result: CompileResult, file: int = 0):
    assert result.program is not None, [d.render() for d in result.diagnostics.items]
    return result.program.files[file].ops
