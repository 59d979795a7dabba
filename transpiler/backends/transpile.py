"""Runs the back ends on one IR program: the ST back end decides the IEC project (once for matiec, and once more
for a target that writes its POUs otherwise), the writers print it as ST and PLCopen XML (and the libraries HH_Lib
and HH_Sys as files of their own), the report module adds report.md, io_map.csv and the screen masks as JSON; for TwinCAT the PLC project
folder follows, and where the import creates no task, a README.md that says which task to create. Returns file
contents (names may hold '/' for sub-folders); writing is the caller's job."""

from __future__ import annotations

import dataclasses
from decimal import Decimal
from pathlib import Path
from typing import Callable, Mapping

from transpiler.diagnostics import Diagnostics
from transpiler.frontend.pipeline import cyclic_gc_paused
from transpiler.ir import Program
from transpiler.backends.st.backend import StBackend, StResult
from transpiler.backends.st.dialect import DEFAULT_TARGET, TARGETS, dialect, for_target, target_section
from transpiler.backends.st import hh_lib
from transpiler.backends.st.sys_library import ST_FILE as LIB_ST, XML_FILE as LIB_XML, library_project, render_library_st
from transpiler.backends.plcopen.project_folder import project_folder
from transpiler.backends.report.loading import how_to_load
from transpiler.backends.readme import README_FILE, render_readme
from transpiler.backends.report.report import io_map_of, render_report
from transpiler.backends.report.screens import mask_files


XmlMade = Callable[[str, bytes], None]


@dataclasses.dataclass(frozen=True)
class Transpiled:
    result: StResult
    st_text: str
    files: dict[str, bytes]           # output file name -> content


def transpile_program(program: Program, diags: Diagnostics, mp: Mapping[tuple[int, int], Decimal],
                      formats: set[str], mp_file: Path | None = None, target: str = DEFAULT_TARGET,
                      xml_made: XmlMade | None = None) -> Transpiled:
    """`mp` are the values of `mp_file`, named in the ST header, report.md and io_map.csv; `target` picks the
    dialect of project.st and project.xml (st/dialect.py). `st_text` is always the matiec text: that is what the
    co-simulation runs; `result` is the matiec translation too, for the report and the I/O map. `xml_made` is
    told each TC6 XML file at the top of the output as soon as it is made (its name and content), before the
    other files are (the caller may check it meanwhile)."""
    with cyclic_gc_paused():
        return _transpile(program, diags, mp, formats, mp_file, target, xml_made or _no_one)


def _no_one(name: str, data: bytes) -> None:
    pass


def _transpile(program: Program, diags: Diagnostics, mp: Mapping[tuple[int, int], Decimal],
               formats: set[str], mp_file: Path | None, target: str, xml_made: XmlMade) -> Transpiled:
    from transpiler.backends.plcopen.writer import render_target_xml, render_xml
    from transpiler.backends.st.writer import StPrinter
    mp_name = mp_file.name if mp_file is not None else None
    result = StBackend(program, diags, mp, mp_file=mp_name).build()
    project = result.project
    files: dict[str, bytes] = {}
    chosen = dialect(target)
    built = project
    if not chosen.builds_like(TARGETS[DEFAULT_TARGET]):
        # The same translation with the target's references and bit reads; its diagnostics are the matiec run's.
        built = StBackend(program, Diagnostics(), mp, mp_file=mp_name, dialect=chosen).build().project
    laid_out = for_target(built, target)
    # (project.xml first, so that it is checked while the rest is made)
    project_xml = render_target_xml(laid_out) if "xml" in formats else None
    if project_xml is not None:
        xml_made("project.xml", project_xml)
    printer = StPrinter()     # (one for the project and the libraries: the templates are compiled once)
    st_text = printer.project(project)
    if "st" in formats:
        # The matiec layout of the matiec translation is st_text itself (printing the target's layout would print it again).
        same_text = laid_out.project is project and laid_out.dialect.st_template == TARGETS[DEFAULT_TARGET].st_template
        files["project.st"] = (st_text if same_text else printer.target(laid_out)).encode("utf-8")
    if project_xml is not None:
        files["project.xml"] = project_xml
        if chosen.xml_globals == "configuration":
            # The editors built on matiec (OpenPLC Editor, Beremiz) open a folder as a project.
            files.update(project_folder(files["project.xml"]))
    # The HH_Sys interface library also as files of its own, for the target IDE (sys_library.py).
    library = library_project(project)
    if library is not None:
        if "st" in formats:
            files[LIB_ST] = render_library_st(library, printer).encode("utf-8")
        if "xml" in formats:
            files[LIB_XML] = render_xml(library)
            xml_made(LIB_XML, files[LIB_XML])
    # HH_Lib: every helper and the timer/counter blocks as a library of their own (hh_lib.py); project.st keeps
    # the ones it uses and stays self-contained.
    helpers = hh_lib.library_project(program.semantics, project.name)
    if "st" in formats:
        files[hh_lib.ST_FILE] = render_library_st(helpers, printer).encode("utf-8")
    if "xml" in formats:
        files[hh_lib.XML_FILE] = render_xml(helpers)
        xml_made(hh_lib.XML_FILE, files[hh_lib.XML_FILE])
    # A native project folder of the target (one file per object), beside project.st and from the same text.
    native = None
    if chosen.project_folder == "twincat" and "st" in formats:
        from transpiler.backends.twincat.layout import plan_project
        from transpiler.backends.twincat.writer import render_project
        native = plan_project(laid_out)
        files.update(render_project(native))
    # The screen masks as data for an HMI, bound to the variables of this translation.
    # (the screens find their variables by operand: the machine-parameter and configuration rows change none)
    iomap = io_map_of(result, mp_name, program)
    files.update(mask_files(program, iomap))
    written = [*files, "report.md", "io_map.csv"] + ([README_FILE] if chosen.task_by_hand else [])
    if chosen.task_by_hand:
        files[README_FILE] = render_readme(laid_out, written, native).encode("utf-8")
    files["report.md"] = (render_report(program, result, diags, iomap, mp_name) + target_section(laid_out)
                          + how_to_load(laid_out, written, native)).encode("utf-8")
    files["io_map.csv"] = iomap.to_csv().encode("utf-8")
    return Transpiled(result, st_text, files)
