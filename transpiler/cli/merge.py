"""The `merge` subcommand: one result from the shard results of `equiv --shard K/N` or `mutate --shard K/N`.

The shards must be shards 1..N of one command on one set of inputs, each given once (verify/shard.check_shards);
anything else is refused with error[E-SHARD] and exit 2, never merged into a partial result. The merged report, JUnit
file and exit code are those of the unsharded command: equiv reloads the project from the arguments the shards
recorded (run merge in the folder the shards ran in), checks that its files are the ones the shards ran on, and
recomputes the coverage from every run's coverage sets; mutate's score is counted over every shard's mutants."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Callable

from transpiler import api
from transpiler.cli.common import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, project_from_args, write_reports
from transpiler.diagnostics import NO_SPAN


def register(sub: argparse._SubParsersAction, common) -> None:
    p = sub.add_parser("merge", help="one verdict, report and JUnit file from the shard results of "
                                     "`equiv --shard K/N` or `mutate --shard K/N`")
    p.add_argument("shards", type=Path, nargs="+", metavar="SHARD.json",
                   help="the --report file of every shard (1/N to N/N, each once)")
    p.add_argument("--report", type=Path, metavar="OUT.json", help="the merged report, as the unsharded command's")
    p.add_argument("--junit", type=Path, metavar="OUT.xml", help="one JUnit file of all runs or mutants")
    p.add_argument("--min-score", type=float, metavar="F",
                   help="mutate: the minimum score (default: the one the shards ran with)")
    p.add_argument("-v", "--verbose", action="store_true", help="also a line for every run or mutant that passed")
    # the parsers of the other subcommands: merge reads the arguments the shards recorded as their command does
    p.set_defaults(handler=cmd_merge, command_parser=p, command_parsers=sub.choices)


def _refuse(problems: list[tuple[str | None, str]]) -> int:
    for where, message in problems:
        at = f"{where}:1:1" if where else NO_SPAN
        print(f"{at}: error[E-SHARD]: {message}", file=sys.stderr)
    print("hh2iec merge: nothing merged", file=sys.stderr)
    return EXIT_BAD_INPUT


def cmd_merge(args: argparse.Namespace) -> int:
    from transpiler.verify.shard import MergeRefused, check_shards
    loaded, problems = [], []
    for path in args.shards:
        try:
            loaded.append((str(path), json.loads(path.read_text(encoding="utf-8"))))
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            problems.append((str(path), f"cannot read the shard result: {exc}"))
    if problems:
        return _refuse(problems)
    try:
        section = check_shards(loaded)
    except MergeRefused as exc:
        return _refuse([(None, problem) for problem in exc.problems])
    shards = [data for _, data in sorted(loaded, key=lambda item: item[1]["shard"]["index"])]
    if section["command"] == "equiv":
        return _merge_equiv(args, section, shards)
    if section["command"] == "mutate":
        return _merge_mutate(args, section, shards)
    return _refuse([(None, f"shard results of `{section['command']}`, which merge does not know")])


def _recorded_args(args: argparse.Namespace, section) -> argparse.Namespace | None:
    """The command's arguments as the shards recorded them, parsed as the command parses them."""
    from transpiler.cli.common import UsageError
    try:
        return args.command_parsers[section["command"]].parse_args(section["argv"])
    except (UsageError, SystemExit):
        return None


