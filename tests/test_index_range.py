"""The interval analysis of the index register X (verify/index_range.py): loops bounded by a compare, guards through
logic brackets, and every place where X must stay unknown (entries, calls, unbounded loops, a guard whose word
changed). Each case runs the program too: every value X takes at the op lies in the interval found."""

from __future__ import annotations

from pathlib import Path

from transpiler.exec.interp import Machine, compile_program
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.verify.index_range import index_ranges, index_values

FULL = (-(1 << 31), (1 << 31) - 1)


def _program(folder: Path, text: str, **semantics):
    (folder / "main.src").write_text(text)
    result = compile_project(ProjectOptions(main=folder / "main.src"), make_semantics("itnc530", semantics))
    assert result.ok, result
    return result.program


def _at(program, mnemonic: str, operand: str, nth: int = 0):
    """The X interval before the nth op written `mnemonic operand` (None: no path reaches it)."""
    ranges = index_ranges(program)
    found = [(f, i) for f, code in enumerate(program.files) for i, op in enumerate(code.ops)
             if op.mnemonic == mnemonic and op.operand is not None and op.operand.display() == operand]
    return ranges.get(found[nth])


def test_loop_bounded_by_a_compare(tmp_path: Path) -> None:
    # REPEAT ... INCX, L X, >= K4, UNTILT: the body runs with X = 0..3, and after the loop X = 4.
    # Catches: the compare's false edge not refined (then the loop widens to the register's limit), INCX off by one.
    program = _program(tmp_path, "L K0\n= X\nREPEAT\nL I1\n= M100[X]\nINCX\nL X\n>= K4\nUNTILT\n"
                                 "L I2\n= M200[X]\nEM\n")
    assert _at(program, "=", "M100[X]") == (0, 3)
    assert _at(program, "=", "M200[X]") == (4, 4)
    machine = Machine(program, compiled=compile_program(program))
    machine.run_cycle(0, [("I", 1, 1), ("I", 2, 1)])
    assert [machine.state.bits("M")[a] for a in range(99, 106)] == [0, 1, 1, 1, 1, 0, 0]
    assert machine.state.bits("M")[204] == 1


def test_backward_jump_loop_and_while_loop(tmp_path: Path) -> None:
    # A loop left by `JPT` at its end (X < 28 jumps back) and a WHILET loop from 1 while X <= 24.
    program = _program(tmp_path, "L K0\n= X\nLBL Scan\nL M10[X]\nS M300[X]\nINCX\nL X\n< K28\nJPT Scan\n"
                                 "L K1\n= X\nL X\n<= K24\nWHILET\nL M6000[X]\n= M400[X]\nINCX\nL X\n<= K24\nENDW\n"
                                 "EM\n")
    assert _at(program, "S", "M300[X]") == (0, 27)
    assert _at(program, "=", "M400[X]") == (1, 24)


def test_guard_through_a_logic_bracket(tmp_path: Path) -> None:
    # W10 >= 1 AND [W10 <= 8]: where the IFT body runs, X = W10 holds 1..8; a word written between the guard and its
    # use is unknown again.
    program = _program(tmp_path, "L W10\n>= K1\nA[\nL W10\n<= K8\n]\nIFT\nL W10\n= X\nL I1\n= M100[X]\nENDI\n"
                                 "L W12\n>= K1\nA[\nL W12\n<= K8\n]\nIFT\nINC W12\nL W12\n= X\nL I1\n= M200[X]\n"
                                 "ENDI\nEM\n")
    assert _at(program, "=", "M100[X]") == (1, 8)
    assert _at(program, "=", "M200[X]") == (-32768, 32767)     # W12 + 1 wraps: only a word's own range is left


def test_or_of_two_compares_bounds_the_path_where_both_fail(tmp_path: Path) -> None:
    # X < 0 OR [X > 1] -> X := 0: after ENDI, X is 0..1 whichever way (the table lookup of the sample's spindle).
    program = _program(tmp_path, "L W10\n-  K1\n= X\nL X\n< K0\nO[\nL X\n> K1\n]\nIFT\nL K0\n= X\nENDI\n"
                                 "L I1\n= M100[X]\nEM\n")
    assert _at(program, "=", "M100[X]") == (0, 1)


