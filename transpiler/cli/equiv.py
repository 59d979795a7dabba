"""The `equiv` subcommand: co-simulation of the original and the translated program, verdict and reports."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Callable

from transpiler import api
from transpiler.cli.common import (EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, UsageError, add_shard_arguments,
                                   check_shard_arguments, input_argv, print_diagnostics, print_screens, report_plan,
                                   project_from_args, write_reports)
from transpiler.cli.progress import ProgressLine
from transpiler.diagnostics import NO_SPAN


def register(sub: argparse._SubParsersAction, common) -> None:
    p = sub.add_parser("equiv", help="co-simulate the original and the translated program and compare every cycle")
    common(p)
    p.add_argument("--scenario", type=Path, action="append", default=[], help="scenario file (repeatable)")
    p.add_argument("--backend", choices=("auto", "matiec", "builtin"), default="auto")
    p.add_argument("--st", type=Path, help="use this ST file instead of transpiling afresh")
    p.add_argument("--io-map", type=Path, help="io_map.csv of the --st file (default: io_map.csv beside it, "
                   "else the map of a fresh transpilation)")
    p.add_argument("--random-cycles", type=int, default=0, metavar="N", help="also run N cycles of random stimulus")
    p.add_argument("--seed", type=int, default=1, metavar="S", help="seed of the random stimulus")
    p.add_argument("--report", type=Path, metavar="OUT.json")
    p.add_argument("--junit", type=Path, metavar="OUT.xml")
    p.add_argument("--cobertura", type=Path, metavar="OUT.xml",
                   help="line and branch coverage of the .src files as Cobertura XML (GitLab, coverage actions)")
    p.add_argument("--lcov", type=Path, metavar="OUT.info", help="the same coverage as an LCOV tracefile (genhtml)")
    p.add_argument("--vcd", type=Path, metavar="DIR", help="write both traces of each run as value-change dumps")
    p.add_argument("--mp", type=Path, help="machine-parameter file used for the transpilation's preset defaults")
    p.add_argument("--no-shrink", action="store_true", help="do not shrink a divergent stimulus")
    p.add_argument("--allow-untranslated", action="store_true",
                   help="co-simulate a translation that left code out; the verdict is then at best NOT PROVEN")
    p.add_argument("--html", type=Path, metavar="DIR",
                   help="write the evidence as one self-contained page, DIR/index.html: verdict, runs, each "
                        "divergence as a timeline, every source file with its coverage")
    p.add_argument("--show-mask", action="append", default=[], metavar="NAME@CYCLE",
                   help="replay each --scenario and print the screen mask NAME after CYCLE from both sides; screens "
                   "that differ fail the run (exit 1; repeatable; docs/masks.md)")
    p.add_argument("-v", "--verbose", action="store_true",
                   help="also a line for every equivalent run and the list of what no run covered")
    add_shard_arguments(p, "runs")
    p.set_defaults(handler=cmd_equiv, command_parser=p)


def cmd_equiv(args: argparse.Namespace) -> int:
    from transpiler.verify.equiv import report_json, report_junit
    if not args.scenario and args.random_cycles <= 0:
        raise UsageError("equiv needs at least one --scenario or --random-cycles N")
    for path in args.scenario:
        if not path.is_file():
            raise UsageError(f"scenario file '{path}' does not exist")
    if args.st is not None and not args.st.is_file():
        raise UsageError(f"ST file '{args.st}' does not exist")
    check_shard_arguments(args)
    if args.show_mask and (args.shard is not None or args.plan is not None):
        raise UsageError("--show-mask replays the scenarios in one process: give it without --shard and --plan")
    project = project_from_args(args, scenario=args.scenario[0] if args.scenario else None)
    print_diagnostics(project.diagnostics)
    inputs = dict(scenarios=args.scenario, random_cycles=args.random_cycles, seed=args.seed, backend=args.backend,
                  st_file=args.st, io_map_file=args.io_map, mp_file=args.mp, shrink=not args.no_shrink,
                  allow_untranslated=args.allow_untranslated)
    if args.plan is not None:
        return _plan(project, args, inputs)
    line = ProgressLine("equiv", "cycles")
    try:
        check = api.check_equivalence(project, **inputs, vcd_dir=args.vcd, progress=_cycle_progress(line),
                                      html=args.html is not None, show_masks=args.show_mask,
                                      share=api.Share(args.shard, args.only, args.plan_file))
    finally:
        line.close()
    print_diagnostics(check.diagnostics)
    if check.backend_note:
        print(f"note: {check.backend_note}", file=sys.stderr)
    result = check.result
    _print_outcomes(result, args.verbose)
    print_screens(check.screens)
    files = {}
    if args.report:
        from transpiler import __version__
        from transpiler.verify.shard import reproduce_command, shard_section
        argv = input_argv(args)
        plan_file = str(args.plan_file) if args.plan_file is not None else None
        section = None if args.shard is None else shard_section(
            "equiv", args.shard, check.plan.digest, __version__, argv, (check.plan.names, check.plan.costs),
            result.run_ids, plan_file=plan_file)
        files[args.report] = report_json(result, lambda run: reproduce_command("equiv", argv, run, plan_file), section,
                                         check.screens)
    if args.junit:
        files[args.junit] = report_junit(result, check.screens)
    if args.cobertura or args.lcov:
        from transpiler.verify.coverage_export import coverage_files
        try:
            files.update(coverage_files(result.source, project.main.parent, Path.cwd(), cobertura=args.cobertura,
                                        lcov=args.lcov))
        except ValueError as exc:           # SOURCE_DATE_EPOCH that is not a number
            raise UsageError(str(exc)) from None
    if args.html is not None and check.html_page is not None:
        from transpiler.verify.html_report import PAGE_FILE
        files[args.html / PAGE_FILE] = check.html_page
    if not write_reports(files):
        return EXIT_BAD_INPUT
    share = (f"shard {args.shard} ({len(result.outcomes)} of {len(check.plan.names)} runs): " if args.shard else
             f"run {args.only} of {len(check.plan.names)}: " if args.only else "")
    if args.shard is not None and not result.outcomes:
        print(f"hh2iec equiv: {share}nothing to run; `hh2iec merge` gives the verdict of all shards")
        return EXIT_OK
    headline = result.verdict
    if check.screens_differ:
        # The screens are a finding of their own: the headline must not read as a pass when the operator's view
        # differs, whatever the compared operands say.
        differing = sorted({f"{s.mask} after cycle {s.cycle} of {s.scenario}" for s in check.screens if s.differs})
        headline = f"SCREENS DIFFER: {'; '.join(differing)}; compared operands: {result.verdict}"
    print(f"hh2iec equiv: {share}{headline} ({len(result.outcomes)} runs, "
          f"{sum(o.result.cycles_run for o in result.outcomes)} cycles, backend {result.backend})")
    if result.errors:
        return EXIT_BAD_INPUT
    return EXIT_OK if result.equivalent and not check.screens_differ else EXIT_FAILED


def _plan(project, args: argparse.Namespace, inputs: dict) -> int:
    """`--plan N`: the runs and the estimated time of each of N shards; `--plan-file` also writes the plan."""
    plan, per_cycle = api.plan_equivalence(project, **inputs)
    note = f"; {1000 * per_cycle:.2f} ms per co-simulated cycle (one calibration run)"
    return EXIT_OK if report_plan("equiv", plan, args, per_cycle, "runs", note) else EXIT_BAD_INPUT


def _cycle_progress(line: ProgressLine) -> Callable[[str, int, int], Callable[[int, int], None]]:
    """The cycle counter of each run, drawn as the progress of all runs' cycles."""
    def run(label: str, before: int, total: int) -> Callable[[int, int], None]:
        return lambda done, _: line.update(before + done, total, label)
    return run


