"""The equivalence verdict cannot lie: each way `hh2iec equiv` once said EQUIVALENT (or hung) on a wrong or partly
tested translation ends non-zero with a message that names the cause."""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import pytest

from transpiler.backends.st.check import find_iec2c
from transpiler.cli import main

ROOT = Path(__file__).resolve().parents[1]
CONSTRUCTS = ROOT / "samples" / "constructs"

MAIN_WITH_MODULE = "USES sub.src\nEXTERN Read_pos\nL I1\n= O1\nCM Read_pos\nEM\n"
# A subprogram that calls PLC module 9006 (additional timers), which the ST back end does not translate: the call
# (at line 8) never happens (M101 AND NOT M101), so only the lost write of O2 can show.
SUB_WITH_MODULE = "GLOBAL Read_pos\nLBL Read_pos\nL K1\n= M100\nPS K96\nL M101\nAN M101\nCMT 9006\nL M100\n= O2\nEM\n"


def _run(args: list, capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def _write(folder: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        (folder / name).write_text(text, encoding="latin-1")
    return folder / "main.src"


# --- 1. code that cannot be translated -------------------------------------------------------


def test_untranslated_code_is_an_error_at_its_line(tmp_path, capsys):
    main_src = _write(tmp_path, {"main.src": MAIN_WITH_MODULE, "sub.src": SUB_WITH_MODULE})
    code, _, err = _run(["transpile", main_src, "--out", tmp_path / "out"], capsys)
    assert code == 2
    assert "sub.src:8:1: error[E-UNSUPPORTED]" in err and "9006" in err
    assert not (tmp_path / "out").exists(), "nothing partial is written"


def test_allowed_untranslated_code_is_written_with_the_list_first_and_never_equivalent(tmp_path, capsys):
    main_src = _write(tmp_path, {"main.src": MAIN_WITH_MODULE, "sub.src": SUB_WITH_MODULE})
    code, _, err = _run(["transpile", main_src, "--out", tmp_path / "out", "--allow-untranslated"], capsys)
    assert code == 0 and "sub.src:8:1: warning[E-UNSUPPORTED]" in err
    report = (tmp_path / "out" / "report.md").read_text()
    first_section = report.split("## ")[1]
    assert first_section.startswith("Not translated") and "sub.src:8:1" in first_section
    code, out, _ = _run(["equiv", main_src, "--random-cycles", "50"], capsys)
    assert code == 2 and "EQUIVALENT" not in out
    # The lost routine wrote O2: the runs show it.
    code, out, _ = _run(["equiv", main_src, "--random-cycles", "50", "--allow-untranslated"], capsys)
    assert code == 1 and "hh2iec equiv: NOT EQUIVALENT" in out and "NOT TRANSLATED: sub.src:8:1" in out
    # A lost routine whose effect no compared operand shows: every run agrees, and still no EQUIVALENT.
    _write(tmp_path, {"sub.src": "GLOBAL Read_pos\nLBL Read_pos\nPS K96\nL M101\nAN M101\nCMT 9006\nEM\n"})
    code, out, _ = _run(["equiv", main_src, "--random-cycles", "50", "--allow-untranslated", "-v",
                         "--report", tmp_path / "equiv.json"], capsys)
    assert code == 1
    assert "equivalent: random_seed1" in out
    assert "hh2iec equiv: NOT PROVEN" in out and "NOT TRANSLATED: sub.src:6:1" in out
    report = json.loads((tmp_path / "equiv.json").read_text())
    assert report["verdict"] == "NOT PROVEN" and report["equivalent"] is False
    assert report["not_translated"][0]["at"] == "sub.src:6:1"


# --- 2. expectations of the scenario ---------------------------------------------------------


def test_an_expectation_the_original_does_not_meet_fails_equiv(tmp_path, capsys):
    folder = CONSTRUCTS / "logic_chain"
    text = (folder / "scenario.yaml").read_text()
    assert "expect:" in text
    scenario = tmp_path / "scenario.yaml"
    shutil.copy(folder / "scenario.yaml", scenario)
    code, out, _ = _run(["equiv", folder / "main.src", "--scenario", scenario], capsys)
    assert code == 0 and "hh2iec equiv: EQUIVALENT" in out
    # The same scenario with one more expectation (the last key of the file) that the original does not meet:
    # M1 is 0 after cycle 1 (see the entry for cycle 1 above it).
    assert text.rstrip().endswith("}")
    scenario.write_text(text.rstrip("\n") + "\n  - {cycle: 1, values: {M1: 1}}\n")
    code, out, err = _run(["equiv", folder / "main.src", "--scenario", scenario], capsys)
    assert code == 1, out + err
    assert "expectation failed: cycle 1: M1: expected 1, actual 0" in err
    assert "hh2iec equiv: EXPECTATION FAILED" in out


# --- 3. the ST as written, with the machine parameters it was made with ----------------------


def test_scenario_machine_parameters_that_differ_from_the_translations_fail_with_both_values(tmp_path, capsys):
    folder = CONSTRUCTS / "timers"
    shutil.copy(folder / "main.src", tmp_path / "main.src")
    shutil.copy(folder / "scenario.yaml", tmp_path / "scenario.yaml")
    # No MP file beside the main program: the translation's presets are 0, and transpile says so.
    code, _, err = _run(["transpile", tmp_path / "main.src", "--out", tmp_path / "out"], capsys)
    assert code == 0 and "warning[E-MP-NONE]" in err
    assert "every timer and counter preset is 0" in (tmp_path / "out" / "project.st").read_text()
    code, out, err = _run(["equiv", tmp_path / "main.src", "--scenario", tmp_path / "scenario.yaml",
                           "--st", tmp_path / "out" / "project.st"], capsys)
    assert code == 2 and "EQUIVALENT" not in out.replace("NOT EQUIVALENT", "")
    assert "MP4110.0: 3 cycles from the scenario's machine parameters, 0 cycles in the translated program" in err


def _timers_project(tmp_path: Path, timer0: str) -> tuple[Path, Path]:
    """The timers example with its MP file, and a scenario that sets MP4110.0 to `timer0` seconds."""
    folder = CONSTRUCTS / "timers"
    for name in ("main.src", "timers.mp"):
        shutil.copy(folder / name, tmp_path / name)
    text = (folder / "scenario.yaml").read_text()
    text = text.replace('"4110.0": 0.06', f'"4110.0": {timer0}').split("\nexpect:")[0] + "\n"
    assert f'"4110.0": {timer0}' in text
    (tmp_path / "other.yaml").write_text(text)
    return tmp_path / "main.src", tmp_path / "other.yaml"


@pytest.mark.parametrize("backend", ["builtin", pytest.param("matiec", marks=pytest.mark.skipif(
    find_iec2c() is None, reason="iec2c not found ($MATIEC_HOME/iec2c or PATH): the matiec backend is skipped"))])
def test_scenario_machine_parameters_are_written_into_the_translation_as_run_time_data(tmp_path, capsys, backend):
    # The project's MP file gives T0 3 cycles; the scenario's 0.2 s (10 cycles) reach both sides.
    main_src, scenario = _timers_project(tmp_path, "0.2")
    code, out, err = _run(["equiv", main_src, "--scenario", scenario, "--backend", backend], capsys)
    assert code == 0 and f"hh2iec equiv: EQUIVALENT (1 runs, 50 cycles, backend {backend})" in out, out + err


def test_a_wrong_conversion_of_the_scenario_machine_parameters_is_a_divergence(tmp_path, capsys, monkeypatch):
    from transpiler.verify import cosim, rundata

    def off_by_one(side, iomap, writes):
        rundata.write_data(side, iomap, [rundata.DataWrite(w.operand, w.value + 1) for w in writes])

    monkeypatch.setattr(cosim, "write_data", off_by_one)
    main_src, scenario = _timers_project(tmp_path, "0.2")
    code, out, _ = _run(["equiv", main_src, "--scenario", scenario, "--backend", "builtin", "--no-shrink"], capsys)
    assert code == 1 and "DIVERGENCE in timers" in out and "NOT EQUIVALENT" in out


def test_machine_parameters_the_translation_cannot_hold_give_no_verdict(tmp_path, capsys):
    # 50,000,000 s are 2.5e9 cycles of 20 ms: more than the DINT preset variable holds.
    main_src, scenario = _timers_project(tmp_path, "50000000")
    code, out, err = _run(["equiv", main_src, "--scenario", scenario, "--backend", "builtin", "-v",
                           "--report", tmp_path / "r.json"], capsys)
    assert code == 2 and "hh2iec equiv: NO VERDICT (1 runs, 0 cycles" in out
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["verdict"] == "NO VERDICT" and report["runs"][0]["error_code"] == "E-MP-UNREPRESENTABLE"
    assert "error[E-MP-UNREPRESENTABLE]" in err and "MP4110.0: 2500000000 cycles" in err and "MP4110_0" in err
    assert "NOT EQUIVALENT" not in out and "not covered" not in out and "coverage: none (no run started)" in out


def test_an_st_made_from_other_machine_parameters_fails_whatever_the_scenario_sets(tmp_path, capsys):
    main_src, scenario = _timers_project(tmp_path, "0.2")
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "stale.mp").write_text("MP4110.1 : 0.3\n")
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "out", "--mp", tmp_path / "old" / "stale.mp"],
                      capsys)
    assert code == 0
    original = scenario.read_text()
    # The scenario as it was, and one that sets the stale file's value itself: neither makes the ST right.
    for overrides in ('"4110.1": 0.1', '"4110.1": 0.3'):
        scenario.write_text(original.replace('"4110.1": 0.1', overrides))
        code, out, err = _run(["equiv", main_src, "--scenario", scenario, "--backend", "builtin",
                               "--st", tmp_path / "out" / "project.st"], capsys)
        assert code == 2 and "EQUIVALENT" not in out.replace("NOT EQUIVALENT", ""), out
        assert "error[E-MP-TRANSLATION]" in err
        assert "MP4110.0: 3 cycles from the project's machine parameters, 0 cycles in the translated program" in err
        assert "MP4110.1: 5 cycles from the project's machine parameters, 15 cycles in the translated program" in err
        assert "not covered" not in out


