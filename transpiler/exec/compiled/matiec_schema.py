"""Mutant schemata on matiec: every mutant of the ST text in one library (schema_st.py writes the ST, iec2c and gcc
build it once), the mutant to run chosen by setting the schema's global number after each initialisation.

The built-in checker first leaves out the mutations it rejects (a mutant that is not valid ST on its own); where
matiec still rejects the schema at lines that hold switched mutations, those mutations are left out (built on
their own by the caller, as without schemata) and the schema is built again; when that does not mend it, the
schema holds no mutation and every mutant is built on its own."""

from __future__ import annotations

import ctypes
import re
from pathlib import Path
from typing import Callable, Sequence

from transpiler.backends.iec_model import IecProject
from transpiler.exec.compiled.matiec_side import MatiecBuildError, build_library, load_library, sides_of
from transpiler.exec.compiled.schema_st import SchemaNames, StSchema, build_schema, checked_schema, leave_out_at
from transpiler.exec.compiled.sysfb import modules_in
from transpiler.exec.stexec.schema import TextMutation

MENDS = 3                      # rebuilds with the rejected lines' mutations left out, before giving up on them all
_REJECTED = re.compile(r":(\d+)-\d+\.\.(\d+)-\d+: error")


def accessors_c(names: SchemaNames) -> str:
    """Harness C that sets the mutant number and reads the infection flags."""
    return "\n".join([
        f"void hh_schema_set(long long number) {{ *__GET_GLOBAL_{names.mutant}() = (DINT)number; }}",
        "void hh_schema_hits(int n, char *out) {",
        f"    for (int i = 0; i < n; i++) out[i] = __GET_GLOBAL_{names.hits}()->table[i] ? 1 : 0;",
        "}", ""])


def rejected_lines(message: str) -> set[int]:
    """The lines iec2c's message names as errors."""
    out: set[int] = set()
    for m in _REJECTED.finditer(message):
        out.update(range(int(m.group(1)), int(m.group(2)) + 1))
    return out


class MatiecSchema:
    """The mutants `mutations` of `st_text` built once on matiec: `factory(number)` gives sides running mutant
    `number` (0 the original; negative: the original, the side's `infected` the mutants the run infected);
    `unswitched` are the mutations it does not hold."""

    def __init__(self, st_text: str, mutations: Sequence[TextMutation], project: IecProject, iec2c: Path,
                 filename: str = "project.st"):
        mutations = list(mutations)
        self.st_text, self.project = st_text, project
        impure = modules_in(st_text)
        left_out: set[int] = set()
        for attempt in range(MENDS + 1):
            schema = checked_schema(st_text, mutations, filename, left_out, impure)
            try:
                self.lib = load_library(build_library(schema.text, project, iec2c, accessors_c(schema.names)))
                break
            except MatiecBuildError as exc:
                lines = rejected_lines(str(exc))
                more = leave_out_at(schema, st_text, mutations, lines, filename) if lines else None
                if not more or attempt == MENDS:
                    schema = build_schema(st_text, [], filename)
                    self.lib = load_library(build_library(schema.text, project, iec2c, accessors_c(schema.names)))
                    break
                left_out |= more
        self.schema: StSchema = schema
        self.unswitched = frozenset(m.number for m in mutations) - schema.switched
        self.lib.hh_schema_set.argtypes = [ctypes.c_longlong]
        self.lib.hh_schema_hits.argtypes = [ctypes.c_int, ctypes.c_char_p]

    def factory(self, number: int) -> Callable[[], object]:
        lib = self.lib
        return sides_of(lib, self.st_text, self.project, lambda: lib.hh_schema_set(number),
                      self._infected if number < 0 else None)

    def _infected(self) -> set[int]:
        size = self.schema.size
        flags = ctypes.create_string_buffer(size)
        self.lib.hh_schema_hits(size, flags)
        return {i + 1 for i, flag in enumerate(flags.raw[:size]) if flag} & self.schema.switched
