"""Address checks of an operand or a defined symbol: alignment and the profile's ranges (interface operands included)."""

from __future__ import annotations

from transpiler.diagnostics import Diagnostics, Span
from transpiler.ir import BIT_KINDS, BYTES, MEM_KINDS
from transpiler.language.semantics import Semantics


def check_range(kind: str, addr: int, semantics: Semantics, span: Span, diags: Diagnostics, what: str,
                count: int = 1) -> bool:
    profile = semantics.profile
    if kind in MEM_KINDS:
        size = BYTES[kind]
        if addr % size:
            prefix = _prefix(kind, addr, what)
            diags.report("E-ADDR-ALIGN", span, f"{prefix}{kind}{addr} is not aligned to {size} bytes")
            return False
        ok = (_inside_one_interval(profile.ranges.B, addr, addr + size - 1)
              or all(profile.ranges.contains("B", a) for a in range(addr, addr + size))
              or profile.is_interface(kind, addr, size))
    elif kind in BIT_KINDS or kind == "S":
        # The fast test (whole span inside one interval) decides almost every operand; the per-address
        # test is only needed for spans that cross an interval border or touch interface operands.
        ok = (_inside_one_interval(getattr(profile.ranges, kind), addr, addr + count - 1)
              or all(profile.ranges.contains(kind, a) or profile.is_interface(kind, a) for a in range(addr, addr + count)))
    else:
        return True
    if not ok:
        prefix = _prefix(kind, addr, what)
        extra = f" (and the following {count - 1})" if count > 1 else ""
        diags.report("E-ADDR-RANGE", span, f"{prefix}{kind}{addr}{extra} is outside the {profile.name} range")
    return ok


def _prefix(kind: str, addr: int, what: str) -> str:
    """How a message names the operand: the symbol when one was written."""
    return "" if what == f"{kind}{addr}" else f"{what}: "


def _inside_one_interval(intervals: tuple[tuple[int, int], ...], first: int, last: int) -> bool:
    for lo, hi in intervals:
        if lo <= first and last <= hi:
            return True
    return False
