"""The random-program generator of the differential test: deterministic, covers spec section 6, well-formed output."""

from __future__ import annotations

import collections
import hashlib
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from tests.difftest import generator  # noqa: E402
from tests.difftest.generator import (  # noqa: E402
    FEATURES, KNOWN_DIVERGENT, GeneratedProject, default_features, generate, main as generator_main)
from transpiler.diagnostics import Diagnostics  # noqa: E402
from transpiler.frontend.load import ProjectOptions  # noqa: E402
from transpiler.exec.interp import Machine  # noqa: E402
from transpiler.language.mnemonics import MNEMONICS, canonical  # noqa: E402
from transpiler.frontend.pipeline import compile_project  # noqa: E402
from transpiler.verify.scenario import OperandRef  # noqa: E402
from transpiler.language.semantics import PROFILES, make_semantics  # noqa: E402
from transpiler.verify.stimulus import Write  # noqa: E402
from transpiler.frontend.mpfile import read_mp_file  # noqa: E402
from transpiler.backends.st.modcalls import translatable  # noqa: E402
from transpiler.language.module_table import CYCLIC, DATA, MACHINE, MODULE_TABLE, PURE, SUBMIT  # noqa: E402

COVERAGE_SEEDS = range(1, 101)

# Mnemonics of spec section 6 by section; =N (A-16, off by default) is not generated.
SECTION_6 = {
    "6.1 load": {"L", "LN", "L-", "LB", "LW", "LD"},
    "6.2 assign": {"=", "B=", "W=", "D=", "S", "R", "SN", "RN"},
    "6.3/6.4 gating": {"A", "AN", "O", "ON", "XO", "XON"},
    "6.5 arithmetic": {"+", "-", "x", "/", "MOD"},
    "6.6 compare": {"==", "<>", "<", ">", "<=", ">="},
    "6.7 shift": {"<<", ">>"},
    "6.8 bit": {"BS", "BC", "BT"},
    "6.9 brackets": {"A[", "AN[", "O[", "ON[", "XO[", "XON[", "+[", "-[", "x[", "/[", "MOD[",
                     "==[", "<>[", "<[", ">[", "<=[", ">=[", "]"},
    "6.10 stack": {"PS", "PL", "PSW", "PLW", "PSL", "PLL", "PSX", "PLX"},
    "6.11 jumps": {"JP", "JPT", "JPF"},
    "6.12 calls": {"CM", "CMT", "CMF", "EM", "EMT", "EMF"},
    "6.14 extended": {"INC", "DEC", "INCW", "DECW", "INCX", "DECX", "NOTL", "NOTW", "TWOC"},
    "6.15 structured": {"IFT", "IFF", "ELSE", "ENDI", "WHILET", "WHILEF", "ENDW", "REPEAT", "UNTILT", "UNTILF",
                        "CASE", "ENDC"},
    "6.18 submit jobs": {"SUBM", "RPLY", "CAN"},
}
NOT_GENERATED = {"=N"}

# What each known-divergent feature writes, and nothing else does.
DIVERGENT_CONSTRUCTS = {
    "strings_long": r'S"[A-H]{60,}"',
}

BIT_OPERAND = re.compile(r"^(?:[MIOTC] ?\d+|[MIOTC][A-Z]_\w+|ML_\w+|MG_\w+)(?:\[X\])?$")
WORD_OPERAND = re.compile(r"^(?:[BWD] ?\d+|K[-+$%]?[0-9A-F]+|[BWD][GL]_\w+|KG_\w+|X|KF \w+\[X\])(?:\[X\])?$")


def instructions(project: GeneratedProject):
    """(file, mnemonic, operand) of every instruction line of every .src file."""
    for name, text in sorted(project.files.items()):
        if not name.endswith(".src"):
            continue
        in_kfield = False
        for raw in text.splitlines():
            line = raw.split(";", 1)[0].strip() if '"' not in raw else raw.strip()
            if not line or line.startswith("#"):
                continue
            word, _, rest = line.partition(" ")
            if word.upper() == "KFIELD":
                in_kfield = True
            if in_kfield:
                in_kfield = word.upper() != "ENDK"
                continue
            if word.upper() in ("LBL", "USES", "GLOBAL", "EXTERN"):
                continue
            yield name, canonical(word), rest.strip()


