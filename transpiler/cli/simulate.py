"""The `simulate` subcommand: the original program on the reference interpreter against one scenario."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from transpiler import api
from transpiler.cli.common import (EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, UsageError, print_diagnostics,
                                   print_screens, project_from_args)


def register(sub: argparse._SubParsersAction, common) -> None:
    p = sub.add_parser("simulate", help="run the original program on the reference interpreter against a scenario")
    common(p)
    p.add_argument("--scenario", type=Path, required=True, help="scenario file (YAML, see docs/scenarios.md)")
    p.add_argument("--trace", type=Path, metavar="OUT.csv", help="write one row per cycle with the observed values")
    p.add_argument("--vcd", type=Path, metavar="OUT.vcd", help="write the trace as a value-change dump (GTKWave)")
    p.add_argument("--show-mask", action="append", default=[], metavar="NAME@CYCLE",
                   help="print the screen mask NAME (M_dia_wz.msk or M_dia_wz) as the PLC window shows it after CYCLE "
                   "(repeatable; docs/masks.md)")
    p.set_defaults(handler=cmd_simulate)


def cmd_simulate(args: argparse.Namespace) -> int:
    if not args.scenario.is_file():
        raise UsageError(f"scenario file '{args.scenario}' does not exist")
    for flag, path in (("--trace", args.trace), ("--vcd", args.vcd)):
        if path is not None and not path.parent.is_dir():      # (checked before the run, not after it)
            raise UsageError(f"{flag} {path}: folder '{path.parent}' does not exist")
    project = project_from_args(args, scenario=args.scenario)
    print_diagnostics(project.diagnostics)
    sim = api.simulate(project, args.scenario, show_masks=args.show_mask)
    print_diagnostics(sim.diagnostics)
    print_screens(sim.screens)
    return _report(args, sim)


def _report(args: argparse.Namespace, simulation: api.Simulation) -> int:
    scenario, sim = simulation.scenario, simulation.run
    written = None
    try:
        if args.trace is not None:
            written = args.trace
            sim.trace.write_csv(args.trace)
        if args.vcd is not None:
            written = args.vcd
            sim.trace.write_vcd(args.vcd, sim.machine.cycle_time_ms)
    except OSError as exc:
        print(f"{written}:1:1: error[E-USAGE]: cannot write the trace: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    _print_warnings(sim.warnings)
    first_marker = sim.machine.profile.interface.error_markers[0]
    for marker, cycle in sorted(sim.machine.error_messages.items()):
        print(f"note: PLC error message {marker - first_marker} (M{marker}) was set, first after cycle {cycle}",
              file=sys.stderr)
    for number, count in sorted(sim.machine.unknown_modules.items()):
        print(f"note: PLC module {number} ran {count} time(s) as a stub without a simulation model (A-46)",
              file=sys.stderr)
    for failure in sim.failures:
        where = failure.span or scenario.span_of("expect")
        print(f"{where}: expectation failed: cycle {failure.cycle}: {failure.name}: expected {failure.expected!r}, "
              f"actual {failure.actual!r}", file=sys.stderr)
    rate = sim.instructions / sim.seconds if sim.seconds > 0 else 0.0
    checked = sum(len(e.values) for e in scenario.expect if e.cycle < sim.cycles_run)
    print(f"hh2iec simulate: {scenario.name}: {sim.cycles_run} of {scenario.cycles} cycles, "
          f"{sim.instructions} instructions ({rate / 1e6:.2f} M/s), {checked} expected values checked, "
          f"{len(sim.failures)} failed")
    if sim.fault is not None:
        print(sim.fault.render(sim.fault_span), file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_FAILED if sim.failures else EXIT_OK


def _print_warnings(warnings) -> None:
    """Each distinct runtime warning once, with its first cycle and how often it occurred."""
    seen: dict[tuple, list] = {}
    for w in warnings:
        seen.setdefault((w.code, w.span, w.job), []).append(w)
    for group in seen.values():
        first = group[0]
        extra = f"; {len(group)} times in total" if len(group) > 1 else ""
        print(first.render() + extra, file=sys.stderr)
