"""Front-end benchmark: generates a 100 000-line project and prints throughput (lines/s) and peak memory."""

from __future__ import annotations

import argparse
import gc
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from transpiler.frontend.load import ProjectOptions  # noqa: E402
from transpiler.frontend.pipeline import compile_project  # noqa: E402
from transpiler.language.semantics import make_semantics  # noqa: E402

TARGET_LINES_PER_SECOND = 100_000     # `check` of the generated project (issue 29)
TARGET_MB = 500
SYMBOLS_PER_MODULE = 24


def _module_defs(m: int, base_marker: int, base_byte: int) -> list[str]:
    """A local .def file per module: fixed markers/words, inputs, a constant and auto-assigned entries."""
    lines = [f"#type module {m}: markers and words", f"; definitions of module {m:03d}"]
    for s in range(8):
        lines.append(f"ML_m{m:03d}_s{s}    M {base_marker + s}    ; marker {s} of module {m}")
    for s in range(4):
        lines.append(f"I_m{m:03d}_in{s}    I {(m * 4 + s) % 4000}")
        lines.append(f"O_m{m:03d}_out{s}   O{(m * 4 + s) % 4000}")
    for s in range(4):
        lines.append(f"WL_m{m:03d}_w{s}    W {base_byte + 2 * s}")
    lines.append(f"DL_m{m:03d}_d0    D {base_byte + 8}")
    lines.append(f"BL_m{m:03d}_step  B {base_byte + 12}")
    lines.append(f"KL_m{m:03d}_limit K {100 + m}")
    lines.append(f"ML_m{m:03d}_auto  M")
    lines.append(f"WL_m{m:03d}_auto  W")
    lines.append(f"/c I_m{m:03d}_alias M &ML_m{m:03d}_s0")
    return lines


def _block(m: int, b: int) -> list[str]:
    """One labelled subprogram of ~40 lines with a realistic instruction mix."""
    p = f"m{m:03d}"
    s = lambda k: f"ML_{p}_s{(b + k) % 8}"  # noqa: E731
    return [
        f";--- block {b} of module {m}",
        f"LBL {p}_b{b}",
        f"L     I_{p}_in{b % 4}        ; input of the block",
        f"A     {s(1)}",
        f"AN    {s(2)}",
        f"O     {s(3)}",
        f"=     {s(4)}",
        f"L     {s(4)}",
        f"S     O_{p}_out{b % 4}",
        f"LN    {s(5)}",
        f"R     O_{p}_out{(b + 1) % 4}",
        f"L     WL_{p}_w{b % 4}",
        f"+     K{b + 1}",
        f"=     WL_{p}_w{(b + 1) % 4}",
        f"L     WL_{p}_w{b % 4}",
        f">=    KL_{p}_limit",
        "A[",
        f"L     {s(6)}",
        f"O     {s(7)}",
        "]",
        f"=     {s(0)}",
        f"L     DL_{p}_d0",
        "x     K3",
        "-[",
        f"L     WL_{p}_w0",
        "+     K7",
        "]",
        f"=     DL_{p}_d0",
        f"L     {s(1)}",
        "IFT",
        f"L     K{b}",
        f"=     BL_{p}_step",
        "ELSE",
        "L     K0",
        f"=     BL_{p}_step",
        "ENDI",
        f"L     {s(2)}",
        f"JPF   {p}_b{b}_skip",
        f"L     ML_{p}_auto",
        f"=     O_{p}_out0",
        f"LBL {p}_b{b}_skip",
        "EM",
    ]


