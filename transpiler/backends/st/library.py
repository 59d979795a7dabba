"""The small emitted ST library: pure helper FUNCTIONs (wrap-around arithmetic, masks, packing) and the timer/counter FBs."""

from __future__ import annotations

from types import MappingProxyType

from transpiler.backends.iec_model import IecVar, Pou, VarSection
from transpiler.language.semantics import Semantics


def _fn(name: str, ret: str, inputs: list[tuple[str, str]], body: str, comment: str,
        local: list[tuple[str, str]] | None = None) -> Pou:
    sections = [VarSection("VAR_INPUT", tuple(IecVar(n, t) for n, t in inputs))]
    if local:
        sections.append(VarSection("VAR", tuple(IecVar(n, t) for n, t in local)))
    return Pou(name, "FUNCTION", tuple(sections), body.strip("\n"), return_type=ret, comment=comment)


# The shift and bit helpers take their count modulo 32; MOD keeps the sign of K, so fold it into 0..31.
_COUNT_MOD_32 = "KK := DINT_TO_INT(K MOD 32);\nIF KK < 0 THEN\n    KK := KK + 32;\nEND_IF;\n"


def _gate(name: str, op: str, comment: str) -> Pou:
    body = (
        "CASE W OF\n    8: M := 16#FF;\n    16: M := 16#FFFF;\nELSE\n    M := 16#FFFFFFFF;\nEND_CASE;\n"
        "U := DINT_TO_DWORD(V) AND M;\n"
        + {"AND": f"{name} := DWORD_TO_DINT((DINT_TO_DWORD(A) AND NOT M) OR (DINT_TO_DWORD(A) AND U));",
           "OR": f"{name} := DWORD_TO_DINT(DINT_TO_DWORD(A) OR U);",
           "XOR": f"{name} := DWORD_TO_DINT(DINT_TO_DWORD(A) XOR U);"}[op])
    return _fn(name, "DINT", [("A", "DINT"), ("V", "DINT"), ("W", "DINT")], body, comment,
               [("M", "DWORD"), ("U", "DWORD")])


def _pack(n: int) -> Pou:
    name = f"HH_PACK{n}"
    lines = ["V := 0;"]
    for i in range(n - 1):
        lines.append(f"IF B{i} THEN\n    V := V + {2 ** i};\nEND_IF;")
    # 2^31 itself is no DINT literal: subtract it in two steps.
    sign = f"V - {2 ** (n - 1)}" if n < 32 else "V - 2147483647 - 1"
    lines.append(f"IF B{n - 1} THEN\n    V := {sign};\nEND_IF;")
    lines.append(f"{name} := V;")
    return _fn(name, "DINT", [(f"B{i}", "BOOL") for i in range(n)], "\n".join(lines),
               f"LB/LW/LD: {n} bit operands into the word accumulator, bit {n - 1} as sign", [("V", "DINT")])


