"""Where each object of the project goes in a TwinCAT 3 PLC project folder, under which GUID, with which text.

TwinCAT keeps one XML file per object (`POUs/X.TcPOU`, `GVLs/X.TcGVL`, `DUTs/X.TcDUT`, the task as `X.TcTTO`)
and lists them in the `.plcproj`. Every object's declaration and body is the text the ST printer writes for
project.st, so the two cannot disagree. GUIDs are name-based (uuid5 of the project and the object), so the same
translation gives byte-identical files and a diff shows only what changed.
"""

from __future__ import annotations

import dataclasses
import re
import uuid
from pathlib import PurePosixPath
from types import MappingProxyType
from typing import Literal

from transpiler.backends.st.dialect import TargetProject
from transpiler.backends.st.task_setup import task_setups
from transpiler.backends.st.writer import StPrinter, target_gvls

# Fixed, so that GUIDs depend only on the project and object names.
GUID_NAMESPACE = uuid.UUID("6f1e2d3c-4b5a-5968-8776-a5b4c3d2e1f0")
ROOT_FOLDER = "twincat"
# The libraries TwinCAT's standard PLC project template references; Tc2_Standard holds the string functions
# (CONCAT, LEN, MID, ...) the translation calls.
LIBRARIES = ("Tc2_Standard", "Tc2_System", "Tc3_Module")
# The project-level objects a .plcproj names by GUID besides the project itself.
PROJECT_GUIDS = ("ProjectGuid", "Application", "TypeSystem", "Implicit_Task_Info", "Implicit_KindOfTask",
                 "Implicit_Jitter_Distribution", "LibraryReferences")
# The implicit objects of a task that a .TcTTO names by GUID.
TASK_GUIDS = ("TaskFBGuid", "Fb_init", "Fb_exit", "CycleUpdate", "PostCycleUpdate")

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_NOT_FILE_NAME = re.compile(r"[^A-Za-z0-9_.-]")

ObjectKind = Literal["POU", "GVL", "DUT"]
_FOLDER = MappingProxyType({"POU": "POUs", "GVL": "GVLs", "DUT": "DUTs"})
_SUFFIX = MappingProxyType({"POU": ".TcPOU", "GVL": ".TcGVL", "DUT": ".TcDUT"})


@dataclasses.dataclass(frozen=True)
class TcObject:
    """One POU, global variable list or data type, as its own file."""

    kind: ObjectKind
    name: str
    path: PurePosixPath               # inside the project folder
    guid: str
    declaration: str
    implementation: str | None        # the ST body of a POU; None for a list or a type


@dataclasses.dataclass(frozen=True)
class TcTask:
    """The cyclic task and the programs it calls, in order."""

    name: str
    path: PurePosixPath
    guid: str
    cycle_time_us: int
    priority: int
    calls: tuple[str, ...]
    implicit_guids: tuple[tuple[str, str], ...]     # (TASK_GUIDS element, GUID)


@dataclasses.dataclass(frozen=True)
class TcProject:
    """The whole PLC project folder."""

    name: str
    folder: PurePosixPath             # inside the output folder
    project_guids: tuple[tuple[str, str], ...]      # (PROJECT_GUIDS element, GUID)
    objects: tuple[TcObject, ...]
    tasks: tuple[TcTask, ...]
    libraries: tuple[str, ...] = LIBRARIES

    @property
    def plcproj(self) -> PurePosixPath:
        return PurePosixPath(f"{self.name}.plcproj")

    @property
    def folders(self) -> tuple[str, ...]:
        """The sub-folders that hold objects, in a fixed order."""
        return tuple(f for f in ("DUTs", "GVLs", "POUs") if any(o.path.parent.name == f for o in self.objects))

    @property
    def compiled(self) -> tuple[PurePosixPath, ...]:
        """Every object and task file, as the .plcproj lists them (sorted, as TwinCAT keeps them)."""
        return tuple(sorted([o.path for o in self.objects] + [t.path for t in self.tasks], key=lambda p: str(p).lower()))


def guid(*parts: str) -> str:
    """`{...}` as TwinCAT writes GUIDs: name-based, so stable across runs."""
    return "{" + str(uuid.uuid5(GUID_NAMESPACE, "\x00".join(parts))) + "}"


def project_name(name: str) -> str:
    """The project's name made safe as a folder and file name (letters, digits, `_`, `-`, `.`; no leading dot)."""
    return _NOT_FILE_NAME.sub("_", name).lstrip(".") or "Project"


def _object(project: str, kind: ObjectKind, name: str, declaration: str, implementation: str | None) -> TcObject:
    if not _IDENTIFIER.fullmatch(name):
        # The back end only makes IEC identifiers; anything else would be a bug, and could name a path.
        raise ValueError(f"{kind} name {name!r} is not an IEC identifier")
    path = PurePosixPath(_FOLDER[kind]) / f"{name}{_SUFFIX[kind]}"
    return TcObject(kind, name, path, guid(project, kind, name), declaration, implementation)


def _task(project: str, name: str, interval_ms: int, priority: int, calls: tuple[str, ...]) -> TcTask:
    if not _IDENTIFIER.fullmatch(name):
        raise ValueError(f"task name {name!r} is not an IEC identifier")
    return TcTask(name, PurePosixPath(f"{name}.TcTTO"), guid(project, "TASK", name), interval_ms * 1000, priority,
                  calls, tuple((key, guid(project, "TASK", name, key)) for key in TASK_GUIDS))


def plan_project(target: TargetProject) -> TcProject:
    """The TwinCAT project of `target` (laid out for TwinCAT): types, lists and POUs in project.st's order."""
    project = target.project
    name = project_name(project.name)
    printer = StPrinter()
    objects = [_object(name, "DUT", t.name, printer.data_type(t), None) for t in project.types]
    objects += [_object(name, "GVL", g.name, printer.gvl(g), None) for g in target_gvls(target)]
    objects += [_object(name, "POU", p.name, printer.pou_head(p), p.body) for p in project.pous]
    tasks = tuple(_task(name, s.name, s.interval_ms, s.priority, s.programs) for s in task_setups(project))
    return TcProject(name, PurePosixPath(ROOT_FOLDER) / name,
                     tuple((key, guid(name, "PROJECT", key)) for key in PROJECT_GUIDS), tuple(objects), tasks)
