"""Format a planned TwinCAT project (layout.py) as its files, with the templates of templates/twincat; decides nothing.

Each object's text goes into a CDATA section, as TwinCAT writes it. XML 1.0 cannot carry some characters at all,
and a CDATA section cannot hold `]]>`: the first become U+FFFD (as in project.xml), the second is split across two
sections, which every XML reader joins back into the same text.
"""

from __future__ import annotations

from pathlib import PurePosixPath

from transpiler.backends.plcopen.writer import xml_safe
from transpiler.backends.templating import template_environment
from transpiler.backends.twincat.layout import TcProject

# The object-file format version and the TwinCAT build the files claim (a 4024 build, as in blark's TcPOU
# fixtures); a newer TwinCAT opens them and offers to update them.
OBJECT_VERSION = "1.1.0.1"
PRODUCT_VERSION = "3.1.4024.0"
# TwinCAT writes its files as UTF-8 with a byte-order mark.
BOM = "\ufeff"


def cdata(text: str | None) -> str:
    """`text` as CDATA section(s) that read back as exactly `text` (after the XML-safe replacement)."""
    safe = xml_safe(text or "")
    return "<![CDATA[" + safe.replace("]]>", "]]]]><![CDATA[>") + "]]>"


def attr(text: str) -> str:
    """`text` escaped for a double-quoted attribute or element text."""
    # (xml.sax.saxutils.escape with '"' added does the same; importing it loads urllib and http, ~15 ms a run)
    return xml_safe(str(text)).replace("&", "&amp;").replace(">", "&gt;").replace("<", "&lt;").replace('"', "&quot;")


def winpath(path: PurePosixPath) -> str:
    """A path inside the project as the .plcproj writes it (backslashes)."""
    return "\\".join(path.parts)


def render_project(project: TcProject) -> dict[str, bytes]:
    """Every file of the project folder, keyed by its path inside the output folder ('/'-separated)."""
    env = template_environment("twincat", {"cdata": cdata, "attr": attr, "winpath": winpath})
    versions = {"object_version": OBJECT_VERSION, "product_version": PRODUCT_VERSION}
    rendered: dict[PurePosixPath, str] = {}
    for obj in project.objects:
        rendered[obj.path] = env.get_template(f"Tc{obj.kind}.j2").render(obj=obj, **versions)
    for task in project.tasks:
        rendered[task.path] = env.get_template("TcTTO.j2").render(task=task, **versions)
    rendered[project.plcproj] = env.get_template("plcproj.j2").render(project=project, **versions)
    return {str(project.folder / path): (BOM + text).encode("utf-8") for path, text in rendered.items()}
