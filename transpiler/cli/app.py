"""The `hh2iec` command line: the parser with every subcommand, and `check`, `explain`, `assumptions`."""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Sequence

from transpiler import api
from transpiler.cli import equiv, simulate, transpile
from transpiler.cli.common import (EXIT_BAD_INPUT, EXIT_OK, ArgumentParser, UsageError, add_project_arguments,
                                   options_from_args, print_diagnostics, semantics_from_args)
from transpiler.diagnostics import NO_SPAN, CompileFailed, explain
from transpiler.frontend.pipeline import CompileResult
from transpiler.language.semantics import ASSUMPTION_BY_KEY, PROFILES

# Each module registers its own subcommands; listed here so that the parser's contents are visible in one place.
SUBCOMMAND_MODULES = (transpile, simulate, equiv)


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="hh2iec", description="HEIDENHAIN TNC PLC to IEC 61131-3 transpiler")
    sub = parser.add_subparsers(dest="command", required=True)
    check = sub.add_parser("check", help="preprocess, parse and resolve a project; print a summary")
    add_project_arguments(check)
    check.add_argument("--json", action="store_true", help="print the summary as JSON")
    check.set_defaults(handler=cmd_check)
    ex = sub.add_parser("explain", help="explain a diagnostic code")
    ex.add_argument("code")
    ex.set_defaults(handler=cmd_explain)
    sub.add_parser("assumptions", help="list every semantic choice with its default per profile").set_defaults(
        handler=cmd_assumptions)
    for module in SUBCOMMAND_MODULES:
        module.register(sub, add_project_arguments)
    return parser


def summary(result: CompileResult) -> dict:
    program = result.program
    diags = result.diagnostics
    data = {"files": 0, "modules": 0, "labels": 0, "symbols": 0, "instructions": 0, "lines": 0,
            "errors": len(diags.errors), "warnings": len(diags.warnings)}
    if program is not None:
        data.update(files=len(program.source_files), modules=len(program.files),
                    labels=sum(len(f.labels) for f in program.files), symbols=len(program.symbols),
                    instructions=program.instruction_count(), lines=program.line_count,
                    routines=len(program.routines), call_depth=program.call_depth,
                    auto_assigned=len(program.auto_assigned), plc_modules=list(program.modules_used),
                    profile=program.semantics.profile.name)
    return data


def cmd_check(args: argparse.Namespace) -> int:
    result = api.check_project(options_from_args(args), semantics_from_args(args))
    print_diagnostics(result.diagnostics.items)
    data = summary(result)
    if args.json:
        print(json.dumps(data, indent=2, sort_keys=True))
    else:
        print(f"hh2iec check: {args.main}")
        for key in ("files", "modules", "labels", "symbols", "instructions", "lines", "routines", "call_depth",
                    "auto_assigned", "errors", "warnings"):
            if key in data:
                print(f"  {key:<14} {data[key]}")
        if data.get("plc_modules"):
            print(f"  {'plc modules':<14} {', '.join(map(str, data['plc_modules']))}")
    return EXIT_BAD_INPUT if result.diagnostics.has_errors() else EXIT_OK


def cmd_explain(args: argparse.Namespace) -> int:
    text = explain(args.code)
    if text is None:
        print(f"{NO_SPAN}: error[E-USAGE]: unknown diagnostic code {args.code}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(text, end="")
    return EXIT_OK


def cmd_assumptions(args: argparse.Namespace) -> int:
    names = sorted(PROFILES)
    print(f"{'id':<6} {'key':<28} " + " ".join(f"{n:<12}" for n in names))
    for key, a in ASSUMPTION_BY_KEY.items():
        print(f"{a.id:<6} {key:<28} " + " ".join(f"{str(PROFILES[n].defaults[key]):<12}" for n in names))
    return EXIT_OK


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except UsageError as exc:
        print(f"{NO_SPAN}: error[E-USAGE]: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SystemExit as exc:
        return EXIT_BAD_INPUT if exc.code not in (0, None) else EXIT_OK
    try:
        return args.handler(args)
    except UsageError as exc:
        print(f"{NO_SPAN}: error[E-USAGE]: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except CompileFailed as exc:
        for d in exc.diagnostics:
            print(d.render(), file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return 130
    except Exception as exc:  # noqa: BLE001 - the last line of defence: a bug must not show users a traceback
        if os.environ.get("HH2IEC_DEBUG"):
            raise
        print(f"{NO_SPAN}: error[E-TOOL]: internal error ({type(exc).__name__}: {exc}); "
              "this is a bug in hh2iec - rerun with HH2IEC_DEBUG=1 for the traceback", file=sys.stderr)
        return EXIT_BAD_INPUT


def entry() -> None:
    sys.exit(main())


if __name__ == "__main__":
    entry()
