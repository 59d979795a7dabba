"""Where a line of emitted ST comes from: its POU and the HEIDENHAIN source line named by the nearest
traceability tag (`(* main.src:32 *)`), so that a fault in the translation points at the original."""

from __future__ import annotations

import re

_POU_START = re.compile(r"^\s*(PROGRAM|FUNCTION_BLOCK|FUNCTION)\s+(\w+)", re.I)
_TAG = re.compile(r"([\w./\\-]+\.\w+:\d+)\s*\*\)")
_LOOP = re.compile(r"^\s*(WHILE|REPEAT|FOR)\b", re.I)


def st_origin(st_text: str, line: int) -> str:
    """`POU name, ST line N, from file:line` for 1-based `line` of `st_text` (parts that cannot be found left out)."""
    lines = st_text.splitlines()
    pou = tag = None
    for number in range(min(line, len(lines)), 0, -1):
        text = lines[number - 1]
        if tag is None:
            found = _TAG.findall(text)
            tag = found[-1] if found else None
        start = _POU_START.match(text)
        if start:
            pou = start.group(2)
            break
    parts = ([f"POU {pou}"] if pou else []) + [f"ST line {line}"] + ([f"from {tag}"] if tag else [])
    return ", ".join(parts)


def loop_sites(st_text: str) -> list[str]:
    """Every WHILE/REPEAT/FOR of the text, located as by st_origin: the places where a cycle can run forever."""
    return [st_origin(st_text, n) for n, text in enumerate(st_text.splitlines(), 1) if _LOOP.match(text)]