@pytest.fixture(scope="module")
def projects() -> list[GeneratedProject]:
    return [generate(seed) for seed in COVERAGE_SEEDS]


# ------------------------------------------------------------------------------------------------------------
# determinism and API


def test_same_seed_gives_identical_files():
    for seed in (0, 1, 17, 123456789):
        a, b = generate(seed), generate(seed)
        assert a == b
        assert a.seed == seed and a.main == "main.src" and a.main in a.files


def test_same_seed_is_identical_across_processes_with_other_hash_seeds():
    code = ("import sys, hashlib; sys.path.insert(0, sys.argv[1]);"
            "from tests.difftest.generator import generate;"
            "p = generate(4242, size=30);"
            "print(hashlib.sha256(repr(sorted(p.files.items())).encode()).hexdigest())")
    digests = set()
    for hash_seed in ("1", "987"):
        env = dict(os.environ, PYTHONHASHSEED=hash_seed)
        out = subprocess.run([sys.executable, "-c", code, str(ROOT)], env=env, capture_output=True, text=True,
                             check=True)
        digests.add(out.stdout.strip())
    p = generate(4242, size=30)
    assert digests == {hashlib.sha256(repr(sorted(p.files.items())).encode()).hexdigest()}


def test_different_seeds_give_different_programs(projects):
    mains = [p.files["main.src"].split("\n", 1)[1] for p in projects]      # without the header naming the seed
    assert len(set(mains)) == len(mains)


def test_size_controls_the_number_of_main_blocks():
    for size in (1, 5, 40, 120):
        project = generate(7, size=size)
        body = project.files["main.src"].split("\nEM\n", 1)[0]
        subs = sum(text.count("\nEM\n") + text.count("\nem\n") for text in project.files.values())
        # `size` blocks, plus at most one call for each subprogram that no block calls
        assert size <= body.count("; @block") <= size + subs
        assert generate(7, size=size, disable={"calls"}).files["main.src"].split("\nEM\n")[0].count("; @block") == size



def test_write_creates_every_file(tmp_path):
    p = generate(3)                                    # a project with an OEM.cfg and an MP file
    main = p.write(tmp_path / "proj")
    assert main == tmp_path / "proj" / "main.src"
    for name, text in p.files.items():
        assert (tmp_path / "proj" / name).read_text(encoding="ascii") == text
    assert p.cfg in p.files and p.cfg.endswith(".cfg")
    assert p.mp in p.files and re.search(r"^MP41[12]0\.\d+ : ", p.files[p.mp], re.M)


def test_command_line_writes_a_project(tmp_path, capsys):
    assert generator_main(["--seed", "5", "--size", "6", "--out", str(tmp_path / "cli")]) == 0
    assert (tmp_path / "cli" / "main.src").read_text() == generate(5, size=6).files["main.src"]
    assert "main.src" in capsys.readouterr().out


def test_feature_switches():
    assert set(KNOWN_DIVERGENT) <= set(FEATURES)     # a misspelt name would switch nothing off
    assert generate(8, features=default_features()) == generate(8)
    with pytest.raises(ValueError):
        generate(1, disable={"no_such_feature"})
    # only logic chains: no word, stack or control-flow mnemonics at all
    logic = generate(11, features={"logic"})
    used = {m for _, m, _ in instructions(logic)}
    assert used and used <= {"L", "LN", "A", "AN", "O", "ON", "XO", "XON", "=", "S", "R", "SN", "RN", "EM"}
    # a switched-off feature leaves no trace
    for seed in range(20):
        text = "\n".join(generate(seed, disable={"stack", "strings"}).files.values())
        assert not re.search(r"^(PS|PL|PSW|PLW|PSL|PLL|PSX|PLX)\b", text, re.M | re.I)
        assert 'S"' not in text and "S#" not in text


