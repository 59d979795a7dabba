"""Screen masks drawn as text, the way the PLC window shows them, from either side of a run.

One renderer serves the reference interpreter and the translated ST: it reads every value through a lookup
`(kind, addr) -> value` (None where the side holds no such operand), so the two screens of one cycle are drawn by
the same code and differ only where the values differ. The undocumented corners (how %d and %D differ, what /c
does) follow assumptions A-63 and A-64; the error queue lists the set PLC error markers (A-41) in ascending order.
"""

from __future__ import annotations

import dataclasses
from decimal import Decimal
from typing import Callable, Iterable, Sequence

from transpiler.ir import WIDTH, Mask, MaskField, MaskStatement, Program
from transpiler.language.semantics import Semantics

Lookup = Callable[[str, int], "int | str | None"]
NOT_HELD = "?"              # a field whose operand the side does not hold
UNKNOWN_STATUS = "----"     # the status letters of an error come from the PLC error table, which hh2iec does not read


@dataclasses.dataclass(frozen=True)
class ScreenRequest:
    """`--show-mask NAME@CYCLE`: draw `mask` after `cycle` (0-based, as the scenario's cycles)."""

    mask: Mask
    cycle: int


@dataclasses.dataclass(frozen=True)
class Screen:
    """One mask drawn after one cycle of one run; `translated` is None where only the reference ran (simulate) and
    both are None where the run ended before that cycle (`note` says why)."""

    scenario: str
    mask: str
    cycle: int
    original: tuple[str, ...] | None
    translated: tuple[str, ...] | None = None
    note: str = ""

    @property
    def differs(self) -> bool:
        return self.original is not None and self.translated is not None and self.original != self.translated


def find_mask(masks: Sequence[Mask], name: str) -> Mask | None:
    """The mask named `name`: its file name, or its file name without the extension, compared ignoring case."""
    wanted = name.lower()
    exact = [m for m in masks if m.name.lower() == wanted]
    if exact:
        return exact[0]
    stems = [m for m in masks if m.name.rsplit(".", 1)[0].lower() == wanted]
    return stems[0] if len(stems) == 1 else None


def parse_requests(masks: Sequence[Mask], specs: Iterable[str]) -> tuple[list[ScreenRequest], list[str]]:
    """The requests of `NAME@CYCLE` texts, and a message for each one that names no mask or no cycle."""
    requests, problems = [], []
    known = ", ".join(m.name for m in masks) or "none (no *.msk or *.a file beside the main program)"
    for spec in specs:
        name, at, cycle = spec.rpartition("@")
        if not at or not name or not cycle.strip().isdigit():
            problems.append(f"--show-mask {spec!r}: expected NAME@CYCLE, e.g. M_dia_wz@40")
            continue
        mask = find_mask(masks, name.strip())
        if mask is None:
            problems.append(f"--show-mask {spec!r}: no mask named {name.strip()!r}; the project's masks: {known}")
            continue
        requests.append(ScreenRequest(mask, int(cycle)))
    return requests, problems


def render_mask(mask: Mask, read: Lookup, program: Program) -> tuple[str, ...]:
    """The screen's lines after the statements of `mask` are drawn with the values `read` gives."""
    out: list[str] = []
    for stmt in mask.statements:
        if stmt.kind in ("text", "line"):
            out.extend(p if isinstance(p, str) else format_field(p, read(p.ref.kind, p.ref.addr), program.semantics)
                       for p in stmt.pieces)
        elif stmt.kind == "errque":
            out.extend(line + "\n" for line in error_queue(stmt, read, program))
    lines = "".join(out).split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return tuple(lines)


def format_field(field: MaskField, value: int | str | None, semantics: Semantics) -> str:
    """One field as printf would write it (flags, width, precision), with the mask's modifiers applied."""
    width = field.width or 0
    if value is None:
        return NOT_HELD * max(width, 1)
    flags = "".join(f for f in "-+ 0#" if f in field.flags)
    precision = "" if field.precision is None else f".{field.precision}"
    if field.conversion == "s":
        text = (f"%{flags.replace('0', '').replace('+', '')}{width or ''}{precision}s") % str(value)
    elif field.conversion == "F":
        text = _fixed_point(int(value), field, flags)
    else:
        number = int(value)
        if field.conversion == "d" and semantics["mask_d_format"] == "d_unsigned" and field.ref.kind in "BWD":
            number &= (1 << WIDTH[field.ref.kind]) - 1
        text = (f"%{flags}{width or ''}{precision}d") % number
    if width and len(text) > width and "c" in field.ref.modifiers and semantics["mask_c_modifier"] == "clip":
        return "*" * width
    return text