def generate_project(folder: Path, target_lines: int = 100_000, module_lines: int = 1_000) -> Path:
    """Write a project of about `target_lines` lines (src + def + cfg) into folder; returns the main file."""
    folder.mkdir(parents=True, exist_ok=True)
    modules = max(1, target_lines // module_lines)
    main = [";*** generated benchmark project", "#define /g GLOBALS.DEF"]
    main += [f"USES mod{m:03d}.src" for m in range(modules)]
    main += [f"EXTERN m{m:03d}_entry" for m in range(modules)]
    main += [f"CM    m{m:03d}_entry" for m in range(modules)]     # the cycle: one call per module
    main += ["L     MG_first", "CMT   Init_all", "EM", "LBL Init_all", "L     K0", "=     WG_count", "EM"]
    (folder / "GLOBALS.DEF").write_text("\n".join([
        "* global definitions", "MG_first  M 4172", "WG_count  W 9000", "KG_one    K 1",
        "#if CFG_variant = \"big\"", "KG_size K 200", "#else", "KG_size K 100", "#endif"]) + "\n", encoding="latin-1")
    (folder / "OEM.cfg").write_text('DEFINE CFG_variant = "big"\nDEFINE ACTIVE = 1\n', encoding="latin-1")
    (folder / "main.src").write_text("\n".join(main) + "\n", encoding="latin-1")
    for m in range(modules):
        defs = _module_defs(m, base_marker=100 + m * 16, base_byte=m * 16)
        (folder / f"mod{m:03d}.def").write_text("\n".join(defs) + "\n", encoding="latin-1")
        body = [f"; module {m}", f"#define mod{m:03d}.def", f"GLOBAL m{m:03d}_entry", f"LBL m{m:03d}_entry"]
        blocks = []
        b = 0
        while len(body) + len(blocks) + len(defs) + 60 < module_lines:
            blocks += _block(m, b)
            b += 1
        body += [f"CM    m{m:03d}_b{k}" for k in range(b)]
        body += ["#if CFG_variant = \"small\"", "CM    never_called", "#endif", "EM"]
        body += blocks
        (folder / f"mod{m:03d}.src").write_text("\n".join(body) + "\n", encoding="latin-1")
    return folder / "main.src"


def _run_once(main: Path):
    semantics = make_semantics("itnc530", {})
    start = time.perf_counter()
    result = compile_project(ProjectOptions(main=main), semantics)
    return time.perf_counter() - start, result


def bench_frontend(lines: int = 100_000, repeat: int = 3, profile: bool = False, heap: bool = True) -> dict:
    """Generate the project, compile it `repeat` times; print best time, lines/s and peak memory."""
    with tempfile.TemporaryDirectory(prefix="hh2iec-bench-") as tmp:
        main = generate_project(Path(tmp), lines)
        times = []
        result = None
        for _ in range(repeat):
            gc.collect()
            elapsed, result = _run_once(main)
            times.append(elapsed)
        program = result.program
        line_count = program.line_count if program else 0
        errors = len(result.diagnostics.errors)
        peak = 0
        if heap:
            # Peak Python heap of one run (tracemalloc slows the run down ~5x, so it is measured separately).
            gc.collect()
            tracemalloc.start()
            _run_once(main)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
        if profile:
            import cProfile
            import pstats
            cProfile.runctx("_run_once(main)", globals(), {"main": main, "_run_once": _run_once}, "/tmp/hh2iec-frontend.prof")
            pstats.Stats("/tmp/hh2iec-frontend.prof").sort_stats("cumulative").print_stats(30)
    best = min(times)
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    figures = {
        "lines": line_count,
        "seconds": round(best, 3),
        "lines_per_second": int(line_count / best) if best else 0,
        "peak_python_heap_mb": round(peak / 2 ** 20, 1),
        "max_rss_mb": round(rss_mb, 1),
        "errors": errors,
    }
    ok = figures["lines_per_second"] >= TARGET_LINES_PER_SECOND and rss_mb <= TARGET_MB and errors == 0
    print(f"front end: {line_count} lines in {best:.3f} s (best of {repeat}: "
          f"{', '.join(f'{t:.3f}' for t in times)}) = {figures['lines_per_second']} lines/s; "
          f"peak Python heap {figures['peak_python_heap_mb']} MB, max RSS {figures['max_rss_mb']} MB; "
          f"{errors} errors; target >= {TARGET_LINES_PER_SECOND} lines/s and <= {TARGET_MB} MB: "
          f"{'met' if ok else 'MISSED'}")
    if errors:
        for d in result.diagnostics.errors[:5]:
            print("  " + d.render())
    return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--lines", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--profile", action="store_true", help="print a cProfile of one run")
    parser.add_argument("--no-heap", action="store_true", help="skip the (slow) tracemalloc run")
    args = parser.parse_args(argv)
    bench_frontend(args.lines, args.repeat, args.profile, heap=not args.no_heap)
    return 0


if __name__ == "__main__":
    sys.exit(main())
