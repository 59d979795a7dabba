"""The CI recipe of docs/ci.md run locally: the plan once, N shards as parallel processes, then `hh2iec merge`.

Usage: python -m tests.shards [--shards 4] [--command equiv|mutate] [--out DIR] [--compare] [-- ARGS...]

ARGS are the command's own arguments (default: equiv of the sample with its scenarios and 2000 generated cycles,
as `make demo`). The steps are those of the recipes: `--plan N --plan-file plan.json` once (the coverage-guided
search runs there only), each shard `--plan-file plan.json --shard K/N --report shard-K.json`, all at once, then
`hh2iec merge shard-*.json`. Exit status: the merge's (0, 1 for a failed verdict or score, 2 for bad input or a
shard that could not run). `--compare` also runs the unsharded command and fails unless the merged report is the
unsharded one (times aside). `make shards N=4` runs this.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "basic_program"
HH2IEC = [sys.executable, "-m", "transpiler.cli"]
# the checkout's own package, whatever is installed
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (str(ROOT), os.environ.get("PYTHONPATH"))))}


def sample_equiv_args() -> list[str]:
    scenarios = sorted((SAMPLE / "scenarios").glob("*.yaml"))
    return [str(SAMPLE / "Main_PGM.src"), *(a for s in scenarios for a in ("--scenario", str(s))),
            "--random-cycles", "2000", "--seed", "1"]


@dataclasses.dataclass
class ShardedRun:
    plan_seconds: float
    shard_seconds: list[float]          # wall time of each shard process (when parallel, from the common start)
    shard_codes: list[int]
    merge_code: int
    merged: Path                        # the merged report
    junit: Path
    output: str                         # what the merge printed
    shard_cpu: list[float] = dataclasses.field(default_factory=list)   # CPU seconds of each (sequential) shard
    plan_cpu: float = 0.0


def run_sharded(command: str, args: list[str], shards: int, out: Path, cwd: Path | None = None,
                parallel: bool = True) -> ShardedRun:
    """Plan once, run the shards (in parallel, or one after the other for timing), merge."""
    out.mkdir(parents=True, exist_ok=True)
    plan = out / "plan.json"
    start, plan_used = time.perf_counter(), _children_cpu()
    subprocess.run([*HH2IEC, command, *args, "--plan", str(shards), "--plan-file", str(plan)], cwd=cwd, env=ENV,
                   check=True, stdout=subprocess.DEVNULL)
    plan_seconds, plan_cpu = time.perf_counter() - start, _children_cpu() - plan_used
    reports = [out / f"shard-{k}.json" for k in range(1, shards + 1)]
    commands = [[*HH2IEC, command, *args, "--plan-file", str(plan), "--shard", f"{k}/{shards}",
                 "--report", str(reports[k - 1])] for k in range(1, shards + 1)]
    seconds: list[float] = []
    codes: list[int] = []
    if parallel:
        started = time.perf_counter()
        processes = [subprocess.Popen(c, cwd=cwd, env=ENV, stdout=subprocess.DEVNULL) for c in commands]
        ended = []
        for p in processes:
            codes.append(p.wait())
            ended.append(time.perf_counter())
        seconds = [e - started for e in ended]
    cpu: list[float] = []
    if not parallel:
        for c in commands:
            t, used = time.perf_counter(), _children_cpu()
            codes.append(subprocess.run(c, cwd=cwd, env=ENV, stdout=subprocess.DEVNULL).returncode)
            seconds.append(time.perf_counter() - t)
            cpu.append(_children_cpu() - used)
    merged, junit = out / "merged.json", out / "merged.junit.xml"
    done = subprocess.run([*HH2IEC, "merge", *map(str, reports), "--report", str(merged), "--junit", str(junit)],
                          cwd=cwd, env=ENV, capture_output=True, text=True)
    return ShardedRun(plan_seconds, seconds, codes, done.returncode, merged, junit, done.stdout + done.stderr, cpu,
                      plan_cpu)


def _children_cpu() -> float:
    """CPU seconds of every finished child process so far (its forked helpers included): a figure a machine shared
    with other work disturbs less than wall time."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed(command: list[str], cwd: Path | None = None) -> tuple[float, float, int]:
    """(wall seconds, CPU seconds, exit status) of one hh2iec command line."""
    t, used = time.perf_counter(), _children_cpu()
    code = subprocess.run([*HH2IEC, *command], cwd=cwd, env=ENV, stdout=subprocess.DEVNULL).returncode
    return time.perf_counter() - t, _children_cpu() - used, code


def comparable(report: Path) -> dict:
    """A report without what differs between one process and merged shards by nature: times, the shard section,
    and the plan file a shard's reproducing command names (so that the search is not made again)."""
    data = json.loads(report.read_text(encoding="utf-8"))
    data.pop("shard", None)
    data.pop("seconds", None)
    for item in data.get("runs", []) + data.get("mutants", []):
        item.pop("seconds", None)
        if isinstance(item.get("reproduce"), str):
            item["reproduce"] = re.sub(r" --plan-file (\S+|'[^']*')", "", item["reproduce"])
    return data


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shards", type=int, default=4)
    parser.add_argument("--command", choices=("equiv", "mutate"), default="equiv")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "shards")
    parser.add_argument("--compare", action="store_true", help="also run unsharded and compare the reports")
    parser.add_argument("args", nargs=argparse.REMAINDER, help="the command's arguments (after --)")
    opts = parser.parse_args(argv)
    args = [a for a in opts.args if a != "--"] or sample_equiv_args()
    run = run_sharded(opts.command, args, opts.shards, opts.out)
    print(run.output, end="")
    print(f"shards: plan {run.plan_seconds:.1f} s; {opts.shards} shards in parallel, each "
          + ", ".join(f"{s:.1f} s (exit {c})" for s, c in zip(run.shard_seconds, run.shard_codes)))
    if any(code not in (0, 1) for code in run.shard_codes):
        print("shards: a shard could not run (exit 2)", file=sys.stderr)
        return 2
    if opts.compare:
        whole = opts.out / "unsharded.json"
        subprocess.run([*HH2IEC, opts.command, *args, "--report", str(whole)], env=ENV, stdout=subprocess.DEVNULL)
        if comparable(whole) != comparable(run.merged):
            print("shards: the merged report differs from the unsharded one", file=sys.stderr)
            return 1
        print("shards: the merged report equals the unsharded one")
    return run.merge_code


if __name__ == "__main__":
    sys.exit(main())
