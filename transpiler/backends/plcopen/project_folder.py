"""The OpenPLC Editor / Beremiz project folder: `plc.xml` (the PLCopen project, byte for byte project.xml) and
`beremiz.xml` (the editor's project settings), so that the translation opens as a project, not only as a file to
import. Both editors keep a project as exactly this folder; OpenPLC Editor is a Beremiz fork and reads the same
settings file."""

from __future__ import annotations

from lxml import etree

FOLDER = "plc_project"
PROGRAM_FILE = "plc.xml"
SETTINGS_FILE = "beremiz.xml"


def settings_xml() -> bytes:
    """The settings of a new local project: the host as target (`TargetType` empty: the editor picks it when it
    builds), no Python runtime extension (the program needs none, and without this line the editor adds it)."""
    root = etree.Element("BeremizRoot", nsmap={"xsd": "http://www.w3.org/2001/XMLSchema"})
    root.set("URI_location", "LOCAL://")
    etree.SubElement(root, "TargetType")
    etree.SubElement(root, "Libraries", Enable_Python_Library="false")
    return etree.tostring(root, pretty_print=True, xml_declaration=True, encoding="utf-8")


def project_folder(project_xml: bytes) -> dict[str, bytes]:
    """Output file name (inside the output folder) -> content of the project folder for `project_xml`."""
    return {f"{FOLDER}/{PROGRAM_FILE}": project_xml, f"{FOLDER}/{SETTINGS_FILE}": settings_xml()}