def test_two_machine_parameter_files_need_a_choice(tmp_path, capsys):
    folder = CONSTRUCTS / "timers"
    shutil.copy(folder / "main.src", tmp_path / "main.src")
    shutil.copy(folder / "timers.mp", tmp_path / "a.mp")
    (tmp_path / "b.mp").write_text("MP4110.0 : 1\n")
    code, _, err = _run(["transpile", tmp_path / "main.src", "--out", tmp_path / "out"], capsys)
    assert code == 2 and "error[E-MP-AMBIGUOUS]" in err and "a.mp, b.mp" in err
    code, _, _ = _run(["transpile", tmp_path / "main.src", "--out", tmp_path / "out", "--mp", tmp_path / "a.mp"],
                      capsys)
    assert code == 0
    st = (tmp_path / "out" / "project.st").read_text()
    assert "machine parameters of a.mp" in st and "MP4110_0 : DINT := 3;" in st
    assert "(from a.mp)" in (tmp_path / "out" / "io_map.csv").read_text()
    assert "`a.mp`" in (tmp_path / "out" / "report.md").read_text()


# --- 4. a translation that never ends its cycle ----------------------------------------------


def _endless_loop_st(tmp_path: Path, capsys) -> Path:
    folder = CONSTRUCTS / "jumps_loop"
    code, _, _ = _run(["transpile", folder / "main.src", "--out", tmp_path], capsys)
    assert code == 0
    st = (tmp_path / "project.st").read_text()
    looped = st.replace("IF W6 >= W10 THEN", "IF W6 >= W10 AND FALSE THEN", 1)
    assert looped != st
    (tmp_path / "project.st").write_text(looped)
    return tmp_path / "project.st"


