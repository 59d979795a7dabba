"""A division whose divisor cannot be 0 (a KFIELD entry of a table of one sign only) needs no zero check in
the ST: the error marker is reset and the helper divides. A table whose range holds 0 keeps the check. All stay
equivalent."""

from __future__ import annotations

import pytest

from tests.text_project import cosim, translate

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
    project = translate(tmp_path, PROGRAM.format(entries=entries), SCENARIO.format())
    assert ("<> 0 THEN" in project.out.st_text) == checked, project.out.st_text
    result = cosim(project)
    assert result.equivalent, (result.divergence, result.error)
