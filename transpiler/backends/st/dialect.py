"""One table per target: how the same program is written for matiec (Beremiz, OpenPLC), CODESYS and TwinCAT 3.

A target overrides tables, not control flow. The ST back end builds the project for one `Dialect`: where its
lists are `qualified_only` every reference to a global is written `GVL_x.name` as its expression is built (the
list a global lands in is `gvl_name` of its group's title), and where it has `bit_access` a bit of a word is read
as `w.3` instead of through the HH_BIT helper. `for_target` then only moves the globals of a GVL target out of
the configuration into named global variable lists, drops the VAR_EXTERNAL lists (CODESYS and TwinCAT see a
GVL from every POU) and gives the task the target's own PLC task priority where it has one. See docs/import.md
for what each target gets.
"""

from __future__ import annotations

import dataclasses
import re
from types import MappingProxyType

from transpiler.backends.iec_model import IecProject, VarSection


@dataclasses.dataclass(frozen=True)
class Dialect:
    name: str
    # matiec needs VAR_EXTERNAL in every POU that names a global and the globals in the CONFIGURATION.
    externals: bool
    # The ST layout (a template of templates/st) and the PLCopen XML home of the globals.
    st_template: str
    xml_globals: str              # "configuration" (TC6 globalVars) or "3s_addData" (CODESYS/TwinCAT GVLs)
    qualified_only: bool = False
    # Initialised array globals written with their ARRAY spec in the ST (see writer._inline_array).
    inline_initialised_arrays: bool = False
    # Bit access `w.3` on integer variables (matiec has none: there the HH_BIT helper reads a bit).
    bit_access: bool = False
    # The priority the target's own project template gives its PLC task, used for the translation's single task
    # (whose priority carries nothing from the control); None keeps the back end's.
    task_priority: int | None = None
    # A native project folder written beside project.st (backends/twincat for "twincat").
    project_folder: str | None = None

    @property
    def task_by_hand(self) -> bool:
        """The target's PLCopen import creates no task (CODESYS, TwinCAT: the GVLs live in addData and the XML carries
        no configuration): the output's README.md and project.st say which task to create (task_setup.py)."""
        return self.xml_globals != "configuration"

    def reference(self, name: str, title: str | None) -> str:
        """How a POU body names the global `name` of the group titled `title`."""
        return f"{gvl_name(title)}.{name}" if self.qualified_only else name

    def builds_like(self, other: "Dialect") -> bool:
        """The back end writes the same POUs for both (it reads only these two columns)."""
        return (self.qualified_only, self.bit_access) == (other.qualified_only, other.bit_access)


TARGETS = MappingProxyType({
    "matiec": Dialect("matiec", externals=True, st_template="project.st.j2", xml_globals="configuration"),
    # OpenPLC v3 runs matiec (with -f -l -p -r -R -a): the same text is right for it.
    "openplc": Dialect("openplc", externals=True, st_template="project.st.j2", xml_globals="configuration"),
    "codesys": Dialect("codesys", externals=False, st_template="project_gvl.st.j2", xml_globals="3s_addData",
                       qualified_only=True, inline_initialised_arrays=True, bit_access=True),
    # TwinCAT's PLC project template gives its PlcTask priority 20 (as its .TcTTO and .tsproj files show).
    "twincat": Dialect("twincat", externals=False, st_template="project_gvl.st.j2", xml_globals="3s_addData",
                       qualified_only=True, inline_initialised_arrays=True, bit_access=True,
                       task_priority=20, project_folder="twincat"),
})

DEFAULT_TARGET = "matiec"

# The global groups of the back end (their section comments) and the list each lands in on a GVL target:
# one list per source area, inputs and outputs together as the I/O list.
GVL_BY_TITLE = MappingProxyType({
    "Inputs (process image)": "GVL_IO",
    "Outputs (process image)": "GVL_IO",
    "NC interface (NC <-> PLC operands)": "GVL_NC",
    "Markers": "GVL_Markers",
    "Timer and counter operands": "GVL_TimersCounters",
    "Byte memory: bytes, words, double words": "GVL_Words",
    "Strings": "GVL_Strings",
    "Machine parameters (presets in PLC cycles)": "GVL_MachineParams",
    "Constant fields (KFIELD tables)": "GVL_Constants",
    "Accumulators, index register, data stack": "GVL_Registers",
    "Submit-job queue": "GVL_Jobs",
    "PLC data tables (MP_Data.tab, MP_Config.tab)": "GVL_MachineData",
})
# The lists the back end's globals land in: a qualifier in a reference is one of these (exprs.unqualified).
GVL_NAMES = frozenset(GVL_BY_TITLE.values())


@dataclasses.dataclass(frozen=True)
class Gvl:
    """One global variable list: its name and its sections (the back end's groups that land in it)."""

    name: str
    sections: tuple[VarSection, ...]
    qualified_only: bool


@dataclasses.dataclass(frozen=True)
class TargetProject:
    """The project as a target sees it: for a GVL target the configuration has no globals and `gvls` holds them."""

    dialect: Dialect
    project: IecProject
    gvls: tuple[Gvl, ...] = ()


def dialect(target: str) -> Dialect:
    """The table of `target`; ValueError names the known targets."""
    try:
        return TARGETS[target]
    except KeyError:
        raise ValueError(f"unknown target '{target}' (known: {', '.join(TARGETS)})") from None


def gvl_name(title: str | None) -> str:
    """The list the global group titled `title` (its section comment) lands in; a group the table does not know
    gets a name from its title."""
    title = title or "Globals"
    return GVL_BY_TITLE.get(title) or "GVL_" + "".join(w.capitalize() for w in re.findall(r"[A-Za-z0-9]+", title))


def for_target(project: IecProject, target: str) -> TargetProject:
    """`project`, as the back end built it for `target`, laid out for it (the matiec project is returned unchanged)."""
    chosen = dialect(target)
    if chosen.externals:
        return TargetProject(chosen, project)
    by_name: dict[str, list[VarSection]] = {}
    for section in project.configuration.globals:
        by_name.setdefault(gvl_name(section.comment), []).append(section)
    gvls = tuple(Gvl(name, tuple(sections), chosen.qualified_only) for name, sections in by_name.items())
    pous = tuple(dataclasses.replace(pou, sections=tuple(s for s in pou.sections if s.kind != "VAR_EXTERNAL"))
                 for pou in project.pous)
    config = dataclasses.replace(project.configuration, globals=())
    if chosen.task_priority is not None:
        config = dataclasses.replace(config, tasks=tuple(dataclasses.replace(t, priority=chosen.task_priority)
                                                         for t in config.tasks))
    return TargetProject(chosen, dataclasses.replace(project, pous=pous, configuration=config), gvls)


def target_section(target: TargetProject) -> str:
    """The closing section of report.md: which target the files are for and where its globals live."""
    lines = ["", f"## Target: {target.dialect.name}", ""]
    if target.dialect.externals:
        lines.append("Globals in the CONFIGURATION's VAR_GLOBAL blocks; each POU that names one declares it in "
                     "VAR_EXTERNAL (matiec needs that).")
    else:
        lines.append("Globals in global variable lists (qualified_only: references are written `GVL.name`), no "
                     "VAR_EXTERNAL; create the cyclic task in the IDE's task configuration.")
        lines += [""] + [f"- {g.name}: " + ", ".join(s.comment or "globals" for s in g.sections) for g in target.gvls]
    return "\n".join(lines) + "\n"
