"""The pure PLC modules, exactly: number/string conversion (9050, 9052-9054, 9070) and stack depth (9019).

They are functions of their parameters and of PLC memory (strings, bytes), so the interpreter runs them
here instead of in the C shim (which has no PLC memory). Each returns (results, error code); code 0 is
success. The details the manuals leave open are assumption A-46r in the module table's rows: the decimal
character follows MP7280 (0 comma, 1 point; point when the MP file has no MP7280), hex digits are
upper case, exponents outside -10..10 are error 2.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Callable, Mapping, Sequence

from transpiler.exec.interp.state import MachineState

INT32_MAX = 2**31 - 1
ERR_STRING, ERR_COUNT, ERR_ADDRESS, ERR_HEX = 2, 1, 4, 5
MAX_EXPONENT = 10

Pure = Callable[[MachineState, Sequence[int], "PureEnv"], tuple[list[int], int]]


class PureEnv:
    """What a pure module may read besides memory: the data stack depth and the decimal character."""

    def __init__(self, stack_words: Callable[[], int], decimal_char: str):
        self.stack_words = stack_words
        self.decimal_char = decimal_char


def _string_ok(state: MachineState, n: int) -> bool:
    return 0 <= n < len(state.S)


def format_number(mantissa: int, exponent: int, point: str) -> str:
    """mantissa x 10^exponent as decimal text: '-' only for negatives, no padding, no trailing fraction zeros."""
    sign = "-" if mantissa < 0 else ""
    digits = str(abs(mantissa))
    if exponent >= 0:
        text = digits + "0" * exponent if mantissa else "0"
        return sign + text
    digits = digits.rjust(-exponent + 1, "0")
    whole, frac = digits[:exponent], digits[exponent:].rstrip("0")
    return sign + whole + (point + frac if frac else "")


def _digit(c: str) -> bool:
    # Only 0-9: str.isdigit() also accepts Latin-1 superscripts such as '\xb2', which int() then refuses.
    return c in "0123456789"


def parse_number(text: str) -> tuple[int, int, int, int] | None:
    """(mantissa, exponent, start offset, end offset) of the first number in text (sign, digits, one '.' or ','), None if none."""
    i, n = 0, len(text)
    while i < n and not (_digit(text[i]) or (text[i] in "+-" and i + 1 < n and _digit(text[i + 1]))):
        i += 1
    if i == n:
        return None
    start = i
    negative = text[i] == "-"
    if text[i] in "+-":
        i += 1
    digits, frac, seen_point = "", 0, False
    while i < n and (_digit(text[i]) or (text[i] in ".," and not seen_point)):
        if text[i] in ".,":
            seen_point = True
        else:
            digits += text[i]
            frac += seen_point
        i += 1
    mantissa, exponent = int(digits), -frac
    while mantissa > INT32_MAX:             # truncated to fit a double word, the exponent adjusted
        mantissa //= 10
        exponent += 1
    return (-mantissa if negative else mantissa), exponent, start, i


def m9019(state: MachineState, p: Sequence[int], env: PureEnv) -> tuple[list[int], int]:
    return [env.stack_words() * 2], 0        # 16-bit words: 2 bytes each (4 per B/W/D/K entry, 2 per bit)


def m9050(state: MachineState, p: Sequence[int], env: PureEnv) -> tuple[list[int], int]:
    mantissa, exponent, s = p
    if not _string_ok(state, s) or abs(exponent) > MAX_EXPONENT:
        return [], ERR_STRING
    state.S[s] = format_number(mantissa, exponent, env.decimal_char)[:state.string_len]
    return [], 0


def m9052(state: MachineState, p: Sequence[int], env: PureEnv) -> tuple[list[int], int]:
    if not _string_ok(state, p[0]):
        return [0, 0], ERR_STRING
    found = parse_number(state.S[p[0]])
    if found is None:
        return [0, 0], ERR_STRING
    return [found[0], found[1]], 0


def m9053(state: MachineState, p: Sequence[int], env: PureEnv) -> tuple[list[int], int]:
    addr, s, count = p
    if count < 0 or 2 * count > state.string_len:
        return [], ERR_COUNT
    if not _string_ok(state, s):
        return [], ERR_STRING
    if addr < 0 or addr + count > state.mem_size:
        return [], ERR_ADDRESS
    state.S[s] = "".join(f"{state.mem[a]:02X}" for a in range(addr, addr + count))
    return [], 0


def m9054(state: MachineState, p: Sequence[int], env: PureEnv) -> tuple[list[int], int]:
    s, addr = p
    if not _string_ok(state, s):
        return [], ERR_STRING
    text = state.S[s]
    if len(text) % 2 or any(c not in "0123456789abcdefABCDEF" for c in text):
        return [], ERR_HEX
    count = len(text) // 2
    if addr < 0 or addr + count > state.mem_size:
        return [], ERR_ADDRESS
    for k in range(count):
        state.mem[addr + k] = int(text[2 * k:2 * k + 2], 16)
    return [], 0


def m9070(state: MachineState, p: Sequence[int], env: PureEnv) -> tuple[list[int], int]:
    src, dst = p
    if not (_string_ok(state, src) and _string_ok(state, dst)):
        return [-1], 1
    text = state.S[src]
    found = parse_number(text)
    if found is None:
        return [-1], ERR_STRING
    start, end = found[2], found[3]
    state.S[dst] = text[start:end]
    return [end], 0


PURE_MODULES: Mapping[int, Pure] = MappingProxyType(
    {9019: m9019, 9050: m9050, 9052: m9052, 9053: m9053, 9054: m9054, 9070: m9070})


def written(number: int, state: MachineState, p: Sequence[int]) -> list[tuple[str, int]]:
    """The operands a successful call of pure module `number` with parameters `p` wrote: the strings of 9050,
    9053 and 9070, the bytes of 9054 (the co-simulation compares them from then on, as it does indexed stores)."""
    if number == 9050:
        return [("S", p[2])]
    if number in (9053, 9070):
        return [("S", p[1])]
    if number == 9054:
        return [("B", a) for a in range(p[1], p[1] + len(state.S[p[0]]) // 2)]
    return []
