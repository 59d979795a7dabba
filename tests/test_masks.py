"""Screen masks (.msk, .a): the reader's model, reference checks with file:line, the report and HMI JSON of a
translation, the text rendering and its agreement between the reference interpreter and the translated ST."""

from __future__ import annotations

import json
import re
import shutil
import time
from datetime import timedelta
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from transpiler import api
from transpiler.cli import main as hh2iec
from transpiler.diagnostics import CODES, Diagnostics
from transpiler.frontend.masks import mask_files, parse_mask
from transpiler.frontend.sources import SourceText
from transpiler.ir import MaskField
from transpiler.language.semantics import make_semantics
from transpiler.verify.screens import ScreenRequest, draw_both_sides, format_field, render_mask

ROOT = Path(__file__).resolve().parents[1]
BASIC = ROOT / "samples" / "basic_program"
SCENARIO = BASIC / "scenarios" / "errors_tool_life.yaml"
DIAG = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+):(?P<col>\d+): error\[(?P<code>[A-Z-]+)\]: (?P<msg>.*)$", re.M)


def _parse(text: str, name: str = "t.msk") -> tuple:
    diags = Diagnostics()
    mask = parse_mask(SourceText(Path(name), name, tuple(text.split("\n"))), diags)
    return mask, diags


# ------------------------------------------------------------------------------------------------ reader


def test_the_reader_gives_settings_text_formatted_lines_and_the_error_queue():
    mask, diags = _parse('/* diagnosis\n   of the tool change */\nCHARSIZE=AUTO;\nLINEDIST=LINEDIST-1;\n'
                         '"DIAG TOOL CHANGE\\n";\n" %4D %4D\\n", $WG_a$/c,\n   $WG_b$/c;\n'
                         '"%+5.0F 100%%", $DG_rpm$/n=3/c;\n"%s\\n", S1/c;\nERRQUE=10/c/l/s;\n')
    assert diags.items == []
    kinds = [(s.kind, s.span.line) for s in mask.statements]
    assert kinds == [("setting", 3), ("setting", 4), ("text", 5), ("line", 6), ("line", 8), ("line", 9),
                     ("errque", 10)]
    settings_ = [(s.key, s.value) for s in mask.statements if s.kind == "setting"]
    assert settings_ == [("CHARSIZE", "AUTO"), ("LINEDIST", "LINEDIST-1")]
    assert mask.statements[2].pieces == ("DIAG TOOL CHANGE\n",)
    line = mask.statements[3]
    assert [p if isinstance(p, str) else (p.spec, p.width, p.conversion, p.ref.symbol, p.ref.span.line)
            for p in line.pieces] == [" ", ("%4D", 4, "D", "WG_a", 6), " ", ("%4D", 4, "D", "WG_b", 7), "\n"]
    fixed = mask.statements[4].fields[0]
    assert (fixed.flags, fixed.width, fixed.precision, fixed.ref.decimals, fixed.ref.modifiers) == \
        ("+", 5, 0, 3, ("n=3", "c"))
    assert mask.statements[4].pieces[-1] == " 100%"
    assert mask.statements[5].fields[0].ref.text == "S1"
    queue = mask.statements[6]
    assert (queue.lines, queue.modifiers) == (10, ("c", "l", "s"))


@pytest.mark.parametrize("text, code, line, col", [
    ('"DIAG"\nCHARSIZE=AUTO;', "E-MASK-SYNTAX", 2, 1),           # missing ';' after the text
    ('" %4D", $WG_a;', "E-MASK-SYNTAX", 1, 9),                   # $ not closed
    ('" %4D", $WG_a$/q;', "E-MASK-SYNTAX", 1, 15),               # unknown modifier
    ('"abc;', "E-MASK-SYNTAX", 1, 1),                            # string not closed
    ('CHARSIZE=;', "E-MASK-SYNTAX", 1, 10),
    ('ERRQUE=0;', "E-MASK-SYNTAX", 1, 8),
    ('/* open', "E-MASK-SYNTAX", 1, 1),
    ('" %4D %4D", $WG_a$;', "E-MASK-FORMAT", 1, 1),              # two fields, one reference
    ('" %4q", $WG_a$;', "E-MASK-FORMAT", 1, 1),
    ('" %4D";', "E-MASK-FORMAT", 1, 1),                          # a field without a reference
])
def test_malformed_statements_are_reported_at_their_place(text, code, line, col):
    _, diags = _parse(text)
    assert [(d.code, d.span.line, d.span.col) for d in diags.errors][:1] == [(code, line, col)]


