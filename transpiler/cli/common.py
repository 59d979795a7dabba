"""What every subcommand shares: exit codes, usage errors, the project arguments and printing diagnostics."""

from __future__ import annotations

import argparse
import gc
import os
import sys
from pathlib import Path
from typing import Iterable

from transpiler import api
from transpiler.diagnostics import Diagnostic
from transpiler.language.semantics import PROFILES

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


class UsageError(Exception):
    """Bad command-line usage: printed as `<command line>:1:1: error[E-USAGE]: ...`, exit 2."""


class ArgumentParser(argparse.ArgumentParser):
    """argparse that reports bad usage as an E-USAGE diagnostic (exit 2) instead of its own error format."""

    def error(self, message: str):
        raise UsageError(f"{message} (see '{self.prog} --help')")


def add_project_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("main", type=Path, help="main program (.src) of the HEIDENHAIN project, or its folder")
    p.add_argument("--cfg", type=Path, help="configuration file with DEFINE lines (default: OEM.cfg beside MAIN)")
    p.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME=VALUE", help="override a DEFINE")
    p.add_argument("-I", dest="include_dirs", action="append", default=[], type=Path, metavar="DIR",
                   help="extra folder to search for modules and definition files")
    p.add_argument("--profile", choices=sorted(PROFILES), help="control profile (default itnc530)")
    p.add_argument("-S", "--semantics", dest="semantic_overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override one semantic choice (see `hh2iec assumptions`)")
    p.add_argument("--encoding", metavar="NAME", help="read every file in this encoding (default: per file, UTF-8 "
                   "with or without BOM when valid, else Windows-1252)")
    p.add_argument("--werror", action="store_true", help="warnings fail the run (exit 2)")
    p.add_argument("--defs", dest="extra_defs", action="append", default=[], type=Path, metavar="FILE",
                   help="extra global definition file (as if loaded with #define /g)")
    p.add_argument("--mp-data", type=Path, metavar="FILE", help="PLC data table MP_Data.tab (default: MP/MP_Data.tab "
                   "or MP_Data.tab beside MAIN)")
    p.add_argument("--mp-config", type=Path, metavar="FILE", help="PLC configuration table MP_Config.tab (default: "
                   "MP/MP_Config.tab or MP_Config.tab beside MAIN)")


def _pairs(items: Iterable[str], flag: str) -> dict[str, str]:
    pairs = {}
    for item in items:
        if "=" not in item:
            raise UsageError(f"{flag} expects {'NAME' if flag == '-D' else 'KEY'}=VALUE, got '{item}'")
        key, value = item.split("=", 1)
        pairs[key.strip()] = value if flag == "-D" else value.strip()
    return pairs


def options_from_args(args: argparse.Namespace):
    return api.project_options(args.main, cfg=args.cfg, defines=_pairs(args.defines, "-D"),
                               include_dirs=args.include_dirs, extra_defs=args.extra_defs,
                               encoding=args.encoding, werror=args.werror, mp_data=args.mp_data,
                               mp_config=args.mp_config)


def semantics_from_args(args: argparse.Namespace, scenario: Path | None = None):
    return api.semantics_for(args.profile, _pairs(args.semantic_overrides, "-S"), scenario)


def project_from_args(args: argparse.Namespace, scenario: Path | None = None) -> api.Project:
    """The loaded project; `scenario` contributes its profile and semantic settings."""
    options = options_from_args(args)
    return api.load_project(options, semantics_from_args(args, scenario))


def one_shot() -> None:
    """For a command that reads a project, writes its result and ends (check, transpile): the cyclic garbage
    collector is switched off for the rest of the process. The front end and the back ends build millions of
    acyclic records (freed by reference counting as usual); each collection of the collector would only walk
    them again (a tenth of `check` on a 100 000-line project), and the process ends right after."""
    gc.disable()


def finish_one_shot(args: argparse.Namespace, code: int) -> int:
    """The last step of a one-shot command (check, transpile): in the `hh2iec` process itself (`app.entry`), the
    process ends here with `code` once its output is flushed, without the interpreter's clean-up, which would free
    the project, its translation and every module one object at a time only to exit (about 0.1 s of `transpile`
    on a 100 000-line project). The output files are written and closed by then; called through `main()` from
    Python, or when a stream cannot be flushed (a closed pipe: the interpreter's own exit reports it), it returns
    `code` as every command does."""
    if getattr(args, "own_process", False):
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except (OSError, ValueError):
            return code
        os._exit(code)
    return code


def print_diagnostics(items: Iterable[Diagnostic], stream=None) -> None:
    stream = stream or sys.stderr
    for d in items:
        print(d.render(), file=stream)


def diagnostics_json(items: Iterable[Diagnostic]) -> list[dict]:
    """Every diagnostic as data for `--json`: code, severity, file, line, col, message and notes."""
    return [{"code": d.code, "severity": d.severity.value, "file": d.span.file, "line": d.span.line,
             "col": d.span.col, "message": d.message, "notes": list(d.notes)} for d in items]


