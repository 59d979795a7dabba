"""Mutation fuzzer of the readers: mutated projects and scenario files must only ever give diagnostics, never an
exception or a hang.

Usage: python -m tests.fuzz --mutations 10000 [--seed 1] [--jobs 2] [--limit 10]

Every mutation takes one project of samples/ (the spec's test vectors when there is none), changes one of its
files (byte flips, line deletions and duplications, token swaps, inserted directives and garbage, ...) and runs
the whole front end on it. One mutation in four (when samples/ has scenarios) is a scenario file instead: mutated
as bytes or as YAML structure (keys, values, types, nesting, events, NC actions, machine parameters, huge numbers,
aliases) and run the way `hh2iec simulate` runs it, with the simulation cut after a few hundred cycles. Mutation i depends only on (seed, i), so any failure can be replayed with
`--replay i`. Workers run in subprocesses; a Python-level hang is cut by an interval timer (the input is then
reported as a hang), and a worker that stops answering altogether is killed by the parent, so even a hang
inside C code is found and reported rather than stalling the run.
"""

from __future__ import annotations

import argparse
import copy
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
from typing import Any, Callable

import yaml

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from transpiler.cli.app import summary  # noqa: E402
from transpiler.diagnostics import CODES, CompileFailed  # noqa: E402
from transpiler.frontend.load import Parsers, ProjectOptions  # noqa: E402
from transpiler.frontend.pipeline import CompileResult, compile_project  # noqa: E402
from transpiler.language.semantics import make_semantics  # noqa: E402

