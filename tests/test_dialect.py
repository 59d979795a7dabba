"""--target: matiec/openplc keep today's text; codesys/twincat get global variable lists, no VAR_EXTERNAL, every
global reference GVL-qualified as the back end builds it, their XML valid TC6 with the lists in the 3S addData, and
ST that blark parses."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest
from lxml import etree

from transpiler.backends.iec_model import Configuration, IecProject, IecVar, Pou, VarSection
from transpiler.backends.plcopen.writer import GVL_DATA_NAME, NS
from transpiler.backends.plcopen.xsd import schema_path, validate_xml
from transpiler.backends.st.check import check_blark
from transpiler.backends.st import exprs as E
from transpiler.backends.st import printer
from transpiler.backends.st.backend import StBackend
from transpiler.backends.st.dialect import GVL_NAMES, TARGETS, for_target, gvl_name
from transpiler.backends.st.layout import GROUP_TITLES
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
    assert "README.md" not in sample[target].files
    # The only folders are the editors' project, whose plc.xml is project.xml itself, and the screen masks' JSON.
    assert {name for name in sample[target].files if "/" in name and not name.startswith("masks/")} == {
        "plc_project/plc.xml", "plc_project/beremiz.xml"}
    assert {name for name in sample[target].files if name.startswith("masks/")} == {
        "masks/M_dia_wz.msk.json", "masks/M_dia_a1.msk.json", "masks/M_error.a.json"}
    assert sample[target].files["plc_project/plc.xml"] == sample[target].files["project.xml"]
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
    # The closing comment says which task to create, with the programs in order, as README.md does.
    priority = 20 if target == "twincat" else 0
    task = [f"Task HH_Cycle: cyclic, interval T#20ms, priority {priority}.",
            "It calls these programs once per cycle, in this order: Main_PGM, HH_SubmitJobs.",
            "HH_SubmitJobs must run in this same task right after Main_PGM; call neither from another task."]
    assert text.rstrip("\n").endswith("\n".join(f"(* {line} *)" for line in task))
    readme = sample[target].files["README.md"].decode()
    assert all(f"- {line}\n" in readme for line in task)


@pytest.mark.parametrize("target", ["codesys", "twincat"])
def test_gvl_targets_read_bits_with_bit_access_instead_of_the_helper(sample, target):
    # Catches: the HH_BIT helper kept where the target reads a bit itself, a widened INT read above its width
    # (bit 15 is its sign, which INT_TO_DINT repeats), or the matiec text losing its helper.
    text = sample[target].files["project.st"].decode()
    assert "HH_BIT(" not in text and "FUNCTION HH_BIT " not in text
    assert "GVL_Markers.M6001 := GVL_Words.DG_pocket_occ_low.1;" in text
    assert "HH_BIT(" in sample["matiec"].files["project.st"].decode()


def test_a_bit_of_a_widened_word_is_read_below_its_width():
    # Catches: a widened INT or SINT read above its width (bit 15 is its sign, which INT_TO_DINT repeats), or the
    # helper's form changed for matiec.
    word, byte = E.to_dint(E.var("GVL_Words.W", "INT")), E.to_dint(E.var("B", "SINT"))
    assert [E.bit_of(word, 3, True).text, E.bit_of(word, 20, True).text, E.bit_of(byte, 9, True).text] == [
        "GVL_Words.W.3", "GVL_Words.W.15", "B.7"]
    assert E.bit_of(E.var("D", "DINT"), 31, True).text == "D.31"
    assert E.bit_of(E.var("W", "INT"), 3, False).text == "HH_BIT(INT_TO_DINT(W), 3)"
    assert E.bit_of(word, 3, True).deps == {"W"}


def test_codesys_reads_bits_of_words_and_stack_entries_with_bit_access_in_the_tree(tmp_path):
    # Catches: a bit read left to the helper on a target with bit access (the emulated stack's bit entries
    # included), the helper declared although nothing calls it, or a body that is not the printed tree.
    projects = _built(tmp_path, "PS I0\nCM 9019\nPL D0\nPL M0\nL W20\nB= M8\nEM\n")
    (main,) = _translated(projects["codesys"]).values()
    assert main.statements and printer.body_text(main.statements) == main.body
    assert "GVL_Markers.M0 := GVL_Registers.HH_STACK[GVL_Registers.HH_SP].7;" in main.body
    assert "GVL_Markers.M9 := tmp3.1;" in main.body and "HH_BIT" not in main.body
    assert "HH_BIT" not in {p.name for p in projects["codesys"].pous}
    assert "HH_BIT" in {p.name for p in projects["matiec"].pous}
    if importlib.util.find_spec("blark") is not None:
        laid_out = for_target(projects["codesys"], "codesys")
        assert check_blark(render_target_st(laid_out), "bits.st") == []


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
    # CODESYS rejects a configuration on import (and everything under it): there is none, the task is described
    assert root.find(f".//{{{NS}}}configuration") is None and root.find(f"{{{NS}}}instances/{{{NS}}}configurations") \
        is not None
    assert b"<task " not in xml and b"pouInstance" not in xml
    lists = root.findall(f"{{{NS}}}addData/{{{NS}}}data[@name='{GVL_DATA_NAME}']/{{{NS}}}globalVars")
    assert [g.get("name") for g in lists] == ["GVL_IO", "GVL_NC", "GVL_Markers", "GVL_TimersCounters", "GVL_Words",
                                              "GVL_Strings", "GVL_MachineParams", "GVL_Constants", "GVL_Registers",
                                              "GVL_Jobs", "GVL_MachineData"]
    # the PLC data tables are kept over a power cycle: only their list is retained
    assert [g.get("name") for g in lists if g.get("retain") == "true"] == ["GVL_MachineData"]
    assert all(g.find(f".//{{{NS}}}Attribute[@Name='qualified_only']") is not None for g in lists)


def test_for_target_moves_the_globals_into_lists_and_drops_the_externals():
    # Catches: a body or statement tree touched by the layout (references are written by the back end), a global
    # section left in the configuration, or the matiec project not returned as it is.
    body = "x := GVL_Markers.g1;"
    pou = Pou("P", "PROGRAM", (VarSection("VAR", (IecVar("x", "INT"),)),
                               VarSection("VAR_EXTERNAL", (IecVar("g1", "INT"),))), body, statements=("tree",))
    conf = Configuration("C", "R", (), (), (VarSection("VAR_GLOBAL", (IecVar("g1", "INT"),), comment="Markers"),
                                            VarSection("VAR_GLOBAL", (IecVar("g2", "INT"),), comment="Odd group")))
    out = for_target(IecProject("P", (), (pou,), conf), "codesys")
    (laid_out,) = out.project.pous
    assert (laid_out.body, laid_out.statements) == (body, ("tree",))
    assert [s.kind for s in laid_out.sections] == ["VAR"]
    assert [(g.name, [v.name for s in g.sections for v in s.vars]) for g in out.gvls] == [
        ("GVL_Markers", ["g1"]), ("GVL_OddGroup", ["g2"])]
    assert out.project.configuration.globals == ()
    assert "GVL_Markers" in render_target_st(out)
    assert for_target(IecProject("P", (), (pou,), conf), "matiec").project.pous[0] is pou
    assert render_target_st(for_target(IecProject("P", (), (pou,), conf), "matiec")) == \
        render_st(IecProject("P", (), (pou,), conf))


def _built(tmp_path, source: str) -> dict[str, IecProject]:
    """The back end's project of `source` for matiec and for codesys."""
    (tmp_path / "main.src").write_text(source)
    result = compile_project(ProjectOptions(main=tmp_path / "main.src"), make_semantics("itnc530", {}))
    assert result.ok, [d.render() for d in result.diagnostics.items]
    return {t: StBackend(result.program, Diagnostics(), dialect=TARGETS[t]).build().project
            for t in ("matiec", "codesys")}


