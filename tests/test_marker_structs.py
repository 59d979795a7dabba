"""Marker structs (A-62): the markers of one symbol prefix become the members of one STRUCT where the I/O map stays
exact, every other prefix stays separate variables with its reason in report.md, and the co-simulation reads and
writes the members on both executors."""

from __future__ import annotations

import csv
import io
import re

import pytest

from tests.text_project import BACKENDS, cosim, translate
from transpiler.backends.st.marker_groups import MIN_MEMBERS, MarkerGroup, SymbolicOperand, plan_groups, split_symbol


def _markers(*symbols: str, first: int = 10) -> list[SymbolicOperand]:
    return [SymbolicOperand("M", first + k, s) for k, s in enumerate(symbols)]


def _free(name: str) -> str | None:
    return None


def test_split_symbol_takes_the_first_two_parts_as_prefix():
    assert split_symbol("ML_ax_inpos") == ("ML_ax", "inpos")
    assert split_symbol("ML_ax_clamp_start") == ("ML_ax", "clamp_start")
    assert split_symbol("MG_ok") is None
    assert split_symbol("ML__x_y") is None and split_symbol("ML_ax_") is None


def test_markers_sharing_a_prefix_make_one_group():
    groups, refusals = plan_groups(_markers("ML_ax_inpos", "ML_ax_clamp_start", "ML_ax_fault", "MG_ok"), _free)
    assert groups == [MarkerGroup("ML_ax", "T_ML_ax", ((10, "inpos"), (11, "clamp_start"), (12, "fault")))]
    assert refusals == []
    assert groups[0].path("inpos") == "ML_ax.inpos"


def test_group_addresses_as_ranges():
    group = MarkerGroup("MG_mag", "T_MG_mag", ((24, "a"), (25, "b"), (26, "c"), (1000, "d")))
    assert group.addresses() == "M24-M26, M1000"


@pytest.mark.parametrize("count", [1, MIN_MEMBERS - 1])
def test_too_few_markers_are_no_group_and_no_refusal(count):
    groups, refusals = plan_groups(_markers(*[f"ML_ax_m{k}" for k in range(count)]), _free)
    assert groups == [] and refusals == []


@pytest.mark.parametrize("operands, reason", [
    (_markers("ML_ax_a", "ML_ax_b", "ML_ax_AND"), "member 'AND' of ML_ax_AND is an IEC keyword or standard name"),
    (_markers("ML_ax_a", "ML_ax_b", "ML_ax_ON"), "member 'ON' of ML_ax_ON is an IEC keyword or standard name"),
    (_markers("ML_ax_a", "ML_ax_b", "ML_ax_4"), "member '4' of ML_ax_4 is no IEC identifier"),
    (_markers("ML_ax_a", "ML_ax_b", "ML_ax_4_mem"), "member '4_mem' of ML_ax_4_mem is no IEC identifier"),
    (_markers("ML_ax_a", "ML_ax_b", "ML_ax_A"), "members 'a' and 'A' differ only in case"),
    (_markers("ML_ax_a", "ML_ax_b", "ml_AX_c"), "the prefix is spelled ML_ax and ml_AX"),
    (_markers("ML_ax_a", "ML_ax_b", "ML_ax_c") + [SymbolicOperand("I", 5, "ML_ax_sensor", "an input")],
     "ML_ax_sensor (I5) is an input, not a plain marker"),
    (_markers("ML_ax_a", "ML_ax_b") + [SymbolicOperand("M", 4200, "ML_ax_err", "a marker of the NC interface")],
     "ML_ax_err (M4200) is a marker of the NC interface, not a plain marker"),
    (_markers("ML_ax_a", "ML_ax_b") + [SymbolicOperand("M", 1000, "ML_ax_kept", retained=True)],
     "ML_ax_kept (M1000) is non-volatile (A-44) and ML_ax_a (M10) is not: RETAIN applies to a whole STRUCT"),
    (_markers("HH_ax_a", "HH_ax_b", "HH_ax_c"), "the group name HH_ax would take the translator's HH_ prefix"),
], ids=["keyword", "keyword_on", "digit", "digit_mem", "case", "spelling", "input", "nc_marker", "retain", "hh"])
def test_a_refused_prefix_stays_separate_with_one_reason(operands, reason):
    groups, refusals = plan_groups(operands, _free)
    assert groups == []
    assert [(r.prefix, r.reason) for r in refusals] == [(refusals[0].prefix, reason)]


@pytest.mark.parametrize("taken, reason", [
    ("ML_ax", "the group name ML_ax is the name of a POU"),
    ("T_ML_ax", "the type name T_ML_ax is the name of a POU"),
])
def test_a_name_in_use_refuses_the_group(taken, reason):
    def in_use(name: str) -> str | None:
        return "the name of a POU" if name.upper() == taken.upper() else None
    groups, refusals = plan_groups(_markers("ML_ax_a", "ML_ax_b", "ML_ax_c"), in_use)
    assert groups == [] and [r.reason for r in refusals] == [reason]


# End to end: ML_ax is grouped (reached directly and through the index register), ML_io stays separate for its
# input, ML_kw for a keyword member, ML_tc for a word symbol that is its type name, ML_pair has two markers only.
DEFS = """\
ML_ax_inpos    M 42
ML_ax_clamp    M 43
ML_ax_fault    M 44
ML_io_a        M 60
ML_io_b        M 61
ML_io_c        I 3
ML_io_d        M 62
ML_kw_a        M 70
ML_kw_b        M 71
ML_kw_AND      M 72
ML_tc_a        M 80
ML_tc_b        M 81
ML_tc_c        M 82
T_ML_tc        W 20
ML_pair_a      M 90
ML_pair_b      M 91
"""