SOURCE_SUFFIXES = (".src", ".def", ".cfg", ".inc", ".mp", ".msk", ".a", ".tab")   # .msk, .a: screen masks; .tab: PLC data tables


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
    # PLC data tables
    b"BEGIN MP_DATA.TAB", b"BEGIN", b"[END]", b"NR   NAME                 VALUE", b"NAME VALUE NAME", b"NR NAMES VALUE",
    b"0    DG_S1_max_torque     99", b"1    MG_marker_one        2", b"2    I_key_NC_start       1",
    b"3    DG_nothing           5", b"x    DG_S1_min_torque     $FFFFFFFFF", b"4    SL_tool_message      \"text\"",
]
VOCAB_TOKENS = [
    b"L", b"LN", b"A", b"=", b"S", b"R", b"EM", b"LBL", b"CM", b"JP", b"CASE", b"ENDC", b"A[", b"]", b"IFT", b"ENDI",
    b"M0", b"M4172", b"M99999", b"I 3", b"W3", b"W4", b"D8", b"B0", b"K0", b"K-2147483648", b"K2147483648",
    b"K$FFFFFFFFF", b"K%1", b"S0", b"S#D4095", b"X", b"[X]", b"KF", b"MG_x", b"#if", b"#else", b"#endif",
    b"USES", b"GLOBAL", b"EXTERN", b"&", b"/c", b"/g", b";", b"\"", b"*", b"9032", b"-1", b"",
    # PLC data tables
    b"[END]", b"BEGIN", b"NR", b"NAME", b"VALUE", b"UNIT", b"$7FFFFFFF", b"%102", b"4294967296",
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


def mutate(seed: Seed, rng: random.Random, targets: list[str] | None = None) -> tuple[dict[str, bytes], str]:
    """One mutant of the seed: 1-3 mutations of one of its files (one of `targets` when given). Returns the files
    and a description."""
    files = dict(seed.files)
    target = rng.choice(targets or seed.targets)
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


# ------------------------------------------------------------------------------------------ scenario files

SCENARIO_SHARE = 0.25            # part of the mutations that are scenario files (when samples/ has scenarios)
SCENARIO_CYCLES = 300            # cycles a scenario mutant is simulated for (its loading sees all of them)


@dataclasses.dataclass(frozen=True)
class ScenarioSeed:
    """A scenario file of a sample project (`name` relative to the project folder, e.g. scenarios/x.yaml)."""

    project: Seed
    name: str
    text: bytes


def scenario_seeds(seeds: list[Seed], samples: Path = ROOT / "samples") -> list[ScenarioSeed]:
    """Every scenarios/*.yaml of the sample projects."""
    found = []
    for seed in seeds:
        folder = ROOT / seed.name
        if seed.name.startswith("samples/") and (folder / "scenarios").is_dir():
            found += [ScenarioSeed(seed, str(p.relative_to(folder)), p.read_bytes())
                      for p in sorted((folder / "scenarios").glob("*.yaml"))]
    return found


def _alias_bomb(levels: int) -> bytes:
    lines = [b"lol0: &lol0 [x, x, x, x, x, x, x, x, x, x]"]
    for i in range(1, levels):
        lines.append(f"lol{i}: &lol{i} [".encode() + b", ".join([f"*lol{i - 1}".encode()] * 10) + b"]")
    return b"\n".join(lines)


# YAML that reaches the corners of the scenario loader: aliases, tags, directives, documents, deep nesting.
SCENARIO_LINES = [
    b"cycles: 99999999999999999999", b"cycles: 1000001", b"cycles: 0", b"cycles: -1", b"cycles: 1e400",
    b"cycles: .nan", b"cycles: '10'", b"cycles: [10]", b"cycle_time_ms: 99999999999999999999", b"cycle_time_ms: 0",
    b"profile: tnc640", b"profile: nope", b"semantics: {byte_order: big}", b"semantics: {nope: 1}",
    b"semantics: [1, 2]", b"machine_parameters: ../MP_data.mp", b"machine_parameters: ../Main_PGM.src",
    b"machine_parameters: /dev/null", b"machine_parameters: .", b"machine_parameters: 5",
    b"mp: {4110.0: 1e400, MP7210: $FFFFFFFFFFFFFFFFFF, x: 1}", b"mp: {4110.3: 99999999999999999999999}",
    b"mp: {'4110.99999999999999999999': 1}", b"mp: {4120.0: -0.000000000000000000001}",
    b"mp_data: {DG_S1_max_torque: 99999999999}", b"mp_data: {nope: 1}", b"mp_data: {DG_S1_max_torque: [1]}",
    b"module_results: {9032: [1, 2]}", b"module_results: {99999999999: [99999999999999999999]}",
    b"module_results: {-1: []}", b"random: {seed: 99999999999999999999, inputs: ['I_*'], toggle_probability: 1}",
    b"random: {seed: 1, inputs: ['*'], toggle_probability: 1.0}", b"random: {seed: 1, inputs: []}",
    b"observe: ['*', 'I_*', '[', '[!]', 'M99999']", b"expect: [{cycle: 99999999999, values: {O_lamp: 1}}]",
    b"  - cycle: 1\n    nc: {m_function: 3}", b"  - cycle: 1\n    nc: {restart: machine_parameters}",
    b"  - cycle: 1\n    nc: {tool_call: {tool: 65535, pocket: -1, second_strobe: yes}}",
    b"  - cycle: 1\n    nc: {fn19: {value1: -2147483648, value2: 4294967295}}",
    b"  - cycle: 1\n    nc: {spindle_speed: 4294967295}", b"  - cycle: 1\n    nc: {mode: 65535}",
    b"  - cycle: 1\n    machine: {axes: {15: {active: no, position: 2147483647}}, drives: {available: -1}}",
    b"  - cycle: 1\n    machine: {tables: [{table: TCH, line: 4294967295, element: 63, value: -1}], status: {255: 1}}",
    b"  - cycle: 2\n    set: {WG_S1_torque: 65536, I_key_NC_start: 2, SG_nothing: x}",
    b"initial: {M0: 1, W3: 1, D4: 99999999999999, S0: 5, B9999999: 1}",
    b"a: &a [1, 2, 3]", b"b: *a", b"<<: *a", b"c: *undefined", b"d: &d [*d]", b"e: &e {e: *e}",
    b"x: !!python/object:os.system ls", b"x: !!binary aGVsbG8=", b"x: !!timestamp 2001-12-14", b"x: !custom 1",
    b"x: !!set {a, b}", b"x: !!omap [a: 1]", b"---", b"...", b"%YAML 1.1", b"%YAML 9.9", b"%TAG ! tag:x,2000:",
    b"? [a, b]\n: 1", b"? {a: 1}\n: 2", b"\t- x", b"'unterminated", b'"\\uD800"', b'"\\x00"', b"&", b"*", b"!", b"|",
    b">-", b"{", b"[", b"}", b"]", b"- - - - -", b"cycles: 10\ncycles: 20", b"name: " + b"n" * 10000,
    b"initial: " + b"[" * 5000 + b"]" * 5000, b"events: " + b"{a: " * 3000 + b"1" + b"}" * 3000,
    b"semantics: " + b"[" * 5000, b"expect:\n" + b"  - " * 2000 + b"x", b"nesting: " + b"- " * 3000 + b"x",
    _alias_bomb(9), b"events: &ev [{cycle: 1, set: {O1: 1}}]\nexpect: *ev",
]
SCENARIO_VALUES: list[Any] = [
    0, 1, -1, 2, 7, 255, 256, 65535, 65536, 2 ** 31 - 1, 2 ** 31, 2 ** 32, -2 ** 31 - 1, 2 ** 63, 10 ** 30, -10 ** 30,
    10 ** 400, 0.5, -0.0, 1e308, float("inf"), float("-inf"), float("nan"), True, False, None, "", "x", "0", "1",
    "4110.0", "$FF", "%101", "I_key_NC_start", "M0", "W3", "D1000000", "S#E1", "*", "I_*", "\x00", "\x85", "é",
    "\u2028", [], {}, [1, 2], {"a": 1}, {"cycle": 1}, [{"cycle": 1}], "machine_parameters", "program", "T", "TCH",
]


def _scenario_keys() -> list[str]:
    """Every key of the scenario format (so renamed and added keys are often valid ones in the wrong place)."""
    from transpiler.verify import scenario as schema
    models = [schema.Scenario, schema.Event, schema.NcAction, schema.ToolCall, schema.ToolDef, schema.Fn19,
              schema.MachineData, schema.Axis, schema.Drives, schema.TableEntry, schema.RandomStimulus,
              schema.Expectation]
    return sorted({key for model in models for key in model.model_fields}) + ["<<", "4110.0", "MP4120", "", "0"]


def _paths(value: Any, path: tuple = ()) -> list[tuple]:
    """Every path into plain YAML data (mappings and lists), the root included."""
    found = [path]
    if isinstance(value, dict):
        for key, sub in value.items():
            found += _paths(sub, path + (key,))
    elif isinstance(value, list):
        for i, sub in enumerate(value):
            found += _paths(sub, path + (i,))
    return found


def _get(value: Any, path: tuple) -> Any:
    for part in path:
        value = value[part]
    return value


def _random_value(rng: random.Random, names: list[str], depth: int = 0) -> Any:
    choice = rng.random()
    if choice < 0.55 or depth > 2:
        return rng.choice(SCENARIO_VALUES + names)
    if choice < 0.8:
        return {rng.choice(_scenario_keys() + names): _random_value(rng, names, depth + 1)
                for _ in range(rng.randint(0, 3))}
    return [_random_value(rng, names, depth + 1) for _ in range(rng.randint(0, 3))]


def _random_event(rng: random.Random, names: list[str]) -> dict:
    cycle = rng.choice([0, 1, 5, 50, 299, 300, 10 ** 9, -1, rng.randrange(400)])
    what = rng.choice(["set", "nc", "machine"])
    if what == "set":
        return {"cycle": cycle, "set": {rng.choice(names or ["I1"]): rng.choice(SCENARIO_VALUES)}}
    if what == "nc":
        kind = rng.choice(["m_function", "spindle_speed", "gear", "tool_call", "tool_def", "fn19", "mode", "restart"])
        value = {"tool_call": {"tool": rng.choice(SCENARIO_VALUES), "pocket": rng.choice(SCENARIO_VALUES)},
                 "tool_def": {"tool": rng.choice(SCENARIO_VALUES), "pocket": rng.choice(SCENARIO_VALUES)},
                 "fn19": {"value1": rng.choice(SCENARIO_VALUES), "value2": rng.choice(SCENARIO_VALUES)},
                 "restart": rng.choice(["program", "machine_parameters", "x"])}.get(kind, rng.choice(SCENARIO_VALUES))
        return {"cycle": cycle, "nc": {kind: value}}
    number = rng.choice([0, 1, 15, 16, 255, 256, -1])
    machine = rng.choice([{"axes": {number: {"active": rng.choice(SCENARIO_VALUES), "position": rng.choice(SCENARIO_VALUES)}}},
                          {"drives": {"available": rng.choice(SCENARIO_VALUES)}},
                          {"tables": [{"table": rng.choice(["T", "D", "TCH", "X"]), "line": rng.choice(SCENARIO_VALUES),
                                       "element": rng.choice([0, 63, 64, -1]), "value": rng.choice(SCENARIO_VALUES)}]},
                          {"status": {number: rng.choice(SCENARIO_VALUES)}}])
    return {"cycle": cycle, "machine": machine}


def mutate_scenario_structure(rng: random.Random, data: Any, names: list[str]) -> tuple[Any, str]:
    """One change of the scenario as YAML data: a key, a value, a type, the nesting, an event, an entry."""
    paths = _paths(data)
    path = rng.choice(paths)
    parent_path, last = path[:-1], (path[-1] if path else None)
    parent = _get(data, parent_path) if path else None
    step = rng.choice(["value", "value", "delete", "rename", "add", "wrap", "duplicate", "event", "event", "top"])
    if step == "value" and path:
        parent[last] = _random_value(rng, names)
    elif step == "delete" and path:
        del parent[last]
    elif step == "rename" and isinstance(parent, dict):
        new_key = rng.choice(_scenario_keys() + names + [str(last).upper(), str(last)[:-1], 5, True, None, 1.5])
        parent[new_key] = parent.pop(last)
    elif step == "add" and isinstance(_get(data, path), dict):
        _get(data, path)[rng.choice(_scenario_keys() + names)] = _random_value(rng, names)
    elif step == "wrap" and path:
        parent[last] = rng.choice([[parent[last]], {rng.choice(_scenario_keys()): parent[last]}])
    elif step == "duplicate" and isinstance(parent, list):
        parent.insert(rng.randrange(len(parent) + 1), copy.deepcopy(parent[last]))
    elif step == "event" and isinstance(data, dict):
        events = data.setdefault("events", [])
        if isinstance(events, list):
            events.insert(rng.randrange(len(events) + 1), _random_event(rng, names))
    elif step == "top" and isinstance(data, dict):
        key = rng.choice(["cycles", "cycle_time_ms", "mp", "mp_data", "random", "expect", "observe", "module_results",
                          "machine", "semantics", "profile", "machine_parameters", "initial", "name"])
        data[key] = rng.choice([_random_value(rng, names), rng.choice(SCENARIO_VALUES),
                                {rng.choice(["4110.0", "4120.0", "7210", "MP4110.3", "x"]): rng.choice(SCENARIO_VALUES)}])
    else:
        return data, f"{step} (nothing to do)"
    return data, step


def mutate_scenario(seed: ScenarioSeed, rng: random.Random) -> tuple[bytes, str]:
    """One mutant of a scenario file: 1-3 changes of its YAML structure or of its bytes."""
    data = seed.text
    steps = []
    for _ in range(rng.choice((1, 1, 2, 3))):
        if rng.random() < 0.5:
            try:
                tree = yaml.safe_load(data.decode("utf-8"))
            except (UnicodeDecodeError, yaml.YAMLError, RecursionError):
                tree = None
            if tree is not None:
                names = sorted(n for n in (tree.get("initial") or {}) if isinstance(n, str)) \
                    if isinstance(tree, dict) and isinstance(tree.get("initial"), dict) else []
                tree, step = mutate_scenario_structure(rng, tree, names)
                data = yaml.safe_dump(tree, sort_keys=False, allow_unicode=rng.random() < 0.5).encode("utf-8")
                steps.append(f"yaml {step}")
                continue
        if rng.random() < 0.3:
            lines = _lines(data)
            lines.insert(rng.randrange(len(lines) + 1), rng.choice(SCENARIO_LINES))
            data = b"\n".join(lines)
            steps.append("insert_yaml_line")
            continue
        mutator = rng.choice(MUTATORS)
        data = mutator(rng, data, [line for line in _lines(seed.text) if line.strip()])
        steps.append(mutator.__name__)
    return data, f"{seed.project.name}: {seed.name}: {', '.join(steps)}"


@dataclasses.dataclass
class ProjectCache:
    """Projects compiled once per profile and semantic settings: a scenario mutant changes no source file."""

    projects: dict[tuple, Any] = dataclasses.field(default_factory=dict)

    def load(self, main: Path, semantics) -> Any:
        from transpiler import api
        key = (str(main), semantics.profile.name, tuple(sorted((k, repr(v)) for k, v in semantics.values.items())))
        if key not in self.projects:
            if len(self.projects) > 8:
                self.projects.clear()
            try:
                self.projects[key] = api.load_project(ProjectOptions(main=main), semantics)
            except CompileFailed as exc:
                self.projects[key] = exc
        found = self.projects[key]
        if isinstance(found, CompileFailed):
            raise found
        return found


def simulate_scenario(main: Path, path: Path, cache: ProjectCache, cycles: int = SCENARIO_CYCLES) -> list:
    """What `hh2iec simulate --scenario path` does, with the run cut after `cycles` cycles: the diagnostics it
    would print (an empty list when the scenario ran). Any other exception is a crash."""
    from transpiler import api
    from transpiler.exec.compiled.shim import ShimUnavailable
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.simulate import project_names, run_scenario
    from transpiler.verify.stimulus import build_stimulus
    from transpiler.diagnostics import Diagnostics
    try:
        project = cache.load(main, api.semantics_for(scenario=path))
        names = project_names(project.program)
        diags = Diagnostics()
        loaded = load_scenario(path, names)
        stimulus = build_stimulus(loaded, names)
        diags.extend(stimulus.diagnostics)
        stimulus = dataclasses.replace(stimulus, cycles=min(stimulus.cycles, cycles))
        run = run_scenario(project.program, loaded, names, stimulus, diags=diags)
        if run.fault is not None:
            run.fault.render(run.fault_span)
        return list(diags.items)
    except CompileFailed as exc:
        return exc.diagnostics
    except ShimUnavailable:
        return []


def check_scenario(folder: Path, files: dict[str, bytes], main: str, name: str, data: bytes, limit: float,
                   cache: ProjectCache | None = None, on_disk: dict[str, bytes] | None = None,
                   cycles: int = SCENARIO_CYCLES) -> list:
    """Write the project and the scenario, simulate it under a time limit and check that what came out are
    diagnostics with registered codes, each error at a line of a file. Returns the diagnostics.

    Raises InputTimeout on a hang, AssertionError when an invariant is broken, and lets any other exception
    through (that is a crash)."""
    write_files(folder, {**files, name: data}, on_disk)
    previous = signal.signal(signal.SIGALRM, _on_alarm)
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        diagnostics = simulate_scenario(folder / main, folder / name, cache or ProjectCache(), cycles)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    for d in diagnostics:
        assert d.code in CODES, d.code
        assert d.span.file and d.span.line >= 1 and d.span.col >= 1, d.render()
        if d.code == "E-SCENARIO":
            assert Path(d.span.file) == folder / name, d.render()      # a scenario fault names the scenario file
        assert d.render().count(f"[{d.code}]") >= 1
    return diagnostics


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


def _is_scenario_mutant(scenarios: list[ScenarioSeed], seed: int, index: int) -> bool:
    return bool(scenarios) and random.Random(f"{seed}:{index}:kind").random() < SCENARIO_SHARE


def _scenario_mutant(scenarios: list[ScenarioSeed], seed: int, index: int) -> tuple[ScenarioSeed, bytes, str]:
    rng = random.Random(f"{seed}:{index}:scenario")
    chosen = scenarios[rng.randrange(len(scenarios))]
    data, description = mutate_scenario(chosen, rng)
    return chosen, data, description


def _check_one(seeds: list[Seed], scenarios: list[ScenarioSeed], seed: int, index: int, folder: Path, limit: float,
               parsers: Parsers | None = None, cache: ProjectCache | None = None,
               on_disk: dict[str, bytes] | None = None) -> str:
    """Check mutation `index` (a project or a scenario file); returns its description."""
    if _is_scenario_mutant(scenarios, seed, index):
        chosen, data, description = _scenario_mutant(scenarios, seed, index)
        check_scenario(folder, chosen.project.files, chosen.project.main, chosen.name, data, limit, cache, on_disk)
        return description
    project, files, description = _mutant(seeds, seed, index)
    check_project(folder, files, project.main, project.profile, limit, parsers, on_disk)
    return description


def worker(seed: int, start: int, count: int, limit: float, with_vectors: bool) -> None:
    """Run mutations start .. start+count-1 and print one JSON line per input (after a 'begin' line)."""
    seeds = _seeds(with_vectors)
    scenarios = scenario_seeds(seeds)
    parsers: dict[str, Parsers] = {}
    cache = ProjectCache()
    on_disk: dict[str, bytes] = {}
    with tempfile.TemporaryDirectory(prefix="hh2iec-fuzz-") as tmp:
        for index in range(start, start + count):
            print(json.dumps({"begin": index}), flush=True)
            # Line caches are shared between inputs of one profile, but renewed now and then to bound memory.
            if index % 500 == 0:
                parsers.clear()
            profile = "itnc530" if _is_scenario_mutant(scenarios, seed, index) else _mutant(seeds, seed, index)[0].profile
            if profile not in parsers:
                parsers[profile] = Parsers.for_semantics(make_semantics(profile))
            status, detail, description = "ok", "", ""
            started = time.perf_counter()
            try:
                description = _check_one(seeds, scenarios, seed, index, Path(tmp) / "p", limit, parsers[profile],
                                         cache, on_disk)
            except InputTimeout:
                status, detail = "hang", f"no result after {limit} s"
                parsers.clear()
                cache.projects.clear()
            except Exception:   # noqa: BLE001 - every exception of the front end is a finding
                status, detail = "crash", traceback.format_exc()
                parsers.clear()
                cache.projects.clear()
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
    scenarios = scenario_seeds(seeds)
    of_scenarios = sum(_is_scenario_mutant(scenarios, args.seed, i) for i in results)
    print(f"fuzz: {len(results)} mutations of {len(seeds)} seed project(s) ({', '.join(s.name for s in seeds[:4])}"
          f"{', ...' if len(seeds) > 4 else ''}) in {elapsed:.0f} s with {args.jobs} job(s), seed {args.seed}; "
          f"{of_scenarios} of them of {len(scenarios)} scenario files")
    if slowest is not None:
        print(f"fuzz: slowest input {slowest.get('seconds', 0):.2f} s (limit {args.limit} s)")
    print(f"fuzz: crashes: {len(crashes)}, hangs: {len(hangs)}" + (f", not run: {missing}" if missing else ""))
    if crashes or hangs:
        print(f"fuzz: failing mutations: {', '.join(str(r['index']) for r in (crashes + hangs)[:50])}")
    for r in (crashes + hangs)[:1]:
        if _is_scenario_mutant(scenarios, args.seed, r["index"]):
            chosen, data, description = _scenario_mutant(scenarios, args.seed, r["index"])
            target, text = chosen.name, data.decode("latin-1")
        else:
            project, files, description = _mutant(seeds, args.seed, r["index"])
            target = description.split(": ")[1]
            text = files.get(target, b"").decode("latin-1")
        print(f"\nfirst failing input: mutation {r['index']} ({description}); replay with "
              f"`python -m tests.fuzz --seed {args.seed} --replay {r['index']}`")
        print(f"--- {target} ({len(text)} characters) ---\n{text[:3000]}{' ...' if len(text) > 3000 else ''}\n---")
        print(r.get("detail", ""))
    return 1 if crashes or hangs or missing else 0


def replay(args) -> int:
    seeds = _seeds(args.with_vectors)
    scenarios = scenario_seeds(seeds)
    with tempfile.TemporaryDirectory(prefix="hh2iec-fuzz-") as tmp:
        folder = Path(tmp) / "p"
        if _is_scenario_mutant(scenarios, args.seed, args.replay):
            description = _scenario_mutant(scenarios, args.seed, args.replay)[2]
        else:
            description = _mutant(seeds, args.seed, args.replay)[2]
        print(f"mutation {args.replay}: {description}", flush=True)
        _check_one(seeds, scenarios, args.seed, args.replay, folder, args.limit)
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
