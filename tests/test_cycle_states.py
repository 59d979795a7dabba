"""States one of which holds at the start of every cycle but the first (verify/cycle_states.py): a step chain's idle
step that takes a flag and a word over together keeps them together for the step that reads them in the next cycle;
whatever breaks that leaves the item missing; and every state a real run starts a cycle in is one of those found
(random power-on memory and inputs on small programs, the sample's scenarios with a generated search)."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from transpiler.exec.interp import Machine, compile_program
from transpiler.exec.interp.faults import MachineHalted
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.verify.cycle_paths import kept_between_cycles
from transpiler.verify.cycle_states import StartStates, start_states
from transpiler.verify.mcdc import decision_coverage
from transpiler.verify.simulate import program_operands

ROOT = Path(__file__).resolve().parents[1]

# B10 is a step word: 0 idle, 1 evaluate. Idle takes the flag M5 = (I1 and W30 >= 1) and the pocket W20 from W30
# (a word the program never writes: any value) together and moves to step 1; Evaluate reads M5 and W20 < 1 in one
# chain and goes back to idle. M5 = 1 comes only with W20 >= 1, one cycle later: no single-cycle analysis sees that.
# {between}: code after Idle's stores, {first}: the first-cycle code.
_TAKE_OVER = """{first}CASE B10
CM Idle
CM Evaluate
ENDC
{between}EM
LBL Init
L K0
= B10
EM
LBL Idle
L I1
A[
L W30
>= K1
]
= M5
L W30
= W20
L K1
= B10
EM
LBL Evaluate
L M5
A[
L W20
< K1
]
= O1
L K0
= B10
EM
"""
_INIT = "L M4172\nCMT Init\n"


def _program(folder: Path, text: str):
    (folder / "main.src").write_text(text)
    result = compile_project(ProjectOptions(main=folder / "main.src"), make_semantics("itnc530", {}))
    assert result.ok
    return result.program


def _condition(program, text: str) -> object:
    cov = decision_coverage(program, [])
    return next(i for i in cov.conditions if i.condition.text == text and i.decision.op.operand is not None
                and i.decision.op.operand.display() == "O1")


def test_a_flag_and_word_taken_over_together_stay_together_into_the_next_step(tmp_path: Path) -> None:
    # Catches: the states not found, not assumed at the main program's start, or not named in the reason.
    program = _program(tmp_path, _TAKE_OVER.format(first=_INIT, between=""))
    item = _condition(program, "W20 < K1")
    assert item.status == "infeasible", item
    assert "kept apart by B10, M5" in item.reason
    assert "M5 = 1 only with W20 < K1 = 0" in item.reason


@pytest.mark.parametrize("first, between", [
    ("", ""),                                       # no first-cycle reset: power-on memory reaches Evaluate
    (_INIT, "L W40\n= W20\n"),                      # the word rewritten after the step chain, in every cycle
    (_INIT, "L I2\nS M5\n"),                        # the flag set after the step chain
    (_INIT, "L I3\nIFT\nL K-3\n= W20\nENDI\n"),   # the word rewritten on one path, after the step chain
], ids=["no_reset", "word_rewritten", "flag_set", "word_rewritten_on_a_path"])
def test_what_breaks_the_pair_leaves_the_condition_missing(tmp_path: Path, first: str, between: str) -> None:
    # Catches: a claim where a state the analysis does not follow reaches Evaluate with M5 = 1 and W20 < 1.
    program = _program(tmp_path, _TAKE_OVER.format(first=first, between=between))
    assert _condition(program, "W20 < K1").status == "missing"


def _covered(states: StartStates, kept, read) -> bool:
    """Whether the memory `read` gives is one of the states (on what the states keep between cycles)."""
    for state in states.states:
        if all(read(k) == v for k, v in state.bits.items() if kept(k)) and \
                all(w.holds(read(k)) for k, w in state.words.items() if kept(k)):
            return True
    return False


def _watch(machine: Machine, found: list[StartStates], kept, failures: list) -> None:
    """Checks the memory at the start of every program phase but the first against each of `found` (failures:
    (the states' keys, cycle))."""
    phase = machine.program_phase

    def checked(cycle: int, report=None):
        for states in found if cycle > 0 else ():
            if not _covered(states, kept, lambda k: machine.read(*k)):
                failures.append((states.names, cycle))
        return phase(cycle, report)
    machine.program_phase = checked


# Init clearing with a loop that also writes the flag (a restart runs it in the middle of a run)
_LOOPED_INIT = "LBL Init\nL K0\n= B10\nL K0\n= X\nLBL Again\nL I7\n= M5\nINCX\nL X\n< K3\nJPT Again\nEM\n"


@pytest.mark.parametrize("between, looped", [("", False), ("L W40\n= W20\n", False),
                                             ("L W40\n= W30\nL K1\n= B10\n", False), ("", True)])
def test_every_state_a_random_run_starts_a_cycle_in_is_found(tmp_path: Path, between: str, looped: bool) -> None:
    # Soundness on small programs: random power-on memory (step word, flag, words, outputs), random inputs and free
    # words every cycle, restarts (the first-cycle marker again); at the start of every cycle but the first the
    # memory is one of the states found.
    text = _TAKE_OVER.format(first=_INIT, between=between)
    if looped:
        text = text.replace("LBL Init\nL K0\n= B10\nEM\n", _LOOPED_INIT)
    program = _program(tmp_path, text)
    states = start_states(program, [("B", 10), ("M", 5)], set(), set(), set())
    assert states is not None and any(("W", 20) in s.words and s.bits.get(("M", 5)) == 1 for s in states.states)
    kept = kept_between_cycles(program, set())
    used = sorted(program_operands(program)[0], key=lambda r: (r.kind, r.addr))
    free = [(r.kind, r.addr) for r in used if not kept((r.kind, r.addr))]
    rng = random.Random(5)
    compiled = compile_program(program)
    failures: list[int] = []
    for _ in range(20):
        machine = Machine(program, compiled=compiled)
        for r in used:
            machine.write(r.kind, r.addr, rng.choice((-2, -1, 0, 1, 2, 7)) if r.kind in "BWD" else rng.randrange(2))
        _watch(machine, [states], kept, failures)
        try:
            for cycle in range(30):
                restart = [("M", 4172, int(rng.random() < 0.1))] if cycle else []
                machine.run_cycle(cycle, restart + [(k, a, rng.choice((-1, 0, 1, 3)) if k in "BWD" else
                                                     rng.randrange(2)) for k, a in free if k != "M"])
        except MachineHalted:
            pass
    assert failures == []


def test_every_state_a_sample_run_starts_a_cycle_in_is_found() -> None:
    # Soundness on the sample: every scenario (power-on states mid tool change, restarts, late first cycles) and a
    # generated search; the keys of the tool change's evaluation (its step word and the automatic-change flag, forked
    # on the NC's tool flags), of the M-function decoder (the strobe memory and three pending markers) and of the
    # chip conveyor's M-function check.
    from transpiler import api
    from transpiler.diagnostics import Diagnostics
    from transpiler.verify.guided import generate
    from transpiler.verify.mcdc import driven_operands, power_on_operands
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.simulate import build_machine, project_names, run_scenario
    sample = ROOT / "samples" / "basic_program"
    program = api.load_project(api.project_options(sample / "Main_PGM.src")).program
    names = project_names(program)
    compiled = compile_program(program)
    scenarios = [load_scenario(p, names) for p in sorted((sample / "scenarios").glob("*.yaml"))]
    scenarios += generate(program, names, 300, seed=8, seeds=scenarios, machine_parameters=sample / "MP_data.mp")
    driven = driven_operands(scenarios, names)
    outside = driven - power_on_operands(scenarios, names)

    def key(name: str) -> tuple[str, int]:
        ref = names.resolve(name)
        return (ref.kind, ref.addr)
    kept = kept_between_cycles(program, outside)
    checks = [(["BG_step_tool", "ML_new_auto"], ["NP_M4522_tool_with_pocket", "NP_M4521_T0", "NP_M4073_strobe_T"]),
              (["ML_strobe_M_mem", "MG_Mpend_M30", "MG_Mpend_M50", "MG_Mpend_M51"], ["NP_M4072_strobe_M"]),
              # the keys KeyChooser picks for Chip_conveyor.src:98
              (["MG_Mpend_M50", "ML_sel_conv_fwd", "MG_Mpend_M51", "MG_control_ok", "ML_strobe_M_mem", "MG_Mpend_M30"],
               ["NP_M4072_strobe_M", "I_control_voltage_on"])]
    found = [start_states(program, [key(n) for n in keys], {key(n) for n in split}, outside, driven, keys)
             for keys, split in checks]
    assert None not in found
    failures: list = []
    for scenario in scenarios:
        machine = build_machine(program, scenario, Diagnostics(), compiled=compiled)
        _watch(machine, found, kept, failures)
        run_scenario(program, scenario, names, machine=machine)
        assert failures == [], (scenario.name, failures[:3])


def test_a_marker_a_random_glob_toggles_is_not_kept_between_cycles(tmp_path: Path) -> None:
    # Catches: driven_operands skipping a glob of `random.inputs`: `M5*` toggles the flag M5 every cycle, so M5 = 1
    # reaches Evaluate with W20 = 0 (W30 stays 0) and the pair of M5 is shown; the states must not keep M5.
    from transpiler.exec.interp import compile_program
    from transpiler.diagnostics import Diagnostics
    from transpiler.verify.mcdc import driven_operands, power_on_operands
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.simulate import build_machine, project_names, run_scenario
    program = _program(tmp_path, _TAKE_OVER.format(first=_INIT, between=""))
    (tmp_path / "s.yaml").write_text("name: glob\ncycles: 200\nrandom:\n  seed: 3\n  inputs: [\"I*\", \"M5*\"]\n"
                                     "  toggle_probability: 0.5\nevents:\n  - cycle: 0\n    set: {W30: 0}\n")
    names = project_names(program)
    scenario = load_scenario(tmp_path / "s.yaml", names)
    driven, power_on = driven_operands([scenario], names), power_on_operands([scenario], names)
    assert ("M", 5) in driven and ("M", 5) not in power_on
    machine = build_machine(program, scenario, Diagnostics(), coverage=True,
                            compiled=compile_program(program, coverage=True))
    run_scenario(program, scenario, names, machine=machine)
    cov = decision_coverage(program, [machine.coverage], driven, power_on=power_on)
    item = next(i for i in cov.conditions if i.condition.text == "M5" and i.decision.op.operand is not None
                and i.decision.op.operand.display() == "O1")
    assert item.status == "shown"
    assert all(i.status != "infeasible" or "kept apart by" not in i.reason for i in cov.conditions)


# M7 carried from the last cycle: with M7 = 1 the loop is entered by a jump forward past its head (Mid), and its
# second pass runs Head with M7 = 1; with M7 = 0 it is entered at Head.
_INTO_LOOP = """L K0
= W50
L M7
JPT Mid
LBL Head
L M7
A I4
= O2
LBL Mid
L W50
+ K1
= W50
L W50
< K3
JPT Head
L I1
= M20
L M20
= M7
EM
"""


def _runs(program, inputs, runs: int, cycles: int, seed: int) -> list[Machine]:
    """Runs from random power-on memory with the inputs `inputs(rng)` gives every cycle."""
    rng = random.Random(seed)
    used = sorted(program_operands(program)[0], key=lambda r: (r.kind, r.addr))
    compiled = compile_program(program, coverage=True)
    machines = []
    for _ in range(runs):
        machine = Machine(program, compiled=compiled, coverage=True)
        for r in used:
            machine.write(r.kind, r.addr, rng.choice((-1, 0, 1, 2)) if r.kind in "BWD" else rng.randrange(2))
        for cycle in range(cycles):
            machine.run_cycle(cycle, inputs(rng))
        machines.append(machine)
    return machines


def test_a_loop_entered_past_its_head_runs_its_passes_from_that_path_too(tmp_path: Path) -> None:
    # Catches: a loop's passes run only from the states that entered its head (pass_start), so the path that jumped
    # forward into the body (M7 = 1) never ran Head: M7 of `M7 AND I4 = O2` was called infeasible (M7 always 0),
    # where a run with I4 = 1 shows it.
    program = _program(tmp_path, _INTO_LOOP)
    weak = _runs(program, lambda rng: [("I", 1, rng.randrange(2)), ("I", 4, 0)], 10, 30, 2)
    cov = decision_coverage(program, [m.coverage for m in weak])
    o2 = [i for i in cov.conditions if i.decision.op.operand is not None and i.decision.op.operand.display() == "O2"]
    assert [i.status for i in o2] == ["missing", "missing"], [i.reason for i in o2]
    full = _runs(program, lambda rng: [("I", 1, rng.randrange(2)), ("I", 4, rng.randrange(2))], 10, 30, 3)
    cov = decision_coverage(program, [m.coverage for m in full])
    assert [i.status for i in cov.conditions if i.decision.op.operand is not None
            and i.decision.op.operand.display() == "O2"] == ["shown", "shown"]


def test_a_subprogram_loop_entered_past_its_head_claims_nothing(tmp_path: Path) -> None:
    # Catches: the same in a called subprogram, with a word: W40 == 1 jumps past Head, whose second pass stores
    # W42 = W40 = 1; `W42 == K1` was called always 0. A run from power-on memory with W40 = 1 shows it.
    program = _program(tmp_path, "CM Sub\nL W42\n== K1\n= O1\nEM\nLBL Sub\nL K0\n= W42\nL K0\n= W50\nL W40\n"
                                 "== K1\nJPT Mid\nLBL Head\nL W40\n= W42\nLBL Mid\nL W50\n+ K1\n= W50\nL W50\n"
                                 "< K3\nJPT Head\nEM\n")
    item = next(i for i in decision_coverage(program, []).conditions if i.condition.text == "W42 == K1")
    assert item.status == "missing", item.reason
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    for cycle in range(3):
        machine.run_cycle(cycle, [("W", 40, cycle % 2)])
    cov = decision_coverage(program, [machine.coverage], explain_missing=False)
    assert next(i for i in cov.conditions if i.condition.text == "W42 == K1").status == "shown"
