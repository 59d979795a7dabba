"""matiec's verdicts on a corpus of small ST files, recorded so that tests without matiec can use them.

Each tests/data/matiec_verdicts/NAME.st is one complete compilation unit (POUs plus one CONFIGURATION).
verdicts.json records, per snippet, what strict `iec2c` (no options), followed by gcc on the C it wrote, said:

    {"NAME": {"accept": bool, "message": first error line of iec2c, or of gcc for a C-FAIL (no paths), or "",
              "matiec_version": "...", "matiec_commit": "..."}}

Usage (from the repository root, with MATIEC_HOME the folder holding iec2c and its lib/):

    python -m tests.matiec_verdicts --measure   # run iec2c on every snippet and rewrite verdicts.json
    python -m tests.matiec_verdicts --check     # run iec2c and compare with verdicts.json (exit 1 on a difference)

The commit of the matiec source is taken from $MATIEC_COMMIT, else from `git -C $MATIEC_HOME rev-parse HEAD`.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from transpiler.backends.st.check import compile_with_matiec, find_iec2c, matiec_home

DATA_DIR = Path(__file__).resolve().parent / "data" / "matiec_verdicts"
VERDICTS_FILE = DATA_DIR / "verdicts.json"
SNIPPET_SUFFIX = ".st"


@dataclass(frozen=True)
class Measured:
    accept: bool
    message: str


def snippet_paths() -> list[Path]:
    return sorted(DATA_DIR.glob(f"*{SNIPPET_SUFFIX}"))


def load_verdicts() -> dict[str, dict]:
    return json.loads(VERDICTS_FILE.read_text(encoding="utf-8"))


def _normalise(line: str, *folders: Path) -> str:
    """Drop absolute paths (the temporary folder, matiec's home) from an iec2c message."""
    for folder in folders:
        line = line.replace(str(folder) + os.sep, "").replace(str(folder), "")
    return re.sub(r"(?<![\w.])/[^\s:]*/", "", line).strip()


def measure_one(iec2c: Path, text: str, filename: str) -> Measured:
    """Strict iec2c, then gcc on the C it wrote: accepted when both succeed (timeouts and crashes reject).

    A file that iec2c accepts but whose C gcc rejects (a matiec bug, "C-FAIL") is recorded as rejected, with
    the gcc message: code that does not build is not accepted by the toolchain.
    """
    home = matiec_home(iec2c)
    with tempfile.TemporaryDirectory(prefix="matiec_verdict_") as tmp:
        work = Path(tmp).resolve()
        errors = compile_with_matiec(text, work, filename)
    if not errors:
        return Measured(True, "")
    first = re.sub(r"^iec2c \(exit \d+\): ", "", errors[0])
    return Measured(False, _normalise(first, work, home.resolve(), home))


def matiec_identity(iec2c: Path) -> tuple[str, str]:
    """(version line of `iec2c -v`, source commit or 'unknown')."""
    try:
        out = subprocess.run([str(iec2c), "-v"], capture_output=True, text=True, timeout=30, check=False).stdout
    except (OSError, subprocess.TimeoutExpired):
        out = ""
    version = next((line.strip() for line in out.splitlines() if "version" in line.lower()), "unknown")
    commit = os.environ.get("MATIEC_COMMIT", "").strip()
    if not commit:
        try:
            commit = subprocess.run(["git", "-C", str(matiec_home(iec2c)), "rev-parse", "HEAD"], capture_output=True,
                                    text=True, timeout=30, check=False).stdout.strip()
        except (OSError, subprocess.TimeoutExpired):
            commit = ""
    return version, commit or "unknown"


def measure_all(iec2c: Path) -> dict[str, Measured]:
    return {path.stem: measure_one(iec2c, path.read_text(encoding="utf-8"), path.name) for path in snippet_paths()}


def _require_iec2c() -> Path:
    iec2c = find_iec2c()
    if iec2c is None:
        sys.exit("iec2c not found: set MATIEC_HOME to the folder holding iec2c and its lib/")
    return iec2c


def cmd_measure() -> int:
    iec2c = _require_iec2c()
    version, commit = matiec_identity(iec2c)
    measured = measure_all(iec2c)
    data = {name: {"accept": m.accept, "message": m.message, "matiec_version": version, "matiec_commit": commit}
            for name, m in measured.items()}
    VERDICTS_FILE.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    accepted = sum(m.accept for m in measured.values())
    print(f"{len(measured)} snippets measured with {iec2c} ({version}, {commit}): "
          f"{accepted} accepted, {len(measured) - accepted} rejected; wrote {VERDICTS_FILE.name}")
    return 0


def cmd_check() -> int:
    iec2c = _require_iec2c()
    recorded = load_verdicts()
    measured = measure_all(iec2c)
    problems: list[str] = []
    for name in sorted(set(recorded) | set(measured)):
        if name not in measured:
            problems.append(f"{name}: recorded but there is no {name}{SNIPPET_SUFFIX}")
        elif name not in recorded:
            problems.append(f"{name}: no recorded verdict (run --measure)")
        elif (recorded[name]["accept"], recorded[name]["message"]) != (measured[name].accept, measured[name].message):
            problems.append(f"{name}: recorded accept={recorded[name]['accept']} {recorded[name]['message']!r}, "
                            f"iec2c now accept={measured[name].accept} {measured[name].message!r}")
    for problem in problems:
        print(problem)
    print(f"{len(measured)} snippets, {len(problems)} difference(s)")
    return 1 if problems else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--measure", action="store_true", help="run iec2c on every snippet and rewrite verdicts.json")
    mode.add_argument("--check", action="store_true", help="run iec2c and compare with verdicts.json")
    args = parser.parse_args(argv)
    return cmd_measure() if args.measure else cmd_check()


if __name__ == "__main__":
    sys.exit(main())