def _fixed_point(value: int, field: MaskField, flags: str) -> str:
    """The value with `/n=k` decimal places (12345 with /n=3 is 12.345), written with the format's precision
    (rounded half to even, exactly: Decimal, not float)."""
    number = Decimal(value).scaleb(-field.ref.decimals)
    align = "<" if "-" in flags else ""
    sign = "+" if "+" in flags else (" " if " " in flags else "")
    zero = "0" if "0" in flags and not align else ""
    precision = 6 if field.precision is None else field.precision
    return format(number, f"{align}{sign}{zero}{field.width or ''}.{precision}f")


def error_queue(stmt: MaskStatement, read: Lookup, program: Program) -> list[str]:
    """`ERRQUE=n`: n lines, one per set PLC error marker in ascending order, then empty lines. A line is the message
    number (with /l), the status column (with /s; shown as ---- because the status letters live in the PLC error
    table, which hh2iec does not read) and the marker's symbol (or the marker itself)."""
    first, last = program.semantics.profile.interface.error_markers
    names: dict[int, str] = {}
    for sym in sorted(program.symbols.values(), key=lambda s: (s.alias_of is not None, s.name)):
        if sym.kind == "M" and first <= sym.addr <= last:
            names.setdefault(sym.addr, sym.name)
    lines = []
    for marker in range(first, last + 1):
        if len(lines) == stmt.lines:
            break
        if read("M", marker):
            parts = [f"{marker - first:3d}"] if "l" in stmt.modifiers else []
            if "s" in stmt.modifiers:
                parts.append(UNKNOWN_STATUS)
            parts.append(names.get(marker, f"M{marker}"))
            lines.append(" ".join(parts))
    return lines + [""] * (stmt.lines - len(lines))


def render_text(screen: Screen) -> str:
    """A screen as the command line prints it: a title line, then each line of the screen between bars."""
    def framed(lines: tuple[str, ...]) -> str:
        return "".join(f"  |{line}\n" for line in lines)
    head = f"mask {screen.mask} after cycle {screen.cycle} of {screen.scenario}"
    if screen.original is None:
        return f"{head}: not drawn: {screen.note}\n"
    if screen.translated is None:
        return f"{head}:\n{framed(screen.original)}"
    if not screen.differs:
        return f"{head} (original and translation draw the same screen):\n{framed(screen.original)}"
    return (f"{head}: SCREENS DIFFER\n original:\n{framed(screen.original)} translated:\n"
            f"{framed(screen.translated)}")


def draw_both_sides(program: Program, make_side, iomap, scenarios, names, requests: Sequence[ScreenRequest],
                    base_mp=None) -> tuple[Screen, ...]:
    """Each scenario replayed in lockstep (cosim.cosimulate) up to the last cycle asked for, each requested mask
    drawn from the interpreter's operands and from the ST's variables (through the io map) after its cycle."""
    from transpiler.verify.cosim import cosimulate
    by_cycle: dict[int, list[int]] = {}
    for i, request in enumerate(requests):
        by_cycle.setdefault(request.cycle, []).append(i)
    screens: list[Screen] = []
    for scenario in scenarios:
        drawn: dict[int, tuple[tuple[str, ...], tuple[str, ...]]] = {}

        def inspect(cycle: int, original: Lookup, translated: Lookup) -> None:
            for i in by_cycle.get(cycle, ()):
                mask = requests[i].mask
                drawn[i] = (render_mask(mask, original, program), render_mask(mask, translated, program))
        last = max(by_cycle) + 1
        result = cosimulate(program, make_side, iomap, scenario, names, cycles=last, base_mp=base_mp, inspect=inspect)
        if result.error is not None:
            why = f"the run stopped: {result.error}"
        elif result.divergence is not None:
            why = f"the run diverged after cycle {result.divergence.cycle} ({result.divergence.name})"
        else:
            why = f"the scenario has {result.cycles_run} cycles"
        for i, request in enumerate(requests):
            original, translated = drawn.get(i, (None, None))
            screens.append(Screen(scenario.name or "scenario", request.mask.name, request.cycle, original, translated,
                                  "" if i in drawn else why))
    return tuple(screens)
