"""`hh2iec mutate --mutation-report` (verify/mutation_report.py): Stryker's report format, validated against the
schema of its npm package (tests/report_schema.py fetches it), every mutant located exactly in the ST."""

from __future__ import annotations

import json
import os
from pathlib import Path

import jsonschema
import pytest

from tests import report_schema
from transpiler import api
from transpiler.backends.iec_model import SourceRange
from transpiler.cli.app import main
from transpiler.verify.mutate import (EQUIVALENT, ERROR, INVALID, KILLED, SURVIVED, MutationResult, Verdict,
                                      mutation_sites)
from transpiler.verify.mutation_report import GENERATED, change_of, mutation_report

ROOT = Path(__file__).resolve().parents[1]
CONSTRUCTS = ROOT / "samples" / "constructs"
TIMERS = CONSTRUCTS / "timers"

ST = """PROGRAM Main
VAR
    a : BOOL;
    b : BOOL;
    n : INT;
    i_Clamp : Clamp;
END_VAR
    a := NOT b AND TRUE; (* main.src:3 *)
    IF n >= 24 OR n < 3 THEN (* main.src:5 *)
        n := 0;
        i_Clamp();
    END_IF;
    CASE n OF
        1: a := FALSE;
        12: a := TRUE;
    END_CASE;
END_PROGRAM
"""


def _required() -> bool:
    """CI (and `make test`) must validate: a missing npm or registry fails there instead of skipping."""
    return os.environ.get("CI", "").lower() not in ("", "0", "false") or bool(os.environ.get("HH2IEC_REQUIRE_SCHEMA"))


@pytest.fixture(scope="module")
def validator() -> jsonschema.Draft7Validator:
    try:
        schema = report_schema.load()
    except report_schema.SchemaUnavailable as exc:
        message = f"{report_schema.PACKAGE}@{report_schema.VERSION} unavailable: {exc}"
        if _required():
            pytest.fail(message)
        pytest.skip(message)
    jsonschema.Draft7Validator.check_schema(schema)
    return jsonschema.Draft7Validator(schema)


def _errors(validator: jsonschema.Draft7Validator, report: dict) -> list[str]:
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator.iter_errors(report)]


def _span(source: str, location: dict) -> tuple[int, int]:
    """The offsets in `source` (lines joined by newlines) of the report's start (inclusive) and end (exclusive)."""
    lines = source.splitlines()

    def offset(position: dict) -> int:
        return sum(len(line) + 1 for line in lines[:position["line"] - 1]) + position["column"] - 1
    return offset(location["start"]), offset(location["end"])


def _text_at(source: str, location: dict) -> str:
    start, end = _span(source, location)
    return "\n".join(source.splitlines())[start:end]


def _replaced(source: str, location: dict, replacement: str) -> str:
    """`source` with the report's location replaced: what the viewer shows as the mutant."""
    start, end = _span(source, location)
    text = "\n".join(source.splitlines())
    return text[:start] + replacement + text[end:] + "\n"


def test_a_change_covers_whole_tokens_and_a_dropped_statement_whole():
    # Catches: the bare character difference (`TRU` -> `FALS`, `=` for `>=` -> `>`, an empty span for `<` -> `<=`)
    # or the expression alone where the statement loses its effect.
    sites = {(m.operator, m.description.split(" at ")[0], m.line): m for m in mutation_sites(ST)}
    cases = {("negation", "TRUE -> FALSE", 8): ("TRUE", "FALSE", (8, 20)),
             ("negation", "NOT dropped", 8): ("NOT ", "", (8, 10)),
             ("and_or", "AND -> OR", 8): ("AND", "OR", (8, 16)),
             ("comparison", "'>=' -> '>'", 9): (">=", ">", (9, 10)),
             ("comparison", "'<' -> '<='", 9): ("<", "<=", (9, 21)),
             ("constant", "24 -> 25", 9): ("24", "25", (9, 13)),
             ("drop_statement", "assignment loses its effect", 8): ("a := NOT b AND TRUE;", "a := a;", (8, 5)),
             ("drop_statement", "call dropped", 11): ("i_Clamp();", "IF FALSE THEN i_Clamp(); END_IF;", (11, 9))}
    for key, (original, replacement, start) in cases.items():
        change = change_of(ST, sites[key])
        assert (change.original, change.replacement, change.start) == (original, replacement, start), key
    swap = change_of(ST, next(m for m in sites.values() if m.operator == "swap_case"))
    assert (swap.start, swap.end) == ((14, 9), (15, 11))
    assert swap.original.startswith("1: a := FALSE;") and swap.replacement.endswith("\n        1")


def test_every_mutant_of_every_construct_is_reproduced_from_its_location():
    # The viewer rebuilds each mutant from location + replacement: that must give exactly the mutated ST.
    checked = set()
    for main_src in sorted(CONSTRUCTS.glob("*/main.src")):
        st_text = api.transpile(api.load_project(api.project_options(main_src)), formats=("st",)).st_text
        for mutant in mutation_sites(st_text):
            change = change_of(st_text, mutant)
            location = {"start": dict(zip(("line", "column"), change.start)),
                        "end": dict(zip(("line", "column"), change.end))}
            assert _text_at(st_text, location) == change.original, (main_src.parent.name, mutant)
            assert _replaced(st_text, location, change.replacement) == mutant.apply(st_text), (main_src, mutant)
            checked.add(mutant.operator)
    assert checked == {"drop_statement", "and_or", "negation", "constant", "comparison", "swap_case"}