def _merge_equiv(args: argparse.Namespace, section, shards: list[dict]) -> int:
    from transpiler.cli.equiv import print_coverage
    from transpiler.verify.equiv import AGREED, FAILED_RUN, REFUSED, data_json, junit_of, merge_reports, run_state
    recorded = _recorded_args(args, section)
    if recorded is None:
        return _refuse([(None, f"the shards' arguments cannot be read: {' '.join(section['argv'])}")])
    project = project_from_args(recorded, scenario=recorded.scenario[0] if recorded.scenario else None)
    digest = api.equivalence_digest(project, scenarios=recorded.scenario, random_cycles=recorded.random_cycles,
                                    seed=recorded.seed, backend=recorded.backend, st_file=recorded.st,
                                    io_map_file=recorded.io_map, mp_file=recorded.mp, shrink=not recorded.no_shrink,
                                    allow_untranslated=recorded.allow_untranslated)
    if digest != section["digest"]:
        return _refuse([(None, "the project, scenarios or settings found here are not the ones the shards ran on "
                               "(merge loads the project from the shards' arguments: run it in the folder they ran "
                               f"in, on the same checkout): {' '.join(section['argv'])}")])
    data = merge_reports(shards, project.program)
    failures = []
    for run in data["runs"]:
        state = run_state(bool(run["divergence"]), bool(run["missing_in_translation"]), run["error"],
                          run.get("error_side"), bool(run["expectation_failures"]), run.get("error_code"))
        if state != AGREED:
            failures.append({"run": run["run"], "scenario": run["scenario"], "what": state,
                             "reproduce": run.get("reproduce")})
            print(f"{state.upper()}: run {run['run']} ({run['scenario']}): "
                  f"{_what(run)}; reproduce: {run.get('reproduce')}")
        elif args.verbose:
            print(f"equivalent: run {run['run']} ({run['scenario']}): {run['cycles']} cycles")
    data["shard"] = {"merged": section["count"], "command": "equiv", "digest": section["digest"],
                     "argv": section["argv"], "failures": failures}
    print_coverage(data["coverage"], args.verbose)
    if not _write_merged(args, data, data_json, junit_of):
        return EXIT_BAD_INPUT
    runs = data["runs"]
    print(f"hh2iec merge: equiv {data['verdict']} ({len(runs)} runs from {section['count']} shards, "
          f"{sum(r['cycles'] for r in runs)} cycles, backend {data['backend']})")
    if any(f["what"] in (FAILED_RUN, REFUSED) for f in failures):
        return EXIT_BAD_INPUT
    return EXIT_OK if data["equivalent"] else EXIT_FAILED


def _write_merged(args: argparse.Namespace, data: dict, as_json: Callable[[dict], str],
                  as_junit: Callable[[dict], str]) -> bool:
    """The merged report and JUnit file where the command line asks for them (False: one could not be written)."""
    files = {}
    if args.report:
        files[args.report] = as_json(data)
    if args.junit:
        files[args.junit] = as_junit(data)
    return write_reports(files)


def _what(run: dict) -> str:
    d = run["divergence"]
    if d:
        return (f"cycle {d['cycle']}: {d['name']} ({d['operand']}): original {d['original']!r}, "
                f"translated {d['translated']!r}")
    if run["missing_in_translation"]:
        return f"{len(run['missing_in_translation'])} operands missing in the translation"
    if run["error"]:
        return run["error"]
    return f"{len(run['expectation_failures'])} expectations failed on the original"


def _merge_mutate(args: argparse.Namespace, section, shards: list[dict]) -> int:
    from transpiler.cli.mutate import DEFAULT_MIN_SCORE
    from transpiler.verify.mutate import (EQUIVALENT, ERROR, INVALID, KILLED, SURVIVED, data_json, junit_of,
                                          merge_reports)
    scores = {data["shard"].get("min_score", DEFAULT_MIN_SCORE) for data in shards}
    if args.min_score is None and len(scores) > 1:
        values = ", ".join(map(str, sorted(scores)))
        return _refuse([(None, f"the shards ran with different --min-score values ({values}): give merge --min-score")])
    min_score = args.min_score if args.min_score is not None else scores.pop()
    if not 0.0 <= min_score <= 1.0:
        return _refuse([(None, "--min-score is a fraction between 0 and 1")])
    data = merge_reports(shards)
    failures = []
    for m in data["mutants"]:
        if m["outcome"] in (SURVIVED, ERROR):
            failures.append({"unit": m.get("unit"), "outcome": m["outcome"], "where": m["where"],
                             "reproduce": m.get("reproduce")})
            print(f"{m['outcome'].upper()}: {m['where']}: {m['operator']}: {m['mutation']}: {m['st']}"
                  + (f" -- {m['by']}" if m["by"] else "") + f"; reproduce: {m.get('reproduce')}")
        elif args.verbose:
            print(f"{m['outcome']}: {m['where']}: {m['operator']}: {m['mutation']}")
    counts = data["counts"]
    denominator = counts[KILLED] + counts[SURVIVED] + counts[ERROR]
    met = denominator > 0 and counts[KILLED] / denominator >= min_score
    data["shard"] = {"merged": section["count"], "command": "mutate", "digest": section["digest"],
                     "argv": section["argv"], "min_score": min_score, "failures": failures}
    if not _write_merged(args, data, data_json, junit_of):
        return EXIT_BAD_INPUT
    print(f"hh2iec merge: mutate score {100 * data['score']:.1f}% ({counts[KILLED]} killed of {denominator} "
          f"non-equivalent mutants from {section['count']} shards; {counts[EQUIVALENT]} judged equivalent, "
          f"{counts[ERROR]} errors, {counts[INVALID]} invalid); minimum {100 * min_score:.1f}%: "
          f"{'met' if met else 'MISSED'}")
    return EXIT_OK if met else EXIT_FAILED
