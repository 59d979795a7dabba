"""Tests of the ST container: layout, body round trip, determinism; also holds the hand-made projects other tests use."""

from __future__ import annotations

import dataclasses
import re

import pytest

from transpiler.backends.iec_model import (
    ArrayDim,
    Configuration,
    DataType,
    IecProject,
    IecVar,
    Pou,
    ProgramInstance,
    SourceRange,
    Task,
    VarSection,
)
from transpiler.backends.st.writer import extract_pou_bodies, render_st

# Comment text that must survive every container: XML specials, a CDATA terminator,
# ST comment markers, non-ASCII, a control character and a line break.
NASTY = "a & b < c > d ]]> e (* f *) g ü ß 😀 \x01 h\nsecond line"

ADD_SAT_BODY = """\
tmp := INT_TO_DINT(a) + INT_TO_DINT(b);
IF tmp > 32767 THEN (* clamp when a & b are too big *)
    AddSat := 32767;
ELSIF tmp < -32768 THEN
    AddSat := -32768;
ELSE
    AddSat := DINT_TO_INT(tmp);
END_IF;"""

COUNTER_BODY = """\
edge(CLK := enable);
IF edge.Q AND (count < maxCount) THEN
    count := AddSat(a := count, b := 1);
    mem[0] := INT_TO_BYTE(count);
    origin.x := count;
END_IF;
"""

MAIN_BODY = """\
(* file.src:12 -- comparisons with < and <= and a comment with & and ]]> and ü *)
cnt(enable := start);
lamp := (cnt.count >= 3) AND (cnt.count < 10);

  (* an indented comment after an empty line *)
grid[1, -1] := cnt.count;
IF mem[0] <> 16#00 THEN
    lamp := NOT lamp;
END_IF;
label := 'x&y<z';
out2 := lamp AND start;"""


def rich_project() -> IecProject:
    """A small project exercising every model feature with texts that are legal ST."""
    tmem = DataType(name="TMem", kind="array", base="BYTE", dims=(ArrayDim(0, 15),), comment=NASTY)
    tgrid = DataType(name="TGrid", kind="array", base="INT", dims=(ArrayDim(0, 2), ArrayDim(-1, 3)))
    tpoint = DataType(name="TPoint", kind="struct", comment="a point <x, y>", fields=(
        IecVar("x", "INT", initial="5", comment="x & co"),
        IecVar("y", "DINT"),
        IecVar("valid", "BOOL", initial="TRUE"),
    ))
    add_sat = Pou(
        name="AddSat", kind="FUNCTION", return_type="INT", comment="saturating add\nno globals",
        sections=(
            VarSection("VAR_INPUT", (IecVar("a", "INT", comment="first"), IecVar("b", "INT"))),
            VarSection("VAR", (IecVar("tmp", "DINT"),)),
        ),
        body=ADD_SAT_BODY,
        source_map=(SourceRange("lib/math.src", 10, 24),),
    )
    counter = Pou(
        name="Counter", kind="FUNCTION_BLOCK", comment=NASTY,
        sections=(
            VarSection("VAR_INPUT", (IecVar("enable", "BOOL"),)),
            VarSection("VAR_OUTPUT", (IecVar("count", "INT", initial="0"),)),
            VarSection("VAR_EXTERNAL", (IecVar("mem", "TMem"), IecVar("origin", "TPoint")), comment="globals"),
            VarSection("VAR_EXTERNAL", (IecVar("maxCount", "INT"),), constant=True),
            VarSection("VAR", (IecVar("edge", "R_TRIG", comment=NASTY),)),
        ),
        body=COUNTER_BODY,
        source_map=(SourceRange("count.src", 3, 40), SourceRange("count.src", 55, 55)),
    )
    main = Pou(
        name="Main", kind="PROGRAM", comment="main program",
        sections=(
            VarSection("VAR", (
                IecVar("start", "BOOL", address="%IX0.0", comment="start key"),
                IecVar("lamp", "BOOL", address="%QX0.1"),
                IecVar("cnt", "Counter"),
                IecVar("grid", "TGrid"),
                IecVar("label", "STRING", initial="'a&b <c> ]]>'", comment=NASTY),
                IecVar("level", "INT", address="%IW2"),
            ), comment="mixed located and plain"),
            VarSection("VAR_EXTERNAL", (IecVar("mem", "TMem"), IecVar("out2", "BOOL"))),
            VarSection("VAR", (IecVar("total", "DINT", initial="0"),), retain=True),
        ),
        body=MAIN_BODY,
        source_map=(SourceRange("Main_PGM.src", 1, 120),),
    )
    configuration = Configuration(
        name="Config0", resource="Res0",
        tasks=(Task("MainTask", 20, 0),),
        instances=(ProgramInstance("inst0", "MainTask", "Main"),),
        globals=(
            VarSection("VAR_GLOBAL", (
                IecVar("mem", "TMem", initial="[1, 2, 3(16#FF), 10(0)]", comment="byte memory"),
                IecVar("out2", "BOOL", address="%QX0.2", comment=NASTY),
                IecVar("origin", "TPoint", initial="(x := 1, y := -2)"),
            )),
            VarSection("VAR_GLOBAL", (IecVar("maxCount", "INT", initial="10"),), constant=True, comment="limits"),
        ),
    )
    return IecProject(
        name="demo & <test>", types=(tmem, tgrid, tpoint), pous=(add_sat, counter, main),
        configuration=configuration, header_comment="generated for tests\n" + NASTY,
    )


