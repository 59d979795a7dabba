"""The HH_Sys interface library as files of its own (hh_sys.st, hh_sys.xml), for the integrator's target IDE.

project.st declares the HH_Sys FUNCTION_BLOCKs the program calls, with stub bodies, so that it compiles and
co-simulates alone. A CODESYS or TwinCAT user implements those blocks in a library of their own: these files
hold exactly the same declarations (interfaces, doc comments, stub bodies) and nothing else, to import there.
Pure modules are not part of it: their blocks are complete portable ST and stay in project.st.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from transpiler.backends.iec_model import Configuration, IecProject
from transpiler.backends.st.hh_sys import fb_names

if TYPE_CHECKING:
    from transpiler.backends.st.writer import StPrinter

ST_FILE, XML_FILE = "hh_sys.st", "hh_sys.xml"
LIBRARY_NAME = "HH_Sys"


def library_project(project: IecProject) -> IecProject | None:
    """The HH_Sys blocks of `project` as a project of their own (no tasks, no instances), None when it has none."""
    known = fb_names()
    pous = tuple(p for p in project.pous if p.name.upper() in known)
    if not pous:
        return None
    header = ("HH_Sys interface library: one FUNCTION_BLOCK per data or machine PLC module the program calls.\n"
              "Implement each body on the target (the stub reports FAULT with FAULT_CODE 1); see docs/modules.md.\n"
              f"Generated for project {project.name}; the same declarations are in its project ST and XML files.")
    config = Configuration(f"{LIBRARY_NAME}_CONFIG", f"{LIBRARY_NAME}_RES", (), (), ())
    return IecProject(LIBRARY_NAME, (), pous, config, header_comment=header)


def render_library_st(library: IecProject, printer: StPrinter | None = None) -> str:
    """The library as ST: the header and the FUNCTION_BLOCKs, without a CONFIGURATION (it is no program); `printer`
    is the translation's, if it has one."""
    from transpiler.backends.st.writer import StPrinter
    text = (printer or StPrinter()).project(library)
    cut = text.find("\nCONFIGURATION ")
    return (text[:cut].rstrip("\n") if cut >= 0 else text.rstrip("\n")) + "\n"
