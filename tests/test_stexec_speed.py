"""The built-in ST executor's fast paths give the same results as the plain ones: a CASE of many disjoint
intervals as a binary search (gen_statements.case_tree), and Runtime.reader (many paths read in one call)."""

from __future__ import annotations

import random

import pytest

from transpiler.exec.stexec import load_st
from transpiler.backends.report.iomap import Place
from transpiler.verify.cosim import runtime_reader

CONFIG = """
CONFIGURATION Cfg
  RESOURCE Res ON PLC
    TASK Fast(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst WITH Fast : Main;
  END_RESOURCE
END_CONFIGURATION
"""


def program(arms: list[str], orelse: str | None) -> str:
    """A program whose CASE over pick writes the arm's number to out (ELSE: -1), and counts its runs in hits."""
    body = "\n".join(f"    {labels}: out := {n}; hits := hits + 1;" for n, labels in enumerate(arms))
    other = f"  ELSE\n    {orelse}\n" if orelse is not None else ""
    return (f"PROGRAM Main\nVAR\n  pick : DINT;\n  out : DINT := 99;\n  hits : DINT;\nEND_VAR\n"
            f"out := 99;\nCASE pick OF\n{body}\n{other}END_CASE;\nEND_PROGRAM\n" + CONFIG)


def reference(arms: list[str], orelse: bool, sel: int) -> int:
    """The first arm whose labels hold sel, as IEC's CASE picks it."""
    for n, labels in enumerate(arms):
        for label in labels.split(","):
            lo, _, hi = label.strip().partition("..")
            if int(lo) <= sel <= int(hi or lo):
                return n
    return -1 if orelse else 99


@pytest.mark.parametrize("seed", range(6))
def test_case_of_many_arms_picks_the_arm_the_chain_picks(seed: int) -> None:
    rng = random.Random(seed)
    arms, at = [], -20
    for _ in range(rng.randint(9, 60)):
        at += rng.randint(1, 4)                      # gaps between the intervals
        width = rng.choice((0, 0, 0, 2))
        if width and rng.random() < 0.5:
            arms.append(f"{at}, {at + 1}..{at + width}")   # one interval spelled as two labels
        else:
            arms.append(f"{at}..{at + width}" if width else str(at))
        at += width
    rng.shuffle(arms)                                 # the order of the arms is not the order of the values
    orelse = rng.random() < 0.7
    project = load_st(program(arms, "out := -1;" if orelse else None), "case.st")
    assert "if _c1 <" in project.python_source, "a CASE of this size is expected to compile to the tree"
    rt = project.instantiate()
    for sel in range(-25, at + 5):
        rt.set("inst.pick", sel)
        rt.run_cycle()
        assert rt.get("inst.out") == reference(arms, orelse, sel), f"sel={sel}"


def test_overlapping_labels_keep_the_first_match() -> None:
    arms = [str(n) for n in range(12)] + ["3..5"]      # 3..5 overlaps: never reached
    project = load_st(program(arms, "out := -1;"), "overlap.st")
    assert "if _c1 <" not in project.python_source      # the chain keeps the first-match rule
    rt = project.instantiate()
    for sel in (3, 4, 5, 12):
        rt.set("inst.pick", sel)
        rt.run_cycle()
        assert rt.get("inst.out") == reference(arms, True, sel)


def test_else_runs_once_and_only_without_a_match() -> None:
    arms = [str(n) for n in range(0, 40, 2)]            # the odd numbers fall in the gaps
    rt = load_st(program(arms, "out := -1; hits := hits + 100;"), "else.st").instantiate()
    rt.set("inst.pick", 7)
    rt.run_cycle()
    assert (rt.get("inst.out"), rt.get("inst.hits")) == (-1, 100)
    rt.set("inst.pick", 8)
    rt.run_cycle()
    assert (rt.get("inst.out"), rt.get("inst.hits")) == (4, 101)


def test_reader_reads_what_get_reads() -> None:
    text = ("PROGRAM Main\nVAR\n  b : BOOL;\n  w : INT;\n  bytes : ARRAY[0..7] OF BYTE;\n  name : STRING;\nEND_VAR\n"
            "b := TRUE;\nw := -5;\nbytes[0] := 16#34;\nbytes[1] := 16#F2;\nbytes[2] := 16#01;\nname := 'ab';\n"
            "END_PROGRAM\n" + CONFIG)
    rt = load_st(text, "read.st").instantiate()
    rt.run_cycle()
    paths = ["inst.b", "inst.w", "inst.bytes[1]", "inst.name"]
    assert rt.reader(paths)() == [rt.get(p) for p in paths]
    places = [Place("inst.b"), Place("inst.w"), Place("inst.bytes[0]", 2), Place("inst.bytes[0]", 2, True),
              Place("inst.bytes[1]", 1), Place("inst.name", text=True)]
    # 0xF234 little endian is -3532; big endian 0x34F2 = 13554; one byte 0xF2 is -14
    assert runtime_reader(rt, places)() == [1, -5, -3532, 13554, -14, "ab"]
    rt.set("inst.w", 7)
    assert runtime_reader(rt, places[1:2])() == [7]      # reads the live value, not a copy
