"""Format an IecProject as PLCopen TC6 XML v2.01: same POUs, types and ST bodies as the ST container.

The tree is built with xmltree (printed as lxml would print it, faster to build); lxml reads the files back.

Text is carried as escaped character data, never CDATA (Beremiz rewrites CDATA, targets.md §4.2).
XML 1.0 cannot carry most control characters (U+0000-U+001F except tab, LF and CR), lone
surrogates, U+FFFE or U+FFFF: every such character in any name, comment, initial value or body is
replaced by U+FFFD REPLACEMENT CHARACTER. Everything else, including `&`, `<`, `]]>` and
non-ASCII text, round-trips exactly.
"""

from __future__ import annotations

import importlib
import os
import re
from datetime import datetime, timezone

from transpiler.backends.iec_model import DataType, IecProject, IecVar, Pou, VarSection
from transpiler.backends.st.dialect import TargetProject
from transpiler.backends.plcopen.xmltree import Element, attribute_text, to_bytes
from transpiler.backends.st.writer import check_formattable

NS = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"
SOURCEMAP_NS = "urn:hh2iec:sourcemap"
SOURCEMAP_DATA_NAME = "https://hh2iec.invalid/sourcemap"
COMPANY_NAME = "hh2iec"
PRODUCT_NAME = "hh2iec"
REPLACEMENT = "\ufffd"
# CODESYS and TwinCAT 3 (whose PLC is CODESYS-based) export and import their global variable lists and POU
# attributes in project addData under these names; the TC6 schema lets addData hold any element.
GVL_DATA_NAME = "http://www.3s-software.com/plcopenxml/globalvars"
ATTRIBUTES_DATA_NAME = "http://www.3s-software.com/plcopenxml/attributes"

_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")

_ELEMENTARY = {name: name for name in (
    "BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT",
    "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT", "TOD")}
_ELEMENTARY.update({"DATE_AND_TIME": "DT", "TIME_OF_DAY": "TOD", "STRING": "string", "WSTRING": "wstring"})

_SECTION_ELEMENT = {
    "VAR": "localVars", "VAR_TEMP": "tempVars", "VAR_INPUT": "inputVars", "VAR_OUTPUT": "outputVars",
    "VAR_IN_OUT": "inOutVars", "VAR_EXTERNAL": "externalVars", "VAR_GLOBAL": "globalVars",
}
_POU_TYPE = {"PROGRAM": "program", "FUNCTION_BLOCK": "functionBlock", "FUNCTION": "function"}
_REPETITION = re.compile(r"^\s*(\d+)\s*\((.*)\)\s*$", re.DOTALL)


def xml_safe(text: str) -> str:
    """`text` with every character XML 1.0 cannot carry replaced by U+FFFD."""
    # (printable ASCII, nearly every name and value, needs no scan)
    return text if text.isascii() and text.isprintable() else _NOT_XML.sub(REPLACEMENT, text)


def _q(tag: str) -> str:
    return f"{{{NS}}}{tag}"


def _element(tag: str, **attributes: str) -> Element:
    """A new element of the TC6 namespace (the root's default namespace: no prefix)."""
    return Element(tag, attribute_text([(key, xml_safe(value)) for key, value in attributes.items()])
                   if attributes else "")


def _sub(parent: Element, tag: str, **attributes: str) -> Element:
    """A new last child of `parent` (as _element)."""
    child = _element(tag, **attributes)
    parent.children.append(child)
    return child


def _formatted(tag: str, text: str) -> Element:
    """A formattedText element: exactly one xhtml:p holding the escaped text."""
    element = Element(tag)
    element.sub("xhtml:p").text = xml_safe(text)
    return element


def _formatted_text(parent: Element, tag: str, text: str) -> None:
    """A new last child of `parent` (as _formatted)."""
    parent.children.append(_formatted(tag, text))


def _documentation(parent: Element, text: str | None) -> None:
    if text:
        _formatted_text(parent, "documentation", text)


# --- initial values -------------------------------------------------------------------------


def _top_level_items(text: str) -> list[str] | None:
    """`text` split at the commas outside brackets, parentheses and string literals; None when those do not balance."""
    items: list[str] = []
    depth = 0
    quote: str | None = None
    escaped = False
    start = 0
    for index, char in enumerate(text):
        if escaped:
            escaped = False
        elif quote:
            if char == "$":
                escaped = True
            elif char == quote:
                quote = None
        elif char in "'\"":
            quote = char
        elif char in "([":
            depth += 1
        elif char in ")]":
            depth -= 1
            if depth < 0:
                return None
        elif char == "," and depth == 0:
            items.append(text[start:index].strip())
            start = index + 1
    if depth or quote:
        return None
    items.append(text[start:].strip())
    return items


