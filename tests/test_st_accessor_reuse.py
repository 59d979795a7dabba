"""An indexed bit read leaves the operand's value in its accessor instance's output Q; a later read of the same
address in straight-line code reuses Q when nothing in between can have changed the operand or the index. These
tests hold the translation to the cases where that is sound: a named store of the same operand kind, an indexed
write that may hit the address, or a change of the index force a new read, and the program stays equivalent when
the scenario makes those addresses meet at run time."""

from __future__ import annotations

import re

import pytest

from tests.text_project import BACKENDS, cosim, translate

PROGRAM = """\
; X comes from W10, which the scenario sets, so no address is known at translation
L     W10
=     X
L     M10[X]
A     M12
=     M50
L     M10[X]
=     M51
L     I0
=     M12
L     M10[X]
=     M52
L     I1
S     M20[X]
L     M20[X]
A     M22[X]
=     M53
INCX
L     M10[X]
=     M54
L     I2
=     M30[X]
L     M30[X]
=     M55
EM
"""

# W10 = 2: M10[X] is M12, written by name between two reads; W10 = 40 and 41: M10[X] is M50, M51 (after INCX,
# M51, M52);
# W10 = 0 and 8: the indexed writes hit addresses read again later.
SCENARIO = """\
name: reuse
cycles: 10
initial: {W10: 2, I0: 1, I1: 1, I2: 1}
events:
  - {cycle: 2, set: {I0: 0}}
  - {cycle: 3, set: {W10: 41, I1: 0}}
  - {cycle: 4, set: {I0: 1, I2: 0}}
  - {cycle: 5, set: {W10: 0}}
  - {cycle: 6, set: {W10: 8, I1: 1}}
  - {cycle: 8, set: {W10: 40, I0: 0, I2: 1}}
"""


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    return translate(tmp_path_factory.mktemp("reuse"), PROGRAM, SCENARIO)


def _reads(st: str, base: int) -> int:
    return len(re.findall(rf"IDX := {base} \+ [^;]*WRITE := FALSE\)", st))


def test_reads_are_reused_only_while_nothing_can_change_them(project):
    st = project.out.st_text
    # M10[X]: read; read again after the named store of M50 (M10[X] is M50 when X = 40), after that of M12 and
    # after INCX (a new index).
    assert _reads(st, 10) == 4, st
    # M20[X]: read once, for S, before its write; not after it, nor M30[X] after its write: Q of the writing
    # instance holds the new value.
    assert _reads(st, 20) == 1 and _reads(st, 30) == 0, st


@pytest.mark.parametrize("backend", BACKENDS)
def test_reused_reads_stay_equivalent_when_addresses_meet(project, backend):
    result = cosim(project, backend=backend)
    assert result.equivalent, (result.divergence, result.error)
    assert result.cycles_run == 10
