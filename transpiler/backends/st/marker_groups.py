"""Marker structs: which symbolic markers the ST declares as the members of one STRUCT, by the prefix of their symbols.

HEIDENHAIN symbols name an operand `<area>_<group>_<name>` (`ML_ax_inpos`: a local marker of the axis clamping).
The markers of one group become one global of a STRUCT type, `ML_ax : T_ML_ax` with `ML_ax.inpos`, where that
changes no more than the spelling of each reference. The rule, applied to the symbolic operands the ST declares
(its first symbol where several name one operand):

- the prefix of a symbol is its first two `_`-separated parts, the member the rest (`ML_ax_clamp_start` ->
  `ML_ax`, `clamp_start`); a symbol with fewer than three parts, or an empty part, has no prefix;
- a prefix that at least MIN_MEMBERS markers share is grouped, unless one of these keeps every symbol of it a
  separate variable (one line of the migration report says which):
  - a symbol of the prefix names another operand than a plain marker: an input, an output, a timer, a word, a
    marker of the NC interface (a STRUCT would split the prefix, and the process image and the NC interface
    keep one variable per operand);
  - some members are non-volatile (the `nonvolatile` setting, A-44) and others are not: RETAIN is declared for
    a whole variable;
  - a member is no IEC identifier as it stands (`ML_inpos_4` -> `4`), an IEC keyword or standard name (`AND`),
    or differs from another member only in case;
  - the prefix is spelled in two ways, or the group name or the type name `T_<prefix>` is already a name of the
    program (a POU, a variable, any symbol, in any case), a keyword, or starts with `HH_` (the translator's own).

Members are always plain BOOL markers without address or initial value. A marker reached through the index
register is one too: the accessor FB's CASE names the member (`42: ML_ax.inpos := VALUE;`), and only the
markers without a symbol live in the array of the unnamed ones.
"""

from __future__ import annotations

import dataclasses
import re
from collections import defaultdict
from typing import Callable, Iterable

from transpiler.backends.st.names import MAX_LEN, RESERVED, legalise
from transpiler.records import quick_init

# Two markers share a prefix by accident about as often as by design (ML_spindle_turning, ML_spindle_turning_mem);
# from three on, the prefix names a group worth a type of its own.
MIN_MEMBERS = 3
PREFIX_PARTS = 2
TYPE_PREFIX = "T_"


@quick_init
@dataclasses.dataclass(frozen=True)
class SymbolicOperand:
    """An operand the ST declares with a symbol; `role` says why it cannot be a member (None: a plain marker)."""

    kind: str
    addr: int
    symbol: str
    role: str | None = None
    retained: bool = False          # in a non-volatile range

    @property
    def operand(self) -> str:
        return f"{self.kind}{self.addr}"


@dataclasses.dataclass(frozen=True)
class MarkerGroup:
    """One STRUCT: the global `name` of type `type_name`, its members (marker address, member name) by address."""

    name: str
    type_name: str
    members: tuple[tuple[int, str], ...]

    def path(self, member: str) -> str:
        return f"{self.name}.{member}"

    def addresses(self) -> str:
        """The members' markers as ranges: `M42-M51`, `M24-M28, M1000`."""
        runs: list[list[int]] = []
        for addr, _ in self.members:
            if runs and addr == runs[-1][1] + 1:
                runs[-1][1] = addr
            else:
                runs.append([addr, addr])
        return ", ".join(f"M{lo}" if lo == hi else f"M{lo}-M{hi}" for lo, hi in runs)


@dataclasses.dataclass(frozen=True)
class Refusal:
    """A prefix MIN_MEMBERS markers share that stays separate variables, and why."""

    prefix: str
    reason: str


def split_symbol(symbol: str) -> tuple[str, str] | None:
    """(prefix, member) of a symbol, or None when it has no prefix."""
    parts = symbol.split("_")
    if len(parts) <= PREFIX_PARTS or not all(parts):
        return None
    return "_".join(parts[:PREFIX_PARTS]), "_".join(parts[PREFIX_PARTS:])