def _translated(project: IecProject) -> dict[str, Pou]:
    return {p.name: p for p in project.pous if p.name in ("main", "Clamp")}


def test_codesys_bodies_are_printed_from_the_tree_with_each_global_qualified_and_no_local(tmp_path):
    # Catches: a body rewritten as text after printing (the tree no longer says what is written), a global
    # written without its list, or a local (the subprogram's instance, a temporary) qualified as if it were one.
    projects = _built(tmp_path, "L D8\n+ D12\nx D16\n= D4\nCM Clamp\nEM\nLBL Clamp\nL I0\n= O0\nEM\n")
    pous = _translated(projects["codesys"])
    assert set(pous) == {"main", "Clamp"}
    for pou in pous.values():
        assert pou.statements and printer.body_text(pou.statements) == pou.body
    main = pous["main"].body
    assert "tmp1 := HH_ADD(GVL_Words.D8, GVL_Words.D12);" in main
    assert "GVL_Words.D4 := HH_MUL(tmp1, GVL_Words.D16);" in main and "GVL_NC.M4200 := " in main
    assert "Clamp_1();" in main and not re.search(r"\.(Clamp_1|tmp1)\b", main)
    assert "GVL_IO.O0 := GVL_IO.I0;" in pous["Clamp"].body
    assert "GVL_" not in "".join(p.body for p in _translated(projects["matiec"]).values())


