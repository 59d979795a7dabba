"""Benchmarks run by `make bench` (`python -m tests.bench`): each function prints its figures and returns them; the
run ends with the ratios a change that costs speed moves (front-end lines/s, transpile seconds, the command line's
check and transpile, mutants per minute per backend, co-simulation against the reference interpreter alone)."""

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
from transpiler.frontend.load import ProjectOptions  # noqa: E402
from transpiler.exec.interp import Machine, compile_program  # noqa: E402
from transpiler.frontend.pipeline import compile_project  # noqa: E402
from transpiler.language.semantics import make_semantics  # noqa: E402

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


TRANSPILE_TARGET = 2.0             # seconds for ST + XML of the 100 000-line project (issue 29; 5 s in issue 5)
CLI_TARGETS = {"check": 1.0, "transpile": 2.0}    # seconds of the commands on the 100 000-line project (issue 29)
COSIM_CYCLES = 2000
MATIEC_CYCLES = 10_000
COSIM_TARGETS = {"matiec": 10_000, "builtin": 5_000}   # equiv cycles/s on the sample (issue 18), setup excluded
MUTANTS = 12


def bench_transpile(lines: int = 100_000, repeat: int = 3) -> dict:
    """ST backend + ST writer + PLCopen XML writer on the generated 100 000-line project (front end excluded),
    best of `repeat` runs."""
    from transpiler.diagnostics import Diagnostics
    from transpiler.backends.transpile import transpile_program
    with tempfile.TemporaryDirectory(prefix="hh2iec-bench-") as tmp:
        main = generate_project(Path(tmp), lines)
        result = compile_project(ProjectOptions(main=main), make_semantics("itnc530", {}))
        if not result.ok:
            print(f"transpile: skipped ({len(result.diagnostics.errors)} compile errors)")
            return {}
        times = []
        for _ in range(repeat):
            gc.collect()
            start = time.perf_counter()
            out = transpile_program(result.program, Diagnostics(), {}, {"st", "xml"})
            times.append(time.perf_counter() - start)
        elapsed = min(times)
    verdict = "met" if elapsed <= TRANSPILE_TARGET else "MISSED"
    st_lines = out.st_text.count("\n")
    print(f"transpile (ST + XML), generated {lines}-line project: {elapsed:.2f} s (best of {repeat}: "
          f"{', '.join(f'{t:.2f}' for t in times)}) for {st_lines} ST lines and "
          f"{len(out.files['project.xml'])} XML bytes; target <= {TRANSPILE_TARGET:.0f} s: {verdict}")
    return {"seconds": round(elapsed, 3), "st_lines": st_lines}


def bench_cli(lines: int = 100_000, repeat: int = 3) -> dict:
    """`hh2iec check` and `hh2iec transpile` of the generated project as a user runs them (a fresh process each:
    start-up, reading, writing and schema validation included), best of `repeat` wall-clock runs after one run
    that is not counted. Python's bytecode cache is on, as after `pip install` (which compiles the package): a
    PYTHONDONTWRITEBYTECODE in the environment would make every start-up compile the whole package again."""
    import os
    import subprocess
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    figures = {}
    with tempfile.TemporaryDirectory(prefix="hh2iec-bench-") as tmp:
        main = generate_project(Path(tmp) / "project", lines)
        commands = {"check": ["check", str(main)], "transpile": ["transpile", str(main), "--out", str(Path(tmp) / "out")]}
        for name, args in commands.items():
            times = []
            for run in range(repeat + 1):
                start = time.perf_counter()
                done = subprocess.run([sys.executable, "-m", "transpiler.cli", *args], env=env, capture_output=True)
                if run:     # the first run writes the bytecode cache (and warms the file cache)
                    times.append(time.perf_counter() - start)
                if done.returncode != 0:
                    print(f"cli {name}: exit {done.returncode}: {done.stderr.decode(errors='replace')[-300:]}")
                    return figures
            best = min(times)
            target = CLI_TARGETS[name]
            print(f"cli, hh2iec {name} of the generated {lines}-line project: {best:.2f} s (best of {repeat}: "
                  f"{', '.join(f'{t:.2f}' for t in times)}); target <= {target:.0f} s: "
                  f"{'met' if best <= target else 'MISSED'}")
            figures[name] = round(best, 3)
    return figures


