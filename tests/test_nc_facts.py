"""The NC model's facts (verify/nc_facts.NC_FACTS) against the NC model itself: random NC jobs played through the C
model and through the reference machine with a PLC that acknowledges at random, every fact checked after every
phase; and the compare outcomes the implication analysis ties to those facts, against the interpreter."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from transpiler.exec.compiled.shim import NcModel
from transpiler.exec.interp import Machine, compile_program
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.verify.implication import _compare_value
from transpiler.verify.nc_facts import NC_FACTS, NC_MODEL_OWNED, TOOL_CALL_STROBE, applicable_facts

_ACKS = (4090, 4091, 4092, 4093, 4094, 4095)
_POCKETS = (-1, 0, 1, 2, 24, 32767)     # the scenario format's pockets (NC_VALUE_RANGES)
_TOOLS = (0, 0, 1, 7, 32767)


def _job(rng: random.Random) -> dict:
    kind = rng.choice(("tool_call", "tool_call", "tool_call", "tool_def", "tool_def", "m_function", "mode",
                       "restart", "gear", "fn19", "spindle_speed"))
    if kind in ("tool_call", "tool_def"):
        job = {"tool": rng.choice(_TOOLS), "pocket": rng.choice(_POCKETS)}
        if kind == "tool_call" and rng.random() < 0.3:
            job["second_strobe"] = True
        return {kind: job}
    return {"m_function": {"m_function": 3}, "mode": {"mode": 2}, "restart": {"restart": "program"},
            "gear": {"gear": 1}, "fn19": {"fn19": {"value1": 1, "value2": 2}},
            "spindle_speed": {"spindle_speed": 100}}[kind]


def _check(state: dict, seen: set) -> None:
    for fact in NC_FACTS:
        values = {k: state.get(k, 0) for k in fact.operands}
        assert fact.holds(values), (fact.text, values)
    if state.get(TOOL_CALL_STROBE):
        seen.add(tuple(state.get(("M", m), 0) for m in (4521, 4522, 4523)))


def test_every_fact_holds_in_every_phase_of_random_nc_jobs() -> None:
    # The C model with a PLC whose acknowledgements flip at random (also while no strobe is up): whatever the PLC
    # does with the markers it owns, the facts hold after every phase. Catches: a fact the model does not keep
    # (a TOOL DEF writing the pocket during a TOOL CALL's strobe, a marker left over from the call before).
    seen: set = set()
    for seed in range(6):
        rng = random.Random(seed)
        nc = NcModel(20, "itnc530")
        state: dict = {}
        acks = {a: 0 for a in _ACKS}
        for cycle in range(1500):
            if rng.random() < 0.08:
                nc.enqueue(_job(rng))
            for kind, addr, value in nc.phase(cycle, lambda marker: acks.get(marker, 0)):
                assert (kind, addr) in NC_MODEL_OWNED
                state[(kind, addr)] = value
            _check({**state, **{("M", a): v for a, v in acks.items()}}, seen)
            for a in _ACKS:                         # the PLC side: follows its strobe, mostly
                strobe = state.get(("M", a - 20), 0) or state.get(("M", 4520), 0) and a == 4093
                if rng.random() < 0.5:
                    acks[a] = strobe if rng.random() < 0.9 else 1 - strobe
    # the strobe was seen with each of the three markers, so the strobe fact was really tried
    assert {(1, 0, 0), (0, 1, 0), (0, 0, 1)} <= seen


def test_every_fact_holds_on_the_reference_machine(tmp_path: Path) -> None:
    # The same through the interpreter's NC side: a program acknowledges the TOOL CALL and TOOL DEF strobes when
    # an input says so; the machine's own memory is checked after every cycle.
    (tmp_path / "main.src").write_text("L M4073\nO M4520\nA I1\n= M4093\nL M4074\nA I2\n= M4094\nL M4072\nA I1\n"
                                       "= M4092\nEM\n")
    program = compile_project(ProjectOptions(main=tmp_path / "main.src"), make_semantics("itnc530", {})).program
    assert applicable_facts(program, set()) == NC_FACTS
    machine = Machine(program, compiled=compile_program(program))
    rng = random.Random(7)
    seen: set = set()
    for cycle in range(3000):
        jobs = [_job(rng)] if rng.random() < 0.05 else []
        jobs = [j for j in jobs if next(iter(j)) in ("tool_call", "tool_def", "m_function", "mode")]
        # the cycle's phases one by one: the facts hold when the program starts (the acknowledgements as the NC
        # read them), and those without an operand of the PLC's also after the program
        machine.apply_writes([("I", 1, rng.randrange(2)), ("I", 2, rng.randrange(2))])
        machine.nc_phase(cycle, jobs)
        machine.input_latch()
        machine.data_phase()
        machine.timer_service()
        _check({k: machine.read(*k) for fact in NC_FACTS for k in fact.operands}, seen)
        machine.program_phase(cycle)
        machine.output_flush()
        machine.end_cycle()
        for fact in NC_FACTS:
            if not fact.plc_owned:
                assert fact.holds({k: machine.read(*k) for k in fact.operands}), fact.text
    assert {(1, 0, 0), (0, 1, 0), (0, 0, 1)} <= seen


def test_a_fact_does_not_apply_where_its_operands_can_be_written_otherwise(tmp_path: Path) -> None:
    # Written by the program (by name, or a double word over the pocket word, or through the index register where
    # it may reach them), set by a scenario, or another word over it named (the stimulus may set it): the facts
    # naming that operand are left out, the others kept. An acknowledgement is the PLC's own: written by the
    # program or a scenario, its handshake fact still applies (mcdc checks the writes before each chain).
    def facts(text: str, driven=frozenset()) -> set:
        (tmp_path / "main.src").write_text(text)
        program = compile_project(ProjectOptions(main=tmp_path / "main.src"),
                                  make_semantics("itnc530", {})).program
        return {f.operands[:2] for f in applicable_facts(program, set(driven))}

    flags, strobe_fact, tool_ack = (("M", 4521), ("M", 4522)), (("M", 4073), ("M", 4521)), (("M", 4073), ("M", 4093))
    pocket, m_code, tool = (("W", 262),), (("W", 260),), (("W", 264),)      # the range facts of single words
    every = facts("L M4521\n= O1\nEM\n")
    assert len(every) == len(NC_FACTS) and {flags, strobe_fact, tool_ack, pocket, m_code, tool} <= every
    assert facts("L I1\nS M4522\nEM\n") == every - {flags, strobe_fact}
    assert facts("L K1\n= W262\nEM\n") == every - {strobe_fact, pocket}
    assert facts("L K1\n= D260\nEM\n") == every - {strobe_fact, pocket, m_code}
    assert facts("L D260\n= D0\nEM\n") == every - {strobe_fact, pocket, m_code}
    assert facts("L M4521\n= O1\nEM\n", {("M", 4073)}) == every - {strobe_fact, tool_ack}
    assert facts("L M4521\n= O1\nEM\n", {("W", 264)}) == every - {strobe_fact, tool}
    # a PLC module that writes to an address it is given (9040: axis coordinates into 5 double words) may write
    # any of them: no fact applies
    assert facts("PS K400\nPS K0\nCM 9040\nEM\n") == set()
    assert facts("L I1\n= M4093\nEM\n", {("M", 4093)}) == every
    # a marker written through an index that may reach anywhere: the facts on markers go, the words' ranges stay
    words_only = {f.operands[:2] for f in NC_FACTS if all(k[0] in "BWD" for k in f.operands)}
    assert facts("L W100\n= X\nL I1\n= M10[X]\nEM\n") == words_only == {pocket, m_code, tool, (("W", 256),),
                                                                      (("W", 272),), (("D", 356),)}


@pytest.mark.parametrize("semantics", [{}, {"load_extension": "zero"}, {"compare_signedness": "unsigned"},
                                       {"load_extension": "zero", "compare_signedness": "unsigned"}])
def test_compare_outcomes_tied_to_the_facts_are_the_interpreters(tmp_path: Path, semantics: dict) -> None:
    # The analysis works out `L W262` `<rel> K<c>` for a pocket value itself; each outcome must be the
    # interpreter's, under every load extension and compare signedness. Catches: a signed compare assumed where
    # the word is zero-extended (-1 is 65535 then).
    rels = ("==", "<>", "<", ">", "<=", ">=")
    constants = (-1, 0, 1, 65535, -32768)
    lines, outputs = [], []
    for rel in rels:
        for c in constants:
            lines += ["L W262", f"{rel} K{c}", f"= M{len(outputs)}"]
            outputs.append((rel, c))
    (tmp_path / "main.src").write_text("\n".join(lines) + "\nEM\n")
    program = compile_project(ProjectOptions(main=tmp_path / "main.src"),
                              make_semantics("itnc530", semantics)).program
    machine = Machine(program, compiled=compile_program(program))
    for cycle, value in enumerate((-32768, -2, -1, 0, 1, 2, 32767)):
        machine.write("W", 262, value)
        machine.program_phase(cycle)
        for n, (rel, c) in enumerate(outputs):
            assert machine.read("M", n) == _compare_value(program.semantics, "W", value, rel, c), (value, rel, c)