def helper_pous() -> dict[str, Pou]:
    """Every helper FUNCTION by name (the backend emits only the ones its code calls)."""
    shift_locals = [("KK", "INT")]
    pous = [
        _fn("HH_ADD", "DINT", [("A", "DINT"), ("B", "DINT")],
            "HH_ADD := LINT_TO_DINT(DINT_TO_LINT(A) + DINT_TO_LINT(B));",
            "A + B modulo 2^32 (A-09, see docs/language.md#arithmetic)"),
        _fn("HH_SUB", "DINT", [("A", "DINT"), ("B", "DINT")],
            "HH_SUB := LINT_TO_DINT(DINT_TO_LINT(A) - DINT_TO_LINT(B));",
            "A - B modulo 2^32 (A-09, see docs/language.md#arithmetic)"),
        _fn("HH_MUL", "DINT", [("A", "DINT"), ("B", "DINT")],
            "HH_MUL := LINT_TO_DINT(DINT_TO_LINT(A) * DINT_TO_LINT(B));",
            "low 32 bits of the product (A-10)"),
        _fn("HH_MULOVF", "BOOL", [("A", "DINT"), ("B", "DINT")],
            "P := DINT_TO_LINT(A) * DINT_TO_LINT(B);\nHH_MULOVF := P < -2147483648 OR P > 2147483647;",
            "multiplication overflow marker (see docs/language.md#arithmetic)", [("P", "LINT")]),
        _fn("HH_DIV", "DINT", [("A", "DINT"), ("B", "DINT")],
            "IF B = 0 THEN\n    HH_DIV := A;\nELSIF B = -1 THEN\n    HH_DIV := HH_SUB(0, A);\nELSE\n    HH_DIV := A / B;\nEND_IF;",
            "division truncating toward zero; -2^31 / -1 = -2^31 (A-11, A-12)"),
        _fn("HH_MOD", "DINT", [("A", "DINT"), ("B", "DINT")],
            "IF B = 0 THEN\n    HH_MOD := A;\nELSIF B = -1 THEN\n    HH_MOD := 0;\nELSE\n    HH_MOD := A MOD B;\nEND_IF;",
            "remainder with the sign of the dividend (A-11, A-12)"),
        _fn("HH_SEXT8", "DINT", [("V", "DINT")], "HH_SEXT8 := SINT_TO_DINT(DINT_TO_SINT(V));",
            "low 8 bits, sign-extended (comparison over the operand width, see docs/language.md#comparisons-shifts-and-bit-commands)"),
        _fn("HH_SEXT16", "DINT", [("V", "DINT")], "HH_SEXT16 := INT_TO_DINT(DINT_TO_INT(V));",
            "low 16 bits, sign-extended (comparison over the operand width, see docs/language.md#comparisons-shifts-and-bit-commands)"),
        _gate("HH_WAND", "AND", "word AND over the operand width W (see docs/language.md#word-logic)"),
        _gate("HH_WOR", "OR", "word OR over the operand width W (see docs/language.md#word-logic)"),
        _gate("HH_WXOR", "XOR", "word XOR over the operand width W (see docs/language.md#word-logic)"),
        _fn("HH_SHL", "DINT", [("A", "DINT"), ("K", "DINT")],
            _COUNT_MOD_32 + "HH_SHL := DWORD_TO_DINT(SHL(DINT_TO_DWORD(A), KK));", "shift left, count mod 32 (A-14)", shift_locals),
        _fn("HH_SHR", "DINT", [("A", "DINT"), ("K", "DINT")],
            _COUNT_MOD_32 + "IF A >= 0 THEN\n    HH_SHR := DWORD_TO_DINT(SHR(DINT_TO_DWORD(A), KK));\nELSE\n"
                   "    HH_SHR := DWORD_TO_DINT(NOT SHR(NOT DINT_TO_DWORD(A), KK));\nEND_IF;",
            "arithmetic shift right, count mod 32 (see docs/language.md#comparisons-shifts-and-bit-commands)", shift_locals),
        _fn("HH_BSET", "DINT", [("A", "DINT"), ("K", "DINT")],
            _COUNT_MOD_32 + "HH_BSET := DWORD_TO_DINT(DINT_TO_DWORD(A) OR SHL(DWORD#1, KK));", "BS (see docs/language.md#comparisons-shifts-and-bit-commands)", shift_locals),
        _fn("HH_BCLR", "DINT", [("A", "DINT"), ("K", "DINT")],
            _COUNT_MOD_32 + "HH_BCLR := DWORD_TO_DINT(DINT_TO_DWORD(A) AND NOT SHL(DWORD#1, KK));", "BC (see docs/language.md#comparisons-shifts-and-bit-commands)", shift_locals),
        _fn("HH_BTEST", "BOOL", [("A", "DINT"), ("K", "DINT")],
            _COUNT_MOD_32 + "HH_BTEST := (SHR(DINT_TO_DWORD(A), KK) AND 16#1) <> 0;", "BT (see docs/language.md#comparisons-shifts-and-bit-commands)", shift_locals),
        _fn("HH_BIT", "BOOL", [("A", "DINT"), ("K", "DINT")],
            "HH_BIT := (SHR(DINT_TO_DWORD(A), DINT_TO_INT(K)) AND 16#1) <> 0;", "bit K (0-31) of a word"),
        _fn("HH_LOWORD", "INT", [("V", "DINT")], "HH_LOWORD := WORD_TO_INT(DWORD_TO_WORD(DINT_TO_DWORD(V)));",
            "low 16-bit word of a value (data stack, A-19)"),
        _fn("HH_HIWORD", "INT", [("V", "DINT")],
            "HH_HIWORD := WORD_TO_INT(DWORD_TO_WORD(SHR(DINT_TO_DWORD(V), 16)));", "high 16-bit word (data stack, A-19)"),
        _fn("HH_FROMWORDS", "DINT", [("HI", "INT"), ("LO", "INT")],
            "HH_FROMWORDS := DWORD_TO_DINT(SHL(WORD_TO_DWORD(INT_TO_WORD(HI)), 16) OR WORD_TO_DWORD(INT_TO_WORD(LO)));",
            "two stack words into a value (A-19)"),
        _fn("HH_MKINT", "INT", [("B0", "BYTE"), ("B1", "BYTE")],
            "HH_MKINT := WORD_TO_INT(SHL(BYTE_TO_WORD(B1), 8) OR BYTE_TO_WORD(B0));",
            "word from its low (B0) and high (B1) byte"),
        _fn("HH_MKDINT", "DINT", [("B0", "BYTE"), ("B1", "BYTE"), ("B2", "BYTE"), ("B3", "BYTE")],
            "HH_MKDINT := DWORD_TO_DINT(SHL(BYTE_TO_DWORD(B3), 24) OR SHL(BYTE_TO_DWORD(B2), 16)\n"
            "    OR SHL(BYTE_TO_DWORD(B1), 8) OR BYTE_TO_DWORD(B0));",
            "double word from its bytes, B0 lowest"),
        _fn("HH_BYTEOF", "BYTE", [("V", "DINT"), ("K", "DINT")],
            "HH_BYTEOF := DWORD_TO_BYTE(SHR(DINT_TO_DWORD(V), DINT_TO_INT(K) * 8));", "byte K (0 = lowest) of a value"),
        _pack(8), _pack(16), _pack(32),
    ]
    return {p.name: p for p in pous}


