"""Corner stimulus (verify/corners.py) and the coverage-guided search (verify/guided.py) on the sample."""

from __future__ import annotations

import json
import random
from pathlib import Path

import pytest

from transpiler import api
from transpiler.cli.app import main
from transpiler.diagnostics import Diagnostics
from transpiler.exec.interp import compile_program
from transpiler.verify.corners import Corners, harvest
from transpiler.verify.nc_facts import NC_MODEL_OWNED
from transpiler.verify.equiv import coverage_summary
from transpiler.verify.guided import generate
from transpiler.verify.mcdc import decision_coverage
from transpiler.verify.scenario import load_scenario
from transpiler.verify.simulate import build_machine, project_names
from transpiler.verify.stimulus import build_stimulus, scenario_to_yaml

SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "basic_program"


@pytest.fixture(scope="module")
def sample():
    project = api.load_project(api.project_options(SAMPLE / "Main_PGM.src"))
    names = project_names(project.program)
    seeds = [load_scenario(p, names) for p in sorted((SAMPLE / "scenarios").glob("*.yaml"))]
    return project.program, names, seeds


def test_harvest_finds_the_decoded_m_codes_their_neighbours_and_the_foreign_words(sample):
    program, names, _ = sample
    corners = harvest(program, names)
    # the M-code table of Mfunction.src
    assert {3, 4, 5, 8, 9, 10, 11, 19, 30, 50, 51} <= set(corners.tables)
    assert {23, 24, 25, 9999, 10000, 10001} <= set(corners.values)      # KG_mag_pockets and K10000, +-1
    words = {name for name, _ in corners.foreign_words}
    assert "NP_W1032_ref_pending" in words and "NP_W1026_axes_in_pos" in words
    # words the NC model writes for nc actions are never driven directly
    assert not any(names.resolve(n) in {(k, a) for k, a in NC_MODEL_OWNED} for n in words)
    assert "NP_M4543_tool_life_expired" in corners.foreign_markers
    rng = random.Random(3)
    jobs = [corners.nc_action(rng, "m_function")["m_function"] for _ in range(200)]
    assert {4, 19, 51, 52} <= set(jobs)


def _coverage(program, names, scenarios):
    compiled = compile_program(program, coverage=True)
    sets = []
    for scenario in scenarios:
        stimulus = build_stimulus(scenario, names)
        machine = build_machine(program, scenario, Diagnostics(), coverage=True, compiled=compiled)
        for cycle in range(stimulus.cycles):
            report = machine.run_cycle(cycle, stimulus.writes(cycle), stimulus.nc_actions(cycle))
            assert not report.faults, (scenario.name, report.faults)
        sets.append(machine.coverage)
    return coverage_summary(program, sets)


def test_guided_stimulus_is_deterministic_within_budget_and_enters_every_case_entry(sample):
    program, names, seeds = sample
    # only scenarios without the rarer M functions (all but M3, M5, M8, M9), so that the search has CASE entries
    # of the M-function decoder to find
    common = {3, 5, 8, 9}
    short = [s for s in seeds if s.cycles <= 1000 and s.name != "restart_with_m_strobe_held"
             and all(e.nc is None or e.nc.kind != "m_function" or e.nc.as_dict()["m_function"] in common
                     for e in s.events)]
    # 2000 generated cycles, as `equiv` draws by default (seed 1)
    first = generate(program, names, 2000, 1, short, machine_parameters=SAMPLE / "MP_data.mp")
    again = generate(program, names, 2000, 1, short, machine_parameters=SAMPLE / "MP_data.mp")
    assert [scenario_to_yaml(s) for s in first] == [scenario_to_yaml(s) for s in again]
    assert 0 < sum(s.cycles for s in first) <= 2000
    before = _coverage(program, names, short)
    after = _coverage(program, names, short + first)
    assert before["case_entries_taken"] < before["case_entries"]
    assert after["case_entries_taken"] == after["case_entries"]
    assert after["branches_both_ways"] > before["branches_both_ways"]
    # what is still not covered is listed with its source line
    assert len(after["never_taken"]) == (after["branches"] - after["branches_both_ways"])
    assert all(":" in item["at"] and item["what"] for item in after["never_taken"])
    untaken_case = [i for i in before["never_taken"] if i["what"].startswith("CASE entry")]
    assert untaken_case and untaken_case[0]["at"].startswith("Mfunction.src:")


def test_generate_without_scenarios_spends_the_budget_on_corner_random_runs(sample):
    program, names, _ = sample
    out = generate(program, names, 300, 1, machine_parameters=SAMPLE / "MP_data.mp")
    assert out and sum(s.cycles for s in out) <= 300
    assert any(e.nc is not None for s in out for e in s.events)