def test_known_divergent_features_are_off_by_default_and_can_be_switched_on(projects):
    assert set(DIVERGENT_CONSTRUCTS) == set(KNOWN_DIVERGENT)
    default_text = "\n".join(t for p in projects for t in p.files.values())
    for feature, pattern in DIVERGENT_CONSTRUCTS.items():
        assert not re.search(pattern, default_text, re.M | re.I), feature
        assert any(re.search(pattern, "\n".join(generate(seed, enable={feature}).files.values()), re.M | re.I)
                   for seed in range(120)), feature


def test_indexed_wide_stores_are_generated_by_default(projects):
    """Once a known divergence (a W/D store through X used a stale X for bytes 1-3); on again since the fix."""
    assert re.search(r"^=\s+[WD]\d+\[X\]", "\n".join(t for p in projects for t in p.files.values()), re.M | re.I)


def test_every_other_feature_is_on_by_default():
    defaults = [generate(seed, size=20) for seed in range(8)]
    for feature in sorted(set(FEATURES) - set(KNOWN_DIVERGENT)):       # switching it off changes the programs
        assert any(generate(seed, size=20, disable={feature}) != p for seed, p in enumerate(defaults)), feature


def test_the_memory_map_agrees_with_the_itnc530_profile():
    """The generator keeps its own operand map (its output depends on the seed alone); this catches a drift."""
    profile = PROFILES["itnc530"]
    assert generator.TIMER_RUNNING == profile.timer_running[0]
    assert generator.N_TIMERS <= profile.timer_start[1] + 1
    assert (generator.COUNTER_RUNNING, generator.COUNTER_RELEASE) == (profile.counter_running[0],
                                                                      profile.counter_release[0])
    assert generator.N_COUNTERS <= profile.counter_start[1] + 1
    interface = profile.interface
    assert generator.ARITH_ERROR_MARKERS == (interface.mul_err, interface.div_err, interface.mod_err)
    nc_markers = generator.IF_READ_BITS + tuple(m for pair in generator.ACKS for m in pair)
    assert [m for m in nc_markers if not profile.is_interface("M", m)] == []
    for word in generator.IF_READ_WORDS:
        assert profile.is_interface(word[0], int(word[1:]), generator.BYTES_PER_OPERAND[word[0]]), word


# ------------------------------------------------------------------------------------------------------------
# coverage of spec section 6


def test_every_mnemonic_group_of_section_6_occurs(projects):
    seen = collections.Counter(m for p in projects for _, m, _ in instructions(p))
    missing = {section: sorted(group - set(seen)) for section, group in SECTION_6.items() if group - set(seen)}
    assert not missing
    # and the table of the front end has nothing else that we should generate
    table = set(MNEMONICS) - NOT_GENERATED
    assert table - set(seen) == set()
    assert not NOT_GENERATED & set(seen)


def test_gates_occur_with_bit_and_word_operands(projects):
    bit, word = set(), set()
    for p in projects:
        for _, m, operand in instructions(p):
            if m in SECTION_6["6.3/6.4 gating"]:
                if BIT_OPERAND.match(operand):
                    bit.add(m)
                elif WORD_OPERAND.match(operand):
                    word.add(m)
    assert bit == word == SECTION_6["6.3/6.4 gating"]