def nonvolatile_ranges(text: str, kind: str) -> list[tuple[int, int]]:
    """The address ranges of `kind` in the `nonvolatile` setting (`M1000-2000,B0-127`); entries it does not
    understand name nothing."""
    ranges = []
    for entry in text.split(","):
        m = re.fullmatch(r"\s*([A-Za-z])\s*(\d+)(?:\s*-\s*(\d+))?\s*", entry)
        if m is not None and m.group(1).upper() == kind:
            ranges.append((int(m.group(2)), int(m.group(3) or m.group(2))))
    return ranges


def plan_groups(operands: Iterable[SymbolicOperand], name_in_use: Callable[[str], str | None]
                ) -> tuple[list[MarkerGroup], list[Refusal]]:
    """The groups of `operands` and the refused prefixes. `name_in_use(name)` says what a would-be group or type
    name already is in the program (None: free); keywords are checked here."""
    by_prefix: dict[str, list[tuple[SymbolicOperand, str, str]]] = defaultdict(list)
    for o in operands:
        split = split_symbol(o.symbol)
        if split is not None:
            by_prefix[split[0].upper()].append((o, *split))
    groups: list[MarkerGroup] = []
    refusals: list[Refusal] = []
    for entries in by_prefix.values():
        entries.sort(key=lambda e: (e[0].kind != "M", e[0].kind, e[0].addr))
        markers = [e for e in entries if e[0].kind == "M"]
        if len(markers) < MIN_MEMBERS:
            continue
        prefix = entries[0][1]
        reason = _refusal(prefix, entries, name_in_use)
        if reason is not None:
            refusals.append(Refusal(prefix, reason))
            continue
        groups.append(MarkerGroup(prefix, TYPE_PREFIX + prefix, tuple((o.addr, member) for o, _, member in entries)))
    groups.sort(key=lambda g: g.members[0][0])
    refusals.sort(key=lambda r: r.prefix.upper())
    return groups, refusals


def _refusal(prefix: str, entries: list[tuple[SymbolicOperand, str, str]],
             name_in_use: Callable[[str], str | None]) -> str | None:
    """Why the prefix's symbols stay separate variables (None: they make one STRUCT)."""
    spellings = sorted({p for _, p, _ in entries})
    if len(spellings) > 1:
        return f"the prefix is spelled {' and '.join(spellings)}"
    for o, _, _ in entries:
        if o.role is not None:
            return f"{o.symbol} ({o.operand}) is {o.role}, not a plain marker"
    retained = {o.retained for o, _, _ in entries}
    if len(retained) > 1:
        kept = next(o for o, _, _ in entries if o.retained)
        lost = next(o for o, _, _ in entries if not o.retained)
        return (f"{kept.symbol} ({kept.operand}) is non-volatile (A-44) and {lost.symbol} ({lost.operand}) is not: "
                "RETAIN applies to a whole STRUCT")
    seen: dict[str, str] = {}
    for o, _, member in entries:
        if legalise(member)[0] != member or len(member) > MAX_LEN:
            return f"member '{member}' of {o.symbol} is no IEC identifier"
        if member.upper() in RESERVED:
            return f"member '{member}' of {o.symbol} is an IEC keyword or standard name"
        if member.upper() in seen:
            return f"members '{seen[member.upper()]}' and '{member}' differ only in case"
        seen[member.upper()] = member
    for what, name in (("group name", prefix), ("type name", TYPE_PREFIX + prefix)):
        if name.upper().startswith("HH_"):
            return f"the {what} {name} would take the translator's HH_ prefix"
        if name.upper() in RESERVED or legalise(name)[0] != name:
            return f"the {what} {name} is no free IEC identifier"
        in_use = name_in_use(name)
        if in_use is not None:
            return f"the {what} {name} is {in_use}"
    return None