def test_layout_order_and_configuration() -> None:
    text = render_st(rich_project())
    keywords = [m.group(1) for m in re.finditer(r"^(TYPE|FUNCTION_BLOCK|FUNCTION|PROGRAM|CONFIGURATION) ", text + " ", re.M)]
    # the TYPE keyword stands alone on its line; count those separately
    assert text.count("\nTYPE\n") == 3
    assert keywords == ["FUNCTION", "FUNCTION_BLOCK", "PROGRAM", "CONFIGURATION"]
    assert text.index("TMem : ARRAY[0..15] OF BYTE;") < text.index("TGrid : ARRAY[0..2, -1..3] OF INT;")
    assert text.index("TPoint : STRUCT") < text.index("FUNCTION AddSat : INT")
    assert "        TASK MainTask(INTERVAL := T#20ms, PRIORITY := 0);\n" in text
    assert "        PROGRAM inst0 WITH MainTask : Main;\n" in text
    assert text.count("CONFIGURATION Config0") == 1 and text.count("RESOURCE Res0 ON PLC") == 1
    # globals come before the resource (IEC grammar), after the CONFIGURATION line
    assert text.index("CONFIGURATION Config0") < text.index("VAR_GLOBAL CONSTANT") < text.index("RESOURCE Res0")


def test_text_format_is_lf_with_one_final_newline() -> None:
    text = render_st(rich_project())
    assert "\r" not in text
    assert text.endswith("END_CONFIGURATION\n") and not text.endswith("\n\n")


def _blocks(text: str, header: str, indent: str) -> list[list[str]]:
    """The declaration lines of every block opened by `indent + header` exactly."""
    lines = text.split("\n")
    found = []
    for i, line in enumerate(lines):
        if line.split(" (*")[0] == indent + header:
            end = lines.index(indent + "END_VAR", i)
            found.append([entry.strip() for entry in lines[i + 1:end]])
    return found


def test_located_and_plain_variables_get_separate_blocks() -> None:
    text = render_st(rich_project())
    # Main's mixed VAR section: runs of located / plain / located variables, in order.
    main = text[text.index("PROGRAM Main"):text.index("END_PROGRAM")]
    blocks = _blocks(main, "VAR", "")
    assert [len(b) for b in blocks] == [2, 3, 1]
    assert blocks[0][0].startswith("start AT %IX0.0 : BOOL;")
    assert blocks[0][1] == "lamp AT %QX0.1 : BOOL;"
    assert all(" AT " not in line for line in blocks[1])
    assert blocks[2] == ["level AT %IW2 : INT;"]
    globals_ = _blocks(text, "VAR_GLOBAL", "    ")
    assert [len(b) for b in globals_] == [1, 1, 1]
    assert globals_[1][0].startswith("out2 AT %QX0.2 : BOOL;")


