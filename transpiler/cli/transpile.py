"""The `transpile` and `fetch-schema` subcommands."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from transpiler.atomic import write_files_atomically
from transpiler.cli.app import (EXIT_BAD_INPUT, EXIT_OK, UsageError, compile_from_args, print_diagnostics)
from transpiler.diagnostics import NO_SPAN
from transpiler.backends.transpile import find_mp_file, read_mp_file, transpile_program, user_pous


def register(sub, common) -> None:
    p = sub.add_parser("transpile", help="write project.st, project.xml, report.md and io_map.csv")
    common(p)
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--format", default="st,xml", help="which of st,xml to write (default both)")
    p.add_argument("--mp", type=Path, help="machine-parameter file for timer/counter presets "
                   "(default: the one *.mp file beside MAIN)")
    p.set_defaults(handler=cmd_transpile)
    f = sub.add_parser("fetch-schema", help="download and verify the official PLCopen TC6 v2.01 schema")
    f.set_defaults(handler=cmd_fetch_schema)


def cmd_transpile(args: argparse.Namespace) -> int:
    formats = {f.strip().lower() for f in args.format.split(",") if f.strip()}
    if not formats or formats - {"st", "xml"}:
        raise UsageError(f"--format takes st, xml or st,xml, not '{args.format}'")
    result = compile_from_args(args)
    diags = result.diagnostics
    if not result.ok:
        print_diagnostics(diags)
        return EXIT_BAD_INPUT
    mp_path = args.mp or find_mp_file(args.main)
    if args.mp is not None and not args.mp.is_file():
        raise UsageError(f"machine-parameter file '{args.mp}' does not exist")
    mp = read_mp_file(mp_path, diags) if mp_path else {}
    if diags.has_errors():
        print_diagnostics(diags)
        return EXIT_BAD_INPUT
    out = transpile_program(result.program, diags, mp, formats)
    if "xml" in formats:
        from transpiler.backends.plcopen.xsd import FETCH_HINT, schema_path, validate_xml
        if schema_path() is None:
            print(f"note: the PLCopen schema is not cached, project.xml was not validated. {FETCH_HINT}", file=sys.stderr)
        else:
            problems = validate_xml(out.files["project.xml"])
            if problems:
                for p in problems:
                    print(p, file=sys.stderr)
                print(f"{NO_SPAN}: error[E-XSD]: project.xml does not validate against the TC6 schema "
                      "(a bug in hh2iec; nothing was written)", file=sys.stderr)
                return EXIT_BAD_INPUT
    try:
        write_files_atomically({args.out / name: data for name, data in out.files.items()})
    except OSError as exc:
        print(f"{args.out}:1:1: error[E-TOOL]: cannot write output: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print_diagnostics(diags)
    print(f"hh2iec transpile: wrote {', '.join(sorted(out.files))} to {args.out} "
          f"({len(user_pous(out.result))} POUs, {len(out.result.fallbacks)} state-machine fallbacks, "
          f"{len(out.result.untranslated)} not translated)")
    return EXIT_OK


def cmd_fetch_schema(args: argparse.Namespace) -> int:
    from transpiler.backends.plcopen.xsd import SchemaUnavailable, fetch_schema
    try:
        path = fetch_schema()
    except SchemaUnavailable as exc:
        print(f"{NO_SPAN}: error[E-TOOL]: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"PLCopen TC6 v2.01 schema verified at {path}")
    return EXIT_OK


