"""Finds and reads project files: case-insensitive lookup inside the allowed folders, text in each file's encoding, split lines."""

from __future__ import annotations

import codecs
import dataclasses
import os
import re
from pathlib import Path
from types import MappingProxyType

from transpiler.diagnostics import Diagnostics, Span

MAX_FILE_BYTES = 64 * 1024 * 1024


@dataclasses.dataclass(frozen=True)
class SourceText:
    path: Path
    display: str            # path shown in diagnostics (relative to the main folder when possible)
    lines: tuple[str, ...]


class ProjectFolders:
    """The folders files may be read from: the main file's folder and each -I folder."""

    def __init__(self, main_dir: Path, include_dirs: list[Path]):
        # path -> its real path, for this run: each file is looked up, checked, loaded and named by its real path,
        # and every resolve() walks the file system again (~3 per file read)
        self._real: dict[Path, Path] = {}
        self.main_dir = self.resolved(main_dir)
        self.roots = [self.main_dir] + [self.resolved(d) for d in include_dirs]

    def resolved(self, path: Path) -> Path:
        """path.resolve(), worked out once per path in a run."""
        real = self._real.get(path)
        if real is None:
            real = self._real[path] = path.resolve()
            self._real.setdefault(real, real)      # (a real path resolves to itself)
        return real

    def display(self, path: Path) -> str:
        try:
            return str(self.resolved(path).relative_to(self.main_dir))
        except ValueError:
            return str(path)

    def inside(self, path: Path) -> bool:
        real = self.resolved(path)
        return any(real == root or root in real.parents for root in self.roots)

    def find(self, name: str, at: Span, diags: Diagnostics, relative_to: Path | None = None) -> Path | None:
        """Resolve a file name from a directive; reports E-FILE-ESCAPE / E-FILE-NOT-FOUND."""
        clean = name.strip().strip('"')
        if not clean:
            diags.report("E-FILE-NOT-FOUND", at, "empty file name")
            return None
        parts = re.split(r"[\\/]", clean)
        if os.path.isabs(clean) or clean.startswith(("/", "\\")) or re.match(r"^[A-Za-z]:", clean) or ".." in parts:
            diags.report("E-FILE-ESCAPE", at, f"file name '{clean}' leaves the project folders")
            return None
        search = ([relative_to] if relative_to else []) + self.roots
        for root in search:
            try:
                found = _find_case_insensitive(root, parts)
                escapes = found is not None and not self.inside(found)
            except (OSError, ValueError, RuntimeError) as exc:
                # The file system rejects the name (too long, NUL byte) or meets a symlink loop: no such file.
                diags.report("E-FILE-NOT-FOUND", at, f"file '{clean[:120]}' cannot be looked up: "
                            f"{getattr(exc, 'strerror', None) or exc}"[:300])
                return None
            if escapes:
                diags.report("E-FILE-ESCAPE", at, f"'{clean}' resolves outside the project folders (symlink)")
                return None
            if found is not None:
                return found
        diags.report("E-FILE-NOT-FOUND", at, f"file '{clean}' not found in {', '.join(map(str, self.roots))}")
        return None


def _find_case_insensitive(root: Path, parts: list[str]) -> Path | None:
    current = root
    for part in parts:
        if not part or part == ".":
            continue
        candidate = current / part
        if candidate.exists():
            current = candidate
            continue
        try:
            matches = sorted(p for p in current.iterdir() if p.name.lower() == part.lower())
        except OSError:
            return None
        if not matches:
            return None
        current = matches[0]
    return current if current.is_file() else None


def read_source(path: Path, folders: ProjectFolders, at: Span, diags: Diagnostics,
                encoding: str | None = None) -> SourceText | None:
    """Read a file and split it into lines, decoded as `encoding` or, when None, as detected (`decode_text`)."""
    try:
        if not path.exists():
            diags.report("E-FILE-NOT-FOUND", at, f"file {path} not found")
            return None
        if not path.is_file():
            # a FIFO or a device (e.g. `--defs /dev/zero`) would block or never end
            diags.report("E-FILE-READ", at, f"{path} is not a regular file")
            return None
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            diags.report("E-FILE-READ", at, f"{path.name} is larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB")
            return None
        data = path.read_bytes()
    except OSError as exc:
        diags.report("E-FILE-READ", at, f"cannot read {path}: {exc.strerror or exc}")
        return None
    display = folders.display(path)
    try:
        text = decode_text(data, encoding)
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        col = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        diags.report("E-ENCODING", Span(display, line, col), f"byte 0x{data[exc.start]:02X} is not valid {encoding} "
                     "(drop --encoding to detect each file's encoding)")
        return None
    lines = split_lines(text)
    if lines and lines[-1] == "":
        lines.pop()
    return SourceText(path, display, tuple(lines))


def split_lines(text: str) -> list[str]:
    """The text split at each CR LF, CR or LF (and at nothing else: str.splitlines also splits at form feeds and
    Unicode line separators)."""
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text.split("\n")     # (several times as fast as a regular expression split on a large file)


def decode_text(data: bytes, encoding: str | None = None) -> str:
    """The text of a file. Detected (encoding None): UTF-8 with or without a byte-order mark when the bytes are
    valid UTF-8, else Windows-1252 (what HEIDENHAIN's PLCdesign writes), whose five unassigned bytes are taken as
    Latin-1 so that every file reads. A forced encoding raises UnicodeDecodeError on bytes it does not allow."""
    if data.startswith(codecs.BOM_UTF8) and (encoding is None or codecs.lookup(encoding).name == "utf-8"):
        data = data[len(codecs.BOM_UTF8):]
        encoding = "utf-8"
    if encoding is not None:
        return data.decode(encoding)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1").translate(_CP1252_C1)


def _cp1252_char(byte: int) -> str | None:
    try:
        return bytes([byte]).decode("cp1252")
    except UnicodeDecodeError:
        return None


# Latin-1 text -> Windows-1252 text: the C1 range 0x80-0x9F holds printable characters in cp1252 (the en dash
# 0x96, the euro sign 0x80, ...); its five unassigned bytes stay as Latin-1 reads them.
_CP1252_C1 = MappingProxyType({b: c for b in range(0x80, 0xA0) if (c := _cp1252_char(b)) is not None})