def _assignment(text: str) -> tuple[str, str] | None:
    """`member := value` at top level, else None."""
    parts = text.split(":=", 1)
    if len(parts) == 2 and re.fullmatch(r"\s*[A-Za-z_]\w*\s*", parts[0]):
        return parts[0].strip(), parts[1].strip()
    return None


def _value(parent: Element, tag: str, literal: str, **attributes: str) -> None:
    """An element of type ppx:value for an ST initial value: arrayValue, structValue or simpleValue."""
    element = _sub(parent, tag, **attributes)
    text = literal.strip()
    items = _top_level_items(text[1:-1]) if text.startswith("[") and text.endswith("]") else None
    if items is not None:
        array = _sub(element, "arrayValue")
        for item in items if text[1:-1].strip() else []:
            repeated = _REPETITION.match(item)
            if repeated and _top_level_items(repeated.group(2)) is not None:
                _value(array, "value", repeated.group(2), repetitionValue=repeated.group(1))
            else:
                _value(array, "value", item)
        return
    parts = _top_level_items(text[1:-1]) if text.startswith("(") and text.endswith(")") else None
    if parts is not None:
        members = [_assignment(part) for part in parts]
        if members and all(members):
            struct = _sub(element, "structValue")
            for member, value in members:  # type: ignore[misc]
                _value(struct, "value", value, member=member)
            return
    simple = _sub(element, "simpleValue")
    if text:
        simple.set("value", xml_safe(text))


# --- types, variables, POUs -----------------------------------------------------------------


def _type_ref(parent: Element, tag: str, type_name: str) -> None:
    parent.children.append(_type_element(tag, type_name))


def _type_element(tag: str, type_name: str) -> Element:
    holder = Element(tag)
    elementary = _ELEMENTARY.get(type_name.upper())
    if elementary is not None:
        holder.sub(elementary)
    else:
        _sub(holder, "derived", name=type_name)
    return holder


class _Shared:
    """The elements of one project tree that stand in many places, each built once and placed under every parent
    that holds it (xmltree prints a shared element once per indent): a global is declared again in the
    externalVars of every POU that uses it (a large project: 22,000 declarations of 3,800 variables), those
    lists carry one of a few titles, and the variables' types are a few dozen."""

    def __init__(self) -> None:
        self._variables: dict[IecVar, Element] = {}
        # (the back end gives a global one declaration record for all its places: found by identity first, without
        # hashing the record's fields; the record is kept with its element, so that its id stays its own)
        self._by_identity: dict[int, tuple[IecVar, Element]] = {}
        self._titles: dict[str, Element] = {}
        self._types: dict[str, Element] = {}

    def variable(self, parent: Element, var: IecVar) -> None:
        known = self._by_identity.get(id(var))
        if known is None:
            element = self._variables.get(var)
            if element is None:
                element = self._variables[var] = _variable(var, self)
            known = self._by_identity[id(var)] = (var, element)
        parent.children.append(known[1])

    def variable_type(self, parent: Element, type_name: str) -> None:
        """As _type_ref of a variable's `type`."""
        element = self._types.get(type_name)
        if element is None:
            element = self._types[type_name] = _type_element("type", type_name)
            element.share()
        parent.children.append(element)

    def documentation(self, parent: Element, text: str | None) -> None:
        """As _documentation."""
        if not text:
            return
        element = self._titles.get(text)
        if element is None:
            element = self._titles[text] = _formatted("documentation", text)
            element.share()
        parent.children.append(element)


def _variable(var: IecVar, shared: _Shared) -> Element:
    attributes = {"name": var.name}
    if var.address:
        attributes["address"] = var.address
    element = _element("variable", **attributes)
    element.share()
    shared.variable_type(element, var.type)
    if var.initial is not None:
        _value(element, "initialValue", var.initial)
    _documentation(element, var.comment)
    return element


def _var_list(parent: Element, section: VarSection, shared: _Shared, tag: str | None = None) -> None:
    attributes = [(name, "true") for name, on in (("constant", section.constant), ("retain", section.retain)) if on]
    element = parent.sub(tag or _SECTION_ELEMENT[section.kind], attribute_text(attributes) if attributes else "")
    for var in section.vars:
        shared.variable(element, var)
    shared.documentation(element, section.comment)


