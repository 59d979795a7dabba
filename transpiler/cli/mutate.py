"""The `mutate` subcommand: how strong is the evidence? Mutants of the emitted ST judged by co-simulation."""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
import sys
from pathlib import Path

from transpiler import api
from transpiler.cli.common import (EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, UsageError, add_shard_arguments,
                                   check_shard_arguments, input_argv, print_diagnostics, report_plan,
                                   project_from_args, write_reports)
from transpiler.cli.progress import ProgressLine

DEFAULT_MIN_SCORE = 0.9


def register(sub: argparse._SubParsersAction, common) -> None:
    p = sub.add_parser("mutate", help="mutate the emitted ST and report how many mutants the scenarios kill")
    common(p)
    p.add_argument("--scenario", type=Path, action="append", default=[], help="scenario file (repeatable)")
    p.add_argument("--random-cycles", type=int, default=2000, metavar="N",
                   help="cycles of coverage-guided generated stimulus on top of the scenarios (default 2000)")
    p.add_argument("--seed", type=int, default=1, metavar="S", help="seed of the generated stimulus and of --count")
    p.add_argument("--backend", choices=("auto", "matiec", "builtin"), default="auto")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1, metavar="J", help="mutants judged in parallel")
    p.add_argument("--count", type=int, default=0, metavar="N",
                   help="judge a seeded sample of N mutants spread over the operators (default: all)")
    p.add_argument("--mutants", type=Path, metavar="FILE",
                   help="judge only the mutants this file lists (the --survivors format): re-judge survivors")
    p.add_argument("--equivalent", type=Path, metavar="FILE",
                   help="YAML list of mutants judged equivalent, each with its reason (left out of the score)")
    p.add_argument("--min-score", type=float, default=DEFAULT_MIN_SCORE, metavar="F",
                   help=f"exit 0 when killed / (non-equivalent mutants) reaches F (default {DEFAULT_MIN_SCORE})")
    p.add_argument("--mp", type=Path, help="machine-parameter file used for the transpilation's preset defaults")
    p.add_argument("--report", type=Path, metavar="OUT.json")
    p.add_argument("--junit", type=Path, metavar="OUT.xml")
    p.add_argument("--survivors", type=Path, metavar="OUT.yaml",
                   help="write the survivors in the --equivalent format, for judging")
    p.add_argument("--mutation-report", type=Path, metavar="OUT.json",
                   help="every mutant in the mutation-testing-report-schema (Stryker's report format, for its HTML "
                        "viewer and dashboard)")
    p.add_argument("--html", type=Path, metavar="DIR",
                   help="write the result as one self-contained page, DIR/index.html: the score and every "
                        "surviving mutant beside the source line it comes from")
    p.add_argument("-v", "--verbose", action="store_true",
                   help="also the table per operator and every mutant judged equivalent or invalid")
    add_shard_arguments(p, "mutants")
    p.set_defaults(handler=cmd_mutate, command_parser=p)