def bench_cosim(cycles: int = COSIM_CYCLES) -> dict:
    """Co-simulation cycles per second on the sample project for each available ST backend (compile excluded)."""
    from transpiler.verify import pipeline
    from transpiler.verify.cosim import builtin_side_factory, cosimulate
    from transpiler.diagnostics import Diagnostics
    from transpiler.verify.equiv import random_scenario
    from transpiler.verify.simulate import project_names
    from transpiler.backends.st.check import find_iec2c
    from transpiler.backends.report.report import io_map_of
    from transpiler.frontend.mpfile import read_mp_file
    from transpiler.backends.transpile import transpile_program
    result = compile_project(ProjectOptions(main=SAMPLE), make_semantics("itnc530", {}))
    diags = Diagnostics()
    out = transpile_program(result.program, diags, read_mp_file(SAMPLE.parent / "MP_data.mp", diags), {"st"})
    names = project_names(result.program)
    factories = {"builtin": (cycles, builtin_side_factory(out.st_text))}
    iec2c = find_iec2c()
    if iec2c is not None:
        from transpiler.exec.compiled.matiec_side import matiec_side_factory
        factories["matiec"] = (MATIEC_CYCLES, matiec_side_factory(out.st_text, out.result.project, iec2c))
    else:
        print("co-simulation, matiec backend: skipped (iec2c not found; set MATIEC_HOME)")
    figures = {}
    reference = compile_program(result.program, coverage=True, exact=False)     # as equiv compiles it
    for backend, (count, factory) in factories.items():
        scenario = random_scenario(result.program, names, count, seed=3, machine_parameters=SAMPLE.parent / "MP_data.mp")
        # as `equiv` runs it: the reference with coverage; the loop's own time (res.seconds, setup excluded)
        res = cosimulate(result.program, factory, io_map_of(out.result), scenario, names, coverage=True,
                         compiled=reference, pipelined=pipeline.worthwhile())
        if res.error:
            print(f"co-simulation, {backend} backend: {res.error}")
        rate = res.cycles_run / res.seconds if res.seconds else 0.0
        target = COSIM_TARGETS[backend]
        print(f"co-simulation, sample project, {backend} backend (interpreter with coverage included): "
              f"{res.cycles_run} cycles in {res.seconds:.2f} s = {rate:.0f} cycles/s "
              f"({'equivalent' if res.equivalent else 'NOT equivalent'}); target >= {target} cycles/s: "
              f"{'met' if rate >= target else 'MISSED'}")
        figures[backend] = int(rate)
    # The ceiling of any backend: equiv runs the reference interpreter every cycle, in Python
    from transpiler.verify.simulate import build_machine
    from transpiler.verify.stimulus import build_stimulus
    scenario = random_scenario(result.program, names, MATIEC_CYCLES, seed=3, machine_parameters=SAMPLE.parent / "MP_data.mp")
    machine = build_machine(result.program, scenario, Diagnostics(), coverage=True, compiled=reference)
    stimulus = build_stimulus(scenario, names)
    gc.collect()
    start = time.perf_counter()
    for cycle in range(stimulus.cycles):
        machine.run_cycle(cycle, stimulus.writes(cycle), stimulus.nc_actions(cycle))
    ceiling = stimulus.cycles / (time.perf_counter() - start)
    print(f"co-simulation ceiling, sample project: the reference interpreter alone (coverage, as equiv runs it) "
          f"on the same stimulus: {ceiling:.0f} cycles/s")
    figures["reference_alone"] = int(ceiling)
    return figures


