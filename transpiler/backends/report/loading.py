"""report.md: "How to load this on <target>": the steps for the chosen target, written from what was emitted (the
files, the configuration and resource, the task and the program instances it calls in order, the global variable
lists, the libraries), so that they name exactly what the integrator will see. For CODESYS and TwinCAT the steps
and the task to create are the README's (backends/readme.py), printed once for both files."""

from __future__ import annotations

from typing import TYPE_CHECKING, Iterable

from transpiler.backends.iec_model import IecProject
from transpiler.backends.plcopen.project_folder import FOLDER as EDITOR_FOLDER
from transpiler.backends.readme import render_loading
from transpiler.backends.st.dialect import TargetProject
from transpiler.backends.st.task_setup import task_setups

if TYPE_CHECKING:   # (an annotation only: a translation imports the TwinCAT layout when it plans such a project)
    from transpiler.backends.twincat.layout import TcProject


def _task_lines(project: IecProject) -> list[str]:
    """One line per task: its name, cycle, priority and the program instances it calls, in order."""
    lines = []
    for setup in task_setups(project):
        calls = [f"`{inst}` (PROGRAM `{typ}`)" for inst, typ in zip(setup.instances, setup.programs)]
        order = " then ".join(calls) if calls else "no program"
        lines.append(f"task `{setup.name}`: cyclic, every {setup.interval_ms} ms, priority {setup.priority}; calls "
                     f"{order}{', in this order, in the same task' if len(calls) > 1 else ''}")
    return lines


def _io_counts(target: TargetProject) -> tuple[int, int]:
    sections = [*target.project.configuration.globals, *(s for g in target.gvls for s in g.sections),
                *(s for pou in target.project.pous for s in pou.sections)]
    located = [v.address for s in sections for v in s.vars if v.address]
    return sum(a.startswith("%I") for a in located), sum(a.startswith("%Q") for a in located)


def _libraries(files: set[str]) -> list[str]:
    return sorted(name for name in files if name.startswith(("hh_lib.", "hh_sys.")))


def how_to_load(target: TargetProject, file_names: Iterable[str], twincat: TcProject | None = None) -> str:
    """The report section for `target`; `file_names` are the files transpile writes, `twincat` the TwinCAT project
    folder among them, if any."""
    files = set(file_names)
    project = target.project
    conf = project.configuration
    name = target.dialect.name
    title = {"matiec": "Beremiz (or any matiec-based IDE)", "openplc": "OpenPLC (runtime and Editor)",
             "codesys": "CODESYS V3", "twincat": "TwinCAT 3"}.get(name, name)
    inputs, outputs = _io_counts(target)
    lines = ["", f"## How to load this on {title}", ""]
    tasks = _task_lines(project)
    folder = f"{EDITOR_FOLDER}/plc.xml" in files
    task = tasks[0] if tasks else "task"
    if name == "openplc":
        upload = ("choose `project.st` as it is" if "project.st" in files else
                  "choose the `project.st` of a translation with `--format st` (not written this time)")
        lines += [
            "OpenPLC runtime (web interface):",
            "",
            f"1. *Programs > Upload Program*: {upload} and launch the compilation. The runtime builds the "
            f"CONFIGURATION `{conf.name}` with RESOURCE `{conf.resource}` (the names its build expects); nothing "
            "needs editing.",
            f"2. The runtime runs the {task} (as the ST declares it).",
            "3. Start the PLC. Outputs `%QXa.b` are Modbus coils 8a+b, inputs `%IXa.b` discrete inputs 8a+b "
            f"({inputs} inputs, {outputs} outputs; `io_map.csv` names each).",
        ]
        if folder:
            lines += ["", f"OpenPLC Editor: open the folder `{EDITOR_FOLDER}/` (*File > Open*), then *Generate "
                          "program for OpenPLC Runtime* writes the .st to upload as above."]
    elif name == "matiec":
        if folder:
            first = (f"1. Open the folder `{EDITOR_FOLDER}/` as a project (*File > Open*; `plc.xml` is "
                     "`project.xml`), or import `project.xml` into a project of your own.")
        else:
            first = "1. Create a project and paste `project.st` into it (no PLCopen XML was written this time)."
        lines += [
            first,
            f"2. Build. The CONFIGURATION `{conf.name}` with RESOURCE `{conf.resource}` holds the {task}.",
            f"3. Map the located variables ({inputs} `%IX` inputs, {outputs} `%QX` outputs; `io_map.csv`) to your "
            "I/O.",
        ]
    else:
        # The import creates no task: the same steps and task as the README of the output folder.
        lines += [render_loading(target, files, twincat).rstrip("\n")]
    libraries = _libraries(files)
    if libraries:
        lines += ["", "Libraries written beside the project (optional: the project is complete without them): "
                  + ", ".join(f"`{n}`" for n in libraries) + " (see docs/hh_lib.md and docs/modules.md)."]
    lines += ["", "Then provide what the section \"What the target must provide\" lists (the NC side, the first-cycle "
              "marker, the PLC modules)."]
    return "\n".join(lines) + "\n"
