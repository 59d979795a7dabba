"""Mutation fuzzer of the front end: mutated projects must only ever give diagnostics, never an exception or a hang.

Usage: python -m tests.fuzz --mutations 10000 [--seed 1] [--jobs 2] [--limit 10]

Every mutation takes one project of samples/ (the spec's test vectors when there is none), changes one of its
files (byte flips, line deletions and duplications, token swaps, inserted directives and garbage, ...) and runs
the whole front end on it. Mutation i depends only on (seed, i), so any failure can be replayed with
`--replay i`. Workers run in subprocesses; a Python-level hang is cut by an interval timer (the input is then
reported as a hang), and a worker that stops answering altogether is killed by the parent, so even a hang
inside C code is found and reported rather than stalling the run.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import random
import re
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from transpiler.cli.app import summary  # noqa: E402
from transpiler.diagnostics import CODES  # noqa: E402
from transpiler.frontend.load import Parsers, ProjectOptions  # noqa: E402
from transpiler.frontend.pipeline import CompileResult, compile_project  # noqa: E402
from transpiler.language.semantics import make_semantics  # noqa: E402

SOURCE_SUFFIXES = (".src", ".def", ".cfg", ".inc", ".mp", ".msk", ".a")     # .msk, .a: screen masks


@dataclasses.dataclass(frozen=True)
class Seed:
    """A project to mutate: its files, the main file and the profile it is meant for."""

    name: str
    files: dict[str, bytes]
    main: str
    profile: str = "itnc530"

    @property
    def targets(self) -> list[str]:
        return sorted(n for n in self.files if n.lower().endswith(SOURCE_SUFFIXES))


def sample_seeds(samples: Path = ROOT / "samples") -> list[Seed]:
    """Each folder of samples/ with a main program (Main*.src, or the only .src file) is one seed."""
    seeds = []
    for folder in sorted(p for p in samples.iterdir() if p.is_dir()) if samples.is_dir() else []:
        files = {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
                 if p.is_file() and p.suffix.lower() in SOURCE_SUFFIXES}
        sources = [n for n in files if n.lower().endswith(".src") and "/" not in n]
        mains = [n for n in sources if n.lower().startswith("main")] or (sources if len(sources) == 1 else [])
        if mains:
            seeds.append(Seed(f"samples/{folder.name}", files, mains[0]))
    return seeds


def vector_seeds() -> list[Seed]:
    """The language test vectors (tests/data/vectors) as small projects."""
    from tests.vectors import load_vectors
    seeds = []
    for v in load_vectors():
        files = {name: text.encode("latin-1", "replace") for name, text in (v.data.get("files") or {}).items()}
        if "program" in v.data:
            files["main.src"] = v.data["program"].encode("latin-1", "replace")
        if "cfg" in v.data:
            files["OEM.cfg"] = v.data["cfg"].encode("latin-1", "replace")
        if "defs" in v.data:
            files["vector_defs.def"] = v.data["defs"].encode("latin-1", "replace")
            files["main.src"] = b"#define /g vector_defs.def\n" + files["main.src"]
        seeds.append(Seed(v.id, files, "main.src", v.profile))
    return seeds


# ----------------------------------------------------------------------------------------------- mutations

# Lines and tokens that reach the corners of the front end: directives, structure, extreme operands.
VOCAB_LINES = [
    b"#if CFG_X = 1", b"#if CFG_X <> &ACTIVE", b"#ifdef CFG_X", b"#ifndef NOPE", b"#else", b"#endif", b"#endif ; x",
    b"DEFINE CFG_X = 1", b"DEFINE CFG_X = &CFG_X", b"DEFINE BAD = 1.5", b"A[", b"O [", b"+[", b"==[", b"]", b"IFT",
    b"IFF", b"ELSE", b"ENDI", b"WHILET", b"ENDW", b"REPEAT", b"UNTILF", b"CASE B0", b"CASE MG_x", b"ENDC",
    b"KFIELD Tab", b"K$FFFFFFFF", b"K99999999999", b"ENDK", b"LBL L1", b"LBL L1", b"EM", b"EMT", b"JP L1", b"JPF Nowhere",
    b"CM L1", b"CM 9999", b"CM 9032", b"CMT Init_first_cycle", b"SUBM L1", b"USES Main_PGM.src", b"USES main.src",
    b"USES ../escape.src", b"USES /etc/passwd", b"USES missing.src", b"INCLUDE main.src", b"INCLUDE Main_PGM.src",
    b'#include "nothing.inc"', b"#define /g GLB_NC.DEF", b"#define /g missing.def", b"#define ../x.def", b"GLOBAL L1",
    b"EXTERN L1", b"EXTERN Nowhere", b"L KF Tab[X]", b"L S\"a;b\"", b"L S#E1000", b"L M10000", b"L W3", b"L D6",
    b"LB M9999", b"L X", b"= X", b"L- M1", b"=N O1", b"NOTL", b"PSW", b"PLL", b"* star", b";;;X9.7a",
    b"MG_new M", b"/c I_x M &MG_nothing", b"M12 M", b"#TYPEDEF Api", b"#type x", b"MP4110.0 : x",
    b"\x00\x01\x02", b"\xff\xfe", b"\"", b"L \x96 W2", b"L\xe2\x80\x93 W2",
]
VOCAB_TOKENS = [
    b"L", b"LN", b"A", b"=", b"S", b"R", b"EM", b"LBL", b"CM", b"JP", b"CASE", b"ENDC", b"A[", b"]", b"IFT", b"ENDI",
    b"M0", b"M4172", b"M99999", b"I 3", b"W3", b"W4", b"D8", b"B0", b"K0", b"K-2147483648", b"K2147483648",
    b"K$FFFFFFFFF", b"K%1", b"S0", b"S#D4095", b"X", b"[X]", b"KF", b"MG_x", b"#if", b"#else", b"#endif",
    b"USES", b"GLOBAL", b"EXTERN", b"&", b"/c", b"/g", b";", b"\"", b"*", b"9032", b"-1", b"",
    # screen masks
    b"$", b"$WG_tc_status$", b"$nope$", b"/*", b"*/", b"%", b"%%", b"%999D", b"%+5.0F", b"%s", b"\\n", b"\\",
    b",", b"/n=3", b"/n=99", b"/x", b"ERRQUE=10/c/l/s;", b"ERRQUE=0;", b"CHARSIZE=AUTO;", b"S1/c", b"S99999",
]


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


def flip_bits(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    if not data:
        return data
    buf = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        buf[rng.randrange(len(buf))] ^= 1 << rng.randrange(8)
    return bytes(buf)


def delete_lines(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    lines = _lines(data)
    start = rng.randrange(len(lines))
    del lines[start:start + rng.randint(1, 6)]
    return b"\n".join(lines)


def duplicate_lines(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    lines = _lines(data)
    start = rng.randrange(len(lines))
    block = lines[start:start + rng.randint(1, 12)]
    at = rng.randrange(len(lines) + 1)
    return b"\n".join(lines[:at] + block * rng.randint(1, 3) + lines[at:])


def swap_lines(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    lines = _lines(data)
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]
    return b"\n".join(lines)


def swap_tokens(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    parts = re.split(rb"(\s+)", data)
    words = [k for k, p in enumerate(parts) if p and not p.isspace()]
    if len(words) < 2:
        return data
    i, j = rng.choice(words), rng.choice(words)
    parts[i], parts[j] = parts[j], parts[i]
    return b"".join(parts)


def replace_token(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    parts = re.split(rb"(\s+)", data)
    words = [k for k, p in enumerate(parts) if p and not p.isspace()]
    if not words:
        return data
    parts[rng.choice(words)] = rng.choice(VOCAB_TOKENS)
    return b"".join(parts)


def insert_line(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    lines = _lines(data)
    new = rng.choice(VOCAB_LINES) if rng.random() < 0.7 or not pool else rng.choice(pool)
    lines.insert(rng.randrange(len(lines) + 1), new)
    return b"\n".join(lines)


def insert_garbage(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    at = rng.randrange(len(data) + 1)
    junk = bytes(rng.choice(b"\x00\r\n\t \"';[]&*#%$\x96\xe2\xff") if rng.random() < 0.5 else rng.randrange(256)
                 for _ in range(rng.randint(1, 64)))
    return data[:at] + junk + data[at:]


def truncate(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    return data[:rng.randrange(len(data) + 1)]


def splice(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    lines = _lines(data)
    at = rng.randrange(len(lines) + 1)
    chunk = [rng.choice(pool) for _ in range(rng.randint(1, 20))] if pool else []
    return b"\n".join(lines[:at] + chunk + lines[at:])


def extreme_number(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    runs = list(re.finditer(rb"[0-9]+", data))
    if not runs:
        return data
    m = rng.choice(runs)
    value = rng.choice([b"0", b"1", b"-1", b"4294967296", b"99999999999999999999", b"9" * 400, b"2147483648", b"65536"])
    return data[:m.start()] + value + data[m.end():]


def mangle_line_ends(rng: random.Random, data: bytes, pool: list[bytes]) -> bytes:
    replacement = rng.choice([b"\r", b"\r\n", b"", b"\n\n", b" "])
    return data.replace(b"\n", replacement, rng.randint(1, 20))


MUTATORS: tuple[Callable[[random.Random, bytes, list[bytes]], bytes], ...] = (
    flip_bits, delete_lines, duplicate_lines, swap_lines, swap_tokens, replace_token, insert_line, insert_line,
    insert_garbage, truncate, splice, extreme_number, mangle_line_ends,
)


def mutate(seed: Seed, rng: random.Random) -> tuple[dict[str, bytes], str]:
    """One mutant of the seed: 1-3 mutations of one of its files. Returns the files and a description."""
    files = dict(seed.files)
    target = rng.choice(seed.targets)
    pool = [line for text in files.values() for line in _lines(text) if line.strip()]
    data = files[target]
    steps = []
    for _ in range(rng.choice((1, 1, 2, 3))):
        mutator = rng.choice(MUTATORS)
        data = mutator(rng, data, pool)
        steps.append(mutator.__name__)
    files[target] = data
    if rng.random() < 0.03:            # now and then a file of the project goes missing
        victim = rng.choice(seed.targets)
        if victim != seed.main:
            del files[victim]
            steps.append(f"delete {victim}")
    return files, f"{seed.name}: {target}: {', '.join(steps)}"


# -------------------------------------------------------------------------------------------- one input


class InputTimeout(Exception):
    """Raised by the interval timer when one input takes longer than the limit."""


def _on_alarm(signum, frame):
    raise InputTimeout()


def write_files(folder: Path, files: dict[str, bytes], on_disk: dict[str, bytes] | None = None) -> None:
    """Make the folder hold exactly `files`. `on_disk` (updated here) is what it holds now, so that only the
    files that differ are written: a mutant changes one file of the project."""
    if on_disk is None:
        if folder.exists():
            shutil.rmtree(folder)
        on_disk = {}
    for name in [n for n in on_disk if n not in files]:
        (folder / name).unlink()
        del on_disk[name]
    for name, data in files.items():
        if on_disk.get(name) != data:
            path = folder / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
            on_disk[name] = data


def check_project(folder: Path, files: dict[str, bytes], main: str, profile: str, limit: float,
                  parsers: Parsers | None = None, on_disk: dict[str, bytes] | None = None) -> None:
    """Write the files, run the front end under a time limit and check that only diagnostics came out.

    Raises InputTimeout on a hang, AssertionError when an invariant is broken, and lets any other
    exception of the front end through (that is a crash)."""
    write_files(folder, files, on_disk)
    semantics = make_semantics(profile)
    main_path = folder / main
    previous = signal.signal(signal.SIGALRM, _on_alarm)
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        if not main_path.is_file():
            return
        result = compile_project(ProjectOptions(main=main_path), semantics, parsers=parsers)
        data = summary(result)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    check_result(result, data)


def check_result(result: CompileResult, data: dict | None = None) -> None:
    """The front end answered with diagnostics only: registered codes, real positions, a consistent summary."""
    for d in result.diagnostics.items:
        assert d.code in CODES, d.code
        assert d.span.line >= 1 and d.span.col >= 1, d.render()
        assert d.render().count(f"[{d.code}]") >= 1
    data = summary(result) if data is None else data
    assert data["errors"] == len(result.diagnostics.errors)
    assert result.ok == (result.program is not None and not result.diagnostics.errors)


# ----------------------------------------------------------------------------------------------- worker


def _seeds(with_vectors: bool) -> list[Seed]:
    seeds = sample_seeds()
    if with_vectors or not seeds:
        seeds += vector_seeds()
    return seeds


def _mutant(seeds: list[Seed], seed: int, index: int) -> tuple[Seed, dict[str, bytes], str]:
    rng = random.Random(f"{seed}:{index}")
    project = seeds[rng.randrange(len(seeds))]
    files, description = mutate(project, rng)
    return project, files, description


def worker(seed: int, start: int, count: int, limit: float, with_vectors: bool) -> None:
    """Run mutations start .. start+count-1 and print one JSON line per input (after a 'begin' line)."""
    seeds = _seeds(with_vectors)
    parsers: dict[str, Parsers] = {}
    on_disk: dict[str, bytes] = {}
    with tempfile.TemporaryDirectory(prefix="hh2iec-fuzz-") as tmp:
        for index in range(start, start + count):
            project, files, description = _mutant(seeds, seed, index)
            print(json.dumps({"begin": index}), flush=True)
            # Line caches are shared between inputs of one profile, but renewed now and then to bound memory.
            if index % 500 == 0:
                parsers.clear()
            if project.profile not in parsers:
                parsers[project.profile] = Parsers.for_semantics(make_semantics(project.profile))
            shared = parsers[project.profile]
            status, detail = "ok", ""
            started = time.perf_counter()
            try:
                check_project(Path(tmp) / "p", files, project.main, project.profile, limit, shared, on_disk)
            except InputTimeout:
                status, detail = "hang", f"no result after {limit} s"
                parsers.clear()
            except Exception:   # noqa: BLE001 - every exception of the front end is a finding
                status, detail = "crash", traceback.format_exc()
                parsers.clear()
            print(json.dumps({"index": index, "status": status, "detail": detail, "what": description,
                              "seconds": round(time.perf_counter() - started, 3)}), flush=True)


# ----------------------------------------------------------------------------------------------- parent


@dataclasses.dataclass
class _Worker:
    proc: subprocess.Popen
    next_index: int
    end: int
    current: int | None = None
    last_output: float = 0.0
    buffer: bytes = b""


def _spawn(args, start: int, end: int) -> _Worker:
    cmd = [sys.executable, "-m", "tests.fuzz", "--worker", "--seed", str(args.seed), "--start", str(start),
           "--count", str(end - start), "--limit", str(args.limit)] + (["--with-vectors"] if args.with_vectors else [])
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    return _Worker(proc, start, end, None, time.monotonic())


def run(args) -> int:
    seeds = _seeds(args.with_vectors)
    if not seeds:
        print("fuzz: no seed projects (no samples/ and no spec vectors)")
        return 2
    started = time.monotonic()
    jobs = max(1, args.jobs)
    share = -(-args.mutations // jobs)
    ranges = [(k * share, min(args.mutations, (k + 1) * share)) for k in range(jobs) if k * share < args.mutations]
    workers = [_spawn(args, a, b) for a, b in ranges]
    results: dict[int, dict] = {}
    next_report = 1000
    # A worker that says nothing for this long is stuck in something the interval timer cannot interrupt.
    silence_limit = args.limit * 3 + 30

    def lost(w: _Worker, status: str, what: str, detail: str) -> None:
        """A finished worker is dropped; one gone in the middle of an input fails that input, and the rest of
        its range goes to a new worker."""
        workers.remove(w)
        if w.current is not None:
            results[w.current] = {"index": w.current, "status": status, "what": what, "detail": detail}
            if w.current + 1 < w.end:
                workers.append(_spawn(args, w.current + 1, w.end))

    while workers:
        ready, _, _ = select.select([w.proc.stdout for w in workers], [], [], 1.0)
        now = time.monotonic()
        for w in list(workers):
            if w.proc.stdout in ready:
                chunk = os.read(w.proc.stdout.fileno(), 1 << 16)
                if not chunk:                        # it ended: done, or killed mid-input (by the OS, say)
                    w.proc.wait()
                    lost(w, "crash", "worker died", f"worker exit status {w.proc.returncode}")
                    continue
                w.buffer += chunk
                w.last_output = now
                *lines, w.buffer = w.buffer.split(b"\n")
                for line in lines:
                    message = json.loads(line)
                    if "begin" in message:
                        w.current = message["begin"]
                    else:
                        results[message["index"]] = message
                        w.current = None
            elif now - w.last_output > silence_limit:
                w.proc.kill()
                w.proc.wait()
                lost(w, "hang", "worker stuck", f"no answer for {silence_limit:.0f} s")
        if len(results) >= next_report:
            print(f"fuzz: {len(results)} / {args.mutations} inputs checked ({time.monotonic() - started:.0f} s)", flush=True)
            next_report += 1000
    return _report(args, seeds, results, time.monotonic() - started)


def _report(args, seeds: list[Seed], results: dict[int, dict], elapsed: float) -> int:
    crashes = sorted((r for r in results.values() if r["status"] == "crash"), key=lambda r: r["index"])
    hangs = sorted((r for r in results.values() if r["status"] == "hang"), key=lambda r: r["index"])
    missing = args.mutations - len(results)
    slowest = max(results.values(), key=lambda r: r.get("seconds", 0), default=None)
    print(f"fuzz: {len(results)} mutations of {len(seeds)} seed project(s) ({', '.join(s.name for s in seeds[:4])}"
          f"{', ...' if len(seeds) > 4 else ''}) in {elapsed:.0f} s with {args.jobs} job(s), seed {args.seed}")
    if slowest is not None:
        print(f"fuzz: slowest input {slowest.get('seconds', 0):.2f} s (limit {args.limit} s)")
    print(f"fuzz: crashes: {len(crashes)}, hangs: {len(hangs)}" + (f", not run: {missing}" if missing else ""))
    if crashes or hangs:
        print(f"fuzz: failing mutations: {', '.join(str(r['index']) for r in (crashes + hangs)[:50])}")
    for r in (crashes + hangs)[:1]:
        project, files, description = _mutant(seeds, args.seed, r["index"])
        print(f"\nfirst failing input: mutation {r['index']} ({description}); replay with "
              f"`python -m tests.fuzz --seed {args.seed} --replay {r['index']}`")
        target = description.split(": ")[1]
        text = files.get(target, b"").decode("latin-1")
        print(f"--- {target} ({len(text)} characters) ---\n{text[:3000]}{' ...' if len(text) > 3000 else ''}\n---")
        print(r.get("detail", ""))
    return 1 if crashes or hangs or missing else 0


def replay(args) -> int:
    project, files, description = _mutant(_seeds(args.with_vectors), args.seed, args.replay)
    print(f"mutation {args.replay}: {description}")
    with tempfile.TemporaryDirectory(prefix="hh2iec-fuzz-") as tmp:
        folder = Path(tmp) / "p"
        check_project(folder, files, project.main, project.profile, args.limit)
        if args.keep:
            shutil.copytree(folder, args.keep)
            print(f"project written to {args.keep}")
    print("ok: only diagnostics")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.fuzz", description=__doc__.splitlines()[0])
    parser.add_argument("--mutations", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--limit", type=float, default=10.0, help="seconds allowed per input")
    parser.add_argument("--with-vectors", action="store_true", help="mutate the spec vectors as well as samples/")
    parser.add_argument("--replay", type=int, help="run one mutation in this process and show its outcome")
    parser.add_argument("--keep", type=Path, help="with --replay: copy the mutated project to this folder")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--start", type=int, default=0, help=argparse.SUPPRESS)
    parser.add_argument("--count", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.seed, args.start, args.count, args.limit, args.with_vectors)
        return 0
    if args.replay is not None:
        return replay(args)
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