def cmd_mutate(args: argparse.Namespace) -> int:
    from transpiler.verify.mutate import (EQUIVALENT, ERROR, INVALID, KILLED, KILLED_ANYWAY, OPERATORS, OUTCOMES,
                                          SURVIVED, survivor_location)
    if not args.scenario and args.random_cycles <= 0:
        raise UsageError("mutate needs at least one --scenario or --random-cycles N")
    if args.jobs < 1:
        raise UsageError("--jobs must be at least 1")
    if not 0.0 <= args.min_score <= 1.0:
        raise UsageError("--min-score is a fraction between 0 and 1")
    for path in [*args.scenario, *(f for f in (args.equivalent, args.mutants) if f)]:
        if not path.is_file():
            raise UsageError(f"file '{path}' does not exist")
    check_shard_arguments(args)
    project = project_from_args(args, scenario=args.scenario[0] if args.scenario else None)
    print_diagnostics(project.diagnostics)
    inputs = dict(scenarios=args.scenario, random_cycles=args.random_cycles, seed=args.seed, backend=args.backend,
                  mp_file=args.mp, jobs=args.jobs, count=args.count, equivalent_file=args.equivalent,
                  mutants_file=args.mutants)
    if args.plan is not None:
        return _plan(project, args, inputs)
    line = ProgressLine("mutate", "mutants judged")
    try:
        run = api.mutate(project, **inputs, progress=line.update,
                         share=api.Share(args.shard, args.only, args.plan_file))
    finally:
        line.close()
    print_diagnostics(run.diagnostics)
    if run.backend_note:
        print(f"note: {run.backend_note}", file=sys.stderr)
    result = run.result
    print(f"{result.sites} mutation sites; {len(result.verdicts)} mutants judged on the {result.backend} backend "
          f"under {len(result.scenarios)} scenarios (shortest first, until one diverges) in {result.seconds:.0f} s")
    if result.listed_absent:
        print(f"note: {result.listed_absent} of the mutants --mutants lists are not mutants of the translation (it "
              "changed since the list was written)")
    if args.verbose:
        print(f"{'operator':<16}{'mutants':>8}" + "".join(f"{o:>11}" for o in OUTCOMES))
        for op in OPERATORS:
            mine = [v for v in result.verdicts if v.mutant.operator == op]
            print(f"{op:<16}{len(mine):>8}" + "".join(f"{sum(1 for v in mine if v.outcome == o):>11}"
                                                      for o in OUTCOMES))
    # Survivors and errors are what the user must act on: always listed. The judged and the invalid only with -v.
    listed = ((SURVIVED, "SURVIVED"), (ERROR, "ERROR (only exceptions, no divergence)"))
    if args.verbose:
        listed += ((INVALID, "invalid (the mutated ST was rejected)"), (EQUIVALENT, "judged equivalent"))
    for outcome, title in listed:
        for v in (v for v in result.verdicts if v.outcome == outcome):
            why = f" -- {v.by}" if v.by else ""
            print(f"{title}: {survivor_location(run.st_text, v.mutant)}: {v.mutant.operator}: "
                  f"{v.mutant.description}: {v.mutant.original}{why}")
    for e, why in result.unmatched_equivalents:
        what = ("judged equivalent, but a scenario killed it: the judgement is wrong" if why == KILLED_ANYWAY
                else "judged equivalent, but the translation has no such mutant: the entry is stale")
        print(f"{e.span}: note: {what}: {e.pou}: {e.mutation}: {e.st}")
    met = result.meets(args.min_score)
    if not write_reports(_report_files(args, project, run)):
        return EXIT_BAD_INPUT
    if args.shard is not None:
        print(f"hh2iec mutate: shard {args.shard}: {len(result.verdicts)} of {len(run.plan.names)} mutants judged; "
              "`hh2iec merge` gives the score of all shards")
        return EXIT_OK          # the score is one of all mutants: the merge compares it with the minimum
    print(f"hh2iec mutate: score {100 * result.score:.1f}% ({result.count(KILLED)} killed of {result.denominator} "
          f"non-equivalent mutants; {result.count(EQUIVALENT)} judged equivalent, {result.count(ERROR)} errors, "
          f"{result.count(INVALID)} invalid); minimum {100 * args.min_score:.1f}%: {'met' if met else 'MISSED'}")
    return EXIT_OK if met else EXIT_FAILED


def _report_files(args: argparse.Namespace, project, run) -> dict:
    """The files the arguments ask for; a shard's report carries its `shard` section (verify/shard.py)."""
    from transpiler.verify.mutate import equivalents_yaml, report_json, report_junit
    result = run.result
    files = {}
    if args.report:
        from transpiler import __version__
        from transpiler.verify.shard import reproduce_command, shard_section
        argv = input_argv(args)
        plan_file = str(args.plan_file) if args.plan_file is not None else None
        section = None if args.shard is None else shard_section(
            "mutate", args.shard, run.plan.digest, __version__, argv, (run.plan.names, run.plan.costs),
            sorted(run.unit_ids.values()), plan_file=plan_file, min_score=args.min_score)
        files[args.report] = report_json(result, run.st_text, run.unit_ids,
                                         lambda unit: reproduce_command("mutate", argv, unit, plan_file), section)
    if args.junit:
        files[args.junit] = report_junit(result, run.st_text)
    if args.survivors:
        files[args.survivors] = equivalents_yaml(result.verdicts)
    if args.mutation_report:
        from transpiler.verify.mutation_report import mutation_report
        files[args.mutation_report] = mutation_report(result, run.st_text, args.min_score)
    if args.html is not None:
        from transpiler.verify.html_report import PAGE_FILE
        files[args.html / PAGE_FILE] = api.mutation_page(project, run, args.min_score)
    return files


CALIBRATION_MUTANTS = 6


def _plan(project, args: argparse.Namespace, inputs: dict) -> int:
    """`--plan N`: the mutants and the estimated time of each of N shards, from a few mutants judged as a sample;
    `--plan-file` also writes the plan."""
    start = time.perf_counter()
    run = api.mutate(project, **inputs, share=api.Share(sample=CALIBRATION_MUTANTS))
    judged = run.result.verdicts
    plan = dataclasses.replace(run.plan, setup_seconds=time.perf_counter() - start - run.result.seconds
                               - run.plan.search_seconds)
    per_mutant = sum(v.seconds for v in judged) / len(judged) / max(1, args.jobs) if judged else 0.0
    per_cost = per_mutant / plan.costs[0] if plan.costs and plan.costs[0] else 0.0
    note = (f" (translation, scenarios, the unmutated run); {per_mutant:.2f} s per mutant with --jobs {args.jobs} "
            f"({len(judged)} mutants judged as a sample)")
    return EXIT_OK if report_plan("mutate", plan, args, per_cost, "mutants", note) else EXIT_BAD_INPUT
