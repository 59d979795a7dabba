"""The ST back end follows the semantic switches that change what a word instruction computes, on run-time and on
constant operands (which it folds): the translation stays equivalent with either setting."""

from __future__ import annotations

import pytest

from transpiler.backends.report.report import io_map_of
from transpiler.backends.transpile import transpile_program
from transpiler.diagnostics import Diagnostics
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.verify.cosim import builtin_side_factory, cosimulate
from transpiler.verify.scenario import load_scenario
from transpiler.verify.simulate import project_names

PROGRAM = """\
L     D0
X     D4
=     D8
L     K65536
X     K65536
=     D12
L     K3
X     K5
=     D16
EM
"""

SCENARIO = """\
name: products
cycles: 4
initial: {D0: 65536, D4: 65536}
events:
  - {cycle: 2, set: {D4: 3}}
"""


@pytest.mark.parametrize("setting", ["low_bits", "unchanged"])
def test_multiplication_overflow_result(tmp_path, setting):
    (tmp_path / "main.src").write_text(PROGRAM)
    (tmp_path / "scenario.yaml").write_text(SCENARIO)
    semantics = make_semantics("itnc530", {"mul_overflow_result": setting})
    program = compile_project(ProjectOptions(main=tmp_path / "main.src"), semantics).program
    out = transpile_program(program, Diagnostics(), {}, {"st"})
    names = project_names(program)
    scenario = load_scenario(tmp_path / "scenario.yaml", names)
    result = cosimulate(program, builtin_side_factory(out.st_text), io_map_of(out.result), scenario, names)
    assert result.equivalent, (result.divergence, result.error)
    # the folded product of two constants that overflows: 65536 kept, or the low bits 0
    assert f"D12 := {65536 if setting == 'unchanged' else 0};" in out.st_text