def write_reports(files: dict) -> bool:
    """Write the report files of a command all-or-nothing and say where they went; False (after an E-TOOL message)
    when they cannot be written."""
    from transpiler.atomic import write_files_atomically
    from transpiler.diagnostics import NO_SPAN
    try:
        write_files_atomically(files)
    except OSError as exc:
        print(f"{NO_SPAN}: error[E-TOOL]: cannot write the reports: {exc}", file=sys.stderr)
        return False
    if files:
        print("reports: " + ", ".join(str(path) for path in files))
    return True


# ---------------------------------------------------------------------------------------------
# sharding (verify/shard.py): the flags equiv and mutate share, and the arguments a shard records

# Flags that choose what a run writes or how it is split, not what it finds: left out of the arguments a shard
# records (merge loads the project from them, and the command that reproduces a failure repeats them).
NOT_INPUTS = frozenset({"shard", "plan", "plan_file", "only", "report", "junit", "cobertura", "lcov", "vcd", "html",
                        "verbose", "survivors", "mutation_report", "jobs", "help", "handler", "command_parser",
                        "show_mask"})


def shard_spec(text: str):
    from transpiler.verify.shard import ShardSpec
    try:
        return ShardSpec.parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_shard_arguments(p: argparse.ArgumentParser, units: str) -> None:
    p.add_argument("--shard", type=shard_spec, metavar="K/N",
                   help=f"run only shard K of N: a share of the {units} every shard computes alike from the same "
                        "inputs; needs --report (the shard's result, for `hh2iec merge`)")
    p.add_argument("--plan", type=int, metavar="N",
                   help=f"run nothing: print the number of {units} and the estimated time of each of N shards")
    p.add_argument("--plan-file", type=Path, metavar="FILE",
                   help="with --plan: also write the plan, with the runs the coverage-guided search chose, to FILE; "
                        "with --shard or --only: take those runs from FILE instead of searching again")
    p.add_argument("--only", type=int, metavar="ID",
                   help=f"run only the one of the {units} with this number (`run` or `unit` in the report; the "
                        "merged report names the command line for each failure)")


def check_shard_arguments(args: argparse.Namespace) -> None:
    if args.plan is not None:
        if args.plan < 1:
            raise UsageError("--plan N needs N of at least 1 shard")
        if args.shard is not None or args.only is not None:
            raise UsageError("--plan runs nothing: give it without --shard and --only")
    elif args.plan_file is not None and not args.plan_file.is_file():
        raise UsageError(f"plan file '{args.plan_file}' does not exist (write it with --plan N --plan-file FILE)")
    if args.shard is not None and args.only is not None:
        raise UsageError("--only runs one unit of the whole plan: give it without --shard")
    if args.shard is not None and args.report is None:
        raise UsageError("--shard needs --report OUT.json: the shard's result, which `hh2iec merge` combines")


def input_argv(args: argparse.Namespace) -> list[str]:
    """The command's arguments that decide what it finds (the project, inputs and settings), rebuilt from the
    parsed values in the parser's order, long flags preferred: what a shard records for merge and reproduction."""
    positional: list[str] = []
    options: list[str] = []
    for action in args.command_parser._actions:
        if action.dest in NOT_INPUTS:
            continue
        value = getattr(args, action.dest, None)
        if not action.option_strings:
            positional.append(str(value))
            continue
        if value == action.default or value is None:
            continue
        flag = max(action.option_strings, key=len)
        if isinstance(action, argparse._StoreTrueAction):
            options.append(flag)
        elif isinstance(action, argparse._AppendAction):
            for item in value:
                options += [flag, str(item)]
        else:
            options += [flag, str(value)]
    return positional + options


def print_plan(command: str, plan, count: int, seconds_per_cost: float, unit: str, setup_note: str) -> None:
    """The plan of `--plan N`: the units and the estimated time of each shard."""
    from transpiler.verify.shard import shard_loads
    loads = shard_loads(plan.costs, plan.assignment(count), count)
    total = sum(plan.costs)
    print(f"{command} plan: {len(plan.costs)} {unit}; set-up per shard {plan.setup_seconds:.1f} s{setup_note}")
    for k, (units, cost) in enumerate(loads, 1):
        print(f"  shard {k}/{count}: {units} {unit}, about {plan.setup_seconds + cost * seconds_per_cost:.0f} s")
    print(f"  unsharded: about {plan.setup_seconds + total * seconds_per_cost:.0f} s; the largest shard carries "
          f"{100.0 * max(c for _, c in loads) / total if total else 0:.0f}% of the work")


def report_plan(command: str, plan, args: argparse.Namespace, seconds_per_cost: float, unit: str,
                setup_note: str) -> bool:
    """`--plan N`: print the plan (with the cost of the coverage-guided search, where it made runs) and write it to
    `--plan-file` where given; False when that file could not be written."""
    if plan.generated:
        setup_note += (f"; the coverage-guided search took {plan.search_seconds:.1f} s: with --plan-file it runs "
                       "once, here, else again in every shard")
    print_plan(command, plan, args.plan, seconds_per_cost, unit, setup_note)
    return write_reports({args.plan_file: api.plan_file_text(plan)} if args.plan_file is not None else {})


def print_screens(screens) -> None:
    """The screen masks asked for with --show-mask, each framed under a title line (stdout)."""
    from transpiler.verify.screens import render_text
    for screen in screens:
        print(render_text(screen), end="")
