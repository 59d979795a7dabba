"""Independent checks of emitted ST: tree-sitter and blark syntax gates, and compilation with matiec (iec2c + gcc)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

IEC2C_TIMEOUT_S = 120
GCC_TIMEOUT_S = 120
# Enough to locate the problem without flooding a CI log with cascading errors.
MAX_MESSAGES = 20

_CONFIG_START = re.compile(r"^\s*CONFIGURATION\b", re.IGNORECASE)
_CONFIG_END = re.compile(r"^\s*END_CONFIGURATION\b", re.IGNORECASE)


class MatiecUnavailable(Exception):
    """iec2c (or gcc for the C stage) cannot be found."""


def _column(line_bytes: bytes, byte_column: int) -> int:
    """tree-sitter counts bytes; report characters (1-based) so non-ASCII text does not shift columns."""
    return len(line_bytes[:byte_column].decode("utf-8", errors="replace")) + 1


def check_tree_sitter(st_text: str, filename: str) -> list[str]:
    """Syntax errors found by tree-sitter-iec61131-3-st on the whole file, as `FILE:LINE:COL: error: ...`."""
    import tree_sitter_iec61131_3_st as tsst
    from tree_sitter import Language, Parser

    source = st_text.encode("utf-8")
    tree = Parser(Language(tsst.language())).parse(source)
    if not tree.root_node.has_error:
        return []
    lines = source.split(b"\n")
    messages: list[str] = []
    stack = [tree.root_node]
    while stack and len(messages) < MAX_MESSAGES:
        node = stack.pop()
        if node.is_missing or node.is_error:
            row, byte_col = node.start_point
            line = lines[row] if row < len(lines) else b""
            where = f"{filename}:{row + 1}:{_column(line, byte_col)}"
            if node.is_missing:
                messages.append(f"{where}: error: MISSING {node.type}")
            else:
                snippet = source[node.start_byte:node.end_byte].decode("utf-8", errors="replace")
                snippet = " ".join(snippet.split())[:60]
                messages.append(f"{where}: error: unexpected {snippet!r}")
            if node.is_error:
                # children of an error node only repeat the same fault
                continue
        if node.has_error:
            stack.extend(reversed(node.children))
    return messages or [f"{filename}:1:1: error: tree-sitter reports a syntax error it does not locate"]


def strip_configuration(st_text: str) -> tuple[str, list[str]]:
    """Blank out CONFIGURATION ... END_CONFIGURATION (blark cannot parse it), keeping line numbers.

    Returns the text and problems found while stripping (an unterminated configuration).
    """
    lines = st_text.split("\n")
    problems: list[str] = []
    index = 0
    while index < len(lines):
        if _CONFIG_START.match(lines[index]):
            start = index
            while index < len(lines) and not _CONFIG_END.match(lines[index]):
                index += 1
            if index == len(lines):
                problems.append(f"{start + 1}:1: error: CONFIGURATION without END_CONFIGURATION")
            for blank in range(start, min(index + 1, len(lines))):
                lines[blank] = ""
        index += 1
    return "\n".join(lines), problems


def check_blark(st_text: str, filename: str) -> list[str]:
    """Syntax errors found by blark on the POUs and types (the configuration is stripped first)."""
    from blark.parse import parse_source_code

    text, problems = strip_configuration(st_text)
    messages = [f"{filename}:{problem}" for problem in problems]
    # blark parses with Earley, which is far slower than linear on a long file: give it one top-level
    # declaration at a time, padded with blank lines so that its line numbers stay those of the file.
    lines = text.split("\n")
    for start, end in _top_level_chunks(lines):
        chunk = "\n" * start + "\n".join(lines[start:end])
        try:
            result = parse_source_code(chunk, fn=filename)
            error = result.exception
            if error is None:
                result.transform()
        except Exception as exc:  # blark's transformer may fail on trees it accepted; that is a finding, not a crash
            error = exc
        if error is not None:
            line = getattr(error, "line", None)
            column = getattr(error, "column", None)
            where = f"{filename}:{line}:{column}" if isinstance(line, int) and line > 0 else f"{filename}:{start + 1}:1"
            first = str(error).strip().splitlines()
            messages.append(f"{where}: error: blark: {first[0] if first else type(error).__name__}")
    return messages


_TOP_START = re.compile(r"^(TYPE|FUNCTION_BLOCK|FUNCTION|PROGRAM|VAR_GLOBAL)\b", re.IGNORECASE)
_TOP_END = re.compile(r"^(END_TYPE|END_FUNCTION_BLOCK|END_FUNCTION|END_PROGRAM|END_VAR)\b", re.IGNORECASE)


def _top_level_chunks(lines: list[str]) -> list[tuple[int, int]]:
    """Line ranges [start, end) of the top-level declarations (a declaration starts at column 0)."""
    chunks: list[tuple[int, int]] = []
    start = None
    for index, line in enumerate(lines):
        if start is None and _TOP_START.match(line):
            start = index
        elif start is not None and _TOP_END.match(line) and not line.startswith((" ", "\t")):
            if (lines[start].upper().startswith("VAR_GLOBAL") or not line.upper().startswith("END_VAR")):
                chunks.append((start, index + 1))
                start = None
    if start is not None or not chunks:
        chunks.append((0 if start is None else start, len(lines)))
    return chunks


def find_iec2c() -> Path | None:
    """$MATIEC_HOME/iec2c when it exists, else iec2c on PATH, else None."""
    home = os.environ.get("MATIEC_HOME")
    if home:
        candidate = Path(home) / "iec2c"
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    found = shutil.which("iec2c")
    return Path(found) if found else None


def matiec_home(iec2c: Path) -> Path:
    """The folder holding iec2c and lib/ ($MATIEC_HOME when set)."""
    home = os.environ.get("MATIEC_HOME")
    if home and (Path(home) / "lib").is_dir():
        return Path(home)
    return iec2c.parent


def _run(command: list[str], cwd: Path, timeout: int) -> tuple[int | None, str]:
    """Return code (None on timeout) and combined output."""
    try:
        result = subprocess.run(command, cwd=cwd, capture_output=True, text=True, errors="replace",
                                timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return None, ""
    return result.returncode, (result.stdout or "") + (result.stderr or "")


def _error_lines(output: str) -> list[str]:
    lines = [line for line in output.splitlines() if "error" in line.lower()]
    return (lines or output.strip().splitlines()[-5:])[:MAX_MESSAGES]


# The option sets the toolchains use (targets.md): strict, Beremiz, OpenPLC v3.
STRICT_FLAGS: tuple[str, ...] = ()
BEREMIZ_FLAGS = ("-f", "-l", "-p")
OPENPLC_FLAGS = ("-f", "-l", "-p", "-r", "-R", "-a")


def compile_with_matiec(st_text: str, workdir: Path, filename: str = "project.st",
                        flags: Sequence[str] = STRICT_FLAGS) -> list[str]:
    """Compile with `iec2c [flags] -I $MATIEC_HOME/lib -T workdir`, then gcc -c the configuration and resource C files.

    Returns error strings (empty = OK). Raises MatiecUnavailable when iec2c or gcc is missing.
    """
    iec2c = find_iec2c()
    if iec2c is None:
        raise MatiecUnavailable("iec2c not found: set MATIEC_HOME or put iec2c on PATH")
    gcc = shutil.which("gcc")
    if gcc is None:
        raise MatiecUnavailable("gcc not found on PATH (needed to compile matiec's C output)")
    home = matiec_home(iec2c)
    workdir = Path(workdir).resolve()
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / filename).write_text(st_text, encoding="utf-8", newline="\n")
    code, output = _run([str(iec2c), *flags, "-I", str(home / "lib"), "-T", str(workdir), filename], workdir, IEC2C_TIMEOUT_S)
    if code is None:
        return [f"{filename}: error: iec2c timed out after {IEC2C_TIMEOUT_S} s"]
    if code != 0:
        return [f"iec2c (exit {code}): {line}" for line in _error_lines(output)]
    return _compile_c(gcc, home, workdir)


def _compile_c(gcc: str, home: Path, workdir: Path) -> list[str]:
    """gcc -c every generated configuration/resource file (POUS.c is included by the resource file)."""
    sources = sorted(path for path in workdir.glob("*.c") if path.name != "POUS.c")
    if not sources:
        return ["iec2c wrote no configuration C file (is there a CONFIGURATION?)"]
    errors: list[str] = []
    for source in sources:
        command = [gcc, f"-I{home / 'lib' / 'C'}", f"-I{workdir}", "-fwrapv", "-Wno-unused-function",
                   "-c", str(source), "-o", str(source.with_suffix(".o"))]
        code, output = _run(command, workdir, GCC_TIMEOUT_S)
        if code is None:
            errors.append(f"{source.name}: error: gcc timed out after {GCC_TIMEOUT_S} s")
        elif code != 0:
            errors.extend(f"gcc {source.name} (C-FAIL, exit {code}): {line}" for line in _error_lines(output))
    return errors