def test_the_clean_up_passes_do_the_same_on_every_target(tmp_path):
    # Catches: a pass that matches a qualified name against the plain one and so keeps a dead register or marker
    # store, joins other IFs or propagates other temporaries on a GVL target than on matiec.
    projects = _built(tmp_path, "L W10\nx K4\n= W0\nL W12\nx K6\n= W2\nL M4200\n= M1\nL W14\nx W16\n= W4\n"
                                "L I0\nS M5\nL I0\nR M6\nL W40\n= X\nCM Clamp\nL K1\n= B20[X]\nL W42\n= X\nEM\n"
                                "LBL Clamp\nL I0\n= O0\nEM\n")
    qualifier = re.compile(r"\b(?:" + "|".join(GVL_NAMES) + r")\.")
    matiec, codesys = _translated(projects["matiec"]), _translated(projects["codesys"])
    assert {n: qualifier.sub("", p.body) for n, p in codesys.items()} == {n: p.body for n, p in matiec.items()}
    assert codesys["main"].body != matiec["main"].body


def test_every_group_of_globals_lands_in_a_known_list():
    # Catches: a new group of globals without a row in GVL_BY_TITLE: its references would carry a qualifier that
    # the clean-up passes do not recognise (exprs.unqualified).
    assert {gvl_name(title) for title in GROUP_TITLES.values()} <= GVL_NAMES


def test_a_qualified_reference_names_its_variable():
    # Catches: the list taken for the variable (GVL_Words.D[3] read as GVL_WORDS), or a member or bit (fb.Q, w.3)
    # taken for a qualifier.
    assert E.base_name("GVL_Words.HH_MEM[GVL_Registers.HH_X + 3]") == "HH_MEM"
    assert E.base_name("GVL_Jobs.HH_Jobs.RESULT") == "HH_JOBS" and E.base_name("inst.Q") == "INST"
    assert E.unqualified("GVL_IO.I5") == "I5" and E.unqualified("GVL_IO.3") == "GVL_IO.3"
    # a member path counts with its head (a marker STRUCT's member is a variable of its own)
    assert E.names_in("GVL_Words.HH_MEM[GVL_Registers.HH_X + 3] AND fb.Q OR NOT GVL_Jobs.HH_Jobs.RESULT") == {
        "HH_MEM", "HH_X", "AND", "FB", "FB.Q", "OR", "NOT", "HH_JOBS", "HH_JOBS.RESULT"}
    assert E.target_name("GVL_Markers.ML_ax.inpos") == "ML_AX.INPOS" and E.target_name("GVL_Words.HH_MEM[3]") == "HH_MEM"


def test_unknown_target_is_refused():
    with pytest.raises(ValueError, match="known: matiec"):
        for_target(IecProject("P", (), (), Configuration("C", "R", (), (), ())), "s7")


def test_report_says_how_to_load_each_target_with_the_names_written(sample):
    # Catches: steps that name another configuration, task or program than the files hold, or lose the order of the
    # two programs (the submit-job program runs after the main program in the same task).
    def section(target: str) -> str:
        report = sample[target].files["report.md"].decode()
        return report.split("## How to load this on ", 1)[1]
    openplc = section("openplc")
    assert openplc.startswith("OpenPLC") and "`project.st` as it is" in openplc
    assert "CONFIGURATION `Config0` with RESOURCE `Res0`" in openplc and "`plc_project/`" in openplc
    assert "calls `PLC_Main_PGM` (PROGRAM `Main_PGM`) then `PLC_HH_SubmitJobs` (PROGRAM `HH_SubmitJobs`)" in openplc
    assert "(42 inputs, 30 outputs" in openplc
    assert section("matiec").startswith("Beremiz") and "task `HH_Cycle`: cyclic, every 20 ms" in section("matiec")
    codesys, readme = section("codesys"), sample["codesys"].files["README.md"].decode()
    assert "- It calls these programs once per cycle, in this order: Main_PGM, HH_SubmitJobs." in codesys
    assert codesys.split("### Loading it", 1)[1].split("### The task")[0].strip() \
        == readme.split("## Loading it", 1)[1].split("## The task")[0].strip()
    assert "twincat/Main_PGM/Main_PGM.plcproj" in section("twincat")


def test_load_steps_name_only_files_that_were_written():
    result = compile_project(ProjectOptions(main=SAMPLE / "Main_PGM.src", cfg=SAMPLE / "OEM.cfg"),
                             make_semantics("itnc530"))
    mp = read_mp_file(SAMPLE / "MP_data.mp", Diagnostics())
    for target in ("openplc", "matiec"):
        st_only = transpile_program(result.program, Diagnostics(), mp, {"st"}, mp_file=SAMPLE / "MP_data.mp",
                                    target=target).files
        steps = st_only["report.md"].decode().split("## How to load this on ", 1)[1]
        assert "plc_project" not in steps and not any(name.startswith("plc_project/") for name in st_only)
    xml_only = transpile_program(result.program, Diagnostics(), mp, {"xml"}, mp_file=SAMPLE / "MP_data.mp",
                                 target="openplc").files
    steps = xml_only["report.md"].decode().split("## How to load this on ", 1)[1]
    assert "not written this time" in steps and "`plc_project/`" in steps
