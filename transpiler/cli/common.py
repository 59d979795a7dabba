"""What every subcommand shares: exit codes, usage errors, the project arguments and printing diagnostics."""

from __future__ import annotations

import argparse
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
                               encoding=args.encoding, werror=args.werror)


def semantics_from_args(args: argparse.Namespace, scenario: Path | None = None):
    return api.semantics_for(args.profile, _pairs(args.semantic_overrides, "-S"), scenario)


def project_from_args(args: argparse.Namespace, scenario: Path | None = None) -> api.Project:
    """The loaded project; `scenario` contributes its profile and semantic settings."""
    options = options_from_args(args)
    return api.load_project(options, semantics_from_args(args, scenario))


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


def print_screens(screens) -> None:
    """The screen masks asked for with --show-mask, each framed under a title line (stdout)."""
    from transpiler.verify.screens import render_text
    for screen in screens:
        print(render_text(screen), end="")
