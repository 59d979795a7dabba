"""Format an IecProject as one IEC 61131-3 Structured Text file (jinja2 templates in templates/st/); decides nothing."""

from __future__ import annotations

import dataclasses
import re
from typing import Iterable

import jinja2

from transpiler.backends.iec_model import DataType, IecProject, IecVar, Pou, VarSection, st_comment
from transpiler.backends.st.dialect import Gvl, TargetProject
from transpiler.backends.st.task_setup import task_lines
from transpiler.backends.templating import template_environment

BODY_INDENT = "    "

_LINE_BREAK = re.compile(r"\r\n|\r|\n")
_POU_HEADER = re.compile(r"^(PROGRAM|FUNCTION_BLOCK|FUNCTION) (\S+)")


def comment_lines(text: str | None) -> list[str]:
    """Own-line comments: one `(* ... *)` per source line, so no comment line can look like a declaration."""
    if not text:
        return []
    return [st_comment(line) for line in _LINE_BREAK.split(text)]


def trailing_comment(text: str | None) -> str:
    """A comment that must fit on its declaration line: line breaks become spaces (the XML keeps them)."""
    if not text:
        return ""
    return " " + st_comment(_LINE_BREAK.sub(" ", text))


def indent_body(body: str) -> str:
    """Indent every non-empty line by BODY_INDENT; extract_pou_bodies undoes exactly this."""
    return "\n".join(BODY_INDENT + line if line else "" for line in body.split("\n"))


def declaration(var: IecVar) -> str:
    """One declaration line without its indent: `name [AT address] : type [:= initial];` and its comment.
    (A filter, not a template macro: a project declares tens of thousands of variables, and a macro call costs
    several times the line's text.)"""
    located = f" AT {var.address}" if var.address else ""
    initial = f" := {var.initial}" if var.initial is not None else ""
    return f"{var.name}{located} : {var.type}{initial};{trailing_comment(var.comment)}"


def var_sections(sections: Iterable[VarSection], indent: str) -> str:
    """The variable sections (of a POU, the configuration or a global variable list), each as located_blocks splits
    it: its header line with the section's comment, one declaration line per variable, END_VAR; every line ends
    with a line break. (A filter, not template loops: tens of thousands of declarations print several times faster
    so.)"""
    lines = []
    for section in sections:
        for block in located_blocks(section):
            lines.append(f"{indent}{section_header(block)}{trailing_comment(block.comment)}\n")
            lines.extend(f"{indent}    {declaration(var)}\n" for var in block.vars)
            lines.append(f"{indent}END_VAR\n")
    return "".join(lines)


def section_header(section: VarSection) -> str:
    if section.constant and section.retain:
        raise ValueError(f"a {section.kind} section cannot be both CONSTANT and RETAIN")
    qualifier = " CONSTANT" if section.constant else " RETAIN" if section.retain else ""
    return section.kind + qualifier


def located_blocks(section: VarSection) -> list[VarSection]:
    """Split a section into runs of located and of plain variables: matiec rejects a block that mixes them."""
    located = [var.address is not None for var in section.vars]
    if all(located) or not any(located):
        return [section]        # (nearly every section: one block, the section itself)
    blocks: list[VarSection] = []
    run: list[IecVar] = []
    for var in section.vars:
        if run and (run[-1].address is None) != (var.address is None):
            blocks.append(_block(section, run, first=not blocks))
            run = []
        run.append(var)
    if run or not blocks:
        blocks.append(_block(section, run, first=not blocks))
    return blocks


def _block(section: VarSection, run: list[IecVar], first: bool) -> VarSection:
    return VarSection(kind=section.kind, vars=tuple(run), constant=section.constant,
                      retain=section.retain, comment=section.comment if first else None)


def _environment() -> jinja2.Environment:
    return template_environment("st", dict(
        comment_lines=comment_lines,
        trailing_comment=trailing_comment,
        indent_body=indent_body,
        declaration=declaration,
        var_sections=var_sections,
    ))


def check_formattable(project: IecProject) -> None:
    """Refuse model shapes that neither container can express (a bug in the producer of the model)."""
    for data_type in project.types:
        if data_type.kind == "array" and (not data_type.base or not data_type.dims):
            raise ValueError(f"array type {data_type.name} needs a base type and at least one dimension")
        if data_type.kind == "struct" and not data_type.fields:
            raise ValueError(f"struct type {data_type.name} has no fields")
    for pou in project.pous:
        if (pou.kind == "FUNCTION") != bool(pou.return_type):
            raise ValueError(f"{pou.kind} {pou.name}: a return type is required for, and only for, a FUNCTION")
    for section in [s for pou in project.pous for s in pou.sections] + list(project.configuration.globals):
        section_header(section)