def test_operand_forms_and_other_constructs_occur(projects):
    text = "\n".join(t for p in projects for n, t in sorted(p.files.items()))
    wanted = {
        "indexed byte": r"\bB\d+\[X\]", "indexed bit": r"\b[MIO]\d+\[X\]", "KF access": r"KF \w+\[X\]",
        "KFIELD": r"^KFIELD \w+$", "X operand": r"^\S+\s+X$", "hex constant": r"K\$[0-9A-F]+",
        "binary constant": r"K%[01]+", "negative constant": r"K-\d+", "plus constant": r"K\+\d+",
        "string literal": r'S"', "error text": r"S#E\d+", "dialog text": r"S#D\d+",
        "timer start": r"^(=|S)\s+(T\d|TS_)", "timer running": r"\bT(4[89]|[5-9]\d)\b|TR_",
        "counter start": r"^=\s+C\d\b", "counter release": r"\bC(9[6-9]|1[01]\d)\b",
        "counter running": r"\bC(4[89]|[56]\d)\b", "first cycle": r"\bM4172\b", "NC code word": r"\bW26[024]\b",
        "acknowledgement": r"^=\s+M409[0-5]$", "error markers": r"\bM420[012]\b",
        "USES": r"^USES \w+\.src$", "GLOBAL": r"^GLOBAL \w+$", "EXTERN": r"^EXTERN \w+$",
        "#define /g": r"^#define /g defs\.def$", "local #define": r"^#define \w+\.def$",
        "#if": r"^#if \w+ (=|<>) ", "#else": r"^#else$", "#ifdef": r"^#ifdef ", "#ifndef": r"^#ifndef ",
        "DEFINE": r"^DEFINE CFG_\w+ = ", "auto-assigned symbol": r"^\w+L_auto\d+\s+[MBWD]$",
        "alias": r"^/c \w+ +M &\w+$", "constant symbol": r"^KG_\w+ +K ", "MP4110": r"^MP4110\.\d+ : ",
        "MP4120": r"^MP4120\.\d+ : ", "label": r"^LBL \w+$",
    }
    missing = [what for what, pattern in wanted.items() if not re.search(pattern, text, re.M)]
    assert not missing


# ------------------------------------------------------------------------------------------------------------
# structure: blocks, labels, balanced stack


def _main_blocks(text: str) -> tuple[list[list[str]], list[str]]:
    """The top-level blocks of the main program and the lines after its EM."""
    body, _, tail = text.partition("\nEM\n")
    blocks = [b.splitlines() for b in body.split("; @block\n")[1:]]
    return blocks, tail.splitlines()


def test_blocks_are_self_contained(projects):
    for p in projects:
        for name, text in p.files.items():
            if not name.endswith(".src"):
                continue
            if name == p.main:
                blocks, tail = _main_blocks(text)
                tail_blocks = [b.splitlines() for b in "\n".join(tail + [""]).split("; @block\n")[1:]]
            else:
                blocks, tail_blocks = [], [b.splitlines() for b in text.split("; @block\n")[1:]]
            for block in blocks + tail_blocks:
                labels = {line.split()[1] for line in block if line.startswith("LBL ")}
                for line in block:
                    word, _, operand = line.partition(" ")
                    if word.upper() in ("JP", "JPT", "JPF"):
                        assert operand.strip() in labels, (p.seed, name, line)
                opened = sum(1 for line in block if line.endswith("[") and " " not in line)
                assert opened == sum(1 for line in block if line == "]")
            for block in tail_blocks:                  # subprograms end with EM, tables with ENDK
                assert block[0].startswith(("LBL ", "GLOBAL ", "KFIELD ")), (p.seed, name, block)
                assert block[-1].upper() in ("EM", "ENDK"), (p.seed, name, block)


def test_the_main_program_ends_outside_the_blocks(projects):
    for p in projects:
        lines = p.files[p.main].splitlines()
        em = lines.index("EM")                       # the first EM ends the main program ...
        assert lines[em + 1:em + 2] in ([], ["; @block"])
        assert lines[em - 1] != "; @block"           # ... after the last block, not inside one
        blocks, _ = _main_blocks(p.files[p.main])
        for block in blocks:                         # no subprogram inside the main program's blocks
            assert not any(line.upper() == "EM" or line.startswith("GLOBAL") for line in block)


def test_the_stack_is_balanced_in_every_block(projects):
    words = {"PS": None, "PSW": 2, "PSL": 1, "PSX": 2, "PL": None, "PLW": -2, "PLL": -1, "PLX": -2}
    for p in projects:
        blocks, _ = _main_blocks(p.files[p.main])
        for block in blocks:
            if any(line.split()[0].upper() in ("CM", "CMT", "CMF", "CASE") and not line.split()[1].isdigit()
                   for line in block if len(line.split()) > 1):
                continue                                # calls of stack subprograms move values across
            depth = 0
            for line in block:
                parts = line.split()
                if parts[:1] and parts[0].upper() == "CM" and parts[1].isdigit():       # a PLC module pulls and pushes 32-bit values
                    row = MODULE_TABLE[int(parts[1])]
                    depth -= 2 * row.nparams
                    assert depth >= 0, (p.seed, block)
                    depth += 2 * row.nresults
                    continue
                if not parts or parts[0].upper() not in words:
                    continue
                m = parts[0].upper()
                if words[m] is not None:
                    depth += words[m]
                else:
                    size = 1 if BIT_OPERAND.match(" ".join(parts[1:])) else 2
                    depth += size if m == "PS" else -size
                assert depth >= 0, (p.seed, block)
            assert depth == 0, (p.seed, block)