def test_every_error_of_a_file_is_reported_and_the_reader_goes_on():
    mask, diags = _parse('"a\\q";\nCHARSIZE AUTO;\n"ok\\n";\n" %d", $x$/n=99;\n"end\\n";\n')
    assert [d.span.line for d in diags.errors] == [1, 2, 4]
    assert [s.pieces for s in mask.statements] == [("ok\n",), ("end\n",)]


# ------------------------------------------------------------------------------------ the sample's masks


@pytest.mark.parametrize("cfg", sorted(BASIC.glob("OEM*.cfg")), ids=lambda p: p.name)
def test_every_reference_of_the_sample_masks_resolves(cfg):
    project = api.load_project(api.project_options(BASIC / "Main_PGM.src", cfg=cfg))
    masks = {m.name: m for m in project.program.masks}
    assert set(masks) == {"M_error.a", "M_dia_wz.msk", "M_dia_a1.msk"}
    fields = [f for m in masks.values() for f in m.fields]
    assert len(fields) >= 20
    for field in fields:
        assert field.ref.kind, field.ref.text
        if field.ref.symbol is not None:
            sym = project.program.symbols[field.ref.symbol]
            assert (sym.kind, sym.addr) == (field.ref.kind, field.ref.addr)
    assert any(s.kind == "errque" for s in masks["M_error.a"].statements)
    assert [f.ref.operand for f in masks["M_error.a"].fields if f.ref.symbol is None] == ["S1"]


def _sample_copy(tmp_path: Path) -> Path:
    folder = tmp_path / "basic"
    shutil.copytree(BASIC, folder, ignore=shutil.ignore_patterns("scenarios"))
    return folder


def test_a_misspelt_symbol_is_an_error_at_its_file_line_with_the_nearest_names(tmp_path, capsys):
    folder = _sample_copy(tmp_path)
    mask = folder / "M_dia_wz.msk"
    lines = mask.read_text().split("\n")
    row = next(i for i, text in enumerate(lines) if "$WG_tc_status$" in text)
    lines[row] = lines[row].replace("$WG_tc_status$", "$WG_tc_stauts$")
    mask.write_text("\n".join(lines))
    assert hh2iec(["check", str(folder / "Main_PGM.src")]) == 2
    found = [m.groupdict() for m in DIAG.finditer(capsys.readouterr().err)]
    assert len(found) == 1
    assert (found[0]["file"], int(found[0]["line"]), found[0]["code"]) == ("M_dia_wz.msk", row + 1, "E-MASK-UNDEF")
    assert int(found[0]["col"]) == lines[row].index("$WG_tc_stauts$") + 1
    assert "nearest names: WG_tc_status" in found[0]["msg"]


def test_a_format_that_does_not_suit_its_operand_is_an_error(tmp_path, capsys):
    folder = _sample_copy(tmp_path)
    (folder / "masks").mkdir()
    (folder / "masks" / "extra.MSK").write_text('"%s\\n", $WG_tc_status$/c;\n" %d\\n", S1;\n" %4D\\n", $KG_err_markers$;\n'
                                               '" %4d\\n", $WG_tc_count$/n=2;\n" %4d\\n", W3;\n" %4d\\n", WG_tc_count;\n')
    assert hh2iec(["check", str(folder)]) == 2
    found = [(m["file"], int(m["line"]), m["code"]) for m in DIAG.finditer(capsys.readouterr().err)]
    assert found == [("masks/extra.MSK", 1, "E-MASK-FORMAT"), ("masks/extra.MSK", 2, "E-MASK-FORMAT"),
                     ("masks/extra.MSK", 3, "E-MASK-FORMAT"), ("masks/extra.MSK", 4, "E-MASK-FORMAT"),
                     ("masks/extra.MSK", 5, "E-ADDR-ALIGN"), ("masks/extra.MSK", 6, "E-MASK-UNDEF")]


