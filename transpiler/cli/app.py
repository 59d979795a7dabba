"""The `hh2iec` command line: the parser with every subcommand, `--version`, and `check`, `explain`, `assumptions`."""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Sequence

from transpiler import __version__, api
from transpiler.cli import equiv, merge, mutate, simulate, transpile
from transpiler.cli.common import (EXIT_BAD_INPUT, EXIT_OK, ArgumentParser, UsageError, add_project_arguments,
                                   diagnostics_json, finish_one_shot, one_shot, options_from_args, print_diagnostics,
                                   semantics_from_args)
from transpiler.diagnostics import CODES, NO_SPAN, CompileFailed, explain
from transpiler.frontend.pipeline import CompileResult
from transpiler.language.semantics import ASSUMPTION_BY_KEY, ASSUMPTIONS, PROFILES, Assumption
from transpiler.resources import DataMissing

# Each module registers its own subcommands; listed here so that the parser's contents are visible in one place.
SUBCOMMAND_MODULES = (transpile, simulate, equiv, mutate, merge)


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="hh2iec", description="HEIDENHAIN TNC PLC to IEC 61131-3 transpiler")
    parser.add_argument("--version", action=_VersionAction, nargs=0, help="show program's version number and exit")
    sub = parser.add_subparsers(dest="command", required=True)
    check = sub.add_parser("check", help="preprocess, parse and resolve a project; print a summary")
    add_project_arguments(check)
    check.add_argument("--json", action="store_true", help="print the summary as JSON")
    check.set_defaults(handler=cmd_check)
    ex = sub.add_parser("explain", help="explain a diagnostic code (E-...) or a semantic assumption (A-...)")
    ex.add_argument("code", nargs="?", help="a diagnostic code such as E-SYNTAX, or an assumption id (A-09) or key")
    ex.add_argument("--list", action="store_true", help="list every diagnostic code and assumption with its summary")
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
                    profile=program.semantics.profile.name, masks=[m.file for m in program.masks])
    return data


def cmd_check(args: argparse.Namespace) -> int:
    one_shot()
    result = api.check_project(options_from_args(args), semantics_from_args(args))
    print_diagnostics(result.diagnostics.items)
    data = summary(result)
    if args.json:
        data["diagnostics"] = diagnostics_json(result.diagnostics.items)
        print(json.dumps(data, indent=2, sort_keys=True))
    else:
        print(f"hh2iec check: {args.main}")
        for key in ("files", "modules", "labels", "symbols", "instructions", "lines", "routines", "call_depth",
                    "auto_assigned", "errors", "warnings"):
            if key in data:
                print(f"  {key:<14} {data[key]}")
        if data.get("plc_modules"):
            print(f"  {'plc modules':<14} {', '.join(map(str, data['plc_modules']))}")
        if data.get("masks"):
            print(f"  {'screen masks':<14} {', '.join(data['masks'])}")
    return finish_one_shot(args, EXIT_BAD_INPUT if result.diagnostics.has_errors() else EXIT_OK)


class _VersionAction(argparse.Action):
    """`--version`: looks the version up only when asked (importlib.metadata costs ~25 ms of every start-up)."""

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"hh2iec {version()}")     # (stdout, as argparse's own version action prints it)
        parser.exit()


def version() -> str:
    """The installed distribution's version; a checkout that was never installed has only the package's own."""
    from importlib import metadata
    try:
        return metadata.version("hh2iec")
    except metadata.PackageNotFoundError:
        return __version__


def _assumption(text: str) -> Assumption | None:
    by_id = {a.id.upper(): a for a in ASSUMPTIONS}
    return by_id.get(text.upper()) or ASSUMPTION_BY_KEY.get(text.lower())


def explain_assumption(a: Assumption) -> str:
    """Text for `hh2iec explain A-xx`: the choice, its default per profile, the alternatives and how to switch."""
    names = sorted(PROFILES)
    defaults = ", ".join(f"{n}: {PROFILES[n].defaults[a.key]!s}" if PROFILES[n].defaults[a.key] != "" else
                         f"{n}: (empty)" for n in names)
    if a.alternatives:
        values = ", ".join(str(v) for v in (a.default, *a.alternatives))
        example = a.alternatives[0]
    elif isinstance(a.default, int) and not isinstance(a.default, bool):
        values, example = "any integer", a.default
    else:
        values, example = "any text", "..."
    lines = [f"{a.id} {a.key}: {a.topic}",
             f"  default per profile: {defaults}",
             f"  values: {values}",
             f"  switch: -S {a.key}={str(example).lower() if isinstance(example, bool) else example} "
             f"(or `semantics: {{{a.key}: ...}}` in a scenario)"]
    if a.vectors:
        lines.append(f"  test vectors: {', '.join(a.vectors)}")
    lines.append("  see docs/assumptions.md")
    return "\n".join(lines) + "\n"


def explain_list() -> str:
    """Every diagnostic code and every assumption with its one-line summary (`hh2iec explain --list`)."""
    width = max(map(len, CODES))
    lines = [f"{info.code:<{width}}  {info.severity.value:<7}  {info.summary}" for info in CODES.values()]
    lines += [f"{a.id:<{width}}  {'assume':<7}  {a.key}: {a.topic}" for a in ASSUMPTIONS]
    return "\n".join(lines) + "\n"


def cmd_explain(args: argparse.Namespace) -> int:
    if args.list:
        if args.code:
            raise UsageError("explain takes either a CODE or --list, not both")
        print(explain_list(), end="")
        return EXIT_OK
    if not args.code:
        raise UsageError("explain needs a diagnostic code, an assumption id, or --list")
    text = explain(args.code)
    if text is None:
        assumption = _assumption(args.code)
        if assumption is None:
            print(f"{NO_SPAN}: error[E-USAGE]: unknown diagnostic code or assumption {args.code} "
                  "(`hh2iec explain --list` lists them)", file=sys.stderr)
            return EXIT_BAD_INPUT
        text = explain_assumption(assumption)
    print(text, end="")
    return EXIT_OK


def cmd_assumptions(args: argparse.Namespace) -> int:
    names = sorted(PROFILES)
    print(f"{'id':<6} {'key':<28} " + " ".join(f"{n:<12}" for n in names))
    for key, a in ASSUMPTION_BY_KEY.items():
        print(f"{a.id:<6} {key:<28} " + " ".join(f"{str(PROFILES[n].defaults[key]):<12}" for n in names))
    return EXIT_OK


def main(argv: Sequence[str] | None = None, *, own_process: bool = False) -> int:
    """Run one command; `own_process` when this is the `hh2iec` process itself (`entry`), whose one-shot commands
    then end the process at once (common.finish_one_shot)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except UsageError as exc:
        print(f"{NO_SPAN}: error[E-USAGE]: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SystemExit as exc:
        return EXIT_BAD_INPUT if exc.code not in (0, None) else EXIT_OK
    args.own_process = own_process
    try:
        return args.handler(args)
    except UsageError as exc:
        print(f"{NO_SPAN}: error[E-USAGE]: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except CompileFailed as exc:
        for d in exc.diagnostics:
            print(d.render(), file=sys.stderr)
        return EXIT_BAD_INPUT
    except DataMissing as exc:
        print(f"{NO_SPAN}: error[E-TOOL]: {exc}", file=sys.stderr)
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
    sys.exit(main(own_process=True))


if __name__ == "__main__":
    entry()