BACKENDS = ["builtin"] + (["matiec"] if find_iec2c() is not None else [])


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_endless_loop_in_the_translation_is_a_finding_not_a_hang(tmp_path, capsys, backend):
    folder = CONSTRUCTS / "jumps_loop"
    st = _endless_loop_st(tmp_path, capsys)
    start = time.monotonic()
    code, out, _ = _run(["equiv", folder / "main.src", "--scenario", folder / "scenario.yaml", "--st", st,
                         "--backend", backend], capsys)
    assert time.monotonic() - start < 60
    assert code == 1
    assert "FAULT OF THE TRANSLATION in jumps_loop" in out and "cycle 0" in out
    assert "POU main" in out and "from main.src:32" in out
    assert "hh2iec equiv: NOT EQUIVALENT" in out


# --- everything the original writes is compared ----------------------------------------------


def test_an_operand_the_translation_lacks_is_missing_never_skipped(tmp_path, capsys):
    folder = CONSTRUCTS / "logic_chain"
    code, _, _ = _run(["transpile", folder / "main.src", "--out", tmp_path], capsys)
    assert code == 0
    rows = (tmp_path / "io_map.csv").read_text().splitlines()
    kept = [r for r in rows if ",O1," not in r]
    assert len(kept) == len(rows) - 1
    (tmp_path / "io_map.csv").write_text("\n".join(kept) + "\n")
    code, out, _ = _run(["equiv", folder / "main.src", "--scenario", folder / "scenario.yaml",
                         "--st", tmp_path / "project.st", "--report", tmp_path / "equiv.json"], capsys)
    assert code == 1
    assert "MISSING in the translation" in out and "(O1) is written by the original at main.src:" in out
    run = json.loads((tmp_path / "equiv.json").read_text())["runs"][0]
    assert run["missing_in_translation"][0]["operand"] == "O1"
    assert "O1" not in run["compared"] and run["compared"]