def test_mask_files_are_found_beside_the_main_program_and_in_its_mask_folder(tmp_path):
    for name in ("Main.src", "a.msk", "B.A", "c.txt", "mask/d.msk", "other/e.msk"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("")
    assert [p.relative_to(tmp_path).as_posix() for p in mask_files(tmp_path / "Main.src")] == ["B.A", "a.msk",
                                                                                                "mask/d.msk"]


@pytest.mark.parametrize("code", ["E-MASK-SYNTAX", "E-MASK-UNDEF", "E-MASK-FORMAT"])
def test_the_mask_codes_are_explained(code, capsys):
    assert code in CODES
    assert hh2iec(["explain", code]) == 0
    assert capsys.readouterr().out.startswith(f"{code} (error)")


# ------------------------------------------------------------------------------------------ translation


@pytest.fixture(scope="module")
def sample_translation():
    project = api.load_project(api.project_options(BASIC / "Main_PGM.src"))
    return project, api.transpile(project, formats=("st",))


def test_transpile_reports_what_the_screens_show_and_writes_one_json_per_mask(sample_translation):
    project, out = sample_translation
    report = out.files["report.md"].decode()
    section = report.split("## What the operator screens show", 1)[1].split("\n## ", 1)[0]
    iomap = out.io_map
    for mask in project.program.masks:
        data = json.loads(out.files[f"masks/{mask.name}.json"])
        assert data["mask"] == mask.name
        fields = [p["field"] for s in data["statements"] for p in s.get("pieces", ()) if "field" in p]
        assert len(fields) == len(mask.fields)
        for field, model in zip(fields, mask.fields):
            row = iomap.by_operand[model.ref.operand]
            assert field["variable"] == row.iec and field["operand"] == model.ref.operand
            assert field["width"] == model.width and field["format"] == model.spec
            assert f"| {mask.file} | {model.ref.span.line} | `{model.ref.text}` ({model.ref.operand}) | `{row.iec}` |" \
                in section
    wz = json.loads(out.files["masks/M_dia_wz.msk.json"])
    text = "".join(p.get("text", "") for s in wz["statements"] for p in s.get("pieces", ()))
    assert text.startswith("DIAG TOOL CHANGE\n")
    queue = next(s for s in json.loads(out.files["masks/M_error.a.json"])["statements"] if s["kind"] == "errque")
    assert queue["lines"] == 10 and queue["error_markers"][27]["operand"] == "M4827"


def test_an_operand_only_a_mask_shows_is_declared_in_the_translation(tmp_path):
    (tmp_path / "Main.src").write_text("#define /g d.def\nL I_a\n= O_b\nEM\n")
    (tmp_path / "d.def").write_text("I_a I 1\nO_b O 2\nWG_shown W 100\n")
    (tmp_path / "screen.msk").write_text('"VALUE %5D\\n", $WG_shown$/c;\n')
    project = api.load_project(api.project_options(tmp_path / "Main.src"))
    out = api.transpile(project, formats=("st",))
    field = json.loads(out.files["masks/screen.msk.json"])["statements"][0]["pieces"][1]["field"]
    assert field["operand"] == "W100" and field["variable"] == "WG_shown"
    assert re.search(r"\bWG_shown\s*:\s*INT\b", out.st_text)


# -------------------------------------------------------------------------------------------- rendering


def _field(spec: str, kind: str = "W", modifiers: tuple[str, ...] = ("c",)):
    mask, diags = _parse(f'"{spec}", W0{"".join("/" + m for m in modifiers)};')
    assert diags.items == []
    field = mask.statements[0].fields[0]
    return MaskField(field.spec, field.flags, field.width, field.precision, field.conversion,
                     type(field.ref)(field.ref.text, None, field.ref.modifiers, field.ref.span, kind, 0))


@pytest.mark.parametrize("spec, kind, modifiers, value, overrides, shown", [
    ("%4D", "W", ("c",), -12, {}, " -12"),
    ("%2d", "B", ("c",), 7, {}, " 7"),
    ("%6d", "W", ("c",), -2, {}, "    -2"),
    ("%6d", "W", ("c",), -2, {"mask_d_format": "d_unsigned"}, " 65534"),
    ("%6D", "W", ("c",), -2, {"mask_d_format": "d_unsigned"}, "    -2"),
    ("%+5.0F", "D", ("n=3", "c"), 12345, {}, "  +12"),
    ("%+10.1F", "D", ("n=3", "c"), -1250, {}, "      -1.2"),       # -1.250 rounds half to even
    ("%.3F", "D", ("n=3",), 5, {}, "0.005"),
    ("%s", "S", ("c",), "READY", {}, "READY"),
    ("%-6s|", "S", ("c",), "OK", {}, "OK    "),
    ("%3d", "W", ("c",), 12345, {}, "12345"),
    ("%3d", "W", ("c",), 12345, {"mask_c_modifier": "clip"}, "***"),
    ("%3d", "W", (), 12345, {"mask_c_modifier": "clip"}, "12345"),
    ("%4D", "W", ("c",), None, {}, "????"),
])
def test_a_field_is_written_as_printf_writes_it(spec, kind, modifiers, value, overrides, shown):
    field = _field(spec, kind, modifiers)
    assert format_field(field, value, make_semantics("itnc530", overrides)) == shown


def test_the_error_queue_lists_the_set_error_markers_in_order_then_blank_lines(sample_translation):
    project, _ = sample_translation
    mask = next(m for m in project.program.masks if m.name == "M_error.a")
    values = {("M", 4827): 1, ("M", 4804): 1, ("W", 224): 2, ("W", 226): 3, ("S", 1): "PLC ERROR"}
    lines = render_mask(mask, lambda kind, addr: values.get((kind, addr), 0), project.program)
    assert lines == ("PLC ERRORS   2  FIRST   3", "PLC ERROR", "  4 ---- MG_err_limit_4", " 27 ---- MG_err_tool_life",
                     *[""] * 8)


def test_both_sides_draw_the_same_screens_at_every_cycle_of_a_sample_scenario(sample_translation):
    from transpiler.verify.cosim import builtin_side_factory
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.simulate import project_names
    project, out = sample_translation
    names = project_names(project.program)
    scenario = load_scenario(SCENARIO, names)
    requests = [ScreenRequest(mask, cycle) for cycle in range(scenario.cycles) for mask in project.program.masks]
    mp = api.machine_parameters_of(project)[1]
    screens = draw_both_sides(project.program, builtin_side_factory(out.st_text), out.io_map, [scenario], names,
                              requests, mp)
    assert len(screens) == len(requests) and all(s.original is not None for s in screens)
    assert [s for s in screens if s.differs] == []
    assert all(s.original == s.translated for s in screens)
    queue = [s.original for s in screens if s.mask == "M_error.a"]
    # the run raises PLC error 27 and clears it again: the screens change, so equal screens mean something
    assert any(" 27 ---- MG_err_tool_life" in lines for lines in queue)
    assert queue[0][2] == "" and queue[-1][2] == ""


def test_screens_that_differ_are_told_apart(sample_translation):
    project, _ = sample_translation
    mask = next(m for m in project.program.masks if m.name == "M_dia_wz.msk")
    a = render_mask(mask, lambda kind, addr: 3 if (kind, addr) == ("W", 222) else 0, project.program)
    b = render_mask(mask, lambda kind, addr: 4 if (kind, addr) == ("W", 222) else 0, project.program)
    assert a != b and [x for x, y in zip(a, b) if x != y] == [" CHANGES      3  TOTAL         0"]


def test_simulate_and_equiv_show_a_mask_at_a_cycle(capsys):
    args = [str(BASIC / "Main_PGM.src"), "--scenario", str(SCENARIO), "--show-mask", "M_error@45"]
    assert hh2iec(["simulate", *args]) == 0
    out = capsys.readouterr().out
    assert "mask M_error.a after cycle 45 of errors_tool_life:\n  |PLC ERRORS   1  FIRST  27\n" in out
    assert hh2iec(["equiv", *args, "--show-mask", "M_dia_wz.msk@79", "--backend", "builtin"]) == 0
    out = capsys.readouterr().out
    assert "mask M_error.a after cycle 45 of errors_tool_life (original and translation draw the same screen)" in out
    assert "mask M_dia_wz.msk after cycle 79 of errors_tool_life (original and translation draw the same screen)" in out
    assert "EQUIVALENT" in out


@pytest.mark.parametrize("spec", ["M_nothing@3", "M_error", "M_error@x"])
def test_a_show_mask_without_a_mask_or_cycle_is_a_usage_error(spec, capsys):
    assert hh2iec(["simulate", str(BASIC / "Main_PGM.src"), "--scenario", str(SCENARIO), "--show-mask", spec]) == 2
    assert "error[E-USAGE]: --show-mask" in capsys.readouterr().err


# ----------------------------------------------------------------------------------------------- fuzzing

TOKENS = ['"', '"DIAG\\n"', '" %4D %4D\\n"', '"%+5.0F"', '"%s"', '"%%"', "%", "%999D", ";", ",", "=", "$WG_tc_status$",
          "$x", "$", "/c", "/n=3", "/n=", "/l", "/s", "/*", "*/", "S1", "S99999", "W3", "ERRQUE", "=10", "CHARSIZE",
          "AUTO", "LINEDIST-1", "-", "+", "\\", "\n", " ", "\t", "é", "\x00", "9" * 30]
FUZZ = settings(max_examples=60, deadline=timedelta(seconds=20), derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def _only_diagnostics(folder: Path, data: bytes) -> None:
    (folder / "fuzz.msk").write_bytes(data)
    started = time.perf_counter()
    result = api.check_project(api.project_options(folder / "Main.src"))
    assert time.perf_counter() - started < 10
    for d in result.diagnostics.items:
        assert d.code in CODES and d.span.line >= 1 and d.span.col >= 1
        if d.code.startswith("E-MASK"):
            assert d.span.file == "fuzz.msk"


@pytest.fixture(scope="module")
def fuzz_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("maskfuzz")
    (folder / "Main.src").write_text("#define /g d.def\nL I_a\n= WG_tc_status\nEM\n")
    (folder / "d.def").write_text("I_a I 1\nWG_tc_status W 100\n")
    return folder


@FUZZ
@given(parts=st.lists(st.sampled_from(TOKENS), max_size=40))
def test_structured_mask_fuzz_gives_only_diagnostics(fuzz_folder, parts):
    _only_diagnostics(fuzz_folder, "".join(parts).encode("utf-8"))


@FUZZ
@given(data=st.binary(max_size=300))
def test_byte_mask_fuzz_gives_only_diagnostics(fuzz_folder, data):
    _only_diagnostics(fuzz_folder, data)


def _transpiled_screen_project(tmp_path: Path) -> Path:
    """A program whose mask shows two operands it uses and a word it never writes, transpiled to tmp_path/out."""
    (tmp_path / "Main.src").write_text("#define /g d.def\nL I_a\n= O_b\nEM\n")
    (tmp_path / "d.def").write_text("I_a I 1\nO_b O 2\nWG_shown W 100\n")
    (tmp_path / "screen.msk").write_text('"IN %d OUT %d\\n", $I_a$/c, $O_b$/c;\n"VALUE %5D\\n", $WG_shown$/c;\n')
    (tmp_path / "s.yaml").write_text("name: s\ncycles: 4\nevents:\n  - cycle: 1\n    set: {I_a: 1}\n")
    out = tmp_path / "out"
    assert hh2iec(["transpile", str(tmp_path / "Main.src"), "--out", str(out), "--format", "st"]) == 0
    return out


def test_equiv_fails_when_the_screens_differ_though_every_compared_operand_agrees(tmp_path, capsys):
    # The mask shows WG_shown, which the program never writes: no compared operand tells the two sides apart. An io
    # map without its row leaves the translated side no place to read it from, so its screen differs.
    out = _transpiled_screen_project(tmp_path)
    assert "masks/ (1 files)" in capsys.readouterr().out
    args = ["equiv", str(tmp_path / "Main.src"), "--scenario", str(tmp_path / "s.yaml"), "--backend", "builtin",
            "--st", str(out / "project.st"), "--show-mask", "screen@2"]
    assert hh2iec(args) == 0
    assert "(original and translation draw the same screen):\n  |IN 1 OUT 1\n  |VALUE     0\n" in capsys.readouterr().out
    rows = (out / "io_map.csv").read_text().splitlines()
    (out / "io_map.csv").write_text("\n".join(r for r in rows if ",W100," not in r) + "\n")
    assert hh2iec(args) == 1
    text = capsys.readouterr().out
    assert " original:\n  |IN 1 OUT 1\n  |VALUE     0\n translated:\n  |IN 1 OUT 1\n  |VALUE ?????\n" in text
    assert "hh2iec equiv: SCREENS DIFFER: screen.msk after cycle 2 of s; compared operands: EQUIVALENT (1 runs" in text


def test_equiv_reports_carry_the_screens(tmp_path, capsys):
    """--report gets a `screens` key (which mask, cycle, scenario, both drawings, whether they differ); in --junit
    each screen is a test case: a failure where the screens differ, skipped where the run never reached the cycle."""
    import xml.etree.ElementTree as ET
    out = _transpiled_screen_project(tmp_path)
    report, junit = tmp_path / "r.json", tmp_path / "j.xml"
    args = ["equiv", str(tmp_path / "Main.src"), "--scenario", str(tmp_path / "s.yaml"), "--backend", "builtin",
            "--st", str(out / "project.st"), "--show-mask", "screen@2", "--show-mask", "screen@9",
            "--report", str(report), "--junit", str(junit)]
    assert hh2iec(args) == 0
    capsys.readouterr()
    data = json.loads(report.read_text())
    assert data["verdict"] == "EQUIVALENT" and len(data["runs"]) == 1          # the keys of before are still there
    assert data["screens"] == [
        {"scenario": "s", "mask": "screen.msk", "cycle": 2, "drawn": True, "differs": False,
         "original": ["IN 1 OUT 1", "VALUE     0"], "translated": ["IN 1 OUT 1", "VALUE     0"], "note": ""},
        {"scenario": "s", "mask": "screen.msk", "cycle": 9, "drawn": False, "differs": False, "original": None,
         "translated": None, "note": data["screens"][1]["note"]}]
    assert "4 cycles" in data["screens"][1]["note"]
    suite = ET.parse(junit).getroot()
    assert (suite.get("tests"), suite.get("failures"), suite.get("skipped")) == ("3", "0", "1")
    cases = {c.get("name"): c for c in suite.iter("testcase")}
    assert "IN 1 OUT 1" in cases["screen.msk after cycle 2 of s"].find("system-out").text
    assert cases["screen.msk after cycle 9 of s"].find("skipped") is not None

    rows = (out / "io_map.csv").read_text().splitlines()
    (out / "io_map.csv").write_text("\n".join(r for r in rows if ",W100," not in r) + "\n")
    assert hh2iec(args) == 1
    capsys.readouterr()
    data = json.loads(report.read_text())
    assert data["verdict"] == "EQUIVALENT"                       # the compared operands still agree ...
    assert data["screens"][0]["differs"] and data["screens"][0]["translated"] == ["IN 1 OUT 1", "VALUE ?????"]
    suite = ET.parse(junit).getroot()
    assert suite.get("failures") == "1"                          # ... but the screens are a failure of their own
    failure = {c.get("name"): c for c in suite.iter("testcase")}["screen.msk after cycle 2 of s"].find("failure")
    assert failure is not None and "VALUE ?????" in failure.text
