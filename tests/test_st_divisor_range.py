"""A division whose divisor cannot be 0 (a KFIELD entry of a table of one sign only) needs no zero check in
the ST: the error marker is reset and the helper divides. A table whose range holds 0 keeps the check. All stay
equivalent."""

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
L     W0
=     X
L     W2
/     KF Divisors[X]
=     W4
L     M4201
=     M10
EM
KFIELD Divisors
{entries}
ENDK
"""

SCENARIO = """\
name: divide
cycles: 4
initial: {{W0: 0, W2: 1000}}
events:
  - {{cycle: 1, set: {{W0: 1}}}}
  - {{cycle: 2, set: {{W0: 2, W2: -7}}}}
"""


@pytest.mark.parametrize("entries, checked", [("K7\nK3\nK250", False), ("K-7\nK-3\nK-250", False),
                                              ("K7\nK0\nK250", True), ("K7\nK-3\nK250", True)])
def test_zero_check_only_where_the_divisor_may_be_zero(tmp_path, entries, checked):
    (tmp_path / "main.src").write_text(PROGRAM.format(entries=entries))
    (tmp_path / "scenario.yaml").write_text(SCENARIO.format())
    program = compile_project(ProjectOptions(main=tmp_path / "main.src"), make_semantics("itnc530", {})).program
    out = transpile_program(program, Diagnostics(), {}, {"st"})
    assert ("<> 0 THEN" in out.st_text) == checked, out.st_text
    names = project_names(program)
    scenario = load_scenario(tmp_path / "scenario.yaml", names)
    result = cosimulate(program, builtin_side_factory(out.st_text), io_map_of(out.result), scenario, names)
    assert result.equivalent, (result.divergence, result.error)