# ------------------------------------------------------------------------------------------------------------
# the front end and the reference interpreter accept the programs


def _compile(project: GeneratedProject, root: Path):
    main = project.write(root)
    result = compile_project(ProjectOptions(main=main, cfg=root / project.cfg if project.cfg else None),
                             make_semantics("itnc530"))
    return result, main


@pytest.mark.parametrize("seed", [2, 3, 5, 8, 13, 21, 34, 55, 89, 144, 233, 377, 610, 987, 1597, 2584, 4181,
                                  6765, 10946, 17711])
def test_front_end_accepts_generated_projects(seed, tmp_path):
    result, _ = _compile(generate(seed), tmp_path / str(seed))
    errors = [d.render() for d in result.diagnostics.items if d.severity.value == "error"]
    assert result.ok and errors == []


def test_all_features_on_and_bigger_projects_pass_the_front_end(tmp_path):
    for seed in (1, 2, 3):
        result, _ = _compile(generate(seed, size=90, enable=set(FEATURES)), tmp_path / str(seed))
        assert result.ok, [d.render() for d in result.diagnostics.items if d.severity.value == "error"]


@pytest.mark.parametrize("seed", [4, 9, 16, 25, 36])
def test_interpreter_runs_without_runtime_faults(seed, tmp_path):
    project = generate(seed, size=25)
    result, main = _compile(project, tmp_path)
    assert result.ok
    mp = read_mp_file(tmp_path / project.mp, Diagnostics()) if project.mp else {}
    machine = Machine(result.program, mp)
    for cycle in range(60):
        writes = []  # inputs stay 0: the program must be well defined for any input
        report = machine.run_cycle(cycle, writes, [])
        assert not report.faults, [f.render() for f in report.faults]


def test_fault_injection_gives_one_runtime_fault(tmp_path):
    faulted = 0
    for seed in range(6):
        project = generate(seed, size=6, faults=True)
        text = project.files[project.main]
        assert text.count("; injected runtime fault") == 1
        result, _ = _compile(project, tmp_path / str(seed))
        assert result.ok
        machine = Machine(result.program, {})
        inputs = [Write(OperandRef("I", i), 1, f"I{i}") for i in range(32)]
        for cycle in range(3):
            report = machine.run_cycle(cycle, inputs, [])
            if report.faults:
                assert report.faults[0].code.startswith("E-RT-")
                faulted += 1
                break
    assert faulted >= 4      # an EMT/EMF in front of the fault may hide it when every input is 1


# ------------------------------------------------------------------------------------------------------------
# PLC module calls and submit jobs


def test_the_module_lists_are_the_modules_that_translate():
    """Every module of the itnc530 profile that the ST back end translates is generated, with the table's shape."""
    translated = {n for n, row in MODULE_TABLE.items() if "itnc530" in row.profiles and translatable(n) is None}
    assert translated == set(generator.PURE_MODULES) | set(generator.SYS_MODULES)
    assert translatable(9006) is not None     # E-UNSUPPORTED at the CM
    for number, (params, results) in {**generator.PURE_MODULES, **generator.SYS_MODULES}.items():
        row = MODULE_TABLE[number]
        assert (len(params), results) == (row.nparams, row.nresults), number
        assert (row.kind == PURE) == (number in generator.PURE_MODULES), number
    assert set(generator.SUBMIT_ONLY_MODULES) == {n for n in generator.SYS_MODULES
                                                  if MODULE_TABLE[n].context == SUBMIT}