def bench_mutants(count: int = MUTANTS) -> dict:
    """`hh2iec mutate` throughput on the sample for each available backend: the same seeded sample of `count`
    mutants (a fixed, small sample: a ratio to watch, not the full check), every core."""
    import os
    from transpiler import api
    from transpiler.backends.st.check import find_iec2c
    project = api.load_project(api.project_options(SAMPLE))
    scenario = SAMPLE.parent / "scenarios" / "spindle_m3_m5.yaml"
    figures = {}
    backends = ["builtin"] + (["matiec"] if find_iec2c() is not None else [])
    if len(backends) == 1:
        print("mutants, matiec backend: skipped (iec2c not found; set MATIEC_HOME)")
    for backend in backends:
        start = time.perf_counter()
        run = api.mutate(project, scenarios=[scenario], random_cycles=300, backend=backend, count=count,
                         jobs=os.cpu_count() or 1)
        total = time.perf_counter() - start
        per_minute = 60 * len(run.result.verdicts) / run.result.seconds if run.result.seconds else 0.0
        print(f"mutants, sample project, {backend} backend, {os.cpu_count()} jobs: {len(run.result.verdicts)} judged "
              f"in {run.result.seconds:.1f} s = {per_minute:.1f} mutants/min (setup {total - run.result.seconds:.1f} s)")
        figures[backend] = round(per_minute, 1)
    return figures


def bench_readability() -> list[dict]:
    """Readability of the emitted ST (matiec dialect) for the sample and every construct project."""
    from transpiler import api
    from transpiler.backends.st.readability import measure
    mains = [SAMPLE] + sorted((ROOT / "samples" / "constructs").glob("*/main.src"))
    out = []
    for main in mains:
        project = api.load_project(api.project_options(main))
        figure = measure(api.transpile(project, formats=("st",)).result.project, project.program.instruction_count())
        label = "sample" if main == SAMPLE else main.parent.name
        print(f"readability, {label}: {figure.line()}")
        out.append({"project": label, **figure.__dict__})
    return out


GENERATOR_TARGET = 0.05            # seconds per random program of the differential tests (issue 8)


def bench_difftest_generator(programs: int = 40) -> dict:
    """The random-program generator of the differential tests: seconds per program."""
    from tests.difftest.generator import generate
    start = time.perf_counter()
    for seed in range(programs):
        generate(seed)
    per_program = (time.perf_counter() - start) / programs
    print(f"difftest generator: {programs} programs, {per_program * 1000:.1f} ms per program; "
          f"target <= {GENERATOR_TARGET * 1000:.0f} ms: {'met' if per_program <= GENERATOR_TARGET else 'MISSED'}")
    return {"seconds_per_program": round(per_program, 4)}


SHARD_OVERHEAD_TARGET = 0.15      # the shards' summed time may exceed the unsharded run's by this share (issue 32)


MUTATE_SHARD_COUNT = 300               # mutants of the sample in the mutate part of bench_shards


def bench_shards(shards: int = 4) -> dict:
    """The CI recipe's cost against one process, for `equiv` of the sample (its scenarios and 2000 generated cycles,
    as `make demo`) and for `mutate` of the sample (a seeded sample of MUTATE_SHARD_COUNT mutants under the same
    runs): each unsharded, then as the recipe does it with the shards one after the other: the plan once, `shards`
    shards, the merge. Wall and CPU time of each (CPU time is less disturbed by other work on a shared machine)
    and each shard's set-up (its time less its units' own seconds)."""
    from tests.shards import sample_equiv_args
    sample = sample_equiv_args()
    mutate_args = [*sample, "--backend", "builtin", "--count", str(MUTATE_SHARD_COUNT), "--jobs", "1",
                   "--min-score", "0", "--equivalent", str(SAMPLE.parent / "equivalent_mutants.yaml")]
    return {command: _shard_overhead(command, args, shards)
            for command, args in (("equiv", sample), ("mutate", mutate_args))}


