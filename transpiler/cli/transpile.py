"""The `transpile` and `fetch-schema` subcommands."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from transpiler import api
from transpiler.cli.common import (EXIT_BAD_INPUT, EXIT_OK, UsageError, finish_one_shot, one_shot,
                                   print_diagnostics, project_from_args)
from transpiler.diagnostics import NO_SPAN


def register(sub, common) -> None:
    p = sub.add_parser("transpile", help="write project.st, project.xml, report.md, io_map.csv and hh_lib.st/hh_lib.xml")
    common(p)
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--format", default="st,xml", help="which of st,xml to write (default both)")
    p.add_argument("--mp", type=Path, help="machine-parameter file for timer/counter presets "
                   "(default: the one *.mp file beside MAIN)")
    p.add_argument("--target", choices=("matiec", "openplc", "codesys", "twincat"), default="matiec",
                   help="dialect of project.st/project.xml: matiec (default; also Beremiz), openplc (matiec's text), "
                   "codesys or twincat (global variable lists, no VAR_EXTERNAL; see docs/import.md)")
    p.add_argument("--allow-untranslated", action="store_true",
                   help="write the output even where code cannot be translated (a warning per place; report.md "
                   "opens with the list)")
    p.set_defaults(handler=cmd_transpile)
    f = sub.add_parser("fetch-schema", help="download and verify the official PLCopen TC6 v2.01 schema")
    f.set_defaults(handler=cmd_fetch_schema)


def cmd_transpile(args: argparse.Namespace) -> int:
    formats = {f.strip().lower() for f in args.format.split(",") if f.strip()}
    if not formats or formats - {"st", "xml"}:
        raise UsageError(f"--format takes st, xml or st,xml, not '{args.format}'")
    one_shot()
    project = project_from_args(args)
    out = api.transpile(project, formats=formats, mp_file=args.mp, allow_untranslated=args.allow_untranslated,
                        target=args.target)
    if "xml" in formats and not out.xml_validated:
        from transpiler.backends.plcopen.xsd import FETCH_HINT
        print(f"note: the PLCopen schema is not cached, project.xml was not validated. {FETCH_HINT}", file=sys.stderr)
    try:
        out.write(args.out)
    except OSError as exc:
        print(f"{args.out}:1:1: error[E-TOOL]: cannot write output: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print_diagnostics(project.diagnostics + out.diagnostics)
    print(f"hh2iec transpile: wrote {', '.join(_written(out.files))} for {args.target} to {args.out} "
          f"({out.pou_count} POUs, {len(out.result.fallbacks)} state-machine fallbacks, "
          f"{len(out.result.untranslated)} not translated)")
    return finish_one_shot(args, EXIT_OK)


def _written(files) -> list[str]:
    """The files at the top of the output folder, and each sub-folder once with its file count (a TwinCAT project
    folder holds one file per POU: listing them all would bury the rest)."""
    counts: dict[str, int] = {}
    for name in files:
        top, _, rest = name.partition("/")
        key = top + "/" if rest else top
        counts[key] = counts.get(key, 0) + 1
    return [f"{name} ({count} files)" if name.endswith("/") else name for name, count in sorted(counts.items())]


def cmd_fetch_schema(args: argparse.Namespace) -> int:
    from transpiler.backends.plcopen.xsd import SchemaUnavailable, fetch_schema
    try:
        path = fetch_schema()
    except SchemaUnavailable as exc:
        print(f"{NO_SPAN}: error[E-TOOL]: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"PLCopen TC6 v2.01 schema verified at {path}")
    return EXIT_OK
