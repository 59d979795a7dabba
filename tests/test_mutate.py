"""`hh2iec mutate` (verify/mutate.py): mutation sites, judging, judged-equivalent files, reports and exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from transpiler.cli.app import main
from transpiler.diagnostics import CompileFailed
from transpiler.verify.mutate import (EQUIVALENT, KILLED, KILLED_ANYWAY, NO_SUCH_MUTANT, SURVIVED, Mutant,
                                      MutationResult, Verdict, apply_equivalents, equivalents_yaml, load_equivalents,
                                      mutation_sites)

ROOT = Path(__file__).resolve().parents[1]
TIMERS = ROOT / "samples" / "constructs" / "timers"

ST = """PROGRAM Main
VAR
    a : BOOL;
    b : BOOL;
    n : INT;
END_VAR
    a := NOT b AND TRUE; (* main.src:3 *)
    IF n >= 24 THEN (* main.src:5 *)
        n := 0;
    END_IF;
    CASE n OF
        1: a := TRUE;
        2: a := FALSE;
    END_CASE;
END_PROGRAM
FUNCTION_BLOCK HH_LIB
VAR
    q : BOOL;
END_VAR
    q := TRUE;
END_FUNCTION_BLOCK
"""


def test_sites_cover_every_operator_and_leave_the_library_alone():
    sites = mutation_sites(ST)
    assert {m.operator for m in sites} == {"drop_statement", "and_or", "negation", "constant", "comparison",
                                           "swap_case"}
    assert all(m.pou == "Main" for m in sites)
    lost = next(m for m in sites if m.operator == "drop_statement" and m.line == 9)
    assert "n := n;" in lost.apply(ST).splitlines()[8]
    comparison = next(m for m in sites if m.operator == "comparison")
    assert "IF n > 24 THEN" in comparison.apply(ST)
    swap = next(m for m in sites if m.operator == "swap_case")
    text = swap.apply(ST).splitlines()
    assert text[11].strip().startswith("2: a := TRUE") and text[12].strip().startswith("1: a := FALSE")
    constants = {m.description.split(" at")[0] for m in sites if m.operator == "constant" and m.line == 8}
    assert constants == {"24 -> 25", "24 -> 23"}


def test_a_dropped_call_stays_a_statement_so_its_block_is_not_left_empty():
    # Catches: the call's line deleted, which leaves `IF c THEN END_IF;` -- ST that no compiler accepts, so the
    # mutant could only be counted invalid, never judged.
    from transpiler.exec.stexec import load_st
    st = ("FUNCTION_BLOCK Clamp\nVAR\n    x : BOOL;\nEND_VAR\n    x := TRUE;\nEND_FUNCTION_BLOCK\n"
          "PROGRAM Main\nVAR\n    c : BOOL;\n    i_Clamp : Clamp;\nEND_VAR\n    IF c THEN\n        i_Clamp();\n    END_IF;\n"
          "END_PROGRAM\nCONFIGURATION C\n    RESOURCE R ON PLC\n        TASK T(INTERVAL := T#20ms, PRIORITY := 0);\n"
          "        PROGRAM P WITH T : Main;\n    END_RESOURCE\nEND_CONFIGURATION\n")
    (dropped,) = [m for m in mutation_sites(st) if m.description == "call dropped"]
    text = dropped.apply(st)
    assert "        IF FALSE THEN i_Clamp(); END_IF;" in text.splitlines()
    load_st(text, "mutant.st")          # compiles (raises StError otherwise)


def _verdict(mutant: Mutant, outcome: str) -> Verdict:
    return Verdict(mutant, outcome, "", 0.0)


def _entry(pou: str, operator: str, mutation: str, st: str, reason: str, occurrence: int = 1) -> str:
    """One entry of a judged-equivalent (or --mutants) file."""
    extra = f"  occurrence: {occurrence}\n" if occurrence > 1 else ""
    return (f"- pou: {pou}\n  operator: {operator}\n  mutation: '{mutation}'\n  st: '{st}'\n{extra}"
            f"  reason: {reason}\n")


def _mutant_entry(m: Mutant, reason: str) -> str:
    return _entry(m.pou, m.operator, m.description, m.original, reason, m.occurrence)


def test_judged_equivalent_file_takes_survivors_out_of_the_denominator(tmp_path):
    sites = mutation_sites(ST)
    survivor, killed = sites[0], sites[1]
    entry = tmp_path / "eq.yaml"
    entry.write_text(_mutant_entry(survivor, "the value written is the one already there")
                     + _mutant_entry(killed, "wrong judgement"))
    judged = load_equivalents(entry)
    verdicts, unmatched = apply_equivalents([_verdict(survivor, SURVIVED), _verdict(killed, KILLED)], judged, sites)
    assert [v.outcome for v in verdicts] == [EQUIVALENT, KILLED]
    assert verdicts[0].by == "the value written is the one already there"
    # a killed 'equivalent' is reported as such
    assert [(u.mutation, why) for u, why in unmatched] == [(killed.description, KILLED_ANYWAY)]
    result = MutationResult(verdicts, 2, [], "builtin", 0.0, unmatched)
    assert result.denominator == 1 and result.score == 1.0


def test_a_judged_equivalent_entry_is_stale_when_its_mutant_is_gone_and_silent_when_not_sampled(tmp_path):
    sites = mutation_sites(ST)
    sampled, left_out = sites[0], sites[1]
    entry = tmp_path / "eq.yaml"
    entry.write_text(_mutant_entry(left_out, "not in this sample")
                     + _entry("Main", "constant", "7 -> 8 at column 1", "X := 7;", "the translation no longer has it"))
    judged = load_equivalents(entry)
    _, unmatched = apply_equivalents([_verdict(sampled, KILLED)], judged, sites)
    assert [(u.st, why) for u, why in unmatched] == [("X := 7;", NO_SUCH_MUTANT)]


def test_a_malformed_equivalent_file_is_an_error_at_its_entry(tmp_path):
    bad = tmp_path / "eq.yaml"
    bad.write_text("- pou: Main\n  operator: comparison\n  mutation: x\n  st: y\n")
    with pytest.raises(CompileFailed) as err:
        load_equivalents(bad)
    assert err.value.diagnostics[0].code == "E-USAGE" and err.value.diagnostics[0].span.line == 1


def test_mutate_cli_on_the_timers_construct_reports_survivors_score_and_exit_code(tmp_path, capsys):
    report, junit = tmp_path / "m.json", tmp_path / "m.xml"
    args = ["mutate", str(TIMERS / "main.src"), "--scenario", str(TIMERS / "scenario.yaml"), "--random-cycles",
            "200", "--backend", "builtin", "--count", "8", "--jobs", "2", "--report", str(report), "--junit",
            str(junit)]
    code = main([*args, "--min-score", "0"])
    out = capsys.readouterr().out
    data = json.loads(report.read_text())
    assert code == 0 and len(data["mutants"]) == 8
    assert data["counts"]["killed"] >= 1
    assert "hh2iec mutate: score" in out
    for m in data["mutants"]:
        assert m["outcome"] in ("killed", "survived", "invalid", "error")
        if m["outcome"] == "survived":
            assert f"SURVIVED: {m['where']}" in out and f"ST line {m['st_line']}" in m["where"]
    assert junit.read_text().count("<testcase") == 8
    # the same run demanding a perfect score fails unless every mutant was killed
    strict = main([*args, "--min-score", "1"])
    capsys.readouterr()
    assert strict == (0 if data["counts"]["killed"] == 8 - data["counts"]["invalid"] else 1)


def test_mutate_cli_bad_input_exits_2_without_traceback(tmp_path, capsys):
    code = main(["mutate", str(TIMERS / "main.src"), "--scenario", str(tmp_path / "none.yaml")])
    assert code == 2 and "does not exist" in capsys.readouterr().err


def test_the_width_32_of_a_word_gate_is_never_mutated():
    # Catches: 31/33 generated for a width the gate treats as 32 anyway (equivalent by construction), or the
    # filter also swallowing a width 8/16 (whose +-1 does change the gate) or a 32 that is no width.
    text = ("PROGRAM Main\nVAR\n    w : DINT;\nEND_VAR\n"
            "    w := HH_WAND(w, 32, 32);\n    w := HH_WOR(w, 5, 16);\n    w := HH_SHL(w, 32);\nEND_PROGRAM\n")
    constants = [m.description for m in mutation_sites(text) if m.operator == "constant"]
    assert "32 -> 33 at column 25" not in constants and "32 -> 31 at column 25" not in constants
    assert {"32 -> 33 at column 21", "16 -> 17 at column 23", "16 -> 15 at column 23"} <= set(constants)
    assert "32 -> 33 at column 20" in constants          # HH_SHL's count is no width


def test_mutate_cli_judges_only_the_mutants_a_list_names(tmp_path, capsys):
    # the --survivors format, as a user re-judges survivors: two mutants of the translation, one no longer in it
    st_text = api_transpiled_st(TIMERS / "main.src")
    first, second = mutation_sites(st_text)[:2]
    listed = tmp_path / "list.yaml"
    listed.write_text(_mutant_entry(first, "TODO") + _mutant_entry(second, "TODO")
                      + _entry("main", "constant", "7 -> 8 at column 1", "X := 7;", "TODO"))
    report = tmp_path / "m.json"
    code = main(["mutate", str(TIMERS / "main.src"), "--scenario", str(TIMERS / "scenario.yaml"), "--random-cycles",
                 "0", "--backend", "builtin", "--jobs", "1", "--mutants", str(listed), "--report", str(report),
                 "--min-score", "0"])
    out = capsys.readouterr().out
    data = json.loads(report.read_text())
    assert code == 0
    assert sorted(m["st_line"] for m in data["mutants"]) == sorted([first.line, second.line])
    assert "note: 1 of the mutants --mutants lists are not mutants of the translation" in out


def api_transpiled_st(main_src: Path) -> str:
    from transpiler import api
    return api.transpile(api.load_project(api.project_options(main_src)), formats=("st",)).st_text


def test_the_same_statement_twice_in_a_pou_gives_mutants_an_entry_tells_apart(tmp_path):
    st_text = ("PROGRAM Main\nVAR\n    a : BOOL;\n    b : BOOL;\nEND_VAR\n    a := FALSE; (* main.src:1 *)\n"
               "    b := a;\n    a := FALSE; (* main.src:3 *)\nEND_PROGRAM\n")
    drops = [m for m in mutation_sites(st_text) if m.operator == "drop_statement" and m.original == "a := FALSE;"]
    assert [(m.line, m.occurrence) for m in drops] == [(6, 1), (8, 2)]
    entry = tmp_path / "eq.yaml"
    entry.write_text(_mutant_entry(drops[1], "the second store writes what is there"))
    verdicts, unmatched = apply_equivalents([_verdict(drops[0], SURVIVED), _verdict(drops[1], SURVIVED)],
                                            load_equivalents(entry), drops)
    assert [v.outcome for v in verdicts] == [SURVIVED, EQUIVALENT] and not unmatched
    # the survivors file names the occurrence where it is not the first
    assert "occurrence: 2" in equivalents_yaml([_verdict(drops[1], SURVIVED)])
    assert "occurrence" not in equivalents_yaml([_verdict(drops[0], SURVIVED)])
