"""Random-program differential testing: generate N projects, co-simulate each on every ST executor, summarise, reduce failures.

Usage: python -m tests.difftest.run [--count 200] [--seed 1] [--cycles 300] [--size 40] [--jobs N]
                                    [--backends auto|builtin|both] [--matiec-every K] [--reduce] [--out DIR]
                                    [--shard K/N]

Program i of a run is generated from seed SEED * 1 000 000 + i, so every failure can be replayed on its own
(`--only SEED_OF_PROGRAM`), and `--shard K/N` checks only shard K of N of the programs (each CI job of N its own
share, dealt out as `hh2iec equiv --shard` deals out runs; every shard's exit status counts). The random stimulus toggles every input the program reads. When both executors run,
a disagreement is blamed on the side that differs from the other two: both ST executors against the reference
interpreter -> translator; one executor alone -> that executor. Exit 0 when every program was equivalent,
1 otherwise.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import multiprocessing
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from tests.difftest.check import OK, PASSING, STR_MAX, TARGET_LIMIT, Verdict, available_backends, check_files  # noqa: E402
from tests.difftest.generator import generate  # noqa: E402
from transpiler.cli.progress import ProgressLine  # noqa: E402
from transpiler.verify.shard import ShardSpec, partition  # noqa: E402

REGRESSIONS = ROOT / "tests" / "regressions"


@dataclasses.dataclass(frozen=True)
class Job:
    program_seed: int
    size: int
    cycles: int
    backends: tuple[str, ...]


def program_seed(run_seed: int, index: int) -> int:
    return run_seed * 1_000_000 + index


def run_job(job: Job) -> tuple[Job, Verdict, float]:
    start = time.perf_counter()
    project = generate(job.program_seed, size=job.size)
    try:
        verdict = check_files(project.files, project.main, project.cfg, project.mp, cycles=job.cycles,
                              seed=job.program_seed, backends=job.backends)
    except Exception as exc:  # noqa: BLE001 - a crash anywhere in the tool chain is a finding, not a stop
        verdict = Verdict("error", "tool", f"{type(exc).__name__}: {exc}")
    return job, verdict, time.perf_counter() - start


def jobs_for(args: argparse.Namespace) -> list[Job]:
    found = available_backends()
    # matiec compiles every program (seconds each): with --backends auto it takes part in every K-th program only.
    every = {"builtin": 0, "both": 1, "auto": args.matiec_every}[args.backends] if "matiec" in found else 0
    seeds = [args.only] if args.only is not None else [program_seed(args.seed, i) for i in range(args.count)]
    if args.shard is not None:
        # every program costs about the same (its size and cycles are the run's): the partition deals them out
        assignment = partition([float(args.size * args.cycles)] * len(seeds), args.shard.count)
        seeds = [s for s, k in zip(seeds, assignment) if k == args.shard.index]
    return [Job(s, args.size, args.cycles, found if every and n % every == 0 else ("builtin",))
            for n, s in enumerate(seeds)]


def _shard(text: str) -> ShardSpec:
    try:
        return ShardSpec.parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--cycles", type=int, default=300, help="random cycles per program")
    parser.add_argument("--size", type=int, default=40, help="top-level blocks per program (about)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--backends", choices=("auto", "builtin", "both"), default="auto")
    parser.add_argument("--matiec-every", type=int, default=10, help="with --backends auto: matiec on every K-th")
    parser.add_argument("--only", type=int, help="check the one program with this program seed")
    parser.add_argument("--shard", type=_shard, metavar="K/N", help="check only shard K of N of the programs")
    parser.add_argument("--reduce", action="store_true", help="reduce each failure into tests/regressions/")
    parser.add_argument("--out", type=Path, default=REGRESSIONS, help="where reduced cases go")
    parser.add_argument("--quiet", action="store_true", help="only the summary")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    results = run_batch(jobs_for(args), args.jobs)
    failures = [(job, v) for job, v, _ in results if v.status not in PASSING]
    print_summary(results, time.perf_counter() - start, quiet=args.quiet)
    if args.reduce:
        for job, verdict in failures:
            print(f"reducing program {job.program_seed} ({verdict.blame}) ...", flush=True)
            print(f"  -> {reduce_failure(job, verdict, args.out)}")
    return 0 if not failures else 1


def run_batch(jobs: list[Job], processes: int) -> list[tuple[Job, Verdict, float]]:
    """Every job, in worker processes when asked; results in program-seed order. A progress line on a terminal."""
    line = ProgressLine("difftest", "programs")
    results: list[tuple[Job, Verdict, float]] = []
    try:
        if processes > 1 and len(jobs) > 1:
            with multiprocessing.get_context("fork").Pool(processes) as pool:
                for res in pool.imap_unordered(run_job, jobs, chunksize=2):
                    results.append(res)
                    line.update(len(results), len(jobs))
        else:
            for job in jobs:
                results.append(run_job(job))
                line.update(len(results), len(jobs))
    finally:
        line.close()
    return sorted(results, key=lambda r: r[0].program_seed)


def print_summary(results: list[tuple[Job, Verdict, float]], seconds: float, quiet: bool = False) -> None:
    statuses = collections.Counter(v.status for _, v, _ in results)
    cycles = sum(v.cycles for _, v, _ in results)
    on_matiec = sum(1 for job, _, _ in results if "matiec" in job.backends)
    blames = collections.Counter(v.blame for _, v, _ in results if v.status not in PASSING)
    print(f"difftest: {len(results)} programs ({on_matiec} also on matiec), {cycles} cycles compared, "
          f"{statuses.get('mismatch', 0)} mismatches, {statuses.get('error', 0)} errors, "
          f"{statuses.get('invalid', 0)} invalid programs, {statuses.get(TARGET_LIMIT, 0)} beyond a target limit "
          f"(string longer than {STR_MAX} characters), in {seconds:.1f} s")
    if blames:
        print("blame: " + ", ".join(f"{who} {n}" for who, n in sorted(blames.items())))
    if not quiet:
        for job, v, _ in results:
            if v.status != OK:
                print(f"  program {job.program_seed}: {v.status} ({v.blame or 'no one'}): {v.detail}")


def reduce_failure(job: Job, verdict: Verdict, out: Path) -> Path:
    from tests.difftest.reduce import Case, Reducer, write_regression
    project = generate(job.program_seed, size=job.size)
    cycles = verdict.divergence_cycle + 1 if verdict.divergence_cycle is not None else job.cycles
    case = Case(dict(project.files), project.main, project.cfg, project.mp, cycles, job.program_seed)
    reduced = Reducer(case, verdict, job.backends).reduce()
    final = check_files(reduced.files, reduced.main, reduced.cfg if reduced.cfg in reduced.files else None,
                        reduced.mp if reduced.mp in reduced.files else None, cycles=reduced.cycles,
                        seed=reduced.seed, backends=job.backends)
    return write_regression(reduced, final, job.backends, out / f"program_{job.program_seed}",
                            f"python -m tests.difftest.run --only {job.program_seed} --size {job.size}")


if __name__ == "__main__":
    sys.exit(main())
