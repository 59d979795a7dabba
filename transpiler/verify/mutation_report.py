"""The mutation analysis as a mutation-testing-report-schema document: the JSON that Stryker's dashboard and its
mutation-testing-elements HTML viewer read. The emitted ST is the one mutated file; each mutant is located
exactly in it and names the HEIDENHAIN source line its statement came from; the scenarios are the tests."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from types import MappingProxyType
from typing import Mapping

import transpiler
from transpiler.backends.iec_model import SourceRange
from transpiler.exec.st_lines import st_origin
from transpiler.verify.mutate import EQUIVALENT, ERROR, INVALID, KILLED, SURVIVED, Mutant, MutationResult, Verdict

# The format's major version as Stryker's own tools write it; the schema accepts 1 and 2.
SCHEMA_VERSION = "1.0"
ST_FILE = "project.st"                  # the name `transpile --out` gives the ST the mutants are made from
GENERATED = "generated stimulus"        # the test file of the coverage-guided runs (--random-cycles)
# No NoCoverage and no Timeout: every valid mutant runs under every scenario until one kills it, and a cycle that
# never ends is a fault of the translated side, which kills.
STATUS = MappingProxyType({KILLED: "Killed", SURVIVED: "Survived", EQUIVALENT: "Ignored",
                           INVALID: "CompileError", ERROR: "RuntimeError"})


@dataclasses.dataclass(frozen=True)
class Change:
    """Where a mutant changes the ST (1-based line and column, end exclusive) and the text it puts there."""

    start: tuple[int, int]
    end: tuple[int, int]
    original: str
    replacement: str


def _joins(a: str, b: str) -> bool:
    """Whether two neighbouring characters belong to one token (a name or number, or a comparison operator)."""
    def word(c: str) -> bool:
        return c.isalnum() or c == "_"
    return (word(a) and word(b)) or (a in "<>=" and b in "<>=")


def _position(text: str, offset: int) -> tuple[int, int]:
    line_start = text.rfind("\n", 0, offset) + 1
    return text.count("\n", 0, offset) + 1, offset - line_start + 1


def change_of(st_text: str, mutant: Mutant) -> Change:
    """The smallest span of `st_text` that the mutant replaces, widened to whole tokens (`TRUE`, not `TRU`; `>=`,
    not `=`) and, when a statement loses its effect, to the whole statement."""
    old = "\n".join(st_text.splitlines())
    new = mutant.apply(st_text)[:-1]                # apply() ends the text with one newline
    prefix = 0
    limit = min(len(old), len(new))
    while prefix < limit and old[prefix] == new[prefix]:
        prefix += 1
    suffix = 0
    while suffix < limit - prefix and old[-1 - suffix] == new[-1 - suffix]:
        suffix += 1
    start, end = prefix, len(old) - suffix          # in `old`; in `new` the same start, the same suffix

    def edges(first: bool) -> str:
        """The first (or last) characters of the old and of the new text of the span."""
        regions = (old[start:end], new[start:len(new) - (len(old) - end)])
        return "".join((r[0] if first else r[-1]) for r in regions if r)
    while start > 0 and any(_joins(old[start - 1], c) for c in edges(True)):
        start -= 1
    while end < len(old) and any(_joins(c, old[end]) for c in edges(False)):
        end += 1
    if mutant.operator == "drop_statement":
        line_start = sum(len(line) + 1 for line in old.split("\n")[:mutant.line - 1])
        line = old.split("\n")[mutant.line - 1]
        indent = len(line) - len(line.lstrip())
        start, end = min(start, line_start + indent), max(end, line_start + indent + len(mutant.original))
    return Change(_position(old, start), _position(old, end), old[start:end], new[start:len(new) - (len(old) - end)])


def mutant_id(mutant: Mutant) -> str:
    """Stable across runs and ST that moved by some lines: made from the key a judged-equivalent entry matches."""
    return hashlib.sha256("\x1f".join(map(str, mutant.key)).encode("utf-8")).hexdigest()[:16]


def _test_ids(names: list[str]) -> list[str]:
    """The scenario names as test ids; a name given twice gets `#2`, `#3` ... so that every id names one run."""
    seen: dict[str, int] = {}
    ids = []
    for name in names:
        seen[name] = seen.get(name, 0) + 1
        ids.append(name if seen[name] == 1 else f"{name}#{seen[name]}")
    return ids


def origin(st_text: str, mutant: Mutant, pou_sources: Mapping[str, tuple[SourceRange, ...]]) -> str:
    """`POU X, ST line N, from file:line` (the nearest tag above it); without a tag, the lines of its POU."""
    where = st_origin(st_text, mutant.line)
    if " from " not in where and mutant.pou in pou_sources:
        where += f", in {', '.join(r.tag() for r in pou_sources[mutant.pou])}"
    return where


def _reason(v: Verdict) -> str:
    if v.outcome == SURVIVED:
        return "no run told it apart from the unmutated translation"
    if v.outcome == EQUIVALENT:
        return f"judged equivalent: {v.by}"
    return v.by


def _mutant(v: Verdict, st_text: str, ids: list[str],
            pou_sources: Mapping[str, tuple[SourceRange, ...]]) -> dict:
    change = change_of(st_text, v.mutant)
    entry = {"id": mutant_id(v.mutant), "mutatorName": v.mutant.operator, "replacement": change.replacement,
             "location": {"start": dict(zip(("line", "column"), change.start)),
                          "end": dict(zip(("line", "column"), change.end))},
             "status": STATUS[v.outcome], "statusReason": _reason(v),
             "description": f"{v.mutant.description} ({origin(st_text, v.mutant, pou_sources)})",
             "duration": round(v.seconds * 1000, 1)}
    ran = [ids[i] for i in v.scenarios_run]
    if v.outcome != INVALID and ran:
        entry["coveredBy"] = ran
        entry["testsCompleted"] = len(ran)
    if v.outcome == KILLED and ran:
        entry["killedBy"] = [ran[-1]]
    return entry


def mutation_report(result: MutationResult, st_text: str, min_score: float) -> str:
    """The report as JSON text. Its thresholds are both the --min-score: the viewer shows a score that reaches it as
    good, any other as bad. Its own score leaves errors out (they are invalid there); hh2iec's, in `config`, counts
    them as not killed."""
    ids = _test_ids(result.scenarios)
    files = result.scenario_files or ("",) * len(ids)
    tests: dict[str, dict] = {}
    for test_id, name, file in zip(ids, result.scenarios, files):
        tests.setdefault(file or GENERATED, {"tests": []})["tests"].append({"id": test_id, "name": name})
    threshold = round(100 * min_score)
    data = {"schemaVersion": SCHEMA_VERSION,
            "thresholds": {"high": threshold, "low": threshold},
            "files": {ST_FILE: {"language": "iecst", "source": st_text,
                                "mutants": [_mutant(v, st_text, ids, result.pou_sources) for v in result.verdicts]}},
            "testFiles": tests,
            "framework": {"name": "hh2iec mutate", "version": transpiler.__version__},
            "config": {"backend": result.backend, "sites": result.sites, "judged": len(result.verdicts),
                       "score": round(result.score, 4), "minScore": min_score, "seconds": round(result.seconds, 1)}}
    return json.dumps(data, indent=2, ensure_ascii=False) + "\n"
