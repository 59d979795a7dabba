"""Robustness: hostile and mutated input only ever gives diagnostics (no exception, no hang) within a time bound."""

from __future__ import annotations

import random
import subprocess
import sys
import time
from datetime import timedelta
from pathlib import Path

import fuzz
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_frontend_support import compile_files, errors

from transpiler.frontend.load import Parsers, ProjectOptions
from transpiler.language.mnemonics import MNEMONICS
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics

LIMIT = 10.0                     # seconds allowed per input (the machine may be shared and slow)
SAMPLE_SEEDS = fuzz.sample_seeds()
VECTOR_SEEDS = fuzz.vector_seeds()
SEEDS = SAMPLE_SEEDS + VECTOR_SEEDS
HYPOTHESIS = settings(max_examples=40, deadline=timedelta(seconds=2 * LIMIT), derandomize=True,
                      suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def _only_diagnostics(tmp_path: Path, files: dict[str, bytes | str], bound: float = LIMIT, **options):
    """Compile under a time bound; the front end must answer with diagnostics only."""
    started = time.perf_counter()
    result = compile_files(tmp_path, files, **options)
    elapsed = time.perf_counter() - started
    assert elapsed < bound, f"took {elapsed:.1f} s"
    fuzz.check_result(result)
    return result


# ------------------------------------------------------------------------------------ mutation properties


@pytest.mark.parametrize("seeds", [
    pytest.param(SAMPLE_SEEDS, id="samples", marks=pytest.mark.skipif(not SAMPLE_SEEDS, reason="no sample projects to mutate")),
    pytest.param(VECTOR_SEEDS, id="vectors",
                 marks=pytest.mark.skipif(not VECTOR_SEEDS, reason="the spec (and its vectors) is not available")),
])
@HYPOTHESIS
@given(index=st.integers(min_value=0, max_value=2 ** 40))
def test_mutated_seed_projects_give_only_diagnostics(tmp_path, seeds, index):
    project, files, _ = fuzz._mutant(seeds, 7, index)
    fuzz.check_project(tmp_path / "p", files, project.main, project.profile, LIMIT)


LINE_PARTS = sorted(MNEMONICS) + ["LBL", "KFIELD", "ENDK", "USES", "GLOBAL", "EXTERN", "#define", "#if", "#else",
                                  "#endif", "DEFINE", "INCLUDE", "*", ";"]
OPERAND_PARTS = ["M0", "I 1", "W2", "D4", "B1", "K-1", "K$FF", "S1", "S#E1", 'S"x;y"', "X", "KF T[X]", "L1", "9032",
                 "[X]", "&A", "/g", "a.def", "main.src", "=", "A = 1", '"s"', ""]


@HYPOTHESIS
@given(st.lists(st.tuples(st.sampled_from(LINE_PARTS), st.sampled_from(OPERAND_PARTS), st.sampled_from(["", " ", "\t"])),
                max_size=60))
def test_random_statement_sequences_give_only_diagnostics(tmp_path, lines):
    text = "\n".join(f"{indent}{m} {o}".rstrip() for m, o, indent in lines)
    _only_diagnostics(tmp_path, {"main.src": text + "\n", "a.def": "A M\n"})


@HYPOTHESIS
@given(st.binary(max_size=4000))
def test_binary_garbage_gives_only_diagnostics(tmp_path, data):
    _only_diagnostics(tmp_path, {"main.src": data, "a.def": data, "OEM.cfg": data[::-1]})


@HYPOTHESIS
@given(st.text(alphabet=st.characters(min_codepoint=0, max_codepoint=255), max_size=300))
def test_random_definition_and_config_lines(tmp_path, text):
    files = {"main.src": "#define /g a.def\nL MG_x\n= O1\nEM\n", "a.def": text, "OEM.cfg": text}
    _only_diagnostics(tmp_path, {name: data.encode("latin-1") for name, data in files.items()})


# --------------------------------------------------------------------------------------- hostile inputs


def test_binary_garbage_project(tmp_path):
    rng = random.Random(5)
    garbage = bytes(rng.randrange(256) for _ in range(200_000))
    result = _only_diagnostics(tmp_path, {"main.src": garbage + b"\nUSES m.src\n", "m.src": garbage})
    assert errors(result)


@pytest.mark.parametrize("line", [b"L " + b"M" * 1_000_000, b"; " + b"x" * 1_000_000, b'L S"' + b"a" * 1_000_000 + b'"',
                                  b"A" * 1_000_000, b"L K" + b"9" * 1_000_000, b"[" * 1_000_000, b"#if A = " + b"1" * 1_000_000,
                                  b"DEFINE A = \"" + b"x" * 1_000_000])
def test_a_one_megabyte_line(tmp_path, line):
    _only_diagnostics(tmp_path, {"main.src": b"L I1\n" + line + b"\nEM\n", "a.def": line + b"\n"})


def test_ten_thousand_nested_ifs(tmp_path):
    depth = 10_000
    text = "DEFINE A = 1\n" + "#if A = 1\n" * depth + "L I1\n= O1\n" + "#endif\n" * depth + "EM\n"
    assert errors(_only_diagnostics(tmp_path, {"main.src": text})) == []
    unbalanced = "DEFINE A = 1\n" + "#if A = 1\n" * depth + "EM\n"   # (defined: an undefined A without a cfg is E-CFG-MISSING)
    assert {e.code for e in errors(_only_diagnostics(tmp_path, {"main.src": unbalanced}))} == {"E-PP-NEST"}


@pytest.mark.parametrize("opener, closer, code", [("A[\nL I1", "]", "E-BRACKET-DEPTH"), ("IFT", "ENDI", "E-STRUCT-NEST"),
                                                  ("WHILET", "ENDW", "E-STRUCT-NEST"), ("+[\nL K1", "]", "E-BRACKET-DEPTH")])
def test_five_thousand_nested_brackets_and_structures(tmp_path, opener, closer, code):
    depth = 5_000
    text = "L I1\nL W0\n" + f"{opener}\n" * depth + f"{closer}\n" * depth + "= O1\nEM\n"
    result = _only_diagnostics(tmp_path, {"main.src": text})
    assert [e.code for e in errors(result)] == [code]          # one fault, one error
    only_open = "L I1\n" + f"{opener}\n" * depth + "EM\n"
    assert errors(_only_diagnostics(tmp_path, {"main.src": only_open}))


def test_unbalanced_everything(tmp_path):
    rng = random.Random(11)
    parts = ["#if A = 1", "#else", "#endif", "A[", "]", "IFT", "ELSE", "ENDI", "WHILET", "ENDW", "REPEAT", "UNTILT",
             "CASE B0", "ENDC", "KFIELD T", "ENDK", "CM L1", "LBL L1", "EM", "L I1", "= O1", "JP L1"]
    text = "\n".join(rng.choice(parts) for _ in range(20_000))
    assert errors(_only_diagnostics(tmp_path, {"main.src": text}))


def test_big_case_table_and_many_labels(tmp_path):
    n = 5_000
    text = "CASE B0\n" + "".join(f"CM S{i}\n" for i in range(n)) + "ENDC\nEM\n" + "".join(f"LBL S{i}\nEM\n" for i in range(n))
    result = _only_diagnostics(tmp_path, {"main.src": text})
    assert errors(result) == []
    case = result.program.files[0].ops[0]
    assert len(case.case_targets) == len(case.case_notes) == n


def test_long_call_chains_and_cycles(tmp_path):
    n = 5_000
    chain = "CM F0\nEM\n" + "".join(f"LBL F{i}\nCM F{i + 1}\nEM\n" for i in range(n)) + f"LBL F{n}\nEM\n"
    assert [e.code for e in errors(_only_diagnostics(tmp_path, {"main.src": chain}))] == ["E-CALL-DEPTH"]
    ring = "CM F0\nEM\n" + "".join(f"LBL F{i}\nCM F{(i + 1) % n}\nEM\n" for i in range(n))
    assert [e.code for e in errors(_only_diagnostics(tmp_path, {"main.src": ring}))] == ["E-CALL-RECURSION"]
    jumps = "".join(f"LBL J{i}\nL I1\nJPT J{(i * 7919) % n}\n" for i in range(n)) + "EM\n"
    assert errors(_only_diagnostics(tmp_path, {"main.src": jumps})) == []


def test_uses_cycles_and_self_inclusion(tmp_path):
    files = {"main.src": "USES a.src\nUSES main.src\nINCLUDE main.src\nINCLUDE main.src\nEM\n",
             "a.src": "USES b.src\nUSES a.src\nEM\n", "b.src": "USES main.src\nINCLUDE b.src\nINCLUDE b.src\nEM\n"}
    result = _only_diagnostics(tmp_path, {**files, "x.def": "#define /g x.def\n"})
    assert {e.code for e in errors(result)} == {"E-FILE-INCLUDE-CYCLE"}
    defs = {"main.src": "#define /g a.def\nEM\n", "a.def": "#define /g b.def\n", "b.def": "#define /g a.def\n"}
    assert {e.code for e in errors(_only_diagnostics(tmp_path, defs))} == {"E-FILE-INCLUDE-CYCLE"}


def test_missing_and_escaping_files(tmp_path):
    files = {"main.src": "USES nope.src\n#define /g nope.def\nINCLUDE nope.inc\nUSES ../../etc/passwd\nUSES /etc/passwd\n"
                         "USES \nUSES .\nUSES sub\nINCLUDE \"\"\nUSES " + "x" * 400 + ".src\nUSES a\x00b.src\nEM\n",
             "sub/x.src": "EM\n"}
    result = _only_diagnostics(tmp_path, files)
    assert [e.code for e in errors(result)] == ["E-FILE-NOT-FOUND"] * 3 + ["E-FILE-ESCAPE"] * 2 + [
        "E-SYNTAX", "E-FILE-NOT-FOUND", "E-FILE-NOT-FOUND", "E-SYNTAX", "E-FILE-NOT-FOUND", "E-FILE-NOT-FOUND"]


def test_chains_of_files_longer_than_the_recursion_limit(tmp_path):
    n = 1_500
    files = {"main.src": "USES m0.src\nEXTERN Z\nCM Z\nEM\n", f"m{n}.src": "GLOBAL Z\nLBL Z\nEM\n"}
    files.update({f"m{i}.src": f"USES m{i + 1}.src\nLBL A{i}\nEM\n" for i in range(n)})
    result = _only_diagnostics(tmp_path, files)
    assert errors(result) == [] and len(result.program.files) == n + 2
    defs = {"main.src": "#define /g d0.def\nEM\n", "d100.def": "MG_z M\n"}
    defs.update({f"d{i}.def": f"#define /g d{i + 1}.def\nMG_{i} M\n" for i in range(100)})
    assert [e.code for e in errors(_only_diagnostics(tmp_path / "defs", defs))] == ["E-FILE-INCLUDE-CYCLE"]


def test_many_modules(tmp_path):
    n = 300
    files = {"main.src": "".join(f"USES m{i}.src\nEXTERN E{i}\nCM E{i}\n" for i in range(n)) + "EM\n"}
    files.update({f"m{i}.src": f"GLOBAL E{i}\nLBL E{i}\nL I{i}\n= O{i}\nEM\n" for i in range(n)})
    result = _only_diagnostics(tmp_path, files)
    assert errors(result) == [] and len(result.program.files) == n + 1


# -------------------------------------------------------------------------------------- the fuzz harness


def test_harness_reports_crashes_and_hangs(tmp_path, monkeypatch):
    """The harness must see a crash as an exception and a hang as InputTimeout (else a clean run proves nothing)."""
    files = {"main.src": b"EM\n"}

    def crash(*args, **kwargs):
        raise ZeroDivisionError("planted")

    def hang(*args, **kwargs):
        while True:
            pass

    monkeypatch.setattr(fuzz, "compile_project", crash)
    with pytest.raises(ZeroDivisionError):
        fuzz.check_project(tmp_path / "p", files, "main.src", "itnc530", LIMIT)
    monkeypatch.setattr(fuzz, "compile_project", hang)
    started = time.perf_counter()
    with pytest.raises(fuzz.InputTimeout):
        fuzz.check_project(tmp_path / "p", files, "main.src", "itnc530", 0.5)
    assert time.perf_counter() - started < 5


def test_mutations_are_reproducible_and_change_one_file():
    if not SEEDS:
        pytest.skip("no seed projects")
    for index in range(50):
        project, files, description = fuzz._mutant(SEEDS, 3, index)
        again = fuzz._mutant(SEEDS, 3, index)
        assert (again[1], again[2]) == (files, description)
        changed = [n for n in project.files if files.get(n) != project.files[n]]
        assert len(changed) <= 2 and description.startswith(project.name)


def test_shared_parsers_give_the_same_diagnostics_as_fresh_ones(tmp_path):
    """The fuzzer shares line caches between inputs; that must not change any result."""
    if not SEEDS:
        pytest.skip("no seed projects")
    shared = Parsers.for_semantics(make_semantics("itnc530"))
    for index in range(15):
        project, files, _ = fuzz._mutant(SEEDS, 9, index)
        if project.profile != "itnc530" or project.main not in files:
            continue
        fresh = compile_files(tmp_path / f"a{index}", files, main=project.main)
        fuzz.write_files(tmp_path / f"b{index}", files)
        warm = compile_project(ProjectOptions(main=tmp_path / f"b{index}" / project.main), make_semantics("itnc530"),
                               parsers=shared)
        assert [d.render() for d in fresh.diagnostics.items] == [d.render() for d in warm.diagnostics.items]


def test_fuzz_command_line(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "tests.fuzz", "--mutations", "12", "--jobs", "1", "--seed", "4"],
                          cwd=Path(__file__).resolve().parents[1], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "crashes: 0, hangs: 0" in proc.stdout and "12 mutations" in proc.stdout


# ------------------------------------------------------------------------------------ PLC data tables

TABLE_SEEDS = [s for s in SAMPLE_SEEDS if any(n.lower().endswith(".tab") for n in s.files)]


@pytest.mark.skipif(not TABLE_SEEDS, reason="no sample project with PLC data tables")
@HYPOTHESIS
@given(index=st.integers(min_value=0, max_value=2 ** 40))
def test_mutated_data_tables_give_only_diagnostics(tmp_path, index):
    rng = random.Random(f"tables:{index}")
    project = TABLE_SEEDS[rng.randrange(len(TABLE_SEEDS))]
    files, _ = fuzz.mutate(project, rng, [n for n in project.files if n.lower().endswith(".tab")])
    fuzz.check_project(tmp_path / "p", files, project.main, project.profile, LIMIT)


TABLE_LINE_PARTS = ["BEGIN", "MP_DATA.TAB", "[END]", "NR", "NAME", "VALUE", "UNIT", "COMMENT", "0", "-1", "$FF",
                    "%101", "4294967296", '"text"', '"', "DG_x", "MG_y", "I_z", "SG_s", "K_c", "x", "\t", "\x00", "é"]


@HYPOTHESIS
@given(lines=st.lists(st.lists(st.sampled_from(TABLE_LINE_PARTS), max_size=6).map(lambda ws: "   ".join(ws)),
                      max_size=12))
def test_the_table_reader_answers_any_text_with_diagnostics_at_real_places(lines):
    from transpiler.diagnostics import Diagnostics
    from transpiler.frontend.datatables import bind_rows, parse_table
    from transpiler.ir import Symbol
    from transpiler.diagnostics import Span
    at = Span("defs.def", 1, 1)
    symbols = {"DG_x": Symbol("DG_x", "D", 100, at), "MG_y": Symbol("MG_y", "M", 5, at),
               "I_z": Symbol("I_z", "I", 1, at), "SG_s": Symbol("SG_s", "S", 2, at), "K_c": Symbol("K_c", "K", 3, at)}
    diags = Diagnostics()
    rows = bind_rows("MP_Data.tab", parse_table("MP_Data.tab", lines, diags), symbols, 16, diags)
    for d in diags.items:
        assert d.span.file == "MP_Data.tab" and 1 <= d.span.line <= max(len(lines), 1) and d.span.col >= 1, d.render()
    for row in rows:
        assert row.symbol in symbols and row.kind in "MBWDS"


# ------------------------------------------------------------------------------------------ scenario files

SCENARIO_SEEDS = fuzz.scenario_seeds(SAMPLE_SEEDS)
needs_scenarios = pytest.mark.skipif(not SCENARIO_SEEDS, reason="no sample project with scenarios")


@pytest.fixture(scope="module")
def compiled_projects():
    """The sample projects compiled once for all scenario mutants (a scenario mutant changes no source file)."""
    return fuzz.ProjectCache()


@needs_scenarios
@settings(max_examples=36, deadline=timedelta(seconds=2 * LIMIT), derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(index=st.integers(min_value=0, max_value=2 ** 40))
def test_mutated_scenario_files_give_only_diagnostics(tmp_path, compiled_projects, index):
    chosen, data, _ = fuzz._scenario_mutant(SCENARIO_SEEDS, 7, index)
    fuzz.check_scenario(tmp_path / "p", chosen.project.files, chosen.project.main, chosen.name, data, LIMIT,
                        compiled_projects)


@needs_scenarios
def test_scenario_mutants_are_reproducible_and_reach_both_outcomes(tmp_path, compiled_projects):
    """Mutants both run and fail to load (a harness whose every mutant is broken YAML would prove little)."""
    outcomes, unchanged = set(), 0
    for index in range(24):
        chosen, data, description = fuzz._scenario_mutant(SCENARIO_SEEDS, 5, index)
        assert fuzz._scenario_mutant(SCENARIO_SEEDS, 5, index) == (chosen, data, description)
        unchanged += data == chosen.text           # (a line swapped with itself, say)
        diagnostics = fuzz.check_scenario(tmp_path / "p", chosen.project.files, chosen.project.main, chosen.name,
                                          data, LIMIT, compiled_projects)
        outcomes.add(any(d.severity.value == "error" for d in diagnostics))
    assert outcomes == {True, False} and unchanged < 4


@needs_scenarios
def test_the_scenario_harness_reports_crashes_and_hangs(tmp_path, monkeypatch, compiled_projects):
    import transpiler.verify.scenario as scenario_module
    chosen = SCENARIO_SEEDS[0]

    def crash(*args, **kwargs):
        raise ZeroDivisionError("planted")

    def hang(*args, **kwargs):
        while True:
            pass

    check = lambda limit: fuzz.check_scenario(tmp_path / "p", chosen.project.files, chosen.project.main,  # noqa: E731
                                              chosen.name, chosen.text, limit, compiled_projects)
    assert not [d for d in check(LIMIT) if d.severity.value == "error"]      # the seed itself runs
    monkeypatch.setattr(scenario_module, "load_scenario", crash)
    with pytest.raises(ZeroDivisionError):
        check(LIMIT)
    monkeypatch.setattr(scenario_module, "load_scenario", hang)
    with pytest.raises(fuzz.InputTimeout):
        check(0.5)


@needs_scenarios
def test_simulate_refuses_an_alias_bomb_with_exit_2_at_its_line(tmp_path):
    bomb = ["lol0: &lol0 [x, x, x, x, x, x, x, x, x, x]"]
    bomb += [f"lol{i}: &lol{i} [" + ", ".join([f"*lol{i - 1}"] * 10) + "]" for i in range(1, 10)]
    path = tmp_path / "bomb.yaml"
    path.write_text("cycles: 5\n" + "\n".join(bomb) + "\n", encoding="utf-8")
    main = fuzz.ROOT / SCENARIO_SEEDS[0].project.name / SCENARIO_SEEDS[0].project.main
    proc = subprocess.run([sys.executable, "-m", "transpiler.cli", "simulate", str(main), "--scenario", str(path)],
                          cwd=fuzz.ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stderr.startswith(f"{path}:1:1: error[E-SCENARIO]: scenario refused") and "Traceback" not in proc.stderr
