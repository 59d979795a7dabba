"""`make mutants`: the mutation check of the sample through `hh2iec mutate` (transpiler/verify/mutate.py).

Usage: python -m tests.mutants [--count 150] [--seed 1] [--backend auto|builtin|matiec] [--jobs N] [--all]
       [--constructs] [any other `hh2iec mutate` option]

Judges a seeded sample of the translated sample's mutants (all of them with --all) under its scenarios plus
2 000 cycles of coverage-guided stimulus, with the checked-in judged-equivalent mutants
(samples/basic_program/equivalent_mutants.yaml) left out of the score. With --constructs, then every mutant of
each construct project that has a scenario, with its own judged-equivalent file. Each run must kill 97% of its
non-equivalent mutants (`--min-score` overrides); exit codes as `hh2iec mutate` (the worst of the runs).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from transpiler.cli.app import main as hh2iec  # noqa: E402

SAMPLE = ROOT / "samples" / "basic_program"
CONSTRUCTS = ROOT / "samples" / "constructs"
MIN_SCORE = "0.97"


def arguments(argv: list[str] | None = None) -> list[list[str]]:
    """The `hh2iec mutate` command lines: the sample's, then (with --constructs) each construct project's."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=150, help="mutants to judge, spread over the operators")
    parser.add_argument("--all", action="store_true", help="judge every mutation site (slow)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--backend", choices=("auto", "builtin", "matiec"), default="auto")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--constructs", action="store_true", help="also every construct project with a scenario")
    args, rest = parser.parse_known_args(argv)
    if "--min-score" not in rest:
        rest = [*rest, "--min-score", MIN_SCORE]
    common = ["--seed", str(args.seed), "--backend", args.backend, "--jobs", str(args.jobs), *rest]
    scenarios = [a for p in sorted((SAMPLE / "scenarios").glob("*.yaml")) for a in ("--scenario", str(p))]
    runs = [["mutate", str(SAMPLE / "Main_PGM.src"), *scenarios, "--random-cycles", "2000",
             "--equivalent", str(SAMPLE / "equivalent_mutants.yaml"),
             "--count", "0" if args.all else str(args.count), *common]]
    if args.constructs:
        for scenario in sorted(CONSTRUCTS.glob("*/scenario.yaml")):
            equivalent = scenario.parent / "equivalent_mutants.yaml"
            judged = ["--equivalent", str(equivalent)] if equivalent.exists() else []
            runs.append(["mutate", str(scenario.parent), "--scenario", str(scenario), *judged, *common])
    return runs


def main(argv: list[str] | None = None) -> int:
    worst = 0
    for run in arguments(argv):
        target = Path(run[1])
        print(f"== {target.parent.name if target.suffix == '.src' else target.name}", flush=True)
        worst = max(worst, hh2iec(run))
    return worst


if __name__ == "__main__":
    sys.exit(main())
