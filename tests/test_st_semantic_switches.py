"""The ST back end follows the semantic switches that change what a word instruction computes, on run-time and on
constant operands (which it folds): the translation stays equivalent with either setting."""

from __future__ import annotations

import pytest

from tests.text_project import cosim, translate

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
    project = translate(tmp_path, PROGRAM, SCENARIO, semantics={"mul_overflow_result": setting})
    result = cosim(project)
    assert result.equivalent, (result.divergence, result.error)
    # the folded product of two constants that overflows: 65536 kept, or the low bits 0
    assert f"D12 := {65536 if setting == 'unchanged' else 0};" in project.out.st_text
