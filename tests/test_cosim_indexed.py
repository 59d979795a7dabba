"""Co-simulation compares operands the program reaches only through the index register (`= M200[X]`, `= W100[X]`,
`= S2[X]`) from the cycle of their first indexed store: a translation that stores to the wrong indexed address, or
the wrong value there, diverges even though no instruction ever reads that address directly."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.text_project import BACKENDS, cosim, translate

ROOT = Path(__file__).resolve().parents[1]

# The index comes from W10, which the scenario sets, so the translator cannot fold the addresses to constants.
PROGRAM = """\
; indexed stores whose index comes from the scenario (W10)
L     W10
=     X
L     I0
=     M200[X]
L     K77
=     W100[X]
L     K-5
=     D300[X]
L     I1
S     M400[X]
L     S"AB"
=     S2[X]
L     K1
=     I20[X]
L     K5
B=    M600[X]
EM
"""

# X = 4 for three cycles, then X = 8: the addresses of the first cycles stay compared.
SCENARIO = """\
name: indexed_stores
cycles: 6
initial: {W10: 4, I0: 1, I1: 1}
events:
  - {cycle: 3, set: {W10: 8, I0: 0}}
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("indexed")


@pytest.fixture(scope="module")
def project(folder):
    return translate(folder, PROGRAM, SCENARIO)


@pytest.mark.parametrize("backend", BACKENDS)
def test_unmodified_translation_is_equivalent(project, backend):
    """Includes `= I20[X]`: from cycle 3 (X = 8) the input latch restores I24 on both sides, the ST side because the
    harness latches an input from its first indexed store on."""
    result = cosim(project, backend=backend)
    assert result.equivalent, (result.divergence, result.error)
    assert result.cycles_run == 6
    # M204 M208, W104/W108 and D304/D308 as bytes, M404 M408, S6 S10, I24 I28, and the byte of bits M604..M611
    # and M608..M615 (overlapping): none is named in the program.
    assert result.compared_indexed == 2 * (1 + 2 + 4 + 1 + 1 + 1) + 12


@pytest.mark.parametrize("pattern, replacement, operand, original, translated", [
    (r"IDX := 200 \+", "IDX := 201 +", "M204", 1, 0),            # = M200[X]: wrong bit address
    (r"HH_MEM\[100 \+ ", "HH_MEM[102 + ", "B104", 77, 0),         # = W100[X]: low byte to the wrong address
    (r"(HH_MEM\[300 \+ [^\]]*\] := )251;", r"\g<1>250;", "B304", -5, -6),  # = D300[X]: wrong value, right address
    (r"IDX := 400 \+ (\w+), WRITE := TRUE", r"IDX := 401 + \1, WRITE := TRUE", "M404", 1, 0),   # S M400[X]
    (r"HH_S\[2 \+ ", "HH_S[3 + ", "S6", "AB", ""),                # = S2[X]
    (r"IDX := 600 \+", "IDX := 601 +", "M604", 1, 0),            # B= M600[X]: bit 0 of K5 to the wrong bit
], ids=["bit", "word_address", "dword_value", "set_bit", "string", "bit_field"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_wrong_indexed_store_diverges(project, pattern, replacement, operand, original, translated, backend):
    broken, count = re.subn(pattern, replacement, project.out.st_text)
    assert count == 1, "the mutation site moved: update the test"
    result = cosim(project, broken, backend)
    assert result.error is None
    d = result.divergence
    assert d is not None, "a wrong indexed store must be seen"
    assert (d.cycle, d.operand, d.name, d.original, d.translated) == (0, operand, operand, original, translated)


def test_indexed_addresses_stay_compared_after_x_moves_on(project):
    """M204 is first stored to while X = 4; the broken translation clears it in cycle 3, when X = 8 and no
    instruction of that cycle reaches M204: the divergence shows that the address is still compared."""
    clear = "    IF HH_MEM[10] = 8 THEN HH_M_index(IDX := 204, WRITE := TRUE, VALUE := FALSE); END_IF;\n"
    broken = project.out.st_text.replace("END_PROGRAM", clear + "END_PROGRAM", 1)
    result = cosim(project, broken)
    d = result.divergence
    assert d is not None and (d.cycle, d.operand, d.original, d.translated) == (3, "M204", 1, 0)


def test_machine_records_indexed_stores_as_operands(project):
    result = cosim(project)
    writes = result.machine.indexed_writes()
    assert ("M", 204) in writes and ("S", 6) in writes and ("I", 24) in writes and ("M", 611) in writes
    assert {("B", b) for b in range(104, 106)} | {("B", b) for b in range(304, 308)} <= set(writes)
    assert not any(kind in "WD" for kind, _ in writes)      # byte memory is reported byte by byte
    assert result.machine.indexed_writes(result.machine.indexed_write_count) == []


def test_program_without_indexed_stores_adds_nothing(tmp_path):
    project = translate(tmp_path, "L     W10\n=     X\nL     M200[X]\n=     O1\nEM\n",
                        "name: reads\ncycles: 3\ninitial: {W10: 4, M204: 1}\n")
    result = cosim(project)
    assert result.equivalent, (result.divergence, result.error)
    assert result.compared_indexed == 0 and result.machine.indexed_write_count == 0


def test_cli_reports_indexed_addresses(folder, project, tmp_path):
    proc = subprocess.run([sys.executable, "-m", "transpiler.cli", "equiv", str(folder / "main.src"),
                           "--scenario", str(folder / "scenario.yaml"), "--backend", "builtin",
                           "--report", str(tmp_path / "r.json"), "-v"],
                          capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "+ 32 indexed addresses from their first indexed store" in proc.stdout
    run = json.loads((tmp_path / "r.json").read_text())["runs"][0]
    assert run["compared_indexed_addresses"] == 32


# Indexed reads leave their value in the accessor instance's Q (no temporary): S through the index with LA still
# needed after it, a value still needed after a write to the same operand, and reads and writes in a loop over X.
READS = """\
L     M5
L     W10
=     X
S     M300[X]
=     O2
L     M200[X]
R     M200[X]
=     O1
L     K0
=     X
LBL   Loop
L     M210[X]
O     M220[X]
=     M230[X]
L     M240[X]
S     M250[X]
INCX
L     X
<     K3
JPT   Loop
EM
"""

READS_SCENARIO = """\
name: indexed_reads
cycles: 4
initial: {W10: 4, M5: 1, M204: 1, M210: 1, M221: 1, M240: 1, M242: 1}
events:
  - {cycle: 2, set: {M5: 0, W10: 5}}
"""


@pytest.mark.parametrize("backend", BACKENDS)
def test_indexed_reads_keep_the_value_of_their_instruction(tmp_path, backend):
    project = translate(tmp_path, READS, READS_SCENARIO)
    st = project.out.st_text
    assert "tmp" not in st
    result = cosim(project, backend=backend)
    assert result.equivalent, (result.divergence, result.error)
    # The value stored to O1 is the one read before the write: reading the instance that wrote breaks it.
    broken, count = re.subn(r"O1 := HH_M_index\.Q;", "O1 := HH_M_index_2.Q;", st)
    assert count == 1, "the mutation site moved: update the test"
    d = cosim(project, broken, backend).divergence
    assert d is not None and d.operand == "O1"