def test_compare_pairs_let_the_search_put_a_compared_word_next_to_its_constant(tmp_path):
    # `L W10 > K100` clamps W10: only 101 tells `> 100` from `> 101`, and no branch or CASE entry is new there. The
    # harvest pairs the word with the constant (either order of load and compare; not an indexed word), the value
    # profile makes 99/100/101 new features, and the search keeps a run with one of them.
    (tmp_path / "main.src").write_text(
        "L     W10\n>     K100\nJPF   Ok\nL     K100\n=     W10\nLBL Ok\nL     K7\n<     W12\n=     O1\n"
        "L     K0\n=     X\nL     W20[X]\n==    K5\n=     O2\n"
        "L     W32\n=     W8\nL     W8\n<     K10\n=     O3\nEM\n")
    project = api.load_project(api.project_options(tmp_path / "main.src"))
    names = project_names(project.program)
    corners = harvest(project.program, names)
    # W32 through its copy W8: the program compares the copy
    assert set(corners.compare_pairs) == {("W10", "W", 100), ("W12", "W", 7), ("W8", "W", 10), ("W32", "W", 10)}
    kept = generate(project.program, names, 200, seed=5)
    near = {value for s in kept for value in [s.initial.get("W10"), *(e.set.get("W10") for e in s.events if e.set)]}
    assert near & {99, 101}, [(s.initial, [e.set for e in s.events]) for s in kept]


def test_dirty_fillers_start_every_written_marker_at_1_once(tmp_path):
    # `R M6` only ever writes M6's power-on value 0: a translation that drops the store is told apart only from a
    # run in which M6 starts at 1. The two dirty filler runs start each written marker at opposite values.
    (tmp_path / "main.src").write_text("L     I1\n=     M5\nL     I2\nR     M6\nL     M6\n=     O1\nEM\n")
    project = api.load_project(api.project_options(tmp_path / "main.src"))
    names = project_names(project.program)
    kept = generate(project.program, names, 2000, seed=3)
    dirty = [s.initial for s in kept if s.name.startswith("random_") and "M6" in s.initial]
    assert len(dirty) == 2 and {d["M6"] for d in dirty} == {0, 1} and {d["M5"] for d in dirty} == {0, 1}, dirty


def test_a_byte_read_through_the_index_register_is_driven_to_the_boundaries_of_its_compare(tmp_path, capsys):
    # `L B10[X]` with X = 2 reads B12, an operand no instruction names. The index analysis says which byte it is,
    # so the stimulus starts it at power-on like a named one; the search then drives it to 6, 7 and 8 (the
    # boundaries of `== K7`), which kills the mutants of the constant and of the address read (B11, B13 are 0).
    source = tmp_path / "main.src"
    source.write_text("L     K2\n=     X\nL     B10[X]\n==    K7\n=     O1\nEM\n")
    project = api.load_project(api.project_options(source))
    names = project_names(project.program)
    assert ("B12", "B") in harvest(project.program, names).remanent_words
    kept = generate(project.program, names, 300, seed=1)
    sets = []
    compiled = compile_program(project.program, coverage=True)
    for scenario in kept:
        stimulus = build_stimulus(scenario, names)
        machine = build_machine(project.program, scenario, Diagnostics(), coverage=True, compiled=compiled)
        for cycle in range(stimulus.cycles):
            machine.run_cycle(cycle, stimulus.writes(cycle), stimulus.nc_actions(cycle))
        sets.append(machine.coverage)
    boundaries = decision_coverage(project.program, sets).boundaries
    assert len(boundaries) == 3 and all(b.status == "reached" for b in boundaries), [b.what() for b in boundaries]
    report = tmp_path / "m.json"
    assert main(["mutate", str(source), "--random-cycles", "300", "--seed", "1", "--backend", "builtin", "--jobs", "1",
                 "--report", str(report), "--min-score", "0"]) == 0
    capsys.readouterr()
    data = json.loads(report.read_text())
    constants = [m for m in data["mutants"] if m["operator"] == "constant"]
    assert len(constants) == 4 and all(m["outcome"] == "killed" for m in constants), constants