HELPER_DEPENDENCIES = MappingProxyType({"HH_DIV": ("HH_SUB",)})


def timer_fb(semantics: Semantics) -> Pou:
    """HH_TIMER: the control's timer service exactly, cycle based; the options of A-34 decide the body."""
    restart = semantics["timer_restart_while_running"]
    consumed = semantics["timer_start_consumed"]
    cond = "START" if restart else "START AND REMAINING = 0"
    body = (f"IF {cond} THEN\n    REMAINING := PRESET;\nELSIF REMAINING > 0 THEN\n    REMAINING := REMAINING - 1;\nEND_IF;\n"
            + ("START := FALSE;\n" if consumed else "")
            + "RUNNING := REMAINING > 0;")
    return Pou("HH_TIMER", "FUNCTION_BLOCK", (
        VarSection("VAR_IN_OUT", (IecVar("START", "BOOL", comment="timer start operand (consumed by the service)"),)),
        VarSection("VAR_INPUT", (IecVar("PRESET", "DINT", comment="duration in PLC cycles (MP4110)"),)),
        VarSection("VAR_OUTPUT", (IecVar("RUNNING", "BOOL", comment="timer running operand"),)),
        VarSection("VAR", (IecVar("REMAINING", "DINT", comment="cycles left"),)),
    ), body, comment="HEIDENHAIN timer service (A-34, see docs/language.md#timers-and-counters): call once per cycle before the program logic")


def counter_fb(semantics: Semantics) -> Pou:
    """HH_COUNTER: the control's counter service exactly; the options of A-36 decide the body."""
    edges = semantics["counter_counts"] == "rising_edges"
    consumed = semantics["counter_start_consumed"]
    release = "RELEASE AND NOT LAST_RELEASE" if edges else "RELEASE"
    body = ("IF START THEN\n    COUNT := PRESET;\n" + ("    START := FALSE;\n" if consumed else "")
            + f"ELSIF COUNT > 0 AND {release} THEN\n    COUNT := COUNT - 1;\nEND_IF;\n"
            + "LAST_RELEASE := RELEASE;\nRUNNING := COUNT > 0;")
    return Pou("HH_COUNTER", "FUNCTION_BLOCK", (
        VarSection("VAR_IN_OUT", (IecVar("START", "BOOL", comment="counter start operand (loads the preset)"),)),
        VarSection("VAR_INPUT", (IecVar("PRESET", "DINT", comment="preset (MP4120)"),
                                 IecVar("RELEASE", "BOOL", comment="release count pulse"))),
        VarSection("VAR_OUTPUT", (IecVar("RUNNING", "BOOL", comment="counter contents not zero"),)),
        VarSection("VAR", (IecVar("COUNT", "DINT"), IecVar("LAST_RELEASE", "BOOL"))),
    ), body, comment="HEIDENHAIN counter service (A-36, see docs/language.md#timers-and-counters): call once per cycle before the program logic")
