"""HH_Lib (transpiler/backends/st/hh_lib.py): every helper FUNCTION and the timer/counter blocks against tables of
inputs and outputs worked out by hand from the documented behaviour of the control (docs/language.md), run on the
built-in ST executor and (with MATIEC_HOME, in one test) on matiec-compiled C; the helpers that mirror one
instruction also against the reference interpreter running that instruction; and the library files transpile
writes (hh_lib.st, hh_lib.xml)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.test_interp import cycles, machine
from transpiler.backends.iec_model import Configuration, IecProject, IecVar, Pou, ProgramInstance, Task, VarSection
from transpiler.backends.plcopen.writer import extract_st_bodies
from transpiler.backends.st import hh_lib
from transpiler.backends.st.arith import gate_value, mul_value, shift_value
from transpiler.backends.st.check import check_blark, find_iec2c
from transpiler.backends.st.library import helper_pous
from transpiler.backends.st.writer import extract_pou_bodies, render_st
from transpiler.language.semantics import make_semantics

MIN, MAX = -2147483648, 2147483647


def _bits(pattern: int, n: int) -> tuple[bool, ...]:
    """The n bit operands B0..Bn-1 of a bit pattern (B0 = bit 0)."""
    return tuple(bool(pattern >> i & 1) for i in range(n))


# Helper -> rows of (arguments in declaration order, expected result). Every expected value is worked out by hand
# from the rule in the helper's doc comment, not computed by a model.
TABLES: dict[str, list[tuple[tuple, object]]] = {
    "HH_ADD": [((1, 2), 3), ((-5, 3), -2), ((0, 0), 0),
               ((MAX, 1), MIN),                       # wraps, no saturation
               ((MIN, -1), MAX),
               ((MAX, MAX), -2),                      # 2^32 - 2
               ((MIN, MIN), 0)],                      # -2^32
    "HH_SUB": [((5, 7), -2), ((0, 1), -1),
               ((MIN, 1), MAX), ((MAX, -1), MIN),
               ((0, MIN), MIN),                       # -(-2^31) wraps to -2^31
               ((-1, MAX), MIN)],
    "HH_MUL": [((6, 7), 42), ((-6, 7), -42), ((123456, 0), 0),
               ((65536, 65536), 0),                   # 2^32: low 32 bits 0
               ((65536, 32768), MIN),                 # 2^31 reads as -2^31
               ((65536, 65537), 65536),               # 2^32 + 2^16
               ((MAX, 2), -2),                        # 2^32 - 2
               ((MIN, -1), MIN),                      # 2^31
               ((MIN, 2), 0),                         # -2^32
               ((46341, 46341), -2147479015)],        # 2147488281 - 2^32
    "HH_MULOVF": [((6, 7), False), ((65536, 32767), False), ((65536, 32768), True),
                  ((-65536, 32768), False),           # exactly -2^31 fits
                  ((MIN, 1), False), ((MIN, -1), True), ((46341, 46341), True), ((46340, 46340), False),
                  ((0, MIN), False)],
    "HH_DIV": [((7, 2), 3), ((-7, 2), -3), ((7, -2), -3), ((-7, -2), 3),      # toward zero
               ((1, 3), 0), ((-1, 3), 0),
               ((5, 0), 5), ((MIN, 0), MIN), ((0, 0), 0),                      # by 0: A unchanged
               ((MIN, -1), MIN),                                               # wraps, no fault
               ((MAX, -1), -MAX), ((MIN, 1), MIN), ((MIN, 2), -1073741824)],
    "HH_MOD": [((7, 2), 1), ((-7, 2), -1), ((7, -2), 1), ((-7, -2), -1),      # sign of the dividend
               ((6, 3), 0), ((MAX, 10), 7),
               ((5, 0), 5), ((-5, 0), -5),                                     # MOD 0: A unchanged
               ((MIN, -1), 0),
               ((MIN, 3), -2),                                                 # -2^31 = 3 * -715827882 - 2
               ((MIN, MAX), -1)],
    "HH_SEXT8": [((0,), 0), ((127,), 127), ((128,), -128), ((255,), -1), ((256,), 0), ((0x17F,), 127), ((-1,), -1),
                 ((-129,), 127), ((0x12345680,), -128), ((MAX,), -1)],
    "HH_SEXT16": [((32767,), 32767), ((32768,), -32768), ((65535,), -1), ((65536,), 0), ((-32769,), 32767),
                  ((0x12348000,), -32768), ((-1,), -1), ((0x7FFF7FFF,), 32767)],
    "HH_WAND": [((0x12345678, 0x0F0F, 16), 0x12340608),          # bits above the width kept
                ((0x12345678, 0x0F, 8), 0x12345608),
                ((0x12345678, 0x0F0F0F0F, 32), 0x02040608),
                ((-1, 0, 8), -256), ((-1, 0, 16), -65536), ((-1, 0, 32), 0),
                ((-1, 0x7FFF0000, 16), -65536),                  # bits of V above the width do not count
                ((0x12345678, 0, 33), 0),                        # another width: all 32 bits
                ((0x12345678, -1, 16), 0x12345678)],
    "HH_WOR": [((0x12340000, 0x5678, 16), 0x12345678), ((0, -1, 8), 255), ((0, -1, 16), 65535), ((0, -1, 32), -1),
               ((0x12345678, 0x0F0F, 16), 0x12345F7F), ((MIN, 1, 8), -2147483647), ((0, 0x12345678, 8), 0x78)],
    "HH_WXOR": [((0x12345678, 0xFFFF, 16), 0x1234A987), ((0x12345678, 0x0F0F, 16), 0x12345977),
                ((-1, -1, 8), -256), ((-1, -1, 32), 0), ((0, 0x12345678, 16), 0x5678),
                ((MAX, -1, 33), MIN)],
    "HH_SHL": [((1, 0), 1), ((1, 4), 16), ((1, 31), MIN),
               ((1, 32), 1), ((1, 33), 2), ((5, 64), 5),                      # count mod 32
               ((1, -1), MIN), ((3, -31), 6),                                   # negative counts: mod 32 into 0..31
               ((1, MIN), 1), ((1, MAX), MIN),
               ((0x7FFFFFFF, 4), -16), ((-1, 1), -2), ((0x40000000, 1), MIN)],
    "HH_SHR": [((16, 2), 4), ((0x12345678, 4), 0x01234567), ((MAX, 31), 0),
               ((-16, 2), -4), ((-1, 31), -1), ((MIN, 31), -1), ((MIN, 1), -1073741824),   # arithmetic
               ((-7, 1), -4),                                                   # rounds down, not toward zero
               ((-16, 32), -16), ((16, 33), 8), ((-16, -1), -1), ((-16, -30), -4)],
    "HH_BSET": [((0, 0), 1), ((0, 8), 256), ((0, 31), MIN), ((0, 32), 1), ((0, -1), MIN), ((5, 2), 5),
                ((1, 63), -2147483647), ((MAX, 31), -1)],
    "HH_BCLR": [((-1, 31), MAX), ((-1, 0), -2), ((MIN, 31), 0), ((7, 1), 5), ((7, 33), 5), ((7, -32), 6),
                ((-1, -1), MAX), ((0, 5), 0)],
    "HH_BTEST": [((MIN, 31), True), ((MAX, 31), False), ((1, 0), True), ((1, 32), True), ((2, 33), True),
                 ((2, 1), True), ((2, 0), False), ((-1, -1), True), ((MAX, -1), False), ((256, 8), True)],
    "HH_BIT": [((1, 0), True), ((2, 0), False), ((MIN, 31), True), ((MAX, 31), False), ((-1, 17), True),
               ((0x80, 7), True), ((0x7F, 7), False)],
    "HH_LOWORD": [((0x12345678,), 0x5678), ((-1,), -1), ((0xFFFF,), -1), ((0x8000,), -32768), ((0x7FFF0000,), 0),
                  ((-65536,), 0), ((65537,), 1)],
    "HH_HIWORD": [((0x12345678,), 0x1234), ((-1,), -1), ((65535,), 0), ((-65536,), -1), ((MIN,), -32768),
                  ((MAX,), 32767), ((65536,), 1)],
    "HH_FROMWORDS": [((0x1234, 0x5678), 0x12345678), ((-1, -1), -1), ((0, -1), 65535), ((-32768, 0), MIN),
                     ((32767, -1), MAX), ((-1, 0), -65536), ((1, 1), 65537)],
    "HH_MKINT": [((0x78, 0x56), 0x5678), ((0xFF, 0xFF), -1), ((0x00, 0x80), -32768), ((0xFF, 0x7F), 32767),
                 ((0x01, 0x00), 1), ((0x00, 0x01), 256)],
    "HH_MKDINT": [((0x78, 0x56, 0x34, 0x12), 0x12345678), ((0xFF, 0xFF, 0xFF, 0xFF), -1), ((0, 0, 0, 0x80), MIN),
                  ((0xFF, 0xFF, 0xFF, 0x7F), MAX), ((1, 0, 0, 0), 1), ((0, 0, 1, 0), 65536)],
    "HH_BYTEOF": [((0x12345678, 0), 0x78), ((0x12345678, 1), 0x56), ((0x12345678, 2), 0x34),
                  ((0x12345678, 3), 0x12), ((-1, 3), 255), ((MIN, 3), 0x80), ((MIN, 0), 0), ((-2, 0), 254)],
    "HH_PACK8": [(_bits(p, 8), want) for p, want in [
        (0x00, 0), (0x01, 1), (0x7F, 127), (0x80, -128), (0xFF, -1), (0x81, -127), (0xAA, -86)]],
    "HH_PACK16": [(_bits(p, 16), want) for p, want in [
        (0x0000, 0), (0x7FFF, 32767), (0x8000, -32768), (0xFFFF, -1), (0x1234, 4660), (0x8001, -32767)]],
    "HH_PACK32": [(_bits(p, 32), want) for p, want in [
        (0, 0), (0x7FFFFFFF, MAX), (0x80000000, MIN), (0xFFFFFFFF, -1), (0x12345678, 0x12345678),
        (0x80000001, -2147483647)]],
}
# HH_FROMWORDS(HH_HIWORD(V), HH_LOWORD(V)) = V: the data stack gives back what it was given.
ROUND_TRIP = [0, 1, -1, MIN, MAX, 0x12345678, -0x12345678, 0x8000, 0x7FFF, 0xFFFF, 0x10000, -65536, -32768, 32767]

# Timer and counter cycles: (START written before the cycle or None, PRESET, RELEASE, RUNNING after, START after).
TIMER_DEFAULT = [                                    # start consumed, a start restarts a running timer
    (True, 3, False, True, False), (None, 3, False, True, False), (None, 3, False, True, False),
    (None, 3, False, False, False),                  # exactly PRESET cycles
    (True, 3, False, True, False), (None, 3, False, True, False),
    (True, 3, False, True, False),                   # restarted: three more cycles
    (None, 3, False, True, False), (None, 3, False, True, False), (None, 3, False, False, False),
    (True, 0, False, False, False),                  # preset 0: never runs
    (True, 1, False, True, False), (None, 1, False, False, False)]
TIMER_HELD_NO_RESTART = [                            # start not consumed, no restart while running
    (True, 2, False, True, True), (None, 2, False, True, True), (None, 2, False, False, True),
    (None, 2, False, True, True),                    # held start: starts again once it has run down
    (False, 2, False, True, False), (None, 2, False, False, False), (None, 2, False, False, False)]
COUNTER_DEFAULT = [                                  # start consumed, counts every released cycle
    (True, 2, False, True, False), (None, 2, True, True, False), (None, 2, True, False, False),
    (None, 2, True, False, False),                   # stays at 0
    (True, 2, True, True, False),                    # a start wins over a release in the same cycle
    (None, 2, False, True, False), (None, 2, True, True, False), (None, 2, True, False, False)]
COUNTER_HELD_EDGES = [                               # start not consumed, counts rising edges of RELEASE
    (True, 2, False, True, True), (None, 2, True, True, True),
    (False, 2, True, True, False),                   # RELEASE still TRUE: no new edge
    (None, 2, False, True, False), (None, 2, True, True, False), (None, 2, False, True, False),
    (None, 2, True, False, False), (None, 2, False, False, False), (None, 2, True, False, False)]
DEFAULT_FB_TABLES = {"TIM": TIMER_DEFAULT, "CNT": COUNTER_DEFAULT}


def _harness(semantics) -> IecProject:
    """One PROGRAM calling every helper on globals <HELPER>_<INPUT> into <HELPER>_R each cycle, the round trip of
    the stack words, and one HH_TIMER (TIM_*) and one HH_COUNTER (CNT_*) instance."""
    lib = hh_lib.library_pous(semantics)
    globals_: list[tuple[str, str]] = [("RT_V", "DINT"), ("RT_R", "DINT")]
    lines = ["RT_R := HH_FROMWORDS(HI := HH_HIWORD(RT_V), LO := HH_LOWORD(RT_V));"]
    for pou in lib:
        if pou.kind != "FUNCTION":
            continue
        inputs = pou.sections[0].vars
        globals_ += [(f"{pou.name}_{v.name}", v.type) for v in inputs] + [(f"{pou.name}_R", pou.return_type)]
        args = ", ".join(f"{v.name} := {pou.name}_{v.name}" for v in inputs)
        lines.append(f"{pou.name}_R := {pou.name}({args});")
    globals_ += [("TIM_START", "BOOL"), ("TIM_PRESET", "DINT"), ("TIM_RELEASE", "BOOL"), ("TIM_RUN", "BOOL"),
                 ("CNT_START", "BOOL"), ("CNT_PRESET", "DINT"), ("CNT_RELEASE", "BOOL"), ("CNT_RUN", "BOOL")]
    lines += ["TIM(START := TIM_START, PRESET := TIM_PRESET);", "TIM_RUN := TIM.RUNNING;",
              "CNT(START := CNT_START, PRESET := CNT_PRESET, RELEASE := CNT_RELEASE);", "CNT_RUN := CNT.RUNNING;"]
    ext = VarSection("VAR_EXTERNAL", tuple(IecVar(n, t) for n, t in globals_))
    insts = VarSection("VAR", (IecVar("TIM", "HH_TIMER"), IecVar("CNT", "HH_COUNTER")))
    prog = Pou("HARNESS", "PROGRAM", (ext, insts), "\n".join(lines))
    config = Configuration("CONFIG0", "RES0", (Task("TASK0", 10),), (ProgramInstance("INST0", "TASK0", "HARNESS"),),
                           (VarSection("VAR_GLOBAL", tuple(IecVar(n, t) for n, t in globals_)),))
    return IecProject("HARNESS", (), lib + (prog,), config)


def _builtin(semantics=None):
    from transpiler.exec.stexec import load_st
    return load_st(render_st(_harness(semantics or make_semantics()))).instantiate()


@pytest.fixture(scope="module")
def builtin():
    return _builtin()


def _inputs(name: str) -> list[str]:
    return [v.name for v in helper_pous()[name].sections[0].vars]


def _call(side, name: str, args: tuple):
    for input_name, value in zip(_inputs(name), args, strict=True):
        side.set(f"{name}_{input_name}", value)
    side.run_cycle()
    return side.get(f"{name}_R")


def _check_table(side, name: str) -> None:
    for args, want in TABLES[name]:
        got = _call(side, name, args)
        assert got == want and isinstance(got, bool) == isinstance(want, bool), f"{name}{args}: {got!r}, want {want!r}"


def _check_round_trip(side) -> None:
    for value in ROUND_TRIP:
        side.set("RT_V", value)
        side.run_cycle()
        assert side.get("RT_R") == value, value


def _check_fb(side, prefix: str, table) -> None:
    for n, (start, preset, release, running, start_after) in enumerate(table):
        if start is not None:
            side.set(f"{prefix}_START", start)
        side.set(f"{prefix}_PRESET", preset)
        side.set(f"{prefix}_RELEASE", release)
        side.run_cycle()
        got = (side.get(f"{prefix}_RUN"), side.get(f"{prefix}_START"))
        assert got == (running, start_after), f"{prefix} cycle {n}: RUNNING, START = {got}, want {(running, start_after)}"


def test_every_helper_has_a_table_and_a_doc() -> None:
    names = list(helper_pous())
    assert set(TABLES) == set(names)
    assert set(hh_lib.DOCS) == set(names)
    pous = hh_lib.library_pous(make_semantics())
    assert [p.name for p in pous] == names + ["HH_TIMER", "HH_COUNTER"]
    assert all(p.comment and len(p.comment) > 60 for p in pous)
    page = (Path(__file__).resolve().parents[1] / "docs" / "hh_lib.md").read_text(encoding="utf-8")
    assert all(f"`{p.name}`" in page for p in pous), "docs/hh_lib.md names every POU of the library"


@pytest.mark.parametrize("name", list(TABLES))
def test_helper_table(builtin, name: str) -> None:
    _check_table(builtin, name)


def test_stack_words_round_trip(builtin) -> None:
    _check_round_trip(builtin)


@pytest.mark.parametrize("overrides, prefix, table", [
    ({}, "TIM", TIMER_DEFAULT),
    ({"timer_start_consumed": False, "timer_restart_while_running": False}, "TIM", TIMER_HELD_NO_RESTART),
    ({}, "CNT", COUNTER_DEFAULT),
    ({"counter_start_consumed": False, "counter_counts": "rising_edges"}, "CNT", COUNTER_HELD_EDGES),
], ids=["timer", "timer_held_no_restart", "counter", "counter_held_edges"])
def test_timer_and_counter_blocks(overrides, prefix: str, table) -> None:
    _check_fb(_builtin(make_semantics("itnc530", overrides)), prefix, table)


def test_the_whole_library_on_matiec() -> None:
    """One compilation of the library and the harness; every table, the round trip and the default blocks."""
    iec2c = find_iec2c()
    if iec2c is None:
        pytest.skip("iec2c not available (MATIEC_HOME)")
    from transpiler.exec.compiled.matiec_side import matiec_side_factory
    project = _harness(make_semantics())
    side = matiec_side_factory(render_st(project), project, iec2c)()
    for name in TABLES:
        _check_table(side, name)
    _check_round_trip(side)
    for prefix, table in DEFAULT_FB_TABLES.items():
        _check_fb(side, prefix, table)


# --- against the reference interpreter: the instruction the helper mirrors, on the same inputs --------------------

# Helper -> (program: operands D0 and D4 in, result in D8 or M0, the result operand, extra inputs to try).
EXTRA = [(0, 0), (1, -1), (MAX, MAX), (MIN, MIN), (MIN, -1), (-1, MIN), (12345, -678), (-99, 7), (1, 31), (-5, 37)]
INSTRUCTIONS = {
    "HH_ADD": ("+", "D8"), "HH_SUB": ("-", "D8"), "HH_MUL": ("x", "D8"), "HH_DIV": ("/", "D8"),
    "HH_MOD": ("MOD", "D8"), "HH_SHL": ("<<", "D8"), "HH_SHR": (">>", "D8"), "HH_BSET": ("BS", "D8"),
    "HH_BCLR": ("BC", "D8"), "HH_BTEST": ("BT", "M0"),
}


@pytest.mark.parametrize("name", list(INSTRUCTIONS))
def test_helper_matches_the_instruction_on_the_interpreter(tmp_path: Path, builtin, name: str) -> None:
    mnemonic, result = INSTRUCTIONS[name]
    m = machine(tmp_path, f"L D0\n{mnemonic} D4\n= {result}\nL M4200\n= M1\nEM\n", profile="itnc530")
    for args in [args for args, _ in TABLES[name]] + EXTRA:
        m.write("D", 0, args[0])
        m.write("D", 4, args[1])
        reports = cycles(m, 1)
        assert not reports[0].faults, (name, args, reports[0].faults)
        want = m.read(result[0], int(result[1:]))
        got = _call(builtin, name, args)
        assert int(got) == int(want), f"{name}{args}: ST {got!r}, interpreter {mnemonic} gives {want!r}"
        if name == "HH_MUL":      # the multiplication error marker
            assert _call(builtin, "HH_MULOVF", args) == bool(m.read("M", 1)), args


@pytest.mark.parametrize("width, operand", [(8, "B16"), (16, "W16"), (32, "D16")])
@pytest.mark.parametrize("name, mnemonic", [("HH_WAND", "A"), ("HH_WOR", "O"), ("HH_WXOR", "XO")])
def test_word_gates_match_the_interpreter(tmp_path: Path, builtin, name: str, mnemonic: str, width: int,
                                          operand: str) -> None:
    m = machine(tmp_path, f"L D0\n{mnemonic} {operand}\n= D8\nEM\n", profile="itnc530")
    for a, v in [(0x12345678, 0x0F0F0F0F), (-1, 0), (0, -1), (MIN, 0x5A5A5A5A), (0x7FFF00FF, -0x7FFF00FF)]:
        stored = (v + 2 ** (width - 1)) % 2 ** width - 2 ** (width - 1)     # v as the signed operand holds it
        m.write("D", 0, a)
        m.write(operand[0], 16, stored)
        cycles(m, 1)
        assert _call(builtin, name, (a, stored, width)) == m.read("D", 8), (name, width, a, v)


@pytest.mark.parametrize("name, n", [("HH_PACK8", 8), ("HH_PACK16", 16)])
def test_packing_matches_lb_and_lw_on_the_interpreter(tmp_path: Path, builtin, name: str, n: int) -> None:
    m = machine(tmp_path, f"L{'B' if n == 8 else 'W'} M100\n= D8\nEM\n", profile="itnc530")
    for bits, _ in TABLES[name]:
        for i, bit in enumerate(bits):
            m.write("M", 100 + i, int(bit))
        cycles(m, 1)
        assert _call(builtin, name, bits) == m.read("D", 8), (name, bits)


# --- the files transpile writes -------------------------------------------------------------------------------------

PROGRAM = "L D0\n+ D4\n= D8\nL D0\n>> K3\n= D12\nL D0\nBT K31\n= M0\nEM\n"


def test_transpile_writes_the_library_beside_project_st(tmp_path: Path, capsys) -> None:
    from transpiler.cli import main
    src = tmp_path / "main.src"
    src.write_text(PROGRAM, encoding="latin-1")
    out = tmp_path / "out"
    assert main(["transpile", str(src), "--out", str(out)]) == 0
    assert "hh_lib.st, hh_lib.xml" in capsys.readouterr().out
    lib_st = (out / "hh_lib.st").read_text()
    lib = extract_pou_bodies(lib_st)
    assert list(lib) == list(helper_pous()) + ["HH_TIMER", "HH_COUNTER"] and "CONFIGURATION" not in lib_st
    # project.st keeps the helpers it uses, with the same bodies: it does not need the library.
    project = extract_pou_bodies((out / "project.st").read_text())
    used = {"HH_ADD", "HH_SHR", "HH_BTEST"}
    assert used <= set(project) and all(project[name] == lib[name] for name in used)
    assert set(extract_st_bodies((out / "hh_lib.xml").read_bytes())) == set(lib)
    assert check_blark(lib_st, "hh_lib.st") == []
    assert "`hh_lib.st` (ST) and `hh_lib.xml` (PLCopen XML)" in (out / "report.md").read_text()
    # The blocks follow the project's semantics (here the default ones) and the header says so.
    assert lib["HH_TIMER"] == hh_lib.library_pous(make_semantics())[-2].body
    assert "counter_counts = cycles" in lib_st


@given(a=st.integers(MIN, 2 ** 31 - 1), v=st.integers(MIN, 2 ** 31 - 1), width=st.sampled_from((8, 16, 32)))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_constant_word_gates_fold_to_what_the_helpers_give(builtin, a: int, v: int, width: int) -> None:
    """The back end folds a gate of two constants (gate_value); the helper must give the same on every input."""
    for name, kind in (("HH_WAND", "A"), ("HH_WOR", "O"), ("HH_WXOR", "X")):
        assert gate_value(kind, a, v, width) == _call(builtin, name, (a, v, width)), (name, a, v, width)


@given(a=st.integers(MIN, 2 ** 31 - 1), count=st.integers(0, 31))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_constant_shifts_fold_to_what_the_helpers_give(builtin, a: int, count: int) -> None:
    """The back end folds a shift or bit set/clear of two constants (shift_value); the helpers must agree."""
    for name in ("HH_SHL", "HH_SHR", "HH_BSET", "HH_BCLR"):
        assert shift_value(name, a, count) == _call(builtin, name, (a, count)), (name, a, count)


@given(a=st.one_of(st.integers(MIN, 2 ** 31 - 1), st.integers(-70000, 70000)),
       b=st.one_of(st.integers(MIN, 2 ** 31 - 1), st.integers(-70000, 70000)), count=st.integers(-40, 40))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_constant_products_and_bit_tests_fold_to_what_the_helpers_give(builtin, a: int, b: int, count: int) -> None:
    """The back end folds MUL of two constants (mul_value) and BT of two constants (bit count mod 32, as the
    helper takes it); the helpers must agree."""
    overflow, low = mul_value(a, b)
    assert (overflow, low) == (_call(builtin, "HH_MULOVF", (a, b)), _call(builtin, "HH_MUL", (a, b))), (a, b)
    assert bool(a >> (count % 32) & 1) == _call(builtin, "HH_BTEST", (a, count)), (a, count)