def _pct(a: int, b: int) -> str:
    return f"{100.0 * a / b:.1f}%" if b else "n/a"


def _compared_text(r) -> str:
    """The operands compared per cycle; addresses the program stored to through the index register are counted
    apart because they join the comparison only from their first indexed store on (see cosim.cosimulate)."""
    text = f"{r.compared} operands compared per cycle"
    if r.compared_indexed:
        text += f" + {r.compared_indexed} indexed addresses from their first indexed store"
    if r.swept:
        text += f"; {r.swept} other addresses after the last cycle"
    return text


def _print_outcomes(result, verbose: bool) -> None:
    """Everything that went wrong, always; a line per equivalent run and the uncovered places with `verbose`."""
    from transpiler.verify.stimulus import scenario_to_yaml
    for o in result.outcomes:
        r = o.result
        if r.error and r.error_side == "translated":
            print(f"FAULT OF THE TRANSLATION in {r.scenario}: {r.error}")
        elif r.error:
            print(f"{NO_SPAN}: error[{r.error_code or 'E-TOOL'}]: {r.scenario}: {r.error}", file=sys.stderr)
        elif r.divergence:
            d = r.divergence
            print(f"DIVERGENCE in {r.scenario} at cycle {d.cycle}: {d.name} ({d.operand}): original {d.original!r}, "
                  f"translated {d.translated!r}")
            if o.shrunk is not None:
                print(f"shortest input trace found ({o.shrunk.cycles} cycles, {len(o.shrunk.events)} events, "
                      f"{o.shrink_runs} runs); rerun it with --scenario:")
                print(scenario_to_yaml(o.shrunk))
        elif r.missing:
            print(f"NOT EQUIVALENT: {r.scenario}: {len(r.missing)} operands the original writes are missing in the "
                  f"translation; {r.cycles_run} cycles, {_compared_text(r)} equal ({r.seconds:.2f} s)")
        elif verbose:
            print(f"equivalent: {r.scenario}: {r.cycles_run} cycles, {_compared_text(r)} ({r.seconds:.2f} s)")
        for m in r.missing:
            print(f"MISSING in the translation ({r.scenario}): {m.render()}")
        for f in r.expectation_failures:
            where = f.span or "<scenario>"
            print(f"{where}: expectation failed: cycle {f.cycle}: {f.name}: expected {f.expected!r}, "
                  f"actual {f.actual!r}", file=sys.stderr)
    for span, text in result.untranslated:
        print(f"NOT TRANSLATED: {span}: {text}")
    if not result.started:
        print("coverage: none (no run started)")
        return
    print_coverage(result.coverage, verbose)