def render_st(project: IecProject) -> str:
    """The whole project as one ST file: header, TYPEs, POUs in the given order, one CONFIGURATION.

    Raises ValueError for model shapes that cannot be written (see check_formattable).
    """
    return StPrinter().project(project)


def render_target_st(target: TargetProject) -> str:
    """The project as `target.dialect` lays it out (the matiec layout is exactly render_st's)."""
    return StPrinter().target(target)


def target_gvls(target: TargetProject) -> tuple[Gvl, ...]:
    """The global variable lists as the target's ST declares them (initialised arrays inlined where it needs that).

    Raises ValueError for a section that cannot be written (see section_header)."""
    for gvl in target.gvls:
        for section in gvl.sections:
            section_header(section)
    if not target.dialect.inline_initialised_arrays:
        return target.gvls
    arrays = {t.name: t for t in target.project.types if t.kind == "array"}
    return tuple(dataclasses.replace(g, sections=tuple(dataclasses.replace(s, vars=tuple(
        _inline_array(v, arrays) for v in s.vars)) for s in g.sections)) for g in target.gvls)


class StPrinter:
    """Prints projects, and one object at a time the pieces of project.st that a per-object project (TwinCAT) stores
    in files of their own, from one template environment for all of them (a translation prints its project and its
    libraries: compiling the templates again for each costs as much as printing a library)."""

    def __init__(self) -> None:
        self._env = _environment()

    def _render(self, template: str, **context: object) -> str:
        return self._env.get_template(template).render(**context).rstrip("\n") + "\n"

    def project(self, project: IecProject) -> str:
        """As render_st."""
        check_formattable(project)
        return self._render("project.st.j2", project=project)

    def target(self, target: TargetProject) -> str:
        """As render_target_st."""
        if target.dialect.st_template == "project.st.j2":
            return self.project(target.project)
        check_formattable(target.project)
        return self._render(target.dialect.st_template, project=target.project, gvls=target_gvls(target),
                            dialect=target.dialect, task_lines=task_lines(target))

    def pou_head(self, pou: Pou) -> str:
        """A POU's declaration part: comments, header and variable sections, no body."""
        return self._env.get_template("pou.st.j2").module.head(pou).rstrip("\n") + "\n"

    def gvl(self, gvl: Gvl) -> str:
        """A global variable list's declaration under the list's name (attribute, VAR_GLOBAL)."""
        return self._render("gvl.st.j2", gvl=gvl)

    def data_type(self, data_type: DataType) -> str:
        """One named TYPE."""
        return self._render("type.st.j2", type=data_type)


def _inline_array(var: IecVar, arrays: dict) -> IecVar:
    """An initialised global of a named array type declared with the array spec itself (blark, which parses as
    TwinCAT does, takes `[..]` initialisers only after an ARRAY spec); the XML keeps the named type."""
    data_type = arrays.get(var.type)
    if data_type is None or var.initial is None:
        return var
    dims = ", ".join(f"{d.lo}..{d.hi}" for d in data_type.dims)
    return dataclasses.replace(var, type=f"ARRAY[{dims}] OF {data_type.base}")


def extract_pou_bodies(st_text: str) -> dict[str, str]:
    """Map each POU name to its body as render_st wrote it, de-indented back to the exact `Pou.body`.

    Raises ValueError when the text is not in render_st's layout.
    """
    lines = st_text.split("\n")
    bodies: dict[str, str] = {}
    index = 0
    while index < len(lines):
        match = _POU_HEADER.match(lines[index])
        if match is None:
            index += 1
            continue
        kind, name = match.group(1), match.group(2)
        index = _skip_sections(lines, index + 1)
        body, index = _collect_body(lines, index, f"END_{kind}")
        bodies[name] = body
    return bodies


def _skip_sections(lines: list[str], index: int) -> int:
    while index < len(lines) and lines[index].startswith("VAR"):
        while index < len(lines) and lines[index] != "END_VAR":
            index += 1
        index += 1
    return index


def _collect_body(lines: list[str], index: int, end: str) -> tuple[str, int]:
    body: list[str] = []
    while index < len(lines) and lines[index] != end:
        line = lines[index]
        if line and not line.startswith(BODY_INDENT):
            raise ValueError(f"line {index + 1}: body line not indented by {len(BODY_INDENT)} spaces: {line!r}")
        body.append(line[len(BODY_INDENT):])
        index += 1
    if index >= len(lines):
        raise ValueError(f"missing {end}")
    return "\n".join(body), index + 1

