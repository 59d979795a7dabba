"""The `hh2iec` command line: check, transpile, simulate, equiv, explain (contract: shared spec cli.md)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Sequence

from transpiler.diagnostics import CompileFailed, Diagnostics, NO_SPAN, explain
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import CompileResult, compile_project
from transpiler.frontend.preprocess import parse_define_value
from transpiler.language.semantics import ASSUMPTION_BY_KEY, PROFILES, SemanticsError, make_semantics

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


class UsageError(Exception):
    pass


class _ArgumentParser(argparse.ArgumentParser):
    """argparse that reports bad usage as an E-USAGE diagnostic (exit 2) instead of its own error format."""

    def error(self, message: str):
        raise UsageError(f"{message} (see '{self.prog} --help')")


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("main", type=Path, help="main program (.src) of the HEIDENHAIN project")
    p.add_argument("--cfg", type=Path, help="configuration file with DEFINE lines (default: OEM.cfg beside MAIN)")
    p.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME=VALUE", help="override a DEFINE")
    p.add_argument("-I", dest="include_dirs", action="append", default=[], type=Path, metavar="DIR",
                   help="extra folder to search for modules and definition files")
    p.add_argument("--profile", choices=sorted(PROFILES), help="control profile (default itnc530)")
    p.add_argument("-S", "--semantics", dest="semantic_overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override one semantic choice (see `hh2iec assumptions`)")
    p.add_argument("--defs", dest="extra_defs", action="append", default=[], type=Path, metavar="FILE",
                   help="extra global definition file (as if loaded with #define /g)")


# Modules of the later stages; each has `register(subparsers, common)`. Imported lazily so that
# `check` does not load the interpreter, the C shim or the ST executor.
SUBCOMMAND_MODULES = ("cli.transpile", "verify.simulate", "verify.equiv")


def build_parser() -> argparse.ArgumentParser:
    import importlib
    parser = _ArgumentParser(prog="hh2iec", description="HEIDENHAIN TNC PLC to IEC 61131-3 transpiler")
    sub = parser.add_subparsers(dest="command", required=True)
    check = sub.add_parser("check", help="preprocess, parse and resolve a project; print a summary")
    _common(check)
    check.add_argument("--json", action="store_true", help="print the summary as JSON")
    ex = sub.add_parser("explain", help="explain a diagnostic code")
    ex.add_argument("code")
    sub.add_parser("assumptions", help="list every semantic choice with its default per profile")
    for name in SUBCOMMAND_MODULES:
        importlib.import_module(f"transpiler.{name}").register(sub, _common)
    return parser


def options_from_args(args: argparse.Namespace) -> ProjectOptions:
    defines = {}
    for item in args.defines:
        if "=" not in item:
            raise UsageError(f"-D expects NAME=VALUE, got '{item}'")
        name, value = item.split("=", 1)
        defines[name.strip()] = parse_define_value(value)
    main = args.main
    if not main.is_file():
        raise UsageError(f"main program '{main}' does not exist")
    if args.cfg is not None and not args.cfg.is_file():
        raise UsageError(f"configuration file '{args.cfg}' does not exist")
    for d in args.include_dirs:
        if not d.is_dir():
            raise UsageError(f"-I folder '{d}' does not exist")
    return ProjectOptions(main=main, cfg=args.cfg, defines=defines, include_dirs=tuple(args.include_dirs),
                          extra_global_defs=tuple(args.extra_defs))


def semantics_from_args(args: argparse.Namespace, scenario_profile: str | None = None, extra: dict | None = None):
    overrides = dict(extra or {})
    for item in args.semantic_overrides:
        if "=" not in item:
            raise UsageError(f"-S expects KEY=VALUE, got '{item}'")
        key, value = item.split("=", 1)
        overrides[key.strip()] = value.strip()
    profile = args.profile or scenario_profile or "itnc530"
    try:
        return make_semantics(profile, overrides)
    except SemanticsError as exc:
        raise UsageError(str(exc)) from None


def print_diagnostics(diags: Diagnostics, stream=None) -> None:
    stream = stream or sys.stderr
    for d in diags.items:
        print(d.render(), file=stream)


def compile_from_args(args: argparse.Namespace, scenario_profile: str | None = None, semantic_extra: dict | None = None) -> CompileResult:
    options = options_from_args(args)
    semantics = semantics_from_args(args, scenario_profile, semantic_extra)
    return compile_project(options, semantics)


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
    result = compile_from_args(args)
    print_diagnostics(result.diagnostics)
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
    handler = {"check": cmd_check, "explain": cmd_explain, "assumptions": cmd_assumptions}.get(args.command)
    if handler is None:
        handler = getattr(args, "handler")
    try:
        return handler(args)
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