def test_a_start_that_faults_from_clean_memory_gets_power_on_memory_that_runs(tmp_path):
    # W10 picks an entry of a three-entry table: from clean memory (W10 = 0) the first cycle faults, and so would
    # every filler run. The generated runs start from power-on memory in which the first cycle runs, and between
    # them read every entry of the table (each one is a feature of the search).
    (tmp_path / "main.src").write_text("L     W10\n-     K1\n=     X\nL     KF Speeds[X]\n=     D60\nEM\n\n"
                                       "KFIELD Speeds\nK500\nK1000\nK2000\nENDK\n")
    project = api.load_project(api.project_options(tmp_path / "main.src"))
    names = project_names(project.program)
    kept = generate(project.program, names, 600, seed=2)
    assert sum(s.cycles for s in kept) > 300, [(s.name, s.cycles) for s in kept]
    assert {s.initial.get("W10") for s in kept} >= {1, 2, 3}
    fillers = [s for s in kept if s.name.startswith("random_")]
    assert fillers and all(s.initial.get("W10") in (1, 2, 3) for s in fillers)


def test_power_on_patterns_tell_every_byte_from_its_neighbours():
    corners = Corners(constants=(), tables=(), values=(0, 1), inputs=(), foreign_words=(), foreign_markers=(),
                      remanent_words=(("W4", "W"), ("D8", "D"), ("B3", "B")), remanent_markers=("M1",))
    rng = random.Random(4)
    for _ in range(50):
        for kind in "BWD":
            value = corners.pattern_value(rng, kind)
            width = {"B": 1, "W": 2, "D": 4}[kind]
            raw = value & ((1 << (8 * width)) - 1)
            parts = [(raw >> (8 * i)) & 255 for i in range(width)]
            assert 0 not in parts and len(set(parts)) == width, (kind, value)
            assert -(1 << (8 * width - 1)) <= value < (1 << (8 * width - 1))
        memory = corners.power_on(rng)
        assert set(memory) == {"W4", "D8", "B3", "M1"} and memory["M1"] in (0, 1)


# D8 reaches the subprogram's D24 through the data stack; W34 is (W30 - W32 + 24) MOD 24, i.e. W30 - W32 + 24 for the
# start values that matter.
STACK_AND_SUM = ("PS    D8\nPS    W12\nCM    Sub\nL     W30\n-     W32\n+     K24\nMOD   K24\n=     W34\n"
                 "L     W34\n==    K0\n=     O3\nEM\n"
                 "LBL Sub\nPL    W20\nPL    D24\nL     D24\n<     K0\n=     O1\nL     K5\n>     W20\n=     O2\nEM\n")


def test_boundary_sources_follow_stack_parameters_and_sums_back_to_power_on_words(tmp_path):
    # Catches: the last pushed taken for the first pulled, a subtracted word's sign lost, the other words' start
    # values left out of the value asked for, and the constant-left compare's difference taken the wrong way.
    (tmp_path / "main.src").write_text(STACK_AND_SUM)
    project = api.load_project(api.project_options(tmp_path / "main.src"))
    sources = harvest(project.program, project_names(project.program)).boundary_sources
    by_name = {}
    for s in sources:
        by_name.setdefault(s.name, []).append(s)
    d8, = by_name["D8"]
    assert (d8.coefficient, d8.offset, d8.others, d8.constant) == (1, 0, (), 0)
    assert d8.value(-1, {}) == -1 and d8.value(1, {}) == 1
    w12, = by_name["W12"]                   # `L K5` `> W20`: left - right = 5 - W20
    assert not w12.word_left and w12.value(-1, {}) == 6
    w32, = by_name["W32"]
    assert (w32.coefficient, w32.offset, w32.others) == (-1, 24, (("W30", 1),))
    assert w32.value(-1, {"W30": 3}) == 28 and w32.value(0, {}) == 24
    w30, = by_name["W30"]
    assert w30.value(-1, {"W32": 28}) == 3
    assert w32.value(-1, {"W30": 40000}) is None or Corners.clamp(w32.value(-1, {"W30": 40000}), "W") == \
        w32.value(-1, {"W30": 40000})


def test_the_search_tries_a_missing_boundary_value_from_its_power_on_source_first(tmp_path):
    # The seed drives D24 and W34 to 0 (every word starts at 0): the first candidates the search runs start D8 and
    # W30 at the values that give -1 and 1 there, the boundary values the seed misses, and all are kept. Catches:
    # the source not found, the value asked for from the wrong side, the directed candidates queued behind random
    # ones.
    (tmp_path / "main.src").write_text(STACK_AND_SUM)
    (tmp_path / "seed.yaml").write_text("name: seed\ncycles: 5\n")
    project = api.load_project(api.project_options(tmp_path / "main.src"))
    names = project_names(project.program)
    seed = load_scenario(tmp_path / "seed.yaml", names)
    kept = generate(project.program, names, 200, seed=7, seeds=[seed])
    first = {tuple(s.initial.items()) for s in kept[:4]}
    assert first == {(("D8", -1),), (("D8", 1),), (("W30", -25),), (("W30", -23),)}, [s.initial for s in kept]
    assert all(s.cycles <= 5 for s in kept[:4])
