"""Benchmarks run by `make bench` (`python -m tests.bench`): each function prints its figures and returns them."""

from __future__ import annotations

import argparse
import gc
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from tests.bench_frontend import bench_frontend, generate_project  # noqa: E402
from transpiler.frontend import ProjectOptions  # noqa: E402
from transpiler.interp import Machine, compile_program  # noqa: E402
from transpiler.pipeline import compile_project  # noqa: E402
from transpiler.semantics import make_semantics  # noqa: E402

INTERP_TARGET = 2_000_000          # source instructions per second on one core (issue 4)
SAMPLE = ROOT / "samples" / "basic_program" / "Main_PGM.src"


def _rate(main: Path, cycles: int, label: str, coverage: bool = False) -> dict:
    """Compile the project, build the machine, run `cycles` cycles with a toggling input; instructions/s."""
    result = compile_project(ProjectOptions(main=main), make_semantics("itnc530", {}))
    if not result.ok:
        print(f"interpreter, {label}: skipped ({len(result.diagnostics.errors)} compile errors)")
        return {}
    start = time.perf_counter()
    code = compile_program(result.program, coverage=coverage)
    codegen = time.perf_counter() - start
    machine = Machine(result.program, compiled=code, coverage=coverage)
    instructions = 0
    gc.collect()
    start = time.perf_counter()
    for cycle in range(cycles):
        report = machine.run_cycle(cycle, [("I", cycle % 64, cycle & 1)])
        if report.faults:
            print(f"interpreter, {label}: stopped by {report.faults[0].render()}")
            break
        instructions += report.instructions
    elapsed = time.perf_counter() - start
    rate = instructions / elapsed if elapsed else 0.0
    figures = {"label": label, "lines": result.program.line_count, "generated_lines": len(code.line_ops),
               "codegen_seconds": round(codegen, 3), "cycles": cycles, "instructions": instructions,
               "seconds": round(elapsed, 3), "instructions_per_second": int(rate),
               "us_per_cycle": round(elapsed / max(cycles, 1) * 1e6, 1)}
    verdict = "met" if rate >= INTERP_TARGET else "MISSED"
    print(f"interpreter, {label}{' (coverage)' if coverage else ''}: {figures['lines']} source lines, "
          f"code generated in {codegen:.2f} s; {instructions} instructions in {elapsed:.3f} s "
          f"= {rate / 1e6:.2f} M instructions/s ({figures['us_per_cycle']} us/cycle); "
          f"target >= {INTERP_TARGET / 1e6:.0f} M/s: {verdict}")
    return figures


def bench_interpreter(lines: int = 100_000, cycles: int = 20, sample_cycles: int = 2000) -> list[dict]:
    """Reference interpreter speed on the sample project and on the generated 100 000-line project."""
    figures = []
    if SAMPLE.exists():
        figures.append(_rate(SAMPLE, sample_cycles, "sample project"))
    with tempfile.TemporaryDirectory(prefix="hh2iec-bench-") as tmp:
        main = generate_project(Path(tmp), lines)
        figures.append(_rate(main, cycles, f"generated {lines}-line project"))
        figures.append(_rate(main, max(cycles // 4, 2), f"generated {lines}-line project", coverage=True))
    return figures


BENCHES: dict[str, Callable[..., object]] = {"frontend": bench_frontend, "interpreter": bench_interpreter}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--only", choices=sorted(BENCHES), action="append", help="run only these benchmarks")
    args = parser.parse_args(argv)
    for name in args.only or BENCHES:
        BENCHES[name]()
    return 0


if __name__ == "__main__":
    sys.exit(main())