def _module_calls(projects):
    return collections.Counter(int(operand) for p in projects for _, m, operand in instructions(p)
                               if m == "CM" and operand.isdigit())


def test_module_calls_of_every_kind_occur(projects):
    calls = _module_calls(projects)
    kinds = collections.Counter(MODULE_TABLE[n].kind for n in calls.elements())
    assert kinds[PURE] >= 10 and kinds[DATA] >= 10 and kinds[MACHINE] >= 20, kinds
    assert set(generator.PURE_MODULES) <= set(calls)
    assert {9032, 9035, 9036} <= set(calls)
    # over more seeds every module the generator knows is called
    more = _module_calls(generate(seed, size=60) for seed in range(1000, 1150))
    assert set(generator.PURE_MODULES) | set(generator.SYS_MODULES) <= set(calls) | set(more)


def test_module_calls_push_their_parameters_and_pull_their_results(projects):
    for p in projects:
        lines = [(m, operand) for _, m, operand in instructions(p)]
        for i, (m, operand) in enumerate(lines):
            if m != "CM" or not operand.isdigit():
                continue
            row = MODULE_TABLE[int(operand)]
            assert row.kind == PURE or row.number != 9006
            pushes = lines[i - row.nparams:i] if row.nparams else []
            assert all(pm == "PS" for pm, _ in pushes), (p.seed, operand, pushes)
            kinds = {**generator.PURE_MODULES, **generator.SYS_MODULES}[row.number][0]
            for kind, (_, po) in zip(kinds, pushes):    # string numbers are constants (the ST needs them so)
                assert kind != "str" or re.fullmatch(r"K-?\d+", po), (p.seed, operand, pushes)
            j = i + 1
            for _ in range(row.nresults):               # PL operand, or PLW and a store
                assert lines[j][0] in ("PL", "PLW"), (p.seed, operand, lines[i:j + 1])
                j += 1 if lines[j][0] == "PL" else 2


def test_submit_jobs_are_queued_and_cancelled_only_where_the_translation_allows(projects):
    with_jobs = 0
    for p in projects:
        text = p.files[p.main]
        jobs = set(re.findall(r"^LBL (Job_\d+)$", text, re.M))
        blocks, tail = _main_blocks(text)
        tail_blocks = ["\n".join(b.splitlines()) for b in "\n".join(tail + [""]).split("; @block\n")[1:]]
        for name, other in p.files.items():
            if name.endswith(".src") and name != p.main:
                assert not re.search(r"^(SUBM|RPLY|CAN)\b", other, re.M | re.I), (p.seed, name)
        submitted = set(re.findall(r"^SUBM\s+(\w+)$", text, re.M | re.I))
        assert submitted == jobs, p.seed                   # every job is queued somewhere, only jobs are
        assert not re.search(r"^CM[TF]?\s+Job_", text, re.M | re.I), p.seed       # a job is never called
        for block in tail_blocks:
            own_job = re.match(r"LBL (Job_\d+)", block)
            if not own_job:                              # no submit command in a subprogram a job may call
                assert not re.search(r"^(SUBM|RPLY|CAN)\b", block, re.M | re.I), (p.seed, block)
        with_jobs += bool(jobs)
        if jobs:
            main_text = "\n".join("\n".join(b) for b in blocks)
            assert re.search(r"^SUBM\s+Job_", main_text, re.M | re.I)
    assert with_jobs >= 30
    text = "\n".join(p.files[p.main] for p in projects)
    job_text = "\n".join(b for p in projects for b in p.files[p.main].split("; @block\n") if b.startswith("LBL Job_"))
    for pattern in (r"^RPLY\s+W20\d\d$", r"^CAN\s+W20\d\d$", r"^SUBM\s+Job_\d+\n=\s+W\d+"):
        assert re.search(pattern, job_text, re.M), pattern      # inside a job: its own state, self-cancel, SUBM (0)
    assert re.search(r"^CAN\s+W20\d\d$", "\n".join(
        "\n".join(b) for p in projects for b in _main_blocks(p.files[p.main])[0]), re.M)
