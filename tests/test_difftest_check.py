"""The difftest verdict: who is to blame, and what is a target limit rather than a mismatch."""

from __future__ import annotations

from tests.difftest.check import MISMATCH, OK, TARGET_LIMIT, judge
from transpiler.verify.cosim import CosimResult, Divergence
from transpiler.exec.stexec.typesys import STR_MAX


def _result(backend: str, divergence: Divergence | None) -> CosimResult:
    return CosimResult("random", backend, 20, divergence, 10)


def test_a_string_cut_at_the_target_length_is_a_target_limit_not_a_mismatch():
    long = "AB" * 64                                                      # 128 characters, fine on the control
    cut = Divergence(7, "S0", "S0", long, long[:STR_MAX])
    assert judge({"builtin": _result("builtin", cut)}).status == TARGET_LIMIT
    assert judge({"builtin": _result("builtin", cut), "matiec": _result("matiec", cut)}).status == TARGET_LIMIT


def test_any_other_string_difference_stays_a_mismatch():
    long = "AB" * 64
    for translated in (long[:STR_MAX - 1], "X" + long[1:STR_MAX], ""):
        verdict = judge({"builtin": _result("builtin", Divergence(7, "S0", "S0", long, translated))})
        assert verdict.status == MISMATCH and verdict.blame == "translator or built-in executor"
    short = "A" * STR_MAX
    assert judge({"builtin": _result("builtin", Divergence(7, "S0", "S0", short, short[:-1]))}).status == MISMATCH


def test_blame_follows_how_the_executors_agree():
    wrong = Divergence(3, "W4", "W4", 1, 2)
    assert judge({"builtin": _result("builtin", None), "matiec": _result("matiec", None)}).status == OK
    assert judge({"builtin": _result("builtin", wrong), "matiec": _result("matiec", wrong)}).blame == "translator"
    assert judge({"builtin": _result("builtin", wrong), "matiec": _result("matiec", None)}).blame == "built-in executor"
    assert judge({"builtin": _result("builtin", None), "matiec": _result("matiec", wrong)}).blame == "matiec"