def test_declaration_lines() -> None:
    text = render_st(rich_project())
    assert "    count : INT := 0;\n" in text
    assert "        mem : TMem := [1, 2, 3(16#FF), 10(0)]; (* byte memory *)\n" in text
    assert "\nVAR RETAIN\n    total : DINT := 0;\nEND_VAR\n" in text
    assert "\nVAR_EXTERNAL CONSTANT\n    maxCount : INT;\nEND_VAR\n" in text
    assert "\nVAR_EXTERNAL (* globals *)\n" in text
    assert "        x : INT := 5; (* x & co *)\n" in text


def test_comments_are_safe_and_single_line_where_trailing() -> None:
    text = render_st(rich_project())
    edge_line = next(line for line in text.split("\n") if line.startswith("    edge : R_TRIG;"))
    # exactly one comment, closed at the end of the line, the control char and line break neutralised
    assert edge_line.count("(*") == 1 and edge_line.endswith("*)") and edge_line.count("*)") == 1
    assert "second line" in edge_line and "\x01" not in edge_line
    # an own-line comment with a line break becomes two comment lines
    assert "(* saturating add *)\n(* no globals *)\nFUNCTION AddSat : INT\n" in text
    for line in text.split("\n"):
        stripped = line.strip()
        if stripped.startswith("(*") and not line.startswith("    "):
            assert stripped.endswith("*)") and stripped.count("(*") == 1


def test_bodies_indented_by_four_and_round_trip() -> None:
    project = rich_project()
    text = render_st(project)
    bodies = extract_pou_bodies(text)
    assert bodies == {pou.name: pou.body for pou in project.pous}
    assert "\n    tmp := INT_TO_DINT(a) + INT_TO_DINT(b);\n" in text
    # the empty line of MAIN_BODY stays empty, the indented comment keeps its own indentation
    assert "lamp := (cnt.count >= 3) AND (cnt.count < 10);\n\n      (* an indented" in text


@pytest.mark.parametrize("body", ["x := 1;", "x := 1;\n", "\nx := 1;\n\n", "   \nx := 1;\t", "(* VAR *)\nVAR_X := 1;"])
def test_body_round_trip_edge_cases(body: str) -> None:
    project = rich_project()
    main = dataclasses.replace(project.pous[2], body=body)
    project = dataclasses.replace(project, pous=project.pous[:2] + (main,))
    assert extract_pou_bodies(render_st(project))["Main"] == body


def test_constant_and_retain_together_is_refused() -> None:
    project = rich_project()
    bad = dataclasses.replace(project.configuration.globals[1], retain=True)
    conf = dataclasses.replace(project.configuration, globals=(project.configuration.globals[0], bad))
    with pytest.raises(ValueError, match="CONSTANT and RETAIN"):
        render_st(dataclasses.replace(project, configuration=conf))


def test_extract_rejects_foreign_layout() -> None:
    with pytest.raises(ValueError):
        extract_pou_bodies("PROGRAM P\nx := 1;\nEND_PROGRAM\n")


def _unwritable_projects() -> list[tuple[str, IecProject]]:
    project = rich_project()
    no_return = dataclasses.replace(project.pous[0], return_type=None)
    fb_return = dataclasses.replace(project.pous[1], return_type="INT")
    no_dims = dataclasses.replace(project.types[0], dims=())
    no_fields = dataclasses.replace(project.types[2], fields=())
    return [
        ("return type", dataclasses.replace(project, pous=(no_return,) + project.pous[1:])),
        ("return type", dataclasses.replace(project, pous=(project.pous[0], fb_return, project.pous[2]))),
        ("dimension", dataclasses.replace(project, types=(no_dims,) + project.types[1:])),
        ("no fields", dataclasses.replace(project, types=project.types[:2] + (no_fields,))),
    ]


@pytest.mark.parametrize(("message", "project"), _unwritable_projects())
def test_unwritable_models_are_refused_by_both_containers(message: str, project: IecProject) -> None:
    from transpiler.backends.plcopen.writer import render_xml

    with pytest.raises(ValueError, match=message):
        render_st(project)
    with pytest.raises(ValueError, match=message):
        render_xml(project)