def test_x_stays_unknown_where_it_cannot_be_known(tmp_path: Path) -> None:
    # At the program's start; after a call (the subprogram may set X); in a loop no compare ends (INCX wraps at the
    # register's limit); loaded from a word; in a subprogram entered with the caller's X.
    program = _program(tmp_path, "L I1\n= M100[X]\nL K0\n= X\nCM Sub\nL I1\n= M200[X]\nL K0\n= X\nLBL Again\n"
                                 "L I1\n= M300[X]\nINCX\nL I2\nJPT Again\nL W4\n= X\nL I1\n= M400[X]\nEM\n"
                                 "LBL Sub\nL I3\n= M500[X]\nEM\n")
    assert _at(program, "=", "M100[X]") == FULL
    assert _at(program, "=", "M200[X]") == FULL
    assert _at(program, "=", "M300[X]") == FULL
    assert _at(program, "=", "M400[X]") == (-32768, 32767)
    assert _at(program, "=", "M500[X]") == FULL


def test_16_bit_index_register_and_unsigned_compares(tmp_path: Path) -> None:
    # With a 16-bit X the unknown register is 16 bits wide; with unsigned compares nothing is learned from them.
    text = "L K0\n= X\nREPEAT\nL I1\n= M100[X]\nINCX\nL X\n>= K4\nUNTILT\nEM\n"
    assert _at(_program(tmp_path, "L W4\n= X\nL I1\n= M100[X]\nEM\n", index_register_width=16),
               "=", "M100[X]") == (-32768, 32767)
    assert _at(_program(tmp_path, text, compare_signedness="unsigned"), "=", "M100[X]")[1] > 4


def _congruence(program, mnemonic: str, operand: str) -> tuple[int, int]:
    """(modulus, residue) of X before the first op written `mnemonic operand`."""
    values = index_values(program)
    key = next((f, i) for f, code in enumerate(program.files) for i, op in enumerate(code.ops)
               if op.mnemonic == mnemonic and op.operand is not None and op.operand.display() == operand)
    return values[key].modulus, values[key].residue


def test_steps_by_two_or_four_keep_x_to_one_residue(tmp_path: Path) -> None:
    # INCX INCX from 0 (a word table): X is even in the loop and at its test; `L X` `+ K4` `= X` from 2: X is 2
    # modulo 4. The run shows every value X takes there. Catches: a join or a step that loses or shifts the residue.
    program = _program(tmp_path, "L K0\n= X\nLBL Next\nL I1\n= M100[X]\nINCX\nINCX\nL X\n< K18\nJPT Next\n"
                                 "L K2\n= X\nLBL Four\nL I1\n= M300[X]\nL X\n+ K4\n= X\nL X\n< K40\nJPT Four\nEM\n")
    assert _congruence(program, "=", "M100[X]") == (2, 0)
    assert _congruence(program, "<", "K18") == (2, 0)
    assert _congruence(program, "=", "M300[X]") == (4, 2)
    values = index_values(program)
    test = values[next(k for k in values if program.files[k[0]].ops[k[1]].mnemonic == "<")]
    assert test.holds(18) and not test.holds(17) and not test.holds(19)
    machine = Machine(program, compiled=compile_program(program))
    machine.run_cycle(0, [("I", 1, 1)])
    marked = [a for a in range(100, 400) if machine.state.bits("M")[a]]
    assert marked == list(range(100, 117, 2)) + list(range(302, 339, 4))


def test_a_residue_is_claimed_only_where_every_path_keeps_it(tmp_path: Path) -> None:
    # One INCX under an input, X loaded from a word, X after a call, and a step that may wrap the 16-bit register:
    # nothing is known of X's residue. Catches: a residue kept over a path that breaks it.
    program = _program(tmp_path, "L K0\n= X\nLBL A\nINCX\nINCX\nL I1\nIFT\nINCX\nENDI\nL I2\n= M100[X]\nL X\n< K20\n"
                                 "JPT A\nL W4\nA K-2\n= X\nL I1\n= M200[X]\nL K0\n= X\nCM Sub\nL I1\n= M300[X]\n"
                                 "L K0\n= X\nLBL B\nINCX\nINCX\nL I1\n= M400[X]\nL I2\nJPT B\nEM\nLBL Sub\nEM\n",
                       index_register_width=16)
    for operand in ("M100[X]", "M200[X]", "M300[X]", "M400[X]"):
        assert _congruence(program, "=", operand)[0] == 1, operand