def test_the_report_lists_what_was_compared_and_nothing_is_missing_on_a_whole_translation(tmp_path, capsys):
    folder = CONSTRUCTS / "multi_file_global_extern"
    code, out, _ = _run(["equiv", folder / "main.src", "--scenario", folder / "scenario.yaml",
                         "--report", tmp_path / "equiv.json"], capsys)
    assert code == 0 and "hh2iec equiv: EQUIVALENT" in out
    report = json.loads((tmp_path / "equiv.json").read_text())
    assert report["verdict"] == "EQUIVALENT"
    for run in report["runs"]:
        assert run["missing_in_translation"] == [] and run["excluded"] == []
        assert len(run["compared"]) == run["compared_operands"] > 0


def test_vcd_holds_both_executors_side_by_side(tmp_path, capsys):
    """One dump per run with a scope per side, so GTKWave shows original and translation in one window."""
    folder = CONSTRUCTS / "timers"
    code, _, _ = _run(["equiv", folder / "main.src", "--scenario", folder / "scenario.yaml", "--vcd", tmp_path / "vcd"],
                      capsys)
    assert code == 0
    assert sorted(p.name for p in (tmp_path / "vcd").iterdir()) == ["timers.vcd"]
    text = (tmp_path / "vcd" / "timers.vcd").read_text()
    assert "$scope module original $end" in text and "$scope module translated $end" in text
    # T48 runs in cycles 3, 4, 5 after the pulse at 2 (the scenario's expectations): both scopes show it rise at 60 ms.
    header, _, body = text.partition("$enddefinitions $end")
    ids = [line.split()[3] for line in header.splitlines() if line.strip().startswith("$var") and " T48 " in line]
    assert len(ids) == 2
    changes_at_60 = body.split("#60\n")[1].split("#")[0].split()
    assert all(f"1{i}" in changes_at_60 for i in ids)


def test_werror_fails_simulate_and_equiv_on_warnings_of_their_own(tmp_path, capsys):
    """--werror covers more than the front end: a scenario warning (a random pattern that matches nothing) fails
    equiv and simulate, each with exit 2 and E-WERROR, and equiv prints no verdict."""
    folder = CONSTRUCTS / "logic_chain"
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text((folder / "scenario.yaml").read_text() + "random:\n  seed: 1\n  inputs: [NO_SUCH_INPUT_*]\n")
    code, _, err = _run(["equiv", folder / "main.src", "--scenario", scenario], capsys)
    assert code == 0 and "warning[E-SCENARIO-UNUSED]" in err
    code, out, err = _run(["equiv", folder / "main.src", "--scenario", scenario, "--werror"], capsys)
    assert code == 2 and "error[E-WERROR]" in err and "EQUIVALENT" not in out
    code, _, err = _run(["simulate", folder / "main.src", "--scenario", scenario, "--werror"], capsys)
    assert code == 2 and "error[E-WERROR]" in err