def _data_type(parent: Element, data_type: DataType, shared: _Shared) -> None:
    element = _sub(parent, "dataType", name=data_type.name)
    base = _sub(element, "baseType")
    if data_type.kind == "array":
        array = _sub(base, "array")
        for dim in data_type.dims:
            _sub(array, "dimension", lower=str(dim.lo), upper=str(dim.hi))
        _type_ref(array, "baseType", data_type.base or "")
    else:
        struct = _sub(base, "struct")
        for field in data_type.fields:
            shared.variable(struct, field)
    _documentation(element, data_type.comment)


# (the attributes every source map has, printed once)
_SOURCEMAP_DATA_ATTRIBUTES = attribute_text((("name", SOURCEMAP_DATA_NAME), ("handleUnknown", "discard")))
_SOURCEMAP_ATTRIBUTES = attribute_text((("xmlns:hh", SOURCEMAP_NS),))


def _source_map(parent: Element, pou: Pou) -> None:
    if not pou.source_map:
        return
    data = parent.sub("addData").sub("data", _SOURCEMAP_DATA_ATTRIBUTES)
    source_map = data.sub("hh:sourceMap", _SOURCEMAP_ATTRIBUTES)
    for source_range in pou.source_map:
        source_map.sub("hh:range", attribute_text((("file", xml_safe(source_range.file)),
                                                   ("first", str(source_range.first_line)),
                                                   ("last", str(source_range.last_line)))))


def _pou(parent: Element, pou: Pou, shared: _Shared) -> None:
    element = _sub(parent, "pou", name=pou.name, pouType=_POU_TYPE[pou.kind])
    interface = element.sub("interface")
    if pou.return_type:
        _type_ref(interface, "returnType", pou.return_type)
    for section in pou.sections:
        _var_list(interface, section, shared)
    _formatted_text(element.sub("body"), "ST", pou.body)
    _source_map(element, pou)
    _documentation(element, pou.comment)


def _instances(parent: Element, project: IecProject, configuration: bool, shared: _Shared) -> None:
    conf = project.configuration
    task_names = {task.name for task in conf.tasks}
    for instance in conf.instances:
        if instance.task not in task_names:
            raise ValueError(f"program instance {instance.name} names unknown task {instance.task}")
    # The schema requires `instances` and lets `configurations` stay empty.
    configurations = _sub(_sub(parent, "instances"), "configurations")
    if not configuration:
        return
    if not conf.instances and not conf.globals:
        # A library (no program runs): an empty resource is no IEC configuration (matiec rejects it after a
        # Beremiz import), so the library has none.
        return
    configuration = _sub(configurations, "configuration", name=conf.name)
    resource = _sub(configuration, "resource", name=conf.resource)
    for task in conf.tasks:
        task_element = _sub(resource, "task", name=task.name, priority=str(task.priority),
                            interval=f"T#{task.interval_ms}ms")
        for instance in conf.instances:
            if instance.task == task.name:
                _sub(task_element, "pouInstance", name=instance.name, typeName=instance.type_name)
    for section in conf.globals:
        _var_list(configuration, section, shared, tag="globalVars")


# --- header and entry point -----------------------------------------------------------------


def _product_version() -> str:
    package = importlib.import_module("transpiler")
    version = getattr(package, "__version__", None)
    return str(version) if version else "0"


def creation_stamp(creation: datetime | None = None) -> str:
    """`YYYY-MM-DDThh:mm:ss` in UTC: `creation`, else $SOURCE_DATE_EPOCH, else now.

    Raises ValueError when SOURCE_DATE_EPOCH is set but is not a usable integer.
    """
    return build_time(creation).strftime("%Y-%m-%dT%H:%M:%S")


def build_time(creation: datetime | None = None) -> datetime:
    """`creation` in UTC, else $SOURCE_DATE_EPOCH (reproducible builds), else now: the time stamped on an output
    file. Raises ValueError when SOURCE_DATE_EPOCH is set but is not a usable integer."""
    if creation is None:
        epoch = os.environ.get("SOURCE_DATE_EPOCH")
        if epoch is not None and epoch.strip():
            try:
                creation = datetime.fromtimestamp(int(epoch.strip()), tz=timezone.utc)
            except (ValueError, OverflowError, OSError) as exc:
                raise ValueError(f"SOURCE_DATE_EPOCH must be an integer count of seconds, got {epoch!r}") from exc
        else:
            creation = datetime.now(timezone.utc)
    if creation.tzinfo is not None:
        creation = creation.astimezone(timezone.utc)
    return creation