def _shard_overhead(command: str, args: list[str], shards: int) -> dict:
    import json
    from tests.shards import comparable, run_sharded, timed
    units = "runs" if command == "equiv" else "mutants"
    with tempfile.TemporaryDirectory(prefix="hh2iec-bench-shards-") as folder:
        whole = Path(folder) / "whole.json"
        wall, cpu, _ = timed([command, *args, "--report", str(whole)])
        run = run_sharded(command, args, shards, Path(folder) / "shards", parallel=False)
        same = run.merge_code in (0, 1) and comparable(run.merged) == comparable(whole)
        setups = [seconds - sum(r["seconds"] for r in json.loads(report.read_text())[units])
                  for seconds, report in zip(run.shard_seconds,
                                             sorted((Path(folder) / "shards").glob("shard-*.json")))]
    shard_cpu, shard_wall = sum(run.shard_cpu), sum(run.shard_seconds)
    over = shard_cpu / cpu - 1 if cpu else 0.0
    with_plan = (shard_cpu + run.plan_cpu) / cpu - 1 if cpu else 0.0
    print(f"shards, sample {command}: unsharded {wall:.1f} s ({cpu:.1f} s CPU); plan {run.plan_seconds:.1f} s "
          f"({run.plan_cpu:.1f} s CPU: the coverage-guided search once"
          f"{', probing every run' if command == 'mutate' else ''}); {shards} shards {shard_wall:.1f} s "
          f"({shard_cpu:.1f} s CPU) in all, largest {max(run.shard_seconds):.1f} s; per-shard set-up "
          f"{min(setups):.1f}-{max(setups):.1f} s; shards' CPU sum {100 * over:+.0f}% of the unsharded run, plan "
          f"included {100 * with_plan:+.0f}% (target <= {100 * SHARD_OVERHEAD_TARGET:.0f}%: "
          f"{'met' if with_plan <= SHARD_OVERHEAD_TARGET else 'MISSED'}); merged report "
          f"{'equals' if same else 'DIFFERS FROM'} the unsharded one")
    return {"unsharded_cpu": round(cpu, 1), "plan_cpu": round(run.plan_cpu, 1), "shards_cpu": round(shard_cpu, 1),
            "setup_seconds": round(max(setups), 1), "same": same}


BENCHES: dict[str, Callable[..., object]] = {"readability": bench_readability, "mutants": bench_mutants,
                                             "frontend": bench_frontend, "interpreter": bench_interpreter,
                                             "transpile": bench_transpile, "cli": bench_cli, "cosim": bench_cosim,
                                             "difftest": bench_difftest_generator, "shards": bench_shards}


def ratios(figures: dict[str, object]) -> list[str]:
    """The figures a change that costs speed moves, one line each, from what the benchmarks that ran returned."""
    lines = []
    front = figures.get("frontend")
    if isinstance(front, dict) and front.get("lines_per_second"):
        lines.append(f"front end: {front['lines_per_second']} lines/s (check of the generated project)")
    transpile = figures.get("transpile")
    if isinstance(transpile, dict) and transpile.get("seconds"):
        lines.append(f"transpile: {transpile['seconds']:.2f} s for the generated project (ST + XML, front end excluded)")
    cli = figures.get("cli")
    if isinstance(cli, dict) and cli:
        lines.append("command line: " + ", ".join(f"{name} {seconds:.2f} s" for name, seconds in cli.items()))
    mutants = figures.get("mutants")
    if isinstance(mutants, dict) and mutants:
        lines.append("mutants per minute, sample: " + ", ".join(f"{b} {rate}" for b, rate in mutants.items()))
    cosim = figures.get("cosim")
    if isinstance(cosim, dict) and cosim.get("reference_alone"):
        alone = cosim["reference_alone"]
        lines += [f"co-simulation / simulate alone, {backend}: {rate / alone:.2f} ({rate} vs {alone} cycles/s)"
                  for backend, rate in cosim.items() if backend != "reference_alone"]
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--only", choices=sorted(BENCHES), action="append", help="run only these benchmarks")
    args = parser.parse_args(argv)
    figures = {name: BENCHES[name]() for name in args.only or BENCHES}
    summary = ratios(figures)
    if summary:
        print("ratios:")
        for line in summary:
            print("  " + line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
