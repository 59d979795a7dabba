"""--target: matiec/openplc keep today's text; codesys/twincat get global variable lists, no VAR_EXTERNAL, every
global reference GVL-qualified, their XML valid TC6 with the lists in the 3S addData, and ST that blark parses."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from lxml import etree

from transpiler.backends.iec_model import Configuration, IecProject, IecVar, Pou, VarSection
from transpiler.backends.plcopen.writer import GVL_DATA_NAME, NS, render_target_xml
from transpiler.backends.plcopen.xsd import schema_path, validate_xml
from transpiler.backends.st.check import check_blark
from transpiler.backends.st.dialect import TARGETS, for_target
from transpiler.backends.st.writer import render_st, render_target_st
from transpiler.backends.transpile import transpile_program
from transpiler.diagnostics import Diagnostics
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.mpfile import read_mp_file
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "basic_program"
GOLDEN = ROOT / "tests" / "golden" / "basic_program"


@pytest.fixture(scope="module")
def sample():
    result = compile_project(ProjectOptions(main=SAMPLE / "Main_PGM.src", cfg=SAMPLE / "OEM.cfg"),
                             make_semantics("itnc530"))
    assert result.ok
    diags = Diagnostics()
    mp = read_mp_file(SAMPLE / "MP_data.mp", diags)
    return {t: transpile_program(result.program, Diagnostics(), mp, {"st", "xml"}, mp_file=SAMPLE / "MP_data.mp",
                                 target=t) for t in TARGETS}


@pytest.mark.parametrize("target", ["matiec", "openplc"])
def test_matiec_targets_write_the_golden_text(sample, target):
    assert sample[target].files["project.st"] == (GOLDEN / "project.st").read_bytes()
    stamp = re.compile(rb"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d")
    assert stamp.sub(b"", sample[target].files["project.xml"]) == stamp.sub(b"", sample["matiec"].files["project.xml"])
    assert b"externalVars" in sample[target].files["project.xml"]


@pytest.mark.parametrize("target", ["codesys", "twincat"])
def test_gvl_targets_have_no_externals_and_qualify_every_global(sample, target):
    text = sample[target].files["project.st"].decode()
    assert "VAR_EXTERNAL" not in text and "CONFIGURATION" not in text
    assert text.count("{attribute 'qualified_only'}") == text.count("(* Global variable list ")
    assert "GVL_IO.I_estop_chain_ok" in text
    # No POU body names a global without its list: every global name outside the GVL blocks is preceded by "GVL_x.".
    project = sample[target].result.project
    names = {v.name for s in project.configuration.globals for v in s.vars}
    bodies = text.split("(* Task configuration")[0]
    pous_part = bodies[bodies.index("END_VAR", bodies.rindex("(* Global variable list ")):]
    pous_part = re.sub(r"\(\*.*?\*\)", "", pous_part, flags=re.S)
    for match in re.finditer(r"(?<![\w.])([A-Za-z_]\w*)", pous_part):
        assert match.group(1) not in names, f"unqualified global {match.group(1)}"
    # The co-simulated text stays the matiec one.
    assert sample[target].st_text == sample["matiec"].st_text
    assert f"## Target: {target}" in sample[target].files["report.md"].decode()


@pytest.mark.parametrize("target", ["codesys", "twincat"])
def test_gvl_targets_read_bits_with_bit_access_instead_of_the_helper(sample, target):
    # Catches: the HH_BIT helper kept where the target reads a bit itself, a widened INT read above its width
    # (bit 15 is its sign, which INT_TO_DINT repeats), or the matiec text losing its helper.
    text = sample[target].files["project.st"].decode()
    assert "HH_BIT(" not in text and "FUNCTION HH_BIT " not in text
    assert "GVL_Markers.M6001 := GVL_Words.DG_pocket_occ_low.1;" in text
    assert "HH_BIT(" in sample["matiec"].files["project.st"].decode()
    from transpiler.backends.st.dialect import _with_bit_access
    body = "a := HH_BIT(INT_TO_DINT(W), 3) AND HH_BIT(INT_TO_DINT(W), 20) OR HH_BIT(SINT_TO_DINT(B), 9);\nc := HH_BIT(D, 31);"
    (pou,) = _with_bit_access((Pou("P", "PROGRAM", (), body),))
    assert pou.body == "a := W.3 AND W.15 OR B.7;\nc := D.31;"


@pytest.mark.parametrize("target", ["codesys", "twincat"])
def test_gvl_targets_parse_with_blark(sample, target):
    pytest.importorskip("blark")
    assert check_blark(sample[target].files["project.st"].decode(), "project.st") == []


@pytest.mark.skipif(schema_path() is None, reason="TC6 schema not cached (hh2iec fetch-schema)")
@pytest.mark.parametrize("target", ["codesys", "twincat"])
def test_gvl_target_xml_validates_and_holds_the_lists(sample, target):
    xml = sample[target].files["project.xml"]
    assert validate_xml(xml) == []
    root = etree.fromstring(xml)
    assert not root.findall(f".//{{{NS}}}externalVars")
    assert root.find(f".//{{{NS}}}configuration/{{{NS}}}globalVars") is None
    lists = root.findall(f"{{{NS}}}addData/{{{NS}}}data[@name='{GVL_DATA_NAME}']/{{{NS}}}globalVars")
    assert [g.get("name") for g in lists] == ["GVL_IO", "GVL_NC", "GVL_Markers", "GVL_TimersCounters", "GVL_Words",
                                              "GVL_Strings", "GVL_MachineParams", "GVL_Constants", "GVL_Registers",
                                              "GVL_Jobs"]
    assert all(g.find(f".//{{{NS}}}Attribute[@Name='qualified_only']") is not None for g in lists)


def test_qualification_skips_locals_members_literals_strings_and_comments():
    body = ("x := g1 + 16#1F + T#10ms; (* g1 in a comment *)\ns := 'g1';\nfb.g1 := g1;\ng2 := 1.5E3;")
    pou = Pou("P", "PROGRAM", (VarSection("VAR", (IecVar("x", "INT"), IecVar("g2", "INT"))),
                               VarSection("VAR_EXTERNAL", (IecVar("g1", "INT"), IecVar("g2", "INT")))), body)
    conf = Configuration("C", "R", (), (), (VarSection("VAR_GLOBAL", (IecVar("g1", "INT"), IecVar("g2", "INT")),
                                                        comment="Markers"),))
    out = for_target(IecProject("P", (), (pou,), conf), "codesys")
    assert out.project.pous[0].body == ("x := GVL_Markers.g1 + 16#1F + T#10ms; (* g1 in a comment *)\n"
                                        "s := 'g1';\nfb.g1 := GVL_Markers.g1;\ng2 := 1.5E3;")
    assert all(s.kind != "VAR_EXTERNAL" for s in out.project.pous[0].sections)
    assert "GVL_Markers" in render_target_st(out)
    assert for_target(IecProject("P", (), (pou,), conf), "matiec").project.pous[0] is pou
    assert render_target_st(for_target(IecProject("P", (), (pou,), conf), "matiec")) == \
        render_st(IecProject("P", (), (pou,), conf))


def test_unknown_target_is_refused():
    with pytest.raises(ValueError, match="known: matiec"):
        for_target(IecProject("P", (), (), Configuration("C", "R", (), (), ())), "s7")