PROGRAM = """\
#define /g defs.def
; the value in flight reads inpos and no other member: the store to clamp saves nothing
L     I0
=     ML_ax_inpos
L     ML_ax_inpos
=     ML_ax_clamp
=     ML_ax_fault
; the value in flight reads the member it is stored to: it must be kept for O2
LN    ML_ax_fault
=     ML_ax_fault
=     O2
; through the index register: M42 + W10 is ML_ax_inpos, ML_ax_clamp or ML_ax_fault
L     W10
=     X
L     I1
=     M42[X]
L     M43[X]
=     O1
L     ML_io_c
=     ML_io_a
=     ML_io_b
=     ML_io_d
L     ML_kw_a
=     ML_kw_b
=     ML_kw_AND
L     ML_tc_a
=     ML_tc_b
=     ML_tc_c
L     T_ML_tc
=     W22
L     ML_pair_a
=     ML_pair_b
EM
"""

SCENARIO = """\
name: marker_structs
cycles: 8
initial: {W10: 0, I0: 1, I1: 0}
events:
  - {cycle: 2, set: {I1: 1, W10: 1}}
  - {cycle: 4, set: {I0: 0, W10: 2}}
  - {cycle: 6, set: {I1: 0, W10: 0, I3: 1}}
"""


def _project(folder, **semantics):
    return translate(folder, PROGRAM, SCENARIO, files={"defs.def": DEFS}, semantics=semantics,
                     formats=frozenset({"st", "xml"}))


@pytest.fixture(scope="module")
def grouped(tmp_path_factory):
    return _project(tmp_path_factory.mktemp("marker_structs"))


def _io_rows(out) -> dict[str, str]:
    return {r["operand"]: r["iec_variable"] for r in csv.DictReader(io.StringIO(out.files["io_map.csv"].decode()))}


def test_the_io_map_names_the_member_paths(grouped):
    _, out, _, _ = grouped
    rows = _io_rows(out)
    assert (rows["M42"], rows["M43"], rows["M44"]) == ("ML_ax.inpos", "ML_ax.clamp", "ML_ax.fault")
    assert (rows["M60"], rows["M70"], rows["M80"], rows["M90"]) == ("ML_io_a", "ML_kw_a", "ML_tc_a", "ML_pair_a")
    st = out.st_text
    assert re.search(r"T_ML_ax : STRUCT\n\s+inpos : BOOL; \(\* M42 \*\)\n\s+clamp : BOOL;", st)
    assert "    ML_ax : T_ML_ax; (* the markers ML_ax_* (M42-M44) *)" in st
    # the accessor of indexed access names the member
    assert "42: ML_ax.inpos := VALUE;" in st and "43: Q := ML_ax.clamp;" in st
    # a store to one member saves nothing that reads another one; one that reads the member stored to is saved
    assert "ML_ax.inpos := I0;\n    ML_ax.clamp := ML_ax.inpos;\n    ML_ax.fault := ML_ax.clamp;\n" in st
    assert "HH_LA := NOT ML_ax.fault;\n    ML_ax.fault := HH_LA;\n    O2 := ML_ax.fault;\n" in st


def test_the_report_lists_the_groups_and_the_refusals(grouped):
    _, out, _, _ = grouped
    report = out.files["report.md"].decode()
    section = report[report.index("## Marker structs"):report.index("## Not translated")]
    assert "- `ML_ax : T_ML_ax`: 3 markers, M42-M44" in section
    assert "- `ML_io_*`: ML_io_c (I3) is an input, not a plain marker" in section
    assert "- `ML_kw_*`: member 'AND' of ML_kw_AND is an IEC keyword or standard name" in section
    assert "- `ML_tc_*`: the type name T_ML_tc is a symbol of the program" in section
    assert "ML_pair" not in section


@pytest.mark.parametrize("backend", BACKENDS)
def test_grouped_translation_is_equivalent(grouped, backend):
    result = cosim(grouped, backend=backend)
    assert result.equivalent, (result.divergence, result.error)
    assert {"M42", "M43", "M44"} <= set(result.compared_operands)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_wrong_member_store_diverges(grouped, backend):
    """The members are compared: an indexed store that reaches the wrong member (M43 for M44) shows at it."""
    broken, count = re.subn(r"44: ML_ax\.fault := VALUE;", "44: ML_ax.clamp := VALUE;", grouped.out.st_text)
    assert count == 1, "the mutation site moved: update the test"
    result = cosim(grouped, broken, backend)
    d = result.divergence
    assert d is not None and (d.cycle, d.operand, d.original, d.translated) == (4, "M43", 0, 1)


def test_switched_off_every_marker_is_a_variable(tmp_path, grouped):
    flat_project = _project(tmp_path, marker_structs=False)
    out = flat_project.out
    assert _io_rows(out)["M42"] == "ML_ax_inpos" and "STRUCT" not in out.st_text
    assert "marker_structs = false" in out.files["report.md"].decode()
    # the statements are the same, only the names differ
    flat = grouped[1].st_text
    for member in ("inpos", "clamp", "fault"):
        flat = flat.replace(f"ML_ax.{member}", f"ML_ax_{member}")
    body = lambda text: text[text.index("PROGRAM main"):text.index("END_PROGRAM")]   # noqa: E731
    assert [line for line in body(flat).splitlines() if "VAR" not in line and " : " not in line] == \
        [line for line in body(out.st_text).splitlines() if "VAR" not in line and " : " not in line]
    result = cosim(flat_project)
    assert result.equivalent, (result.divergence, result.error)