def print_coverage(c: dict, verbose: bool) -> None:
    """The coverage line (and with `verbose` every branch outcome, CASE entry, MC/DC condition and boundary value no
    run took, and every infeasible one with its reason)."""
    from transpiler.verify.mcdc import figures
    print(f"coverage: instructions {c['instructions_executed']}/{c['instructions']} ({_pct(c['instructions_executed'], c['instructions'])}), "
          f"conditional branches both ways {c['branches_both_ways']}/{c['branches']} "
          f"({_pct(c['branches_both_ways'], c['branches'])}), CASE entries {c['case_entries_taken']}/{c['case_entries']}"
          + (f", {figures(c)}" if "mcdc" in c else ""))
    never = c.get("never_taken", ())
    if verbose:
        for item in never:
            print(f"  not covered: {item['at']}: {item['what']}")
    elif never:
        print(f"  {len(never)} branch outcomes or CASE entries no run took (-v lists them)")
    if "mcdc" in c:
        missing = c["mcdc"]["not_shown"] + c["boundaries"]["not_reached"]
        infeasible = c["mcdc"]["infeasible"] + c["boundaries"]["infeasible"]
        if verbose:
            for item in missing:
                print(f"  not covered: {item['at']}: {item['what']}")
            for item in infeasible:
                print(f"  infeasible: {item['at']}: {item['what']}: {item['reason']}")
        elif missing or infeasible:
            print(f"  {len(missing)} MC/DC conditions or boundary values no run covered, {len(infeasible)} "
                  "infeasible (-v lists them)")