def _result(outcomes: list[tuple[str, str, int]]) -> MutationResult:
    """A result over the first mutants of ST with the given (outcome, by, runs)."""
    verdicts = [Verdict(m, outcome, by, 0.25, runs) for m, (outcome, by, runs) in zip(mutation_sites(ST), outcomes)]
    return MutationResult(verdicts, len(mutation_sites(ST)), ["short", "long", "random_seed1"], "builtin", 1.0,
                          scenario_files=("scenarios/short.yaml", "scenarios/long.yaml", ""),
                          pou_sources={"Main": (SourceRange("main.src", 1, 9),)})


def test_each_outcome_has_its_status_and_the_report_validates(validator):
    result = _result([(KILLED, "long: a differs at cycle 4", 2), (SURVIVED, "", 3),
                      (EQUIVALENT, "b is always 1 here", 3), (INVALID, "rejected: StError: no such type", 0),
                      (ERROR, "short: ZeroDivisionError", 3)])
    report = json.loads(mutation_report(result, ST, 0.9))
    assert _errors(validator, report) == []
    mutants = report["files"]["project.st"]["mutants"]
    assert [m["status"] for m in mutants] == ["Killed", "Survived", "Ignored", "CompileError", "RuntimeError"]
    killed, survived, equivalent, invalid, error = mutants
    assert killed["killedBy"] == ["long"] and killed["coveredBy"] == ["short", "long"]
    assert killed["statusReason"] == "long: a differs at cycle 4"
    assert survived["coveredBy"] == ["short", "long", "random_seed1"] and "killedBy" not in survived
    assert equivalent["statusReason"] == "judged equivalent: b is always 1 here"
    assert "coveredBy" not in invalid and invalid["statusReason"].startswith("rejected")
    assert error["statusReason"] == "short: ZeroDivisionError"
    # the source line of the statement: the tag above it
    assert killed["description"].endswith("(POU Main, ST line 8, from main.src:3)")
    # every killing test is defined, in the file it came from; generated runs have a file of their own
    assert report["testFiles"] == {"scenarios/short.yaml": {"tests": [{"id": "short", "name": "short"}]},
                                   "scenarios/long.yaml": {"tests": [{"id": "long", "name": "long"}]},
                                   GENERATED: {"tests": [{"id": "random_seed1", "name": "random_seed1"}]}}
    assert report["thresholds"] == {"high": 90, "low": 90}
    assert len({m["id"] for m in mutants}) == len(mutants)


def test_the_schema_check_can_fail(validator):
    # Catches: a validator that accepts anything (a wrong or empty schema file in the cache).
    report = json.loads(mutation_report(_result([(EQUIVALENT, "reason", 1)]), ST, 0.9))
    assert _errors(validator, report) == []
    report["files"]["project.st"]["mutants"][0]["status"] = "Equivalent"
    del report["thresholds"]
    errors = _errors(validator, report)
    assert any("thresholds" in e for e in errors) and any("Equivalent" in e for e in errors)


def test_a_cached_schema_that_is_not_the_pinned_one_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path))
    report_schema.cached_path().write_text("{}")
    assert report_schema.verified_cache() is None
    with pytest.raises(report_schema.SchemaUnavailable, match="sha256"):
        report_schema.extract(report_schema.cached_path())


def test_mutate_cli_writes_a_mutation_report_that_validates(tmp_path, capsys, validator):
    # One of the construct's two judged-equivalent entries: the other mutant survives.
    equivalent = tmp_path / "eq.yaml"
    equivalent.write_text("\n".join((TIMERS / "equivalent_mutants.yaml").read_text().splitlines()[:8]) + "\n")
    out = tmp_path / "out" / "mutation.json"
    scenario = TIMERS / "scenario.yaml"
    code = main(["mutate", str(TIMERS / "main.src"), "--scenario", str(scenario), "--random-cycles", "100",
                 "--backend", "builtin", "--jobs", "2", "--equivalent", str(equivalent), "--min-score", "0.5",
                 "--mutation-report", str(out), "--report", str(tmp_path / "m.json")])
    capsys.readouterr()
    report = json.loads(out.read_text())
    assert code == 0 and _errors(validator, report) == []
    st = report["files"]["project.st"]
    by_status: dict[str, list[dict]] = {}
    for m in st["mutants"]:
        by_status.setdefault(m["status"], []).append(m)
        assert _text_at(st["source"], m["location"]) in st["source"].splitlines()[m["location"]["start"]["line"] - 1]
    assert set(by_status) == {"Killed", "Survived", "Ignored"}
    (ignored,) = by_status["Ignored"]
    assert _text_at(st["source"], ignored["location"]) == "T51 := T3_timer.RUNNING;"
    assert ignored["statusReason"].startswith("judged equivalent: MP4110.3 = 0: the timer never runs")
    (survivor,) = by_status["Survived"]
    assert _text_at(st["source"], survivor["location"]) == "O4 := T51;" and survivor["replacement"] == "O4 := O4;"
    assert survivor["description"] == "assignment loses its effect (POU main, ST line 101, in main.src:9-35)"
    tests = {t["id"]: file for file, entry in report["testFiles"].items() for t in entry["tests"]}
    assert tests["timers"] == str(scenario) and set(tests.values()) == {str(scenario), GENERATED}
    assert all(m["killedBy"][0] in tests for m in by_status["Killed"])
    assert len(json.loads((tmp_path / "m.json").read_text())["mutants"]) == len(st["mutants"])