def _headers(root: Element, project: IecProject, stamp: str) -> None:
    _sub(root, "fileHeader", companyName=COMPANY_NAME, productName=PRODUCT_NAME,
         productVersion=_product_version(), creationDateTime=stamp)
    content = _sub(root, "contentHeader", name=project.name, modificationDateTime=stamp)
    if project.header_comment:
        _sub(content, "Comment").text = xml_safe(project.header_comment)
    coordinates = _sub(content, "coordinateInfo")
    for language in ("fbd", "ld", "sfc"):
        _sub(_sub(coordinates, language), "scaling", x="0", y="0")


def render_xml(project: IecProject, creation: datetime | None = None, *, configuration: bool = True) -> bytes:
    """The project as TC6 XML v2.01 bytes: UTF-8, XML declaration, pretty-printed, deterministic.

    The timestamp is `creation`, else $SOURCE_DATE_EPOCH (UTC), else the current UTC time. Without
    `configuration` the file has an empty `configurations` element (no task, no program instance).
    Raises ValueError for model shapes that cannot be written (st_writer.check_formattable).
    """
    return to_bytes(_project_tree(project, creation, configuration, _Shared()))


def _project_tree(project: IecProject, creation: datetime | None, configuration: bool, shared: _Shared
                  ) -> Element:
    check_formattable(project)
    root = Element("project", attribute_text((("xmlns", NS), ("xmlns:xhtml", XHTML))))
    _headers(root, project, creation_stamp(creation))
    types = _sub(root, "types")
    data_types = _sub(types, "dataTypes")
    for data_type in project.types:
        _data_type(data_types, data_type, shared)
    pous = _sub(types, "pous")
    for pou in project.pous:
        _pou(pous, pou, shared)
    _instances(root, project, configuration, shared)
    return root


def render_target_xml(target: TargetProject, creation: datetime | None = None) -> bytes:
    """The project in `target.dialect`'s XML flavour: for a GVL target the POUs have no externalVars, there is no
    configuration, and each global variable list is a `globalVars` in the project's addData where the
    CODESYS/TwinCAT importers look for it (with the qualified_only attribute).

    No configuration because CODESYS rejects one on import and skips everything under it (its task and program
    instances included); its own exports of POUs and lists leave `configurations` empty and keep the lists in
    addData. The task is described to the user instead (task_setup.py)."""
    if target.dialect.xml_globals == "configuration":
        return render_xml(target.project, creation)
    shared = _Shared()
    root = _project_tree(target.project, creation, False, shared)
    add_data = _sub(root, "addData")
    for gvl in target.gvls:
        # One data element per list: a TC6 data element holds exactly one child.
        data = _sub(add_data, "data", name=GVL_DATA_NAME, handleUnknown="implementation")
        qualifiers = {(s.constant, s.retain) for s in gvl.sections}
        if len(qualifiers) > 1:
            raise ValueError(f"global variable list {gvl.name} mixes CONSTANT/RETAIN sections")
        constant, retain = qualifiers.pop() if qualifiers else (False, False)
        flags = {k: "true" for k, on in (("constant", constant), ("retain", retain)) if on}
        element = _sub(data, "globalVars", name=gvl.name, **flags)
        for section in gvl.sections:
            for var in section.vars:
                shared.variable(element, var)
        if gvl.qualified_only:
            attributes = _sub(_sub(_sub(element, "addData"), "data", name=ATTRIBUTES_DATA_NAME,
                                   handleUnknown="implementation"), "Attributes")
            _sub(attributes, "Attribute", Name="qualified_only", Value="")
    return to_bytes(root)


def extract_st_bodies(xml: bytes) -> dict[str, str]:
    """Map each POU name to the text of its `<ST><xhtml:p>` body (for the one-translation equality check)."""
    from lxml import etree
    root = etree.fromstring(xml, etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=True))
    bodies: dict[str, str] = {}
    for pou in root.iterfind(f"{_q('types')}/{_q('pous')}/{_q('pou')}"):
        paragraph = pou.find(f"{_q('body')}/{_q('ST')}/{{{XHTML}}}p")
        bodies[pou.get("name")] = (paragraph.text or "") if paragraph is not None else ""
    return bodies
